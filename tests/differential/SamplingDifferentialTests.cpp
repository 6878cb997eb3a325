// Sampling differential test (SPEC 8): the JIT samplers of random materials
// against the interpreter's reference sampler for the same u.
//
// One pass of the random stream: one material for each NDF x masking x
// Fresnel x diffuse combination the checker accepts (RandomMaterial.h; the
// eval differential test runs the stream longer, and a sampler's code
// differs between combinations, not between random parameter expressions).
// Each is compiled as one kernel, scalar or SIMD 4, 8, 16 in turn, of one
// math mode (exact and fast in turn; the twelve Fresnel x diffuse
// combinations of an NDF and masking see all eight); every eighth material
// also as a SIMD kernel, which must agree with the scalar one. The kernels sample the same float lanes: the
// random directions and inputs of the eval differential test, wo on the
// hard-case directions (n.wo down to 1e-7), and u drawn at random with the
// edges 0 and 1 - 2^-24 in every combination. Against the reference, which
// reads the very same floats widened to double:
//   - the same validity per lane;
//   - wi within 1e-5 (exact; 2e-3 fast, on the regular lanes below)
//     wherever both chose the same lobe
//     (lanes whose u0 lies within rounding of the lobe probability may
//     choose either and are left out, at most a handful);
//   - pdf and weight within the eval bounds: 99.9% within 1e-5 relative and
//     every value within 2e-3 (exact kernels); fast kernels on the regular
//     lanes (random wo and u) 99.9% within 2e-3 and every value within 5e-2. Either of the reference's sample or of
//     the reference's pdf and f cos / pdf at the kernel's own float wi
//     counts (where an ulp of wi moves the pdf by more than that, see
//     compareWithReferenceSampler). On the hard-case wo and at the edges of
//     u, fast kernels are held, like fast eval on its hard cases, to finite
//     non-negative results only, and their worst differences are printed:
//     fast math computes the sampler in float, and there the direction is
//     the small difference of two nearly opposite vectors (wi + wo with
//     n.wo = 1e-7 and wi near -wo; the spherical cap's point next to -wo at
//     u2 = 1 - 2^-24), which float and an approximate sqrt or sine move by
//     far more than 2e-3;
//   - a pdf that underflows float has weight 0 (the reference's, in
//     double, divides by its tiny pdf);
//   - no NaN, Inf or negative pdf or weight on any lane;
//   - paired scalar and SIMD kernels of one math mode: wi within 2e-5 and
//     pdf and weight within 2e-3 of each other (exact: the SIMD sampler of
//     a float-first material computes its well-conditioned lanes in float,
//     the scalar one in double, each within its bounds of the reference),
//     2e-3 (fast, regular lanes: the vector and scalar approximations of
//     sqrt and division differ).
// Every kernel has a compiled sampler (Kernel::samplerTier() is "jit"; a
// kernel that fell back to the reference sampler fails the test).
#include "DiffHarness.h"
#include "RandomMaterial.h"

#include "Checker.h"
#include "ReferenceComparison.h"
#include "Sampling.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cmath>
#include <map>

using namespace facet;
using namespace facet::test;

