// Hard-case tests (SPEC section 7).
//
// Over the hard-case sample (compiler/hardcases/HardCases.h) of every generated
// material -- every NDF form x masking x Fresnel the checker accepts, with
// the model parameters as unranged inputs, plus constant extreme parameters
// -- on the interpreter, scalar and SIMD16 kernels (SIMD4 and SIMD8
// alternating between materials, to fit the time budget) in both math modes
// (exact, fast):
//   - no NaN, no Inf, no negative output; invalid inputs give 0 and are
//     counted by the batch call;
//   - the double interpreter against the __float128 one: within 1e-12
//     relative, except at ill-conditioned inputs (error within 16 kappa u,
//     kappa estimated in __float128), which are listed with kappa;
//   - the exact-mode JIT against the double interpreter within the bound of
//     apps/verify/Verify.h at well-conditioned inputs, and no valid lane
//     reported invalid (fast mode: measured and printed);
//   - fast kernels within max(1e-3, 2 x the error of the SPEC formula
//     evaluated in float, Interpreter<float>) on every lane, except the
//     named gaps of kFastGaps (counted and printed).
// Everything is computed once (two worker threads) and asserted by the test
// cases below; the numbers quoted in docs/numerics.md are printed here.
//
//   FACET_HARDCASE_FILTER=substring   only materials whose name contains it
//   FACET_HARDCASE_NO_JIT=1           skip the kernels (reference checks only)
//   FACET_HARDCASE_ALL_WIDTHS=1       SIMD4 and SIMD8 on every material (default: alternating)
#include "QuadMath.h"

#include "Checker.h"
#include "HardCases.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "TableCache.h"
#include "Verify.h"

#include <doctest/doctest.h>
#if defined(__x86_64__)
#include <xmmintrin.h>
#endif
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <thread>

using namespace facet;

