// assume=unit, the host's promise of valid inputs (LoweringPlan::trustInputs):
// on valid inputs the kernels give the default kernels' bits, and on any
// other input they still return (no crash, no read outside a table).
//
// Materials: of the hard-case materials (every catalog example of every NDF
// x masking x Fresnel combination, and every model's own hard cases), those
// that bring a model not seen before: every NDF, masking and Fresnel term,
// every NDF under a Smith masking (the tabulated Lambdas of gtr, student_t
// and epd among them), and energy compensation (the Kulla-Conty tables)
// with and without one; all 534 took 100 s, these a few. Each is compiled in one of the
// eight kernel kinds (scalar, SIMD 4/8/16, exact and fast) in turn, with and
// without the promise. Lanes: the material's hard-case sample and random
// pairs with random in-range inputs; the valid ones are compared bit for
// bit, every lane (NaN, infinite, huge, zero and non-unit directions,
// non-finite inputs) is evaluated. The sampler (sample and pdf batches) of
// every other material, where it has one in IR, is compared the same way.
#include "Checker.h"
#include "HardCases.h"
#include "Kernel.h"
#include "LoweringPlan.h"

#include "../CoveringMaterials.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <thread>

using namespace facet;

namespace {

const char* const kKinds[] = {
    "backend=scalar;math=exact", "backend=simd;width=4;math=exact",  "backend=simd;width=8;math=exact",
    "backend=simd;width=16;math=exact", "backend=scalar;math=fast", "backend=simd;width=4;math=fast",
    "backend=simd;width=8;math=fast",  "backend=simd;width=16;math=fast",
};

// Lanes in SoA, as the batch entry points take them.
struct Lanes {
    std::array<std::vector<float>, 3> wi, wo, u;
    std::vector<std::vector<float>> slots;
    std::vector<char> valid;  // within the host's promise
    size_t size() const { return valid.size(); }
    void add(const std::array<double, 3>& a, const std::array<double, 3>& b, const std::vector<double>& s, bool ok,
             std::mt19937& rng) {
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        for (int c = 0; c < 3; ++c) {
            wi[c].push_back(float(a[c]));
            wo[c].push_back(float(b[c]));
            u[c].push_back(std::min(unit(rng), 0x1.fffffep-1f));
        }
        for (size_t k = 0; k < s.size(); ++k) slots[k].push_back(float(s[k]));
        valid.push_back(ok);
    }
};

// Whether a case keeps the promise: finite unit directions, away from the
// 1e-3 bound (where a float body and a double body may decide either way),
// and finite inputs. Inputs outside their ranges are kept: the kernels still
// clamp them.
bool promised(const HardCase& c) {
    if (c.invalidInput) return false;
    for (const auto* w : {&c.wi, &c.wo}) {
        double len = std::sqrt((*w)[0] * (*w)[0] + (*w)[1] * (*w)[1] + (*w)[2] * (*w)[2]);
        if (!(std::fabs(len - 1) <= 0.9e-3)) return false;
    }
    return true;
}

Lanes lanesFor(const CheckedMaterial& m, size_t seed) {
    Lanes l;
    l.slots.resize(size_t(m.slotCount));
    std::mt19937 rng{unsigned(seed)};
    for (const HardCase& c : hardCases(m)) l.add(c.wi, c.wo, c.slots, promised(c), rng);
    // Random pairs over the sphere (below the horizon too), inputs uniform
    // in their ranges (unranged ones at their defaults).
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<double> defaults = m.defaultSlots();
    for (int i = 0; i < 96; ++i) {
        std::array<double, 3> d[2];
        for (auto& w : d) {
            for (double& x : w) x = gauss(rng);
            double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            for (double& x : w) x /= len;
            w[2] = std::fabs(w[2]) * (unit(rng) < 0.9 ? 1 : -1);
        }
        std::vector<double> s = defaults;
        for (const CheckedInput& in : m.inputs)
            for (int ch = 0; ch < in.slotCount() && in.hasRange; ++ch)
                s[in.firstSlot + ch] = std::clamp(double(float(in.lo + unit(rng) * (in.hi - in.lo))), in.lo, in.hi);
        l.add(d[0], d[1], s, true, rng);
    }
    return l;
}

struct Outputs {
    std::array<std::vector<float>, 3> rgb, wi, weight;
    std::vector<float> pdf, pdfOfWi;
    int64_t evalReturned = 0, sampleReturned = 0, pdfReturned = 0;
};

Outputs run(const Kernel& k, const Lanes& l, bool sampler) {
    const int64_t n = int64_t(l.size());
    Outputs o;
    std::vector<const float*> slotP;
    for (const auto& s : l.slots) slotP.push_back(s.data());
    const float* const* inputs = slotP.empty() ? nullptr : slotP.data();
    const float* wi[3] = {l.wi[0].data(), l.wi[1].data(), l.wi[2].data()};
    const float* wo[3] = {l.wo[0].data(), l.wo[1].data(), l.wo[2].data()};
    const float* u[3] = {l.u[0].data(), l.u[1].data(), l.u[2].data()};
    for (auto* v : {&o.rgb, &o.wi, &o.weight})
        for (auto& c : *v) c.assign(size_t(n), -1.0f);
    float* rgb[3] = {o.rgb[0].data(), o.rgb[1].data(), o.rgb[2].data()};
    o.evalReturned = k.evalBatch(n, wi, wo, inputs, rgb);
    if (sampler) {
        o.pdf.assign(size_t(n), -1.0f);
        o.pdfOfWi.assign(size_t(n), -1.0f);
        float* swi[3] = {o.wi[0].data(), o.wi[1].data(), o.wi[2].data()};
        float* weight[3] = {o.weight[0].data(), o.weight[1].data(), o.weight[2].data()};
        o.sampleReturned = k.sampleBatch(n, wo, u, inputs, swi, o.pdf.data(), weight);
        o.pdfReturned = k.pdfBatch(n, wi, wo, inputs, o.pdfOfWi.data());
    }
    return o;
}

std::unique_ptr<Kernel> compile(Compiler& c, const CheckedMaterial& m, const std::string& options, std::string& error) {
    CompileOptions o;
    error = CompileOptions::parse(options, o);
    if (!error.empty()) return nullptr;
    DiagnosticEngine d;
    std::unique_ptr<Kernel> k = c.compileMaterial(m, o, d);
    if (!k) error = d.str();
    return k;
}

struct MaterialRun {
    std::vector<std::string> failures;
    size_t valid = 0, lanes = 0;
    bool sampled = false;
};

// The first lane (if any) where a and b differ in their bits on valid lanes.
void compareBits(const char* what, const std::vector<float>& a, const std::vector<float>& b, const Lanes& l,
                 const std::string& where, MaterialRun& r) {
    for (size_t i = 0; i < l.size(); ++i)
        if (l.valid[i] && std::memcmp(&a[i], &b[i], sizeof(float)) != 0) {
            r.failures.push_back(fmt::format("{}: {} lane {} default {:a} assume=unit {:a}", where, what, i, a[i], b[i]));
            return;
        }
}

MaterialRun runMaterial(const HardCaseMaterial& hm, size_t index, Compiler& compiler) {
    MaterialRun r;
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramText(hm.text, hm.name + ".mat", diags);
    if (program.materials.empty()) {
        r.failures.push_back(hm.name + ": " + diags.str());
        return r;
    }
    const CheckedMaterial& m = program.materials.front();
    // Quick codegen gives the optimized code's bits (JitTierUpTests, "tiered compile").
    const std::string kind = std::string(kKinds[index % 8]) + ";codegen=quick;cache=off";
    const std::string where = fmt::format("{} [{}]", hm.name, kKinds[index % 8]);
    std::string error;
    std::unique_ptr<Kernel> plain = compile(compiler, m, kind, error);
    std::unique_ptr<Kernel> trusting = plain ? compile(compiler, m, kind + ";assume=unit", error) : nullptr;
    if (!trusting) {
        r.failures.push_back(where + ": " + error);
        return r;
    }
    Lanes l = lanesFor(m, index);
    r.lanes = l.size();
    r.valid = size_t(std::count(l.valid.begin(), l.valid.end(), 1));
    r.sampled = index % 2 == 0 && plain->samplerTier() == "jit";
    Outputs a = run(*plain, l, r.sampled), b = run(*trusting, l, r.sampled);
    for (int c = 0; c < 3; ++c) compareBits("rgb", a.rgb[c], b.rgb[c], l, where, r);
    if (b.evalReturned != 0) r.failures.push_back(fmt::format("{}: eval batch returned {}", where, b.evalReturned));
    if (r.sampled) {
        for (int c = 0; c < 3; ++c) {
            compareBits("sample wi", a.wi[c], b.wi[c], l, where, r);
            compareBits("sample weight", a.weight[c], b.weight[c], l, where, r);
        }
        compareBits("sample pdf", a.pdf, b.pdf, l, where, r);
        compareBits("pdf", a.pdfOfWi, b.pdfOfWi, l, where, r);
        if (b.sampleReturned != 0 || b.pdfReturned != 0)
            r.failures.push_back(fmt::format("{}: sample/pdf batch returned {} / {}", where, b.sampleReturned, b.pdfReturned));
    }
    return r;
}

}  // namespace