namespace {

constexpr float kLastU = 1 - 0x1p-24f;

CompileOptions samplerOptions(Backend backend, int width, MathMode math) {
    CompileOptions o;
    o.backend = backend;
    o.width = width;
    o.math = math;
    o.cache = CompileOptions::Cache::Memory;
    o.codegen = CompileOptions::Codegen::Quick;
    return o;
}

// The sampler's lanes: wo and the inputs from an eval sample, u per lane.
struct SamplerLanes {
    LaneBatch eval;
    std::array<std::vector<float>, 3> u;
    size_t randomLanes = 0;  // lanes [0, randomLanes) are random, the rest hard cases
    size_t size() const { return eval.size(); }
};

SamplerLanes samplerLanes(const CheckedMaterial& m, uint64_t seed) {
    SamplerLanes lanes;
    lanes.eval = randomSample(m, 400, seed);
    lanes.randomLanes = lanes.size();
    LaneBatch hard = hardSample(m);
    // wo from the hard sample's wi as well: both columns hold its grazing and
    // near-normal directions, and wo is the sampler's only direction.
    for (size_t i = 0; i < hard.size(); ++i)
        for (int side : {0, 3}) {
            double wo[3] = {hard.dir[side][i], hard.dir[side + 1][i], hard.dir[side + 2][i]};
            std::vector<double> slots;
            for (const auto& column : hard.slots) slots.push_back(column[i]);
            lanes.eval.push(wo, wo, slots);
        }
    lanes.eval.finish();
    std::mt19937_64 rng(seed * 7 + 1);
    std::uniform_real_distribution<float> uniform(0, 1);
    const float edge[2] = {0, kLastU};
    for (size_t i = 0; i < lanes.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            float x = (i % 16) < 8 ? edge[((i % 16) >> c) & 1] : uniform(rng);
            lanes.u[c].push_back(x < 1 ? x : kLastU);
        }
    return lanes;
}

struct SamplerOutput {
    std::array<std::vector<float>, 3> wi, weight;
    std::vector<float> pdf;
    int64_t invalid = 0;
};

SamplerOutput runSampler(const Kernel& k, const SamplerLanes& lanes) {
    SamplerOutput out;
    size_t n = lanes.size();
    for (int c = 0; c < 3; ++c) out.wi[c].assign(n, -1), out.weight[c].assign(n, -1);
    out.pdf.assign(n, -1);
    const float* u[3] = {lanes.u[0].data(), lanes.u[1].data(), lanes.u[2].data()};
    float* wi[3] = {out.wi[0].data(), out.wi[1].data(), out.wi[2].data()};
    float* weight[3] = {out.weight[0].data(), out.weight[1].data(), out.weight[2].data()};
    out.invalid = k.sampleBatch(int64_t(n), lanes.eval.wo(), u, lanes.eval.inputs(), wi, out.pdf.data(), weight);
    return out;
}

struct SamplerStats {
    size_t compared = 0, values = 0, within1e5 = 0, beyond = 0, beyondFast = 0, nonFinite = 0, negative = 0, validityMismatch = 0,
           choiceAmbiguous = 0, wiBeyond = 0, referenceInvalid = 0;
    double maxRel = 0, maxWi = 0, maxRelHardFast = 0, maxWiHardFast = 0;
    std::string worst;