namespace {

constexpr double kQuadTolerance = 1e-12;
constexpr double kUnit = 0x1p-53;

struct Variant {
    const char* name;
    const char* options;
};
const Variant kVariants[] = {
    {"scalar exact", "backend=scalar;math=exact"},      {"simd4 exact", "backend=simd;width=4;math=exact"},
    {"simd8 exact", "backend=simd;width=8;math=exact"},  {"simd16 exact", "backend=simd;width=16;math=exact"},
    {"scalar fast", "backend=scalar;math=fast"},        {"simd4 fast", "backend=simd;width=4;math=fast"},
    {"simd8 fast", "backend=simd;width=8;math=fast"},    {"simd16 fast", "backend=simd;width=16;math=fast"},
};

struct IllCase {
    double kappa, err;
    std::string material, text;
};

struct QuadStats {
    size_t cases = 0, illConditioned = 0, unexplained = 0, mismatches = 0;
    size_t subnormal = 0;  // cases with a double-subnormal direction component (validity only)
    double worstWell = 0;
    std::string worstWellCase;
    std::vector<IllCase> ill;             // the most ill-conditioned (by kappa)
    std::vector<std::string> failures;    // unexplained errors and validity mismatches
};

// A fast kernel against the SPEC formula evaluated in float (the catalog's
// reference formulas through Interpreter<float>), both measured against the
// double interpreter: fast mode may lose accuracy only where float itself
// does, err_fast <= max(kFastFloor, kFastFactor err_float) on every valid lane.
constexpr double kFastFloor = 1e-3, kFastFactor = 2;

// The known gaps, counted and printed instead of failed (docs/numerics.md,
// "Fast mode"): materials whose name contains `material`, at input sweeps
// (case label "<input> VALUE ...") with min <= VALUE <= max.
struct FastGap {
    const char *material, *input;
    double min, max;
    const char* why;
};
const FastGap kFastGaps[] = {
    {"beckmann", "input alpha=", 0x1p64, INFINITY, "alpha^2 overflows float: the lane is dropped (diffuse or compensation lost)"},
    {"beckmann", "all inputs=", 0x1p64, INFINITY, "alpha^2 overflows float, as above"},
    {"gtr", "input gamma=", 1e29, INFINITY, "mirror pairs at n.h = 1: the lobe (width ~1e-31 in sin^2 theta_h) is narrower than the ~1e-15 rounding of the corrected sums' tangential h (docs/numerics.md)"},
};
const FastGap* fastGap(const std::string& material, const HardCase& c) {
    for (const FastGap& g : kFastGaps) {
        size_t n = std::strlen(g.input);
        if (material.find(g.material) == std::string::npos || c.label.compare(0, n, g.input) != 0) continue;
        double v = std::strtod(c.label.c_str() + n, nullptr);
        if (v >= g.min && v <= g.max) return &g;
    }
    return nullptr;
}

struct FloatFormulaStats {
    size_t compared = 0, beyond = 0;
    std::map<const FastGap*, size_t> knownGap;  // values beyond at a case of kFastGaps
    double worstRatio = 0;  // max of err_fast / max(kFastFloor, kFastFactor err_float)
    double worstFast = 0, worstFloat = 0;
    std::string worstCase;
    std::vector<std::string> failures;  // the first few lanes beyond
};

struct KernelResult {
    std::string variant;
    SampleStats stats;
    FloatFormulaStats vsFloat;  // fast kernels only
    std::vector<std::string> failureText;  // described failing cases
    std::string compileError;
};

struct MaterialResult {
    HardCaseMaterial hm;
    size_t cases = 0;
    SampleStats interp, interpRaw;
    std::vector<std::string> interpFailures;
    QuadStats quad, quadRaw;
    std::vector<KernelResult> kernels;
};

// The float evaluation of the formula on the sample (the kernels' float
// inputs, converted exactly), in fast mode's floating-point environment:
// fast kernels read a float-subnormal cosine as 0 (docs/numerics.md), and
// so does the float formula under FTZ/DAZ: the comparison measures the
// formulas and approximations, not that documented choice.
std::vector<EvalResult<float>> evaluateInFloat(const Interpreter<float>& interp, const std::vector<HardCase>& cases) {
#if defined(__x86_64__)
    struct FlushSubnormals {
        unsigned saved = _mm_getcsr();
        FlushSubnormals() { _mm_setcsr(saved | 0x8040u); }  // FTZ (bit 15) and DAZ (bit 6)
        ~FlushSubnormals() { _mm_setcsr(saved); }
    } flush;
#endif
    std::vector<EvalResult<float>> out;
    out.reserve(cases.size());
    for (const HardCase& c : cases) {
        float wi[3], wo[3];
        for (int k = 0; k < 3; ++k) wi[k] = float(c.wi[k]), wo[k] = float(c.wo[k]);
        std::vector<float> slots(c.slots.begin(), c.slots.end());
        out.push_back(interp.eval(wi, wo, slots.empty() ? nullptr : slots.data()));
    }
    return out;
}

// Fast kernel vs float formula on every lane the reference finds valid and
// float can hold. A lane the kernel drops (reports invalid) counts as 0; the
// float formula's error is Inf where it is invalid or not finite (any fast
// value passes there).
FloatFormulaStats compareWithFloatFormula(const CheckedMaterial& m, const std::string& name, const char* variant,
                                          const KernelRun& run, const std::vector<HardCase>& cases,
                                          const HardCaseReference& ref, const std::vector<EvalResult<float>>& fl) {
    FloatFormulaStats s;
    for (size_t i = 0; i < cases.size(); ++i) {
        const EvalResult<double>& r = ref.results[i];
        if (cases[i].invalidInput || !r.valid || ref.floatOverflow[i]) continue;
        for (int ch = 0; ch < 3; ++ch) {
            double want = r.rgb[ch];
            if (beyondFloatRange(want)) continue;
            ++s.compared;
            double fast = relativeError(run.invalid[i] ? 0.0 : run.rgb[i][ch], want);
            double flt = fl[i].valid ? relativeError(fl[i].rgb[ch], want) : INFINITY;
            double ratio = fast / std::max(kFastFloor, kFastFactor * flt);
            if (const FastGap* g = ratio > 1 ? fastGap(name, cases[i]) : nullptr) {
                ++s.knownGap[g];
                continue;
            }
            if (ratio > s.worstRatio) {
                s.worstRatio = ratio;
                s.worstFast = fast;
                s.worstFloat = flt;
                s.worstCase = describeCase(m, cases[i]);
            }
            if (ratio > 1 && ++s.beyond <= 3)
                s.failures.push_back(fmt::format("{} [{}] ch {}: fast {:.9g} (err {:.3g}), float formula {:.9g} "
                                                 "(err {:.3g}), want {:.17g} at {}",
                                                 name, variant, ch, run.rgb[i][ch], fast, fl[i].rgb[ch], flt, want,
                                                 describeCase(m, cases[i])));
        }
    }
    return s;
}

void quadCheck(const CheckedMaterial& m, const std::string& name, const std::vector<HardCase>& cases,
               const QuadReference& quad, const std::function<double(size_t)>& condition, QuadStats& q) {
    q.cases = cases.size();
    for (size_t i = 0; i < cases.size(); ++i) {
        QuadComparison c = quad.compare(cases[i]);
        if (c.validMismatch) {
            ++q.mismatches;
            if (q.failures.size() < 8)
                q.failures.push_back(fmt::format("{}: validity double {} quad {} at {}", name, c.doubleValid,
                                                 c.quadValid, describeCase(m, cases[i])));
            continue;
        }
        if (QuadReference::subnormalDirection(cases[i])) {
            ++q.subnormal;  // validity checked above; precision out of double's reach
            continue;
        }
        if (c.relError <= kQuadTolerance) {
            if (c.relError >= q.worstWell) {
                q.worstWell = c.relError;
                q.worstWellCase = describeCase(m, cases[i]);
            }
            continue;
        }
        double kappa = condition(i);
        if (c.relError <= kConditionAllowance * kappa * kUnit) {
            ++q.illConditioned;
            q.ill.push_back({kappa, c.relError, name, describeCase(m, cases[i])});
        } else {
            ++q.unexplained;
            if (q.failures.size() < 8)
                q.failures.push_back(fmt::format("{}: rel err {:.3g} kappa {:.3g} (ch {} double {:.17g} quad {:.17g}) at {}",
                                                 name, c.relError, kappa, c.channel, c.d[c.channel], c.q[c.channel],
                                                 describeCase(m, cases[i])));
        }
    }
    std::sort(q.ill.begin(), q.ill.end(), [](const IllCase& a, const IllCase& b) { return a.kappa > b.kappa; });
    if (q.ill.size() > 4) q.ill.resize(4);
}

MaterialResult runMaterial(const HardCaseMaterial& hm, size_t index, Compiler& compiler) {
    MaterialResult r;
    r.hm = hm;
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramText(hm.text, hm.name + ".mat", diags);
    if (diags.hasErrors() || program.materials.empty()) {  // (hardCaseMaterials returns checked texts only)
        r.interpFailures.push_back(hm.name + ": " + diags.str());
        r.interp.nan = 1;
        return r;
    }
    const CheckedMaterial& m = program.materials.front();
    std::vector<HardCase> cases = hardCases(m);
    // The double-only sample: directions at full double precision, with
    // double subnormals (the input sweeps are float values already).
    HardCaseOptions rawOptions;
    rawOptions.roundToFloat = false;
    rawOptions.inputSweeps = false;
    std::vector<HardCase> raw = hardCases(m, rawOptions);
    r.cases = cases.size();

    // One table per key for the whole run (the Fresnel variants of an NDF x
    // masking pair share it), from the test's cache directory like the kernels'.
    static TableCache referenceTables;
    std::shared_ptr<const EnergyTable> table;
    if (m.singleLobe().compensatesEnergy()) table = referenceTables.getFor(m);
    // A tabulated Lambda through the same cache, before the interpreters ask
    // the process's memory layer for it: a file an earlier run wrote is
    // loaded (and spot-checked) instead of the table being built again.
    if (usesTabulatedLambda(m)) referenceTables.lambdaFor(m);
    QuadReference quad(m, table);
    std::map<size_t, double> kappas, kappasRaw;
    auto condition = [&](size_t i) {
        auto it = kappas.find(i);
        return it != kappas.end() ? it->second : kappas[i] = quad.condition(cases[i]);
    };
    auto conditionRaw = [&](size_t i) {
        auto it = kappasRaw.find(i);
        return it != kappasRaw.end() ? it->second : kappasRaw[i] = quad.condition(raw[i]);
    };

    // The reference on both samples (float-rounded and with double-only values).
    Interpreter<double> interp(m, table);
    HardCaseReference ref = evaluateHardCaseReference(interp, cases), refRaw = evaluateHardCaseReference(interp, raw);
    std::vector<EvalResult<float>> inFloat = evaluateInFloat(Interpreter<float>(m, table), cases);
    r.interp = checkReference(cases, ref);
    r.interpRaw = checkReference(raw, refRaw);
    for (const SampleStats* s : {&r.interp, &r.interpRaw})
        for (const auto& [i, why] : s->failures)
            r.interpFailures.push_back(fmt::format("{}: {} at {}", hm.name, why,
                                                   describeCase(m, (s == &r.interp ? cases : raw)[i])));

    quadCheck(m, hm.name, cases, quad, condition, r.quad);
    quadCheck(m, hm.name, raw, quad, conditionRaw, r.quadRaw);

    if (std::getenv("FACET_HARDCASE_NO_JIT")) return r;
    for (const Variant& v : kVariants) {
        // Scalar and SIMD16 run on every material; SIMD4 and SIMD8 (the same
        // lane code at other widths) alternate between materials, so that
        // every width meets every NDF x masking pair within the time budget
        // (FACET_HARDCASE_ALL_WIDTHS=1: all widths everywhere).
        std::string vn = v.name;
        bool w4 = vn.rfind("simd4", 0) == 0, w8 = vn.rfind("simd8", 0) == 0;
        if ((w4 || w8) && !std::getenv("FACET_HARDCASE_ALL_WIDTHS") && (w4 != (index % 2 == 0))) continue;
        KernelResult k;
        k.variant = v.name;
        CompileOptions o;
        // Quick codegen: the same bits as optimized code (JitTierUpTests, "tiered
        // compile"), without a tier-up compiling every kernel a second time.
        std::string error = CompileOptions::parse(std::string(v.options) + ";codegen=quick", o);
        DiagnosticEngine kd;
        std::unique_ptr<Kernel> kernel = error.empty() ? compiler.compileMaterial(m, o, kd) : nullptr;
        if (!kernel) {
            k.compileError = error.empty() ? kd.str() : error;
            r.kernels.push_back(std::move(k));
            continue;
        }
        KernelRun run = runKernel(*kernel, cases);
        k.stats = checkKernel(v.name, run, cases, ref, hardCaseBound(o.math), condition, hardCaseRoundoff(o.math));
        if (o.math == MathMode::Fast) k.vsFloat = compareWithFloatFormula(m, hm.name, v.name, run, cases, ref, inFloat);
        for (const auto& [i, why] : k.stats.failures)
            k.failureText.push_back(fmt::format("{} [{}] {}: {}", hm.name, v.name, why, describeCase(m, cases[i])));
        r.kernels.push_back(std::move(k));
    }
    return r;
}

struct Suite {
    std::vector<HardCaseMaterial> materials;
    std::vector<std::string> rejected;
    std::vector<MaterialResult> results;
    double seconds = 0;
};

const Suite& suite() {
    static const Suite s = [] {
        Suite out;
        auto start = std::chrono::steady_clock::now();
        out.materials = hardCaseMaterials(&out.rejected);
        if (const char* f = std::getenv("FACET_HARDCASE_FILTER")) {
            std::vector<HardCaseMaterial> kept;
            for (const HardCaseMaterial& m : out.materials)
                if (m.name.find(f) != std::string::npos) kept.push_back(m);
            out.materials = kept;
        }
        out.results.resize(out.materials.size());
        std::atomic<size_t> next{0};
        auto worker = [&] {
            Compiler compiler;  // one JIT per thread
            for (size_t i; (i = next++) < out.materials.size();) out.results[i] = runMaterial(out.materials[i], i, compiler);
        };
        unsigned threads = std::max(1u, std::min(2u, std::thread::hardware_concurrency()));
        std::vector<std::thread> pool;
        for (unsigned t = 0; t < threads; ++t) pool.emplace_back(worker);
        for (std::thread& t : pool) t.join();
        out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        size_t cases = 0;
        for (const MaterialResult& r : out.results) cases += r.cases;
        std::printf("hard cases: %zu materials, %zu cases each sample on average, %.1f s\n", out.results.size(),
                    out.results.empty() ? 0 : cases / out.results.size(), out.seconds);
        return out;
    }();
    return s;
}

// Every NDF x masking x Fresnel model the checker accepts (enumerated from
// the catalog, independently of the generator).
std::set<std::string> acceptedCombinations() {
    std::set<std::string> out;
    std::vector<const ModelInfo*> ndfs = catalogSlot(ModelSlot::Ndf), maskings = catalogSlot(ModelSlot::Masking),
                                  fresnels = catalogSlot(ModelSlot::Fresnel);
    auto args = [](const ModelInfo& m) {
        std::string a;
        for (const ModelForm::Param& p : m.forms.front().params)
            a += (a.empty() ? "" : ", ") + std::string(p.type == ValueType::Rgb ? "rgb(0.5, 0.5, 0.5)" : "0.5");
        return a.empty() ? std::string(m.name) : std::string(m.name) + "(" + a + ")";
    };
    for (const ModelInfo* n : ndfs)
        for (const ModelInfo* g : maskings)
            for (const ModelInfo* f : fresnels) {
                std::string text = "material t { ndf = " + args(*n) + "; masking = " + args(*g) +
                                   "; fresnel = " + args(*f) + "; }";
                DiagnosticEngine diags;
                loadProgramText(text, "t.mat", diags);
                if (!diags.hasErrors()) out.insert(std::string(n->name) + "/" + g->name + "/" + f->name);
            }
    return out;
}

std::string familyOf(const MaterialResult& r) { return r.hm.ndf; }

}  // namespace

