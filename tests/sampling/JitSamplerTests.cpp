// The JIT samplers (SPEC 8) against the reference sampler and against
// themselves: the same u gives the same wi, pdf and weight as the
// interpreter (scalar and SIMD, exact and fast); the sampled pdf is the
// kernel's pdf(wi, wo) and the weight its f cos / pdf; chi-square of the
// JIT samples against the reference pdf on a subset of the catalog's
// combinations; bounded visible-normal weights and no NaN/Inf/negative
// result on the hard-case sample; invalid lanes through Kernel and the C
// API.
#include "SamplingCases.h"
#include "SamplingCheck.h"

#include "HardCases.h"
#include "Kernel.h"
#include "LoweringPlan.h"
#include "facet/facet.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cfloat>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <random>

namespace {

using namespace sampling_test;
using facet::SampleResult;

constexpr double kPi = std::numbers::pi;
constexpr double kViewDegrees[4] = {0, 45, 80, 89.9};
constexpr double kRoughness[4] = {0.01, 0.1, 0.5, 1};

V3 viewAt(double degrees, double azimuth = 0.3) {
    double t = degrees * kPi / 180;
    return {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
}

// A float direction as the kernels read it: in double, renormalized.
V3 unit(const float w[3]) {
    double len = std::sqrt(double(w[0]) * w[0] + double(w[1]) * w[1] + double(w[2]) * w[2]);
    return {w[0] / len, w[1] / len, w[2] / len};
}

// Relative difference; values below float's normal range (a Beckmann pdf at
// slopes of 8 alpha, 1e-56) compare as 0, as the float results hold them.
double relDiff(double a, double b) {
    double scale = std::max(std::abs(a), std::abs(b));
    return scale < double(FLT_MIN) ? 0 : std::abs(a - b) / scale;
}

facet::Compiler& compiler() {
    static facet::Compiler c;
    return c;
}

// The kernel of `text` with `options` (memory cache only: the suite's
// kernels are compiled once per run).
std::unique_ptr<facet::Kernel> compile(const std::string& text, const std::string& options) {
    facet::CompileOptions o;
    REQUIRE(facet::CompileOptions::parse(options + ";cache=memory;codegen=quick", o) == "");
    facet::DiagnosticEngine diags;
    auto k = compiler().compileText(text, "jit-sampling.mat", "", o, diags);
    INFO(text, "\n", diags.str());
    REQUIRE(k);
    return k;
}

// n lanes of one wo with u from `rng` (plus u at 0 and 1 - 2^-24 in the
// first lanes), in SoA.
struct Lanes {
    std::array<std::vector<float>, 3> wo, u, wi, weight;
    std::vector<float> pdf;
    explicit Lanes(const V3& view, int n, std::mt19937_64& rng) {
        std::uniform_real_distribution<float> uniform(0, 1);
        const float edge[2] = {0, 1 - 0x1p-24f};
        for (int i = 0; i < n; ++i) {
            float w[3] = {float(view.x), float(view.y), float(view.z)};
            for (int c = 0; c < 3; ++c) {
                wo[c].push_back(w[c]);
                float x = i < 8 ? edge[(i >> c) & 1] : uniform(rng);
                u[c].push_back(x < 1 ? x : edge[1]);
                wi[c].push_back(-1), weight[c].push_back(-1);
            }
            pdf.push_back(-1);
        }
    }
    int64_t size() const { return int64_t(pdf.size()); }
    int64_t sample(const facet::Kernel& k) {
        const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
        const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
        float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
        float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
        return k.sampleBatch(size(), woP, uP, nullptr, wiP, pdf.data(), weightP);
    }
};

// One material per combination, at the roughness and shape variant its
// index picks (every combination covers one of the four roughnesses; the
// combinations of one NDF cover them all between them, and its shape
// parameters below, at and above their typical values).
struct JitCase {
    const Combo* combo;
    double alpha;
    std::unique_ptr<TestMaterial> material;
};

std::vector<JitCase> jitCases() {
    std::vector<JitCase> out;
    int index = 0;
    for (const Combo& c : combos()) {
        double alpha = kRoughness[index % 4];
        auto m = makeMaterial(c, alpha, index++);
        REQUIRE(m);
        out.push_back({&c, alpha, std::move(m)});
    }
    return out;
}

}  // namespace

// Exact kernels, scalar and SIMD, against the reference on the same u:
// wi within 1e-5 (absolute), pdf and weight within 1e-5 (relative) where
// the lobe choice agrees; the choice may differ only where u0 is within
// float rounding of the lobe probability. Fast kernels: the same within
// the fast math's error (2e-3).
TEST_CASE("jit sampling: the same u gives the reference's wi, pdf and weight") {
    std::mt19937_64 rng(11);
    int compared = 0, choiceDiffers = 0, kernels = 0;
    std::map<std::string, double> worst;
    for (JitCase& jc : jitCases()) {
        const std::string& text = jc.material->text;
        const facet::ResolvedMaterial<double>& r = jc.material->resolved;
        for (const char* options : {"backend=scalar;math=exact", "backend=simd;math=exact",
                                    "backend=simd;math=fast", "backend=scalar;math=fast"}) {
            auto k = compile(text, options);
            // Every NDF has a compiled sampler: none falls back to the reference.
            REQUIRE_MESSAGE(k->samplerTier() == "jit", text);
            ++kernels;
            const bool exact = std::string(options).find("exact") != std::string::npos;
            const double tol = exact ? 1e-5 : 2e-3;
            for (double theta : kViewDegrees) {
                V3 view = viewAt(theta);
                Lanes lanes(view, 64, rng);
                REQUIRE(lanes.sample(*k) == 0);
                float woF[3] = {lanes.wo[0][0], lanes.wo[1][0], lanes.wo[2][0]};
                V3 wo = unit(woF);
                double p = facet::specularProbability(r, wo);
                for (int64_t i = 0; i < lanes.size(); ++i) {
                    std::array<double, 3> u = {lanes.u[0][i], lanes.u[1][i], lanes.u[2][i]};
                    SampleResult<double> ref = facet::sampleBrdf(r, wo, u);
                    INFO(text, " ", std::string(options), " theta_o ", theta, " u ", u[0], " ", u[1], " ", u[2], " wi ",
                         lanes.wi[0][i], " ", lanes.wi[1][i], " ", lanes.wi[2][i], " reference ", ref.wi.x, " ", ref.wi.y,
                         " ", ref.wi.z);
                    if (p < 1 && std::abs(u[0] - p) <= 1e-6) {
                        ++choiceDiffers;  // at most: the choice may go either way here
                        continue;
                    }
                    double wiErr = std::max({std::abs(lanes.wi[0][i] - ref.wi.x), std::abs(lanes.wi[1][i] - ref.wi.y),
                                             std::abs(lanes.wi[2][i] - ref.wi.z)});
                    double pdfErr = relDiff(lanes.pdf[i], ref.pdf);
                    // The weight is right if it is the reference's for the
                    // sample or the reference's f cos / pdf at the float wi
                    // the kernel returned (as in the differential test): at
                    // grazing wi, where f moves with n.wi relative to itself,
                    // an ulp of wi moves the weight by more than 1e-5, and a
                    // renderer sees the kernel's own wi.
                    float wiK[3] = {lanes.wi[0][i], lanes.wi[1][i], lanes.wi[2][i]};
                    std::array<double, 3> weightAtWi{};
                    if (wiK[2] > 0) {
                        V3 wiU = unit(wiK);
                        double pdfAtWi = facet::brdfPdf(r, wiU, wo);
                        std::array<double, 3> f = r.brdf(wiU, wo);
                        for (int c = 0; c < 3; ++c) weightAtWi[c] = pdfAtWi > 0 ? f[c] * wiU.z / pdfAtWi : 0;
                    }
                    double weightErr = 0;
                    for (int c = 0; c < 3; ++c) {
                        auto err = [&](double want) {
                            return std::abs(lanes.weight[c][i] - want) / std::max({std::abs(want), 1e-6});
                        };
                        weightErr = std::max(weightErr, std::min(err(ref.weight[c]), err(weightAtWi[c])));
                    }
                    // A density below float's range (D at slopes of 8 alpha for
                    // u = 0) is pdf 0, and then weight 0: a renderer cannot
                    // divide by it (the double reference still does).
                    if (ref.pdf < FLT_MIN && lanes.pdf[i] == 0) {
                        weightErr = 0;
                        for (int c = 0; c < 3; ++c) weightErr = std::max(weightErr, lanes.weight[c][i] == 0 ? 0.0 : 1.0);
                    }
                    CHECK(wiErr <= (exact ? 1e-5 : tol));
                    CHECK(pdfErr <= tol);
                    CHECK(weightErr <= tol);
                    double& w = worst[options];
                    w = std::max({w, wiErr, pdfErr, weightErr});
                    ++compared;
                }
            }
        }
    }
    CHECK(compared > 0);
    CHECK(choiceDiffers <= compared / 1000 + 4);
    for (auto& [options, w] : worst) MESSAGE(fmt::format("{}: worst difference {:.3g}", options, w));
    MESSAGE(fmt::format("{} samples of {} kernels compared, {} within rounding of the lobe probability", compared,
                        kernels, choiceDiffers));
}

// Per kernel: pdf(wi, wo) is the pdf the sample returned, the weight is
// eval(wi, wo) (n.wi) / pdf, and scalar and SIMD samples agree. The sampled
// pdf is the density at the drawn normal (as the reference's), pdf() the
// density at the half vector of the returned float wi: where rounding wi to
// float moves that half vector measurably (grazing wo, narrow lobes, where
// |wi + wo| is small) the two differ by as much as the reference's own pdf
// does between the two, which the bound adds.
TEST_CASE("jit sampling: pdf and weight agree with the kernel's pdf and eval; scalar agrees with SIMD") {
    std::mt19937_64 rng(12);
    double worstPdf = 0, worstWeight = 0, worstScalar = 0;
    int checked = 0;
    for (JitCase& jc : jitCases()) {
        const facet::ResolvedMaterial<double>& r = jc.material->resolved;
        for (std::string math : {"exact", "fast"}) {
            auto simd = compile(jc.material->text, std::string("backend=simd;math=") + math);
            REQUIRE(simd->samplerTier() == "jit");
            auto scalar = compile(jc.material->text, std::string("backend=scalar;math=") + math);
            for (double theta : kViewDegrees) {
                // Fast kernels form the half vector in float: at 89.9 degrees
                // its rounding moves narrow lobes by percents (as in fast eval).
                if (math == "fast" && theta > 89) continue;
                Lanes lanes(viewAt(theta), 40, rng), scalarLanes = lanes;
                REQUIRE(lanes.sample(*simd) == 0);
                REQUIRE(scalarLanes.sample(*scalar) == 0);
                for (int64_t i = 0; i < lanes.size(); ++i) {
                    INFO(jc.combo->name(), " alpha ", jc.alpha, " math ", math, " theta ", theta, " lane ", i);
                    float wi[3] = {lanes.wi[0][i], lanes.wi[1][i], lanes.wi[2][i]};
                    float wo[3] = {lanes.wo[0][i], lanes.wo[1][i], lanes.wo[2][i]};
                    V3 wod = unit(wo);
                    SampleResult<double> ref = facet::sampleBrdf(r, wod, {lanes.u[0][i], lanes.u[1][i], lanes.u[2][i]});
                    double refAtWi = facet::brdfPdf(r, unit(wi), wod);
                    double rounding = relDiff(refAtWi, ref.pdf);
                    const double tol = math == "exact" ? 1e-5 : 2e-3;
                    const double bound = 2 * tol + 2 * rounding;
                    float pdf = simd->pdf(wi, wo, nullptr);
                    // Fast kernels form the half vector in float: only where
                    // wi + wo does not cancel.
                    V3 sum{wod.x + unit(wi).x, wod.y + unit(wi).y, wod.z + unit(wi).z};
                    if (math == "fast" && sum.x * sum.x + sum.y * sum.y + sum.z * sum.z < 0.01) continue;
                    // Each side against the reference: pdf() at this wi, the
                    // sampled pdf at the drawn normal. Where wi is nearly -wo
                    // (reflected about a normal near the horizon), the half
                    // vector of the float wi is ill-conditioned and D, unless
                    // flat there (student_t at gamma = 2), follows it: pdf()
                    // may then differ from the reference by as much as the
                    // reference's own pdf at wi with and without renormalizing.
                    double conditioning = relDiff(refAtWi, facet::brdfPdf(r, V3{wi[0], wi[1], wi[2]}, wod));
                    CHECK(relDiff(pdf, refAtWi) <= tol + 2 * conditioning);
                    CHECK(relDiff(lanes.pdf[i], ref.pdf) <= tol);
                    worstPdf = std::max(worstPdf, relDiff(pdf, lanes.pdf[i]) - 2 * rounding);
                    CHECK(relDiff(pdf, lanes.pdf[i]) <= bound);
                    float f[3];
                    simd->eval(wi, wo, nullptr, f);
                    // A density below float range (Beckmann's D at slopes of 8
                    // alpha for u = 0) is 0 as a float, and so is f there: the
                    // weight, from both in the precise type, has no float check.
                    if (lanes.pdf[i] == 0 && ref.pdf > 0 && ref.pdf < FLT_MIN) continue;
                    for (int c = 0; c < 3; ++c) {
                        double expected = wi[2] > 0 && lanes.pdf[i] > 0 ? double(f[c]) * wi[2] / lanes.pdf[i] : 0.0;
                        double err = std::abs(lanes.weight[c][i] - expected) / std::max(std::abs(expected), 1e-6);
                        worstWeight = std::max(worstWeight, err - 2 * rounding);
                        CHECK(err <= bound);
                    }
                    // Exact kernels: a float-first SIMD sampler computes its
                    // well-conditioned lanes in float, the scalar one in
                    // double, each within 1e-5 of the reference; the weights
                    // of the two wi differ by as much as f at grazing wi
                    // moves with an ulp of n.wi, so each is checked against
                    // eval at its own wi (above) rather than against the
                    // other. Fast kernels: the scalar and vector
                    // approximations of sqrt and division differ (up to
                    // 2.3e-5 measured, Beckmann's visible slopes at alpha 0.01).
                    double s = std::max({double(std::abs(lanes.wi[0][i] - scalarLanes.wi[0][i])),
                                         double(std::abs(lanes.wi[2][i] - scalarLanes.wi[2][i])),
                                         relDiff(lanes.pdf[i], scalarLanes.pdf[i]) - 2 * rounding});
                    if (math == "fast") s = std::max(s, relDiff(lanes.weight[0][i], scalarLanes.weight[0][i]));
                    worstScalar = std::max(worstScalar, s);
                    CHECK(s <= (math == "exact" ? 2e-5 : 1e-4));
                    ++checked;
                }
            }
        }
    }
    CHECK(checked > 0);
    MESSAGE(fmt::format("{} samples: worst pdf(wi) against the sampled pdf {:.3g}, weight against eval {:.3g} "
                        "(beyond the rounding of wi), scalar against SIMD {:.3g}",
                        checked, worstPdf, worstWeight, worstScalar));
}

// Chi-square goodness of fit of the SIMD exact sampler's samples against
// the reference pdf, on every fifth combination at one (roughness, view)
// pair each (the reference sampler's own test covers the whole grid); and
// the test of the test: the same samples against the pdf scaled by 1.01
// fail the normalization check.
TEST_CASE("jit sampling: chi-square of the JIT samples against the reference pdf") {
    std::vector<JitCase> cases = jitCases();
    std::vector<std::pair<JitCase*, std::unique_ptr<facet::Kernel>>> runs;
    for (size_t i = 0; i < cases.size(); i += 5) {
        auto k = compile(cases[i].material->text, "backend=simd;math=exact");
        REQUIRE(k->samplerTier() == "jit");
        runs.push_back({&cases[i], std::move(k)});
    }
    REQUIRE(runs.size() >= 8);
    const double level = sidakLevel(0.01, int(runs.size()) + 1);
    int index = 0;
    for (auto& [jc, kernel] : runs) {
        double theta = kViewDegrees[index % 4];
        V3 view = viewAt(theta);
        float wo[3] = {float(view.x), float(view.y), float(view.z)};
        V3 wod = unit(wo);
        const facet::Kernel& k = *kernel;
        Sampler sampler = [&](const std::array<double, 3>& u) {
            float uf[3] = {float(u[0]), float(u[1]), float(u[2])};
            for (float& x : uf) x = x < 1 ? x : 1 - 0x1p-24f;
            float wi[3], pdf, weight[3];
            SampleResult<double> s;
            s.valid = k.sample(wo, uf, nullptr, wi, &pdf, weight);
            s.wi = {wi[0], wi[1], wi[2]};
            s.pdf = pdf;
            return s;
        };
        const facet::ResolvedMaterial<double>& r = jc->material->resolved;
        PdfFunction pdf = [&](const V3& wi) { return facet::brdfPdf(r, wi, wod); };
        CheckSettings s;
        s.samples = 100000;
        s.level = level;
        s.seed = 500 + uint64_t(index);
        CheckOutcome out = checkSampler(sampler, pdf, lobeGrid(r, wod), s);
        INFO(jc->combo->name(), " alpha ", jc->alpha, " theta ", theta, "\n", out.describe());
        CHECK(out.chi2.failure == "");
        CHECK(std::abs(out.integral - 1) <= 1e-4);
        if (index == 0) {
            PdfFunction scaled = [&](const V3& wi) { return 1.01 * facet::brdfPdf(r, wi, wod); };
            CheckOutcome wrong = checkSampler(sampler, scaled, lobeGrid(r, wod), s);
            CHECK(std::abs(wrong.integral - 1) > 1e-4);
        }
        ++index;
    }
    MESSAGE(fmt::format("{} chi-square runs of the JIT sampler, per-test level {:.3g}", runs.size(), level));
}

// A single Smith lobe with visible-normal sampling and F <= 1 has weight F
// G2 / G1(wo) <= 1; and nothing is NaN, Inf or negative. Over the hard-case
// directions and inputs (roughness 1e-5 .. huge, anisotropy 1e4, grazing
// wo), with u at 0, 1/2 and 1 - 2^-24, exact and fast SIMD kernels; both
// NDFs sample through their compiled visible-normal samplers.
TEST_CASE("jit sampling: bounded visible-normal weights and finite results on the hard cases") {
    const float uEdge[3] = {0, 0.5f, 1 - 0x1p-24f};
    int checked = 0, kernels = 0, hugeChecked = 0, hugeOnlyJitInvalid = 0;
    double worst = 0;
    for (const char* ndf : {"ggx", "beckmann"})
        for (const char* masking : {"smith_height_correlated", "smith_separable"})
            for (std::string math : {"exact", "fast"}) {
                std::string text = fmt::format(
                    "material t {{ input alpha_x = 0.3; input alpha_y = 0.3; ndf = {}(alpha_x = alpha_x, alpha_y = "
                    "alpha_y); masking = {}; fresnel = schlick(0.9); }}",
                    ndf, masking);
                auto k = compile(text, std::string("backend=simd;math=") + math);
                REQUIRE(k->samplerTier() == "jit");
                REQUIRE(facet::planLowering(k->material(), facet::MathVariant::exact()).sampling.specular ==
                        facet::SpecularSampling::VisibleNormals);
                ++kernels;
                facet::Interpreter<double> interp(k->material(), k->energyTable());
                facet::HardCaseOptions options;
                for (const facet::HardCase& hc : facet::hardCases(k->material(), options)) {
                    float wo[3] = {float(hc.wo[0]), float(hc.wo[1]), float(hc.wo[2])};
                    std::vector<float> in(hc.slots.begin(), hc.slots.end());
                    // Alphas beyond 1e6 (1e9 .. FLT_MAX): the float terms of
                    // the kernel's D and Lambda (mz^4, (vx ax)^2) leave float
                    // range where the reference's double ones do not.
                    const bool huge = std::max(hc.slots[0], hc.slots[1]) > 1e6;
                    for (float u1 : uEdge)
                        for (float u2 : uEdge) {
                            float u[3] = {0.5f, u1, u2}, wi[3], pdf, weight[3];
                            bool valid = k->sample(wo, u, in.data(), wi, &pdf, weight);
                            INFO(text, " ", math, " ", facet::describeCase(k->material(), hc), " u ", u1, " ", u2);
                            // Invalid exactly where the reference's lane is (wi
                            // plays no part), except with huge alphas, where the
                            // kernel alone may be invalid.
                            double ud[3] = {u[0], u[1], u[2]};
                            bool refValid = interp.sample(hc.wo.data(), ud, hc.slots.data()).valid;
                            if (!refValid) CHECK(!valid);
                            if (huge) {
                                ++hugeChecked;
                                hugeOnlyJitInvalid += refValid && !valid;
                            } else {
                                CHECK(valid == refValid);
                            }
                            CHECK(std::isfinite(pdf));
                            CHECK(pdf >= 0);
                            for (float w : weight) {
                                CHECK(std::isfinite(w));
                                CHECK(w >= 0);
                                CHECK(w <= 1 + 1e-5);
                                worst = std::max(worst, double(w));
                            }
                            ++checked;
                        }
                }
            }
    CHECK(kernels == 8);
    CHECK(hugeOnlyJitInvalid <= hugeChecked / 4);
    MESSAGE(fmt::format("{} samples of {} kernels: largest weight {:.9g}; {} of {} lanes with alphas beyond 1e6 invalid "
                        "in the kernel only",
                        checked, kernels, worst, hugeOnlyJitInvalid, hugeChecked));
}

// Invalid lanes through the C API: non-unit, NaN or infinite wo, u outside
// [0, 1) (1, -0.25, NaN); each is counted and gives wi = pdf = weight = 0,
// while n.wo <= 0 is a valid lane without a sample; the batch calls reject
// NULL arrays with -1.
TEST_CASE("jit sampling: invalid lanes and the C API") {
    const char* text =
        "material t { input roughness = 0.3; ndf = ggx(roughness); masking = smith_height_correlated; fresnel = "
        "schlick(0.04); diffuse = lambert(0.5); }";
    for (const char* options : {"backend=simd", "backend=scalar", "backend=interp"}) {
        char err[256];
        facet_kernel* k = facet_compile_text(text, "t.mat", nullptr, options, err, sizeof err);
        INFO(options, " ", err);
        REQUIRE(k);
        const float nan = std::nanf(""), inf = INFINITY;
        // lanes: valid, no sample (wo below), non-unit wo, NaN wo, Inf wo, u0 = 1, u1 = -0.25, u2 = NaN
        std::vector<std::array<float, 3>> wos = {{0.6f, 0, 0.8f}, {0, 0.6f, -0.8f}, {0.5f, 0, 0.5f}, {nan, 0, 1},
                                                 {inf, 0, 1},     {0, 0, 1},        {0, 0, 1},       {0, 0, 1}};
        std::vector<std::array<float, 3>> us = {{0.3f, 0.4f, 0.5f}, {0.3f, 0.4f, 0.5f}, {0.3f, 0.4f, 0.5f},
                                                {0.3f, 0.4f, 0.5f}, {0.3f, 0.4f, 0.5f}, {1, 0.4f, 0.5f},
                                                {0.3f, -0.25f, 0.5f}, {0.3f, 0.4f, nan}};
        const int n = int(wos.size());
        std::array<std::vector<float>, 3> wo, u, wi, weight;
        std::vector<float> pdf(n, -1), pdf2(n, -1);
        for (int c = 0; c < 3; ++c) {
            for (int i = 0; i < n; ++i) wo[c].push_back(wos[i][c]), u[c].push_back(us[i][c]);
            wi[c].assign(n, -1), weight[c].assign(n, -1);
        }
        const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
        const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
        float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
        float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
        CHECK(facet_sample_batch(k, n, woP, uP, nullptr, wiP, pdf.data(), weightP) == 6);
        CHECK(pdf[0] > 0);
        CHECK(std::abs(wi[0][0] * wi[0][0] + wi[1][0] * wi[1][0] + wi[2][0] * wi[2][0] - 1) < 1e-5);
        for (int i = 1; i < n; ++i) {
            INFO("lane ", i);
            CHECK(pdf[i] == 0);
            for (int c = 0; c < 3; ++c) {
                CHECK(wi[c][i] == 0);
                CHECK(weight[c][i] == 0);
            }
        }
        // The scalar twins agree with the batch (within exact mode's error:
        // a float-first SIMD sampler computes the valid lane in float).
        for (int i = 0; i < n; ++i) {
            float w[3], p, wt[3];
            CHECK(facet_sample(k, wos[i].data(), us[i].data(), nullptr, w, &p, wt) == (i >= 2 ? 1 : 0));
            CHECK(relDiff(p, pdf[i]) <= 1e-5);
            CHECK(std::abs(w[2] - wi[2][i]) <= 1e-5);
        }
        // pdf: wi = the valid lane's sample; the invalid wo lanes count.
        const float* wiC[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
        std::array<std::vector<float>, 3> sampled;
        for (int c = 0; c < 3; ++c) sampled[c].assign(n, wi[c][0]);
        const float* sampledP[3] = {sampled[0].data(), sampled[1].data(), sampled[2].data()};
        CHECK(facet_pdf_batch(k, n, sampledP, woP, nullptr, pdf2.data()) == 3);
        CHECK(relDiff(pdf2[0], pdf[0]) <= 1e-5);
        CHECK(pdf2[1] == 0);  // wo below the horizon: no density
        float wi0[3] = {wi[0][0], wi[1][0], wi[2][0]};
        CHECK(relDiff(facet_pdf(k, wi0, wos[0].data(), nullptr), pdf[0]) <= 1e-5);
        // NULL arrays and n < 0.
        CHECK(facet_sample_batch(k, n, nullptr, uP, nullptr, wiP, pdf.data(), weightP) == -1);
        CHECK(std::string(facet_last_error()) == "facet_sample_batch: error: wo is NULL");
        CHECK(facet_sample_batch(k, n, woP, uP, nullptr, wiP, nullptr, weightP) == -1);
        CHECK(facet_pdf_batch(k, -1, wiC, woP, nullptr, pdf.data()) == -1);
        CHECK(facet_pdf_batch(k, 0, nullptr, nullptr, nullptr, nullptr) == 0);
        CHECK(std::string(facet_sampler(k)) == (std::string(options) == "backend=interp" ? "reference" : "jit"));
        facet_release(k);
    }
}

// A one-lane sample or pdf call of optimized code (the sampler always is)
// runs the batch entry's one-lane body (LoweringPlan::oneLaneBody): every
// lane must get the bits it gets in a long batch, valid or not, with a
// float-first body (exact) and without (fast), at every width. Beckmann's
// visible slopes stop each lane's Newton steps where that lane settles and
// take the Gaussian quantile's far-tail step in a branch: lanes with u in
// the far tails (u2 = 1e-9, u1 = 1 - 2^-24) sit beside ordinary ones.
TEST_CASE("jit sampling: short sample and pdf batches (n = 1 .. 9) give the long batch's bits") {
    for (const char* text :
         {"material t { input roughness = 0.3; ndf = ggx(roughness); masking = smith_height_correlated; fresnel = "
          "schlick(0.04); diffuse = lambert(0.5); }",
          "material t { input roughness = 0.3; ndf = beckmann(roughness); masking = smith_separable; fresnel = "
          "schlick(0.04); diffuse = lambert(0.5); }"})
    for (const char* options : {"backend=simd;math=exact;width=16", "backend=simd;math=fast;width=8",
                                "backend=simd;math=exact;width=4"}) {
        char err[256];
        facet_kernel* k = facet_compile_text(text, "t.mat", nullptr, options, err, sizeof err);
        INFO(text, " ", options, " ", err);
        REQUIRE(k);
        constexpr int n = 45;  // 1 + 2 + ... + 9
        std::mt19937 rng(17);
        std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
        std::array<std::vector<float>, 3> wo, u;
        for (int i = 0; i < n; ++i) {
            V3 w = viewAt(89.5 * uniform(rng), 6.28 * uniform(rng));
            // Every seventh lane invalid (wo not unit), every fifth below the horizon.
            float scale = i % 7 == 3 ? 2.0f : 1.0f, side = i % 5 == 1 ? -1.0f : 1.0f;
            wo[0].push_back(float(w.x) * scale), wo[1].push_back(float(w.y) * scale),
                wo[2].push_back(float(w.z) * scale * side);
            for (int c = 0; c < 3; ++c) u[c].push_back(uniform(rng));
            if (i % 11 == 4) u[2].back() = 1e-9f;
            if (i % 13 == 6) u[1].back() = 0.99999994f;
        }
        struct Outputs {
            std::array<std::vector<float>, 3> wi, weight;
            std::vector<float> pdf, pdfAgain;
            int64_t invalid = 0, pdfInvalid = 0;
        };
        auto run = [&](bool pieces) {
            Outputs o;
            for (int c = 0; c < 3; ++c) o.wi[c].assign(n, -1), o.weight[c].assign(n, -1);
            o.pdf.assign(n, -1), o.pdfAgain.assign(n, -1);
            for (int begin = 0, m = pieces ? 1 : n; begin < n; begin += m, m += pieces ? 1 : 0) {
                const float* woP[3] = {&wo[0][begin], &wo[1][begin], &wo[2][begin]};
                const float* uP[3] = {&u[0][begin], &u[1][begin], &u[2][begin]};
                float* wiP[3] = {&o.wi[0][begin], &o.wi[1][begin], &o.wi[2][begin]};
                float* weightP[3] = {&o.weight[0][begin], &o.weight[1][begin], &o.weight[2][begin]};
                o.invalid += facet_sample_batch(k, m, woP, uP, nullptr, wiP, &o.pdf[begin], weightP);
                const float* sampled[3] = {&o.wi[0][begin], &o.wi[1][begin], &o.wi[2][begin]};
                o.pdfInvalid += facet_pdf_batch(k, m, sampled, woP, nullptr, &o.pdfAgain[begin]);
            }
            return o;
        };
        Outputs whole = run(false), pieces = run(true);
        CHECK(std::string(facet_sampler(k)) == "jit");
        CHECK(whole.invalid == 6);  // lanes 3, 10, 17, 24, 31, 38
        CHECK(pieces.invalid == whole.invalid);
        CHECK(pieces.pdfInvalid == whole.pdfInvalid);
        CHECK(pieces.pdf == whole.pdf);
        CHECK(pieces.pdfAgain == whole.pdfAgain);
        for (int c = 0; c < 3; ++c) {
            CHECK(pieces.wi[c] == whole.wi[c]);
            CHECK(pieces.weight[c] == whole.weight[c]);
        }
        int sampled = 0;
        for (int i = 0; i < n; ++i) sampled += whole.pdf[size_t(i)] > 0;
        CHECK(sampled > 25);  // the valid lanes above the horizon
        facet_release(k);
    }
}

// A float-first SIMD sampler (exact GGX where eval is float-first) draws
// each lane in float and recomputes in the double body the lanes it does
// not trust: the plan says so only there; the float lanes stay within
// exact mode's bounds of the all-double sampler (float_first=off) while
// differing from it in most lanes; a lane the guards reject (the spherical
// cap's point next to -v, where v + c cancels) comes from the double body
// bit for bit and changes no neighbour, and an invalid lane stays invalid.
TEST_CASE("jit sampling: float-first SIMD sampler, its guards and its fallback lanes") {
    using facet::BatchBodies;
    for (const char* diffuse : {"", " diffuse = lambert(0.5);"}) {
        std::string text = fmt::format("material t {{ input roughness = 0.3; ndf = ggx(roughness); "
                                       "masking = smith_height_correlated; fresnel = schlick(0.04);{} }}",
                                       diffuse);
        INFO(text);
        auto floatFirst = compile(text, "backend=simd;width=8;math=exact");
        auto plain = compile(text, "backend=simd;width=8;math=exact;float_first=off");
        const facet::CheckedMaterial& m = floatFirst->material();
        CHECK(facet::planLowering(m, facet::MathVariant::exact()).sampling.batchBodies == BatchBodies::FloatFirst);
        // Fast kernels take the exact kernel's float body for eval, but
        // sample in their plain fast body.
        CHECK(facet::planLowering(m, facet::MathVariant::fast()).batchBodies == BatchBodies::FloatFirst);
        CHECK(facet::planLowering(m, facet::MathVariant::fast()).sampling.batchBodies == BatchBodies::Plain);
        facet::MathVariant doubleOnly = facet::MathVariant::exact();
        doubleOnly.floatFirst = false;
        CHECK(facet::planLowering(m, doubleOnly).sampling.batchBodies == BatchBodies::Plain);

        // Random wo over the hemisphere (down to n.wo ~ 1e-4) and u.
        std::mt19937_64 rng(21);
        std::uniform_real_distribution<double> uniform(0, 1);
        Lanes a(viewAt(45), 4096, rng);
        for (int64_t i = 0; i < a.size(); ++i) {
            V3 w = viewAt(89.99 * uniform(rng), 2 * kPi * uniform(rng));
            a.wo[0][i] = float(w.x), a.wo[1][i] = float(w.y), a.wo[2][i] = float(w.z);
        }
        Lanes b = a;
        REQUIRE(a.sample(*floatFirst) == 0);
        REQUIRE(b.sample(*plain) == 0);
        int differing = 0;
        double worstWi = 0, worstPdf = 0;
        for (int64_t i = 0; i < a.size(); ++i) {
            bool same = a.pdf[i] == b.pdf[i];
            for (int c = 0; c < 3; ++c) {
                same = same && a.wi[c][i] == b.wi[c][i];
                worstWi = std::max(worstWi, double(std::abs(a.wi[c][i] - b.wi[c][i])));
            }
            differing += !same;
            worstPdf = std::max(worstPdf, relDiff(a.pdf[i], b.pdf[i]));
        }
        MESSAGE(fmt::format("float-first against float_first=off: {} of {} lanes differ; worst wi {:.3g}, pdf {:.3g}",
                            differing, a.size(), worstWi, worstPdf));
        CHECK(differing > a.size() / 2);
        CHECK(worstWi <= 2e-5);
        CHECK(worstPdf <= 2e-5);

        // Lane 5: wo at azimuth 0.3, u1 turning the cap's point to the
        // azimuth of -v and u2 = 1 - 2^-24 putting it at -v's height:
        // v + c ~ 0, a lane the float body distrusts. Lane 9: u0 = 1.5, invalid.
        Lanes g(viewAt(45), 16, rng);
        REQUIRE(g.sample(*floatFirst) == 0);
        Lanes before = g;
        V3 w = viewAt(60, 0.3);
        g.wo[0][5] = float(w.x), g.wo[1][5] = float(w.y), g.wo[2][5] = float(w.z);
        g.u[0][5] = 0.01f, g.u[1][5] = float((0.3 + kPi) / (2 * kPi)), g.u[2][5] = 1 - 0x1p-24f;
        g.u[0][9] = 1.5f;
        Lanes h = g;
        CHECK(g.sample(*floatFirst) == 1);
        CHECK(h.sample(*plain) == 1);
        CHECK(g.pdf[5] > 0);
        CHECK(g.pdf[5] == h.pdf[5]);
        CHECK(g.pdf[9] == 0);
        for (int c = 0; c < 3; ++c) {
            CHECK(g.wi[c][5] == h.wi[c][5]);
            CHECK(g.weight[c][5] == h.weight[c][5]);
            CHECK(g.wi[c][9] == 0);
        }
        for (int64_t lane = 0; lane < g.size(); ++lane) {
            if (lane == 5 || lane == 9) continue;
            INFO("lane ", lane);
            CHECK(g.pdf[lane] == before.pdf[lane]);
            for (int c = 0; c < 3; ++c) CHECK(g.wi[c][lane] == before.wi[c][lane]);
        }
    }
}

// Fast kernels read a float-subnormal n.wo or n.wi as 0, in eval and in
// the sampler alike: a lane whose wo.z is 7.2e-43 or 3e-39 gives the bits
// of the same lane with wo.z = 0 (at the horizon: no sample and no
// density), everywhere the sampler reads wo: the frame it draws in, the
// density and f; the same for wi.z in the density.
TEST_CASE("jit sampling: fast samplers read a float-subnormal cosine as 0") {
    const char* materials[] = {
        "material t { input roughness = 0.3; ndf = ggx(roughness); masking = smith_height_correlated; "
        "fresnel = schlick(0.04); diffuse = lambert(0.5); }",
        "material t { ndf = ggx(alpha_x = 0.2, alpha_y = 0.05); masking = smith_height_correlated; "
        "fresnel = dielectric(eta = 1.5); }"};
    for (const char* text : materials) {
        for (const char* options : {"backend=simd;width=8;math=fast", "backend=simd;width=16;math=fast",
                                    "backend=scalar;math=fast"}) {
            INFO(text, "\n", options);
            auto k = compile(text, options);
            const facet::LoweringPlan plan = facet::planLowering(k->material(), facet::MathVariant::fast());
            CHECK(plan.sampling.body.subnormalCosinesAsZero);
            std::mt19937_64 rng(28);
            std::uniform_real_distribution<double> uniform(0, 1);
            Lanes subnormal(viewAt(45), 301, rng);
            const float tiny[2] = {7.2e-43f, 3e-39f};
            for (int64_t i = 0; i < subnormal.size(); ++i) {
                V3 w = viewAt(89 * uniform(rng), 2 * kPi * uniform(rng));
                subnormal.wo[0][i] = float(w.x), subnormal.wo[1][i] = float(w.y), subnormal.wo[2][i] = float(w.z);
                if (i % 3 == 0) {
                    // A unit direction whose z is subnormal.
                    double phi = 2 * kPi * uniform(rng);
                    subnormal.wo[0][i] = float(std::cos(phi)), subnormal.wo[1][i] = float(std::sin(phi));
                    subnormal.wo[2][i] = tiny[(i / 3) % 2];
                }
            }
            Lanes zero = subnormal;
            for (int64_t i = 0; i < zero.size(); i += 3) zero.wo[2][i] = 0;
            CHECK(subnormal.sample(*k) == zero.sample(*k));
            int sampledSubnormal = 0;
            for (int64_t i = 0; i < subnormal.size(); ++i) {
                INFO("lane ", i, " wo.z ", subnormal.wo[2][i]);
                CHECK(subnormal.pdf[i] == zero.pdf[i]);
                for (int c = 0; c < 3; ++c) {
                    CHECK(subnormal.wi[c][i] == zero.wi[c][i]);
                    CHECK(subnormal.weight[c][i] == zero.weight[c][i]);
                }
                sampledSubnormal += i % 3 == 0 && subnormal.pdf[i] > 0;
            }
            CHECK(sampledSubnormal == 0);
            // The density: lanes with wo.z subnormal (those above) and
            // lanes with a normal wo and wi.z subnormal, against the same
            // lanes with 0.
            std::array<std::vector<float>, 3> wiTiny, wiZero;
            for (int64_t i = 0; i < subnormal.size(); ++i) {
                V3 v = viewAt(89 * uniform(rng), 2 * kPi * uniform(rng));
                const float w[3] = {float(v.x), float(v.y), float(v.z)};
                for (int c = 0; c < 3; ++c) wiTiny[c].push_back(w[c]), wiZero[c].push_back(w[c]);
                if (i % 3 == 1) wiTiny[2][i] = tiny[i % 2], wiZero[2][i] = 0;
            }
            std::vector<float> pdfTiny(subnormal.size(), -1), pdfZero(subnormal.size(), -1);
            auto pointers = [](const std::array<std::vector<float>, 3>& w) {
                return std::array<const float*, 3>{w[0].data(), w[1].data(), w[2].data()};
            };
            CHECK(k->pdfBatch(subnormal.size(), pointers(wiTiny).data(), pointers(subnormal.wo).data(), nullptr,
                              pdfTiny.data()) == k->pdfBatch(subnormal.size(), pointers(wiZero).data(),
                                                             pointers(zero.wo).data(), nullptr, pdfZero.data()));
            int positive = 0;
            for (int64_t i = 0; i < subnormal.size(); ++i) {
                INFO("pdf lane ", i);
                CHECK(pdfTiny[i] == pdfZero[i]);
                positive += pdfZero[i] > 0;
            }
            CHECK(positive > 0);
        }
    }
}

// A sampled density of 0 comes with weight 0, in every backend and math
// mode: Beckmann's D at the slopes u = 0 draws (8 alpha and beyond, 1e-56)
// underflows float, and the weight F G2 / G1, in which D cancels, would
// otherwise be ~1 beside it.
TEST_CASE("jit sampling: a pdf that underflows float has weight 0") {
    const std::string text = "material tail { ndf = beckmann(0.01); masking = smith_separable; fresnel = schlick(0.9); }";
    for (const char* options : {"backend=scalar;math=exact", "backend=simd;math=exact", "backend=simd;math=fast",
                                "backend=interp"}) {
        INFO(options);
        auto k = compile(text, options);
        int underflowed = 0;
        for (float u1 : {0.0f, 1e-30f, 0.99999994f})
            for (float u2 : {0.0f, 0.25f, 0.5f, 0.99999994f}) {
                const float wo[3] = {0.6f, 0.0f, 0.8f}, u[3] = {0.0f, u1, u2};
                float wi[3], pdf = -1, weight[3] = {-1, -1, -1};
                k->sample(wo, u, nullptr, wi, &pdf, weight);
                INFO("u1 ", u1, " u2 ", u2, " pdf ", pdf, " weight ", weight[0]);
                CHECK(pdf >= 0);
                if (pdf == 0) {
                    ++underflowed;
                    for (float w : weight) CHECK(w == 0);
                }
            }
        CHECK(underflowed > 0);  // the test of the test: the tail draws do underflow
    }
}

// The exact density where n.wo is float-subnormal: wo.m is |wi + wo| / 2
// for the mirror pair (1, 0, 1e-40) and (-1, 0, 4.33e-24), not the dot
// product of the near-cancelling components (which gave pdf 0 where the
// interpreter gives 9.3e24 for clearcoat_gtr, 4.1e23 for cook_torrance_classic).
TEST_CASE("jit sampling: the exact pdf at a float-subnormal n.wo is the interpreter's") {
    for (const char* file : {"clearcoat_gtr.mat", "cook_torrance_classic.mat"}) {
        const std::string path = std::string(FACET_SOURCE_DIR) + "/materials/" + file;
        std::ifstream in(path);
        REQUIRE(in);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const float wo[3] = {1.0f, 0.0f, 1e-40f}, wi[3] = {-1.0f, 0.0f, 4.33e-24f};
        auto interp = compile(text, "backend=interp");
        const float want = interp->pdf(wi, wo, nullptr);
        INFO(std::string(file), " interpreter pdf ", want);
        CHECK(want > 1e20f);  // (the compiled pdf was 0 here)
        for (const char* options : {"backend=scalar;math=exact", "backend=simd;math=exact"}) {
            const float got = compile(text, options)->pdf(wi, wo, nullptr);
            INFO(options, " pdf ", got);
            CHECK(relDiff(got, want) <= 1e-5);
        }
    }
}