    bool ok(bool exact, std::string& why) const {
        if (nonFinite || negative) why = fmt::format("{} non-finite and {} negative pdf or weight", nonFinite, negative);
        else if (validityMismatch) why = fmt::format("{} lanes valid on one side only", validityMismatch);
        else if (wiBeyond) why = fmt::format("{} directions beyond the bound (max {:.3g}); worst: {}", wiBeyond, maxWi, worst);
        else if (exact && beyond) why = fmt::format("{} pdf or weight values beyond 2e-3; worst: {}", beyond, worst);
        // Fast math: at most one value in a thousand (plus one) beyond 2e-3,
        // none beyond 5e-2. Its float half vector and approximate sqrt move
        // the pdf of a narrow lobe near grazing (pdf ~ 1e6) by up to ~2%
        // even at the kernel's own wi.
        else if (!exact && beyond > values / 1000 + 1)
            why = fmt::format("{} of {} pdf or weight values beyond 2e-3; worst: {}", beyond, values, worst);
        else if (!exact && beyondFast) why = fmt::format("{} pdf or weight values beyond 5e-2; worst: {}", beyondFast, worst);
        else if (exact && double(within1e5) < 0.999 * double(values))
            why = fmt::format("only {}/{} within 1e-5; worst: {}", within1e5, values, worst);
        // u0 within the band around p: 2e-6 (exact) or 4e-3 (fast) of the
        // lanes expected.
        else if (choiceAmbiguous > compared / (exact ? 1000 : 100) + 4)
            why = fmt::format("{} of {} lanes at the lobe probability", choiceAmbiguous, compared);
        return why.empty();
    }
};

void compareWithReferenceSampler(const Kernel& k, const CheckedMaterial& m, const SamplerLanes& lanes,
                                 const SamplerOutput& out, bool exact, SamplerStats& stats) {
    Interpreter<double> interp(m, k.energyTable());
    const double wiBound = exact ? 1e-5 : 2e-3;
    // Lanes [0, randomLanes) with i % 16 >= 8 have random wo and u.
    auto regular = [&](size_t i) { return i < lanes.randomLanes && i % 16 >= 8; };
    std::vector<double> slots(size_t(m.slotCount));
    for (size_t i = 0; i < lanes.size(); ++i) {
        double wo[3], u[3];
        for (int c = 0; c < 3; ++c) wo[c] = lanes.eval.wo()[c][i], u[c] = lanes.u[c][i];
        for (int s = 0; s < m.slotCount; ++s) slots[size_t(s)] = lanes.eval.slots[size_t(s)][i];
        SampleResult<double> ref = interp.sample(wo, u, slots.data());
        for (float v : {out.pdf[i], out.weight[0][i], out.weight[1][i], out.weight[2][i]}) {
            stats.nonFinite += !std::isfinite(v);
            stats.negative += v < 0;
        }
        if (!ref.valid) {
            ++stats.referenceInvalid;
            // The kernel's lane must be all zeros too (and counted invalid).
            bool zeros = out.pdf[i] == 0 && out.wi[0][i] == 0 && out.wi[1][i] == 0 && out.wi[2][i] == 0;
            stats.validityMismatch += !zeros;
            continue;
        }
        ++stats.compared;
        // Where u0 is within rounding of the lobe probability the two may
        // pick different lobes.
        double len = std::sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
        Vec3<double> woUnit{wo[0] / len, wo[1] / len, wo[2] / len};
        if (woUnit.z > 0) {
            double p = specularProbability(interp.resolve(slots.data()), woUnit);
            if (p < 1 && std::abs(u[0] - p) <= (exact ? 1e-6 : 2e-3)) {
                ++stats.choiceAmbiguous;
                continue;
            }
        }
        auto describe = [&](const char* what, double got, double want) {
            return fmt::format("{} {:.9g} vs {:.9g} at wo ({:.9g}, {:.9g}, {:.9g}) u ({:.9g}, {:.9g}, {:.9g})", what, got,
                               want, wo[0], wo[1], wo[2], u[0], u[1], u[2]);
        };
        double wiErr = std::max({std::abs(out.wi[0][i] - ref.wi.x), std::abs(out.wi[1][i] - ref.wi.y),
                                 std::abs(out.wi[2][i] - ref.wi.z)});
        if (!exact && !regular(i)) stats.maxWiHardFast = std::max(stats.maxWiHardFast, wiErr);
        else if (wiErr > stats.maxWi) stats.maxWi = wiErr;
        if (wiErr > wiBound && (exact || regular(i))) {
            ++stats.wiBeyond;
            stats.worst = describe("wi.x", out.wi[0][i], ref.wi.x);
        }
        // The kernel's pdf and weight are right if they are the
        // reference's for the sample, or the reference's density and f cos /
        // pdf at the float wi the kernel returned: where pdf varies fast
        // with wi (n.wo near 0 and wi near -wo, where the half vector is the
        // small difference wi + wo) an ulp of wi moves it by more than the
        // eval bounds, and a renderer sees the kernel's own wi.
        double wiK[3] = {out.wi[0][i], out.wi[1][i], out.wi[2][i]};
        bool haveAtWi = false;
        double pdfAtWi = 0;
        std::array<double, 3> weightAtWi{};
        auto atKernelWi = [&] {
            if (haveAtWi) return;
            haveAtWi = true;
            if (wiK[0] == 0 && wiK[1] == 0 && wiK[2] == 0) return;
            pdfAtWi = interp.pdf(wiK, wo, slots.data()).pdf;
            EvalResult<double> f = interp.eval(wiK, wo, slots.data());
            double len = std::sqrt(wiK[0] * wiK[0] + wiK[1] * wiK[1] + wiK[2] * wiK[2]);
            for (int c = 0; c < 3; ++c)
                weightAtWi[c] = pdfAtWi > 0 && wiK[2] > 0 ? f.rgb[c] * (wiK[2] / len) / pdfAtWi : 0;
        };
        auto value = [&](const char* what, float got, double want, const double& wantAtWi) {
            if (beyondFloatRange(want)) return;
            double rel = relativeError(got, want);
            if (rel > 1e-5) {
                atKernelWi();
                rel = std::min(rel, relativeError(got, wantAtWi));
            }
            if (!exact && !regular(i)) {
                stats.maxRelHardFast = std::max(stats.maxRelHardFast, rel);
                return;
            }
            ++stats.values;
            stats.within1e5 += rel <= 1e-5;
            if (rel > 2e-3) ++stats.beyond;
            if (rel > 5e-2) ++stats.beyondFast;
            if (rel > stats.maxRel) {
                stats.maxRel = rel;
                if (stats.wiBeyond == 0) stats.worst = describe(what, got, want);
            }
        };
        value("pdf", out.pdf[i], ref.pdf, pdfAtWi);
        // A density that underflows float is no density a renderer can
        // divide by: the kernel's weight is then 0 (pdf 0 means weight 0),
        // where the double reference still divides by its tiny pdf.
        const bool pdfUnderflows = float(ref.pdf) == 0.0f && out.pdf[i] == 0.0f;
        for (int c = 0; c < 3; ++c)
            value("weight", out.weight[c][i], pdfUnderflows ? 0.0 : ref.weight[c], weightAtWi[c]);
    }
}

// Scalar and SIMD kernels of one math mode: the largest difference of wi
// (absolute) and of pdf and weight (relative) over the lanes `counted`
// selects.
struct ScalarSimdDifference {
    double wi = 0, value = 0;
};
template <typename Counted>
ScalarSimdDifference scalarSimdDifference(const SamplerOutput& a, const SamplerOutput& b, Counted counted) {
    ScalarSimdDifference worst;
    for (size_t i = 0; i < a.pdf.size(); ++i) {
        if (!counted(i)) continue;
        worst.value = std::max(worst.value, relativeError(a.pdf[i], b.pdf[i]));
        for (int c = 0; c < 3; ++c) {
            worst.wi = std::max(worst.wi, std::abs(double(a.wi[c][i]) - b.wi[c][i]));
            worst.value = std::max(worst.value, relativeError(a.weight[c][i], b.weight[c][i]));
        }
    }
    return worst;
}

}  // namespace