TEST_CASE("hard-case materials cover every NDF x masking x Fresnel the checker accepts") {
    const Suite& s = suite();
    for (const std::string& t : s.rejected) FAIL_CHECK("the checker rejected a generated material:\n" << t);
    if (std::getenv("FACET_HARDCASE_FILTER")) return;
    std::set<std::string> covered;
    for (const HardCaseMaterial& m : s.materials) covered.insert(m.ndf + "/" + m.masking + "/" + m.fresnel);
    std::set<std::string> accepted = acceptedCombinations();
    // Every NDF and every masking takes part in some accepted combination
    // with every Fresnel model (the checker's rules, read from the catalog,
    // decide which pairs; a catalog entry added later is counted here too).
    std::set<std::string> ndfsSeen, maskingsSeen;
    for (const std::string& c : accepted) {
        ndfsSeen.insert(c.substr(0, c.find('/')));
        maskingsSeen.insert(c.substr(c.find('/') + 1, c.rfind('/') - c.find('/') - 1));
    }
    CHECK(ndfsSeen.size() == catalogSlot(ModelSlot::Ndf).size());
    CHECK(maskingsSeen.size() == catalogSlot(ModelSlot::Masking).size());
    CHECK(accepted.size() % catalogSlot(ModelSlot::Fresnel).size() == 0);
    for (const std::string& c : accepted) CHECK_MESSAGE(covered.count(c), "not covered: " << c);
    MESSAGE(s.materials.size() << " materials cover " << accepted.size() << " accepted combinations");
}