TEST_CASE("assume=unit: the default kernels' bits on valid inputs, and no crash on any input") {
    auto start = std::chrono::steady_clock::now();
    std::vector<std::string> rejected;
    const std::vector<HardCaseMaterial> all = hardCaseMaterials(&rejected);
    REQUIRE(rejected.empty());
    const std::vector<HardCaseMaterial> materials = test::coveringMaterials(all);
    std::vector<MaterialRun> runs(materials.size());
    std::atomic<size_t> next{0};
    auto worker = [&] {
        Compiler compiler;  // one JIT per thread
        for (size_t i; (i = next++) < materials.size();) runs[i] = runMaterial(materials[i], i, compiler);
    };
    unsigned threads = std::max(1u, std::min(2u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(worker);
    for (std::thread& t : pool) t.join();
    size_t lanes = 0, valid = 0, sampled = 0;
    for (const MaterialRun& r : runs) {
        for (const std::string& f : r.failures) FAIL_CHECK(f);
        lanes += r.lanes;
        valid += r.valid;
        sampled += r.sampled;
    }
    // The sample must reach the lanes it is for.
    CHECK(materials.size() >= 20);
    CHECK(valid > materials.size() * 200);
    CHECK(lanes - valid > materials.size() * 50);
    CHECK(sampled * 3 > materials.size());
    MESSAGE(fmt::format("assume=unit: {} of {} materials, {} lanes ({} valid), {} samplers compared, {:.1f} s",
                        materials.size(), all.size(), lanes, valid, sampled,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()));
}

TEST_CASE("assume=unit: the option, its canonical text and its plan") {
    CompileOptions o;
    CHECK(CompileOptions::parse("assume=unit", o) == "");
    CHECK(o.assumeUnit);
    CHECK(o.canonical().find(";assume=unit") != std::string::npos);
    CHECK(CompileOptions::parse("assume=none", o) == "");
    CHECK_FALSE(o.assumeUnit);
    CHECK(o.canonical().find("assume") == std::string::npos);
    CHECK(CompileOptions::parse("assume=finite", o) == "assume 'finite' is not unit or none");
    CHECK(CompileOptions::parse("assume=unit", o) == "");
    CHECK(loweringOptionsFor(o, nullptr, true, 8).trustInputs);
    DiagnosticEngine d;
    CheckedProgram p = loadProgramText("material m { input r = 0.5 in 0 .. 1; ndf = ggx(r * r); }", "m.mat", d);
    REQUIRE(p.materials.size() == 1);
    LoweringPlan plan = planLowering(p.materials[0], MathVariant::exact(), true);
    CHECK(plan.trustInputs);
    CHECK(printPlan(p.materials[0], plan).find("trust-inputs: yes") != std::string::npos);
    CHECK(printPlan(p.materials[0], planLowering(p.materials[0], MathVariant::exact())).find("trust-inputs: no") !=
          std::string::npos);
}