TEST_CASE("random materials: JIT samplers against the reference sampler for the same u") {
    Compiler compiler;
    const int widths[] = {4, 8, 16};
    int failures = 0, jitKernels = 0;
    std::map<std::string, SamplerStats> byRun;
    ScalarSimdDifference worstScalarSimdExact, worstScalarSimdFast;
    int pairs = 0;
    size_t lanesTotal = 0;
    // Rounded up to whole groups of eight (the pairing and the alternation
    // of widths and math modes above).
    const int materials = (randomMaterialCombinationCount() + 7) / 8 * 8;
    for (int i = 0; i < materials && failures < 20; ++i) {
        RandomMaterial rm = randomMaterial(4321, i);
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramText(rm.text, "random.mat", diags);
        REQUIRE_MESSAGE(!diags.hasErrors(), rm.text << diags.str());
        const CheckedMaterial& m = program.materials.front();
        // Each material gets one kernel, scalar or SIMD 4/8/16 in turn, in
        // one math mode (alternating every four materials); every second
        // scalar material also gets a SIMD kernel, for the scalar-vs-SIMD
        // check. (Each kernel compiles eval and sampler, so a second kernel
        // for every material would double the test's time for little more
        // coverage.)
        const bool exact = (i / 4) % 2 == 0;
        const MathMode math = exact ? MathMode::Exact : MathMode::Fast;
        const int width = i % 4 == 0 ? 1 : widths[i % 4 - 1];
        const bool paired = i % 8 == 0;
        DiagnosticEngine kd;
        std::vector<std::pair<std::unique_ptr<Kernel>, std::string>> kernels;
        kernels.emplace_back(compiler.compileText(rm.text, "random.mat", "",
                                                  samplerOptions(width == 1 ? Backend::Scalar : Backend::Simd, width, math), kd),
                             width == 1 ? std::string("scalar") : fmt::format("simd{}", width));
        if (paired) {
            int partner = widths[(i / 8) % 3];
            kernels.emplace_back(compiler.compileText(rm.text, "random.mat", "",
                                                      samplerOptions(Backend::Simd, partner, math), kd),
                                 fmt::format("simd{}", partner));
        }
        for (const auto& k : kernels) REQUIRE_MESSAGE(k.first, kd.str() << rm.text);
        REQUIRE_MESSAGE(kernels.front().first->samplerTier() == "jit",
                        rm.combination << " samples through the reference\n" << rm.text);
        SamplerLanes lanes = samplerLanes(m, 500 + uint64_t(i));
        lanesTotal += lanes.size();
        std::vector<SamplerOutput> outputs;
        for (const auto& k : kernels) {
            REQUIRE(k.first->samplerTier() == "jit");
            outputs.push_back(runSampler(*k.first, lanes));
        }
        if (paired) {
            const SamplerOutput &a = outputs[0], &b = outputs[1];
            CHECK(a.invalid == b.invalid);
            // Exact kernels on every lane; fast ones on the regular lanes (see
            // compareWithReferenceSampler).
            ScalarSimdDifference difference = scalarSimdDifference(a, b, [&](size_t lane) {
                return exact || (lane < lanes.randomLanes && lane % 16 >= 8);
            });
            ScalarSimdDifference& worst = exact ? worstScalarSimdExact : worstScalarSimdFast;
            worst.wi = std::max(worst.wi, difference.wi);
            worst.value = std::max(worst.value, difference.value);
            ++pairs;
        }
        for (size_t k = 0; k < kernels.size(); ++k) {
            const SamplerOutput* out = &outputs[k];
            ++jitKernels;
            SamplerStats stats;
            compareWithReferenceSampler(*kernels[k].first, m, lanes, *out, exact, stats);
            if (size_t(out->invalid) != stats.referenceInvalid) ++stats.validityMismatch;
            std::string run = fmt::format("{} {}", kernels[k].second, exact ? "exact" : "fast");
            SamplerStats& total = byRun[run];
            total.compared += stats.compared;
            total.choiceAmbiguous += stats.choiceAmbiguous;
            total.values += stats.values;
            total.beyond += stats.beyond;
            total.maxRel = std::max(total.maxRel, stats.maxRel);
            total.maxWi = std::max(total.maxWi, stats.maxWi);
            total.maxRelHardFast = std::max(total.maxRelHardFast, stats.maxRelHardFast);
            total.maxWiHardFast = std::max(total.maxWiHardFast, stats.maxWiHardFast);
            std::string why;
            if (!stats.ok(exact, why)) {
                ++failures;
                FAIL_CHECK("random material " << i << " (" << rm.combination << ") " << run << ": " << why << "\n"
                                              << rm.text);
            }
        }
    }
    for (const auto& [run, s] : byRun)
        MESSAGE(fmt::format("{}: {} lanes compared, worst wi difference {:.3g}, worst pdf/weight error {:.3g} ({} of {} "
                            "values beyond 2e-3){}, {} at the lobe probability",
                            run, s.compared, s.maxWi, s.maxRel, s.beyond, s.values,
                            run.ends_with("fast") ? fmt::format(" (hard cases and u edges, not bounded: wi {:.3g}, pdf/weight {:.3g})",
                                                                    s.maxWiHardFast, s.maxRelHardFast) : "",
                            s.choiceAmbiguous));
    MESSAGE(fmt::format("{} materials, {} JIT kernels over {} lanes; scalar vs SIMD ({} pairs) worst difference "
                        "wi {:.3g}, pdf/weight {:.3g} exact; wi {:.3g}, pdf/weight {:.3g} fast",
                        materials, jitKernels, lanesTotal, pairs, worstScalarSimdExact.wi, worstScalarSimdExact.value,
                        worstScalarSimdFast.wi, worstScalarSimdFast.value));
    CHECK(worstScalarSimdExact.wi <= 2e-5);
    CHECK(worstScalarSimdExact.value <= 2e-3);
    CHECK(worstScalarSimdFast.wi <= 2e-3);
    CHECK(worstScalarSimdFast.value <= 2e-3);
    // Every material of the stream was compared, and every eighth twice.
    CHECK(pairs == materials / 8);
    CHECK(jitKernels == materials + pairs);
    CHECK(byRun.size() == 8);  // scalar and SIMD 4/8/16, exact and fast
}