TEST_CASE("hard cases: the reference interpreter is finite, non-negative, and counts invalid inputs") {
    const Suite& s = suite();
    size_t invalid = 0, byInput = 0;
    for (const MaterialResult& r : s.results) {
        CHECK_MESSAGE(r.interp.ok(), r.hm.name << ": " << r.interp.summary());
        CHECK_MESSAGE(r.interpRaw.ok(), r.hm.name << " (double-only values): " << r.interpRaw.summary());
        for (const std::string& f : r.interpFailures) MESSAGE(f);
        invalid += r.interp.invalid;
        byInput += r.interp.expectedInvalid;
    }
    MESSAGE("reference: " << invalid << " invalid lanes, " << byInput << " of them by a non-finite or non-unit input");
}

TEST_CASE("hard cases: double reference against __float128 within 1e-12 except ill-conditioned inputs") {
    const Suite& s = suite();
    std::map<std::string, std::pair<double, std::string>> worst;  // per NDF family
    std::map<std::string, size_t> illCount;
    std::vector<IllCase> ill;
    size_t total = 0, illTotal = 0;
    for (const MaterialResult& r : s.results) {
        for (const QuadStats* q : {&r.quad, &r.quadRaw}) {
            CHECK_MESSAGE(q->unexplained == 0, r.hm.name << ": " << q->unexplained << " errors beyond 1e-12 and 16 kappa u");
            CHECK_MESSAGE(q->mismatches == 0, r.hm.name << ": " << q->mismatches << " validity mismatches");
            for (const std::string& f : q->failures) MESSAGE(f);
            auto& w = worst[familyOf(r)];
            if (q->worstWell >= w.first) w = {q->worstWell, r.hm.name + " " + q->worstWellCase};
            illCount[familyOf(r)] += q->illConditioned;
            illTotal += q->illConditioned;
            total += q->cases;
            ill.insert(ill.end(), q->ill.begin(), q->ill.end());
        }
    }
    std::printf("\ndouble vs __float128 on %zu cases (float-rounded and double-only samples):\n", total);
    std::printf("  %-12s %-12s %-8s %s\n", "ndf", "worst rel", "ill", "worst well-conditioned case");
    for (const auto& [family, w] : worst)
        std::printf("  %-12s %-12.3g %-8zu %s\n", family.c_str(), w.first, illCount[family], w.second.c_str());
    std::sort(ill.begin(), ill.end(), [](const IllCase& a, const IllCase& b) { return a.kappa > b.kappa; });
    // One line per distinct label, the highest kappa first.
    std::printf("ill-conditioned: %zu cases (error > 1e-12, within 16 kappa u); by label, highest kappa:\n", illTotal);
    std::set<std::string> seen;
    size_t shown = 0;
    for (const IllCase& c : ill) {
        std::string label = c.text.substr(c.text.rfind('['));
        if (!seen.insert(label).second) continue;
        std::printf("  kappa %-9.3g err %-9.3g %s %s\n", c.kappa, c.err, c.material.c_str(), c.text.c_str());
        if (++shown >= 40) break;
    }
}

TEST_CASE("hard cases: JIT kernels never output NaN, Inf or negative values, and count invalid inputs") {
    const Suite& s = suite();
    std::map<std::string, size_t> lanes;
    for (const MaterialResult& r : s.results)
        for (const KernelResult& k : r.kernels) {
            CHECK_MESSAGE(k.compileError.empty(), r.hm.name << " [" << k.variant << "]: " << k.compileError);
            const SampleStats& st = k.stats;
            INFO(r.hm.name, " [", k.variant, "]: ", st.summary());
            CHECK(st.nan == 0);
            CHECK(st.inf == 0);
            CHECK(st.negative == 0);
            CHECK(st.missedInvalid == 0);
            CHECK(st.invalidNonZero == 0);
            CHECK_FALSE(st.countMismatch);
            lanes[k.variant] += st.cases;
        }
    for (const auto& [v, n] : lanes) MESSAGE(v << ": " << n << " lanes");
}

// The JIT's accuracy on the hard cases. Exact mode is enforced: every
// valid lane stays valid (unless float cannot hold the reference value or a
// parameter) and agrees with the double interpreter within the bound of
// apps/verify/Verify.h. Fast mode computes geometry, D and G in float, so at
// float-subnormal cosines, near-opposite grazing directions with small alpha
// and Beckmann tails it loses accuracy or drops lanes (docs/numerics.md,
// "Fast mode"): its numbers are printed, not asserted here (its NaN/Inf/
// negative/invalid-count guarantees are asserted above, and its accuracy on
// the regular sample in tests/jit and tests/bench; its bound relative to
// float, in the next test case).
TEST_CASE("hard cases: exact JIT kernels keep valid lanes valid and agree with the reference") {
    const Suite& s = suite();
    struct Worst {
        double err = 0, within = 0, normal = 0;
        std::string where, whereWithin;
    };
    std::map<std::string, Worst> worst;  // per math mode x NDF family
    std::map<std::string, std::pair<size_t, std::vector<std::string>>> failures;  // per kind
    for (const MaterialResult& r : s.results)
        for (const KernelResult& k : r.kernels) {
            const SampleStats& st = k.stats;
            std::string mode = k.variant.substr(k.variant.find(' ') + 1);
            if (mode == "exact") {
                CHECK_MESSAGE(st.unexpectedInvalid == 0, r.hm.name << " [" << k.variant << "]: " << st.summary());
                CHECK_MESSAGE(st.validityMismatch == 0, r.hm.name << " [" << k.variant << "]: " << st.summary());
                CHECK_MESSAGE(st.beyondBound == 0, r.hm.name << " [" << k.variant << "]: " << st.summary());
            }
            Worst& w = worst[mode + " " + familyOf(r)];
            if (st.maxRel > w.err) {
                w.err = st.maxRel;
                w.where = r.hm.name + " [" + k.variant + "]";
            }
            w.normal = std::max(w.normal, st.maxRelNormal);
            if (st.maxRelWithin > w.within) {
                w.within = st.maxRelWithin;
                w.whereWithin = r.hm.name + " [" + k.variant + "]";
            }
            for (const std::string& f : k.failureText) {
                std::string why = f.substr(f.find("] ") + 2);
                // Kind: the reason and the case label with its numbers masked.
                std::string label = f.substr(f.rfind('['));
                label = std::regex_replace(label, std::regex("^\\[inputs? [^/]*/ "), "[");
                label = std::regex_replace(label, std::regex("=-?[0-9][^ \\]]*"), "=#");
                std::string kind = mode + ": " + why.substr(0, why.find_first_of(":0123456789(")) + " " + label;
                auto& entry = failures[kind];
                ++entry.first;
                if (entry.second.size() < 3) entry.second.push_back(f);
            }
        }
    std::printf("\nJIT against the double interpreter on the hard-case sample (inputs not ill-conditioned):\n"
                "  max err: every value; passing: values within the bound; normal: passing, no float-subnormal cosine\n"
                "  %-20s %-10s %-10s %-10s %s\n", "mode ndf", "max err", "passing", "normal", "where (max err; passing)");
    for (const auto& [key, w] : worst)
        std::printf("  %-20s %-10.3g %-10.3g %-10.3g %s; %s\n", key.c_str(), w.err, w.within, w.normal, w.where.c_str(),
                    w.whereWithin.c_str());
    if (!failures.empty()) std::printf("JIT values beyond the bound by kind (fast mode: reported only; counted up to 16 per kernel and kind):\n");
    for (const auto& [kind, entry] : failures) {
        std::printf("  %zu x %s\n", entry.first, kind.c_str());
        for (const std::string& e : entry.second) std::printf("      %s\n", e.c_str());
    }
}

// Fast mode's accuracy on the hard cases: on every lane, within
// max(1e-3, 2 x the error of the SPEC formula evaluated in float on the same
// inputs), both errors against the double interpreter. Where float itself
// cannot resolve f (near-opposite grazing pairs with small alpha, float-
// subnormal cosines) fast mode may be as far off as float is, never worse.
TEST_CASE("hard cases: fast kernels are never less accurate than the formula evaluated in float") {
    const Suite& s = suite();
    struct Worst {
        double ratio = 0, fast = 0, flt = 0;
        std::string where;
    };
    std::map<std::string, Worst> worst;  // per NDF family
    size_t compared = 0;
    std::map<const FastGap*, size_t> gaps;
    for (const MaterialResult& r : s.results)
        for (const KernelResult& k : r.kernels) {
            if (k.variant.find("fast") == std::string::npos) continue;
            const FloatFormulaStats& f = k.vsFloat;
            compared += f.compared;
            for (const auto& [g, n] : f.knownGap) gaps[g] += n;
            CHECK_MESSAGE(f.beyond == 0, r.hm.name << " [" << k.variant << "]: " << f.beyond
                                                   << " values less accurate than float; worst ratio " << f.worstRatio);
            for (const std::string& e : f.failures) MESSAGE(e);
            Worst& w = worst[familyOf(r)];
            if (f.worstRatio > w.ratio)
                w = {f.worstRatio, f.worstFast, f.worstFloat, r.hm.name + " [" + k.variant + "] " + f.worstCase};
        }
    std::printf("\nfast kernels against the formula in float on %zu values: err_fast / max(%g, %g err_float),\n"
                "  errors against the double interpreter\n  %-12s %-8s %-10s %-10s %s\n",
                compared, kFastFloor, kFastFactor, "ndf", "ratio", "err fast", "err float", "where (worst ratio)");
    for (const auto& [family, w] : worst)
        std::printf("  %-12s %-8.3g %-10.3g %-10.3g %s\n", family.c_str(), w.ratio, w.fast, w.flt, w.where.c_str());
    for (const FastGap& g : kFastGaps)
        std::printf("known gap, %zu values beyond: %s, %s%g..%g: %s\n", gaps[&g], g.material, g.input, g.min, g.max,
                    g.why);
}

// The __float128 reference must compute in __float128 throughout: limits,
// the std math overloads of QuadMath.h and std::complex<__float128> (the
// conductor Fresnel), checked against independent quad formulas.
TEST_CASE("QuadMath: __float128 limits, math and complex Fresnel at full precision") {
    using Q = __float128;
    CHECK(std::isinf(std::numeric_limits<Q>::infinity()));
    CHECK(std::numeric_limits<Q>::epsilon() < Q(1e-33));
    Q two = 2, r = std::sqrt(two);
    CHECK(fabsq(r * r - 2) < Q(1e-33));
    CHECK(Q(double(r)) != r);  // more than double's 53 bits
    std::complex<Q> z = std::sqrt(std::complex<Q>(-4, 0));
    CHECK(fabsq(z.real()) < Q(1e-33));
    CHECK(fabsq(z.imag() - 2) < Q(1e-32));
    // Conductor F from the interpreter (complex) against Born & Wolf's real
    // form, all in quad.
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramText("material c { ndf = ggx(0.3); fresnel = conductor(eta = 0.2, k = 3.7); }",
                                       "c.mat", diags);
    REQUIRE_FALSE(diags.hasErrors());
    Interpreter<Q> interp(p.materials.front());
    ResolvedMaterial<Q> m = interp.resolve(nullptr);
    for (Q c : {Q(1), Q(0.9), Q(0.5), Q(0.1), Q(1e-3)}) {
        Q n = m.fresnelArgs.channel(0, 0), k = m.fresnelArgs.channel(1, 0), s2 = 1 - c * c;  // eta, k
        Q t0 = n * n - k * k - s2, a2b2 = sqrtq(t0 * t0 + 4 * n * n * k * k), a = sqrtq((a2b2 + t0) / 2);
        Q t1 = a2b2 + c * c, t2 = 2 * c * a;
        Q rs = (t1 - t2) / (t1 + t2);
        Q t3 = c * c * a2b2 + s2 * s2, t4 = t2 * s2;
        Q rp = rs * (t3 - t4) / (t3 + t4);
        Q want = (rs + rp) / 2, got = m.F(c, 0);
        INFO("c = ", quadToString(c, 6), " got ", quadToString(got), " want ", quadToString(want));
        CHECK(fabsq(got - want) <= Q(1e-30) * want);
    }
}
