// The compiled random-walk lobe (`energy = random_walk`, SPEC 13,
// compiler/lowering/LaneWalk.cpp) against its reference
// (compiler/reference/WalkLobe.h) and against what it must conserve:
// - the sampler on the same u walks the reference's path (wi, weight, pdf),
//   scalar and SIMD, exact and fast (fast computes as exact);
// - eval is the interpreter's f (single scattering + the one-walk estimate
//   of the higher orders, same seed);
// - with F = 1, eval's albedo over the hemisphere is 1 within 4 standard
//   errors (the single-scattering lobe alone must fail it), and the sampled
//   directions match a histogram of the reference walk with its own random
//   numbers (chi-square; the walk cut at order 1 must fail it);
// - the checker's errors for what the compiled walk cannot take.
#include "ChiSquare.h"
#include "Checker.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "MicrosurfaceWalk.h"
#include "Sampling.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <cfloat>
#include <cmath>
#include <numbers>
#include <random>

namespace {

using facet::Vec3;
using V3 = Vec3<double>;
constexpr double kPi = std::numbers::pi;

facet::Compiler& compiler() {
    static facet::Compiler c;
    return c;
}

std::unique_ptr<facet::Kernel> compile(const std::string& text, const std::string& options) {
    facet::CompileOptions o;
    REQUIRE(facet::CompileOptions::parse(options + ";cache=memory;codegen=quick", o) == "");
    facet::DiagnosticEngine diags;
    auto k = compiler().compileText(text, "walk.mat", "", o, diags);
    INFO(text, "\n", diags.str());
    REQUIRE(k);
    return k;
}

// The checked material of `text` and its interpreter (kept alive together).
struct Reference {
    facet::CheckedProgram program;
    std::unique_ptr<facet::Interpreter<double>> interp;
    facet::ResolvedMaterial<double> lobe;
    explicit Reference(const std::string& text) {
        facet::DiagnosticEngine diags;
        program = facet::loadProgramText(text, "walk.mat", diags);
        INFO(diags.str());
        REQUIRE_FALSE(diags.hasErrors());
        interp = std::make_unique<facet::Interpreter<double>>(*program.find("t"));
        lobe = interp->resolve(nullptr);
    }
};

std::string material(const std::string& ndf, const std::string& fresnel, const std::string& energy = "random_walk") {
    return fmt::format("material t {{ ndf = {}; masking = smith_height_correlated; fresnel = {}; energy = {}; }}\n", ndf,
                       fresnel, energy);
}

const char* kConductor = "conductor(eta = rgb(0.2, 0.9, 1.1), k = rgb(3.9, 2.4, 2.2))";

V3 viewAt(double degrees, double azimuth = 0.7) {
    double t = degrees * kPi / 180;
    return {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
}

V3 unit(const float w[3]) {
    double len = std::sqrt(double(w[0]) * w[0] + double(w[1]) * w[1] + double(w[2]) * w[2]);
    return {w[0] / len, w[1] / len, w[2] / len};
}

double relDiff(double a, double b) {
    double scale = std::max(std::abs(a), std::abs(b));
    return scale < 1e-30 ? 0 : std::abs(a - b) / scale;
}

}  // namespace

TEST_SUITE("compiled walk") {

TEST_CASE("the same u walks the reference's path: wi, weight and pdf, scalar and SIMD") {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<float> uniform(0, 1);
    int compared = 0, differ = 0;
    for (const char* ndf : {"ggx(0.1)", "ggx(0.5)", "ggx(1)", "ggx(alpha_x = 0.2, alpha_y = 0.9)"}) {
        std::string text = material(ndf, kConductor);
        Reference ref(text);
        for (const char* options : {"backend=scalar;math=exact", "backend=simd;math=exact", "backend=simd;math=fast"}) {
            auto k = compile(text, options);
            REQUIRE(k->samplerTier() == "jit");
            for (double theta : {0.0, 45.0, 80.0, 89.5}) {
                const int n = 257;
                V3 view = viewAt(theta);
                std::array<std::vector<float>, 3> wo, u, wi, weight;
                std::vector<float> pdf(n);
                for (int c = 0; c < 3; ++c) wo[c].assign(n, float(c == 0 ? view.x : c == 1 ? view.y : view.z));
                for (int c = 0; c < 3; ++c)
                    for (int i = 0; i < n; ++i) u[c].push_back(std::min(uniform(rng), 1 - 0x1p-24f));
                for (int c = 0; c < 3; ++c) wi[c].resize(n), weight[c].resize(n);
                const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
                const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
                float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
                float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
                REQUIRE(k->sampleBatch(n, woP, uP, nullptr, wiP, pdf.data(), weightP) == 0);
                float woF[3] = {wo[0][0], wo[1][0], wo[2][0]};
                V3 o = unit(woF);
                for (int i = 0; i < n; ++i) {
                    double uu[3] = {u[0][i], u[1][i], u[2][i]};
                    double oo[3] = {woF[0], woF[1], woF[2]};
                    facet::SampleResult<double> want = ref.interp->sample(oo, uu, nullptr);
                    REQUIRE(want.valid);
                    double wiErr = std::max({std::abs(wi[0][i] - want.wi.x), std::abs(wi[1][i] - want.wi.y),
                                             std::abs(wi[2][i] - want.wi.z)});
                    double err = std::max(wiErr, relDiff(pdf[i], want.pdf));
                    for (int c = 0; c < 3; ++c) err = std::max(err, relDiff(weight[c][i], want.weight[c]));
                    ++compared;
                    if (err > 1e-5) {
                        ++differ;
                        MESSAGE(fmt::format("{} {} theta_o {} lane {}: wi ({}, {}, {}) against ({}, {}, {})", ndf, options,
                                            theta, i, wi[0][i], wi[1][i], wi[2][i], want.wi.x, want.wi.y, want.wi.z));
                    }
                    // The kernel's pdf entry gives the sample's pdf.
                    if (i < 4 && wi[2][i] > 0) {
                        float wiF[3] = {wi[0][i], wi[1][i], wi[2][i]};
                        CHECK(relDiff(k->pdf(wiF, woF, nullptr), facet::brdfPdf(ref.lobe, unit(wiF), o)) <= 1e-5);
                    }
                }
            }
        }
    }
    // Both walk in double from the same numbers: a path may leave the
    // reference's only where a height test falls within rounding of its
    // threshold (~1e-16 per test).
    CHECK(differ == 0);
    MESSAGE(fmt::format("{} samples compared, {} differ", compared, differ));
}

TEST_CASE("eval is the interpreter's: single scattering plus the same walk's higher orders") {
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> uniform(0, 1);
    for (const char* ndf : {"ggx(0.3)", "ggx(1)", "ggx(alpha_x = 0.2, alpha_y = 0.9)"}) {
        std::string text = material(ndf, kConductor);
        Reference ref(text);
        auto scalar = compile(text, "backend=scalar;math=exact");
        auto simd = compile(text, "backend=simd;math=exact");
        const int n = 500;
        std::array<std::vector<float>, 3> wi, wo, rgbS, rgbV;
        for (int i = 0; i < n; ++i) {
            V3 a = viewAt(89.9 * std::sqrt(uniform(rng)), 2 * kPi * uniform(rng));
            V3 b = viewAt(89.9 * std::sqrt(uniform(rng)), 2 * kPi * uniform(rng));
            wi[0].push_back(float(a.x)), wi[1].push_back(float(a.y)), wi[2].push_back(float(a.z));
            wo[0].push_back(float(b.x)), wo[1].push_back(float(b.y)), wo[2].push_back(float(b.z));
        }
        for (int c = 0; c < 3; ++c) rgbS[c].resize(n), rgbV[c].resize(n);
        const float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
        const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
        float* s[3] = {rgbS[0].data(), rgbS[1].data(), rgbS[2].data()};
        float* v[3] = {rgbV[0].data(), rgbV[1].data(), rgbV[2].data()};
        REQUIRE(scalar->evalBatch(n, wiP, woP, nullptr, s) == 0);
        REQUIRE(simd->evalBatch(n, wiP, woP, nullptr, v) == 0);
        int withWalk = 0;
        facet::ResolvedMaterial<double> single = ref.lobe.withoutEnergy();
        for (int i = 0; i < n; ++i) {
            double a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]};
            facet::EvalResult<double> want = ref.interp->eval(a, b, nullptr);
            float fa[3] = {wi[0][i], wi[1][i], wi[2][i]}, fb[3] = {wo[0][i], wo[1][i], wo[2][i]};
            std::array<double, 3> ss = single.brdf(unit(fa), unit(fb));
            for (int c = 0; c < 3; ++c) {
                INFO(ndf, " lane ", i, " channel ", c);
                CHECK(rgbS[c][i] == rgbV[c][i]);  // one lane's walk whatever its neighbours
                CHECK(relDiff(rgbS[c][i], want.rgb[c]) <= 2e-6);
                withWalk += c == 0 && want.rgb[c] > ss[c] * (1 + 1e-6);
            }
        }
        // The walk adds to the pairs where it met a second facet (at alpha
        // 0.3 most walks leave after one).
        MESSAGE(fmt::format("{}: the walk adds to {} of {} pairs", ndf, withWalk, n));
        CHECK(withWalk >= n / 20);
    }
}

TEST_CASE("F = 1: eval's albedo is 1 within 4 standard errors; single scattering alone is not") {
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<float> uniform(0, 1);
    for (double alpha : {0.4, 1.0}) {
        for (const char* energy : {"random_walk", "none"}) {
            auto k = compile(material(fmt::format("ggx({})", alpha), "none", energy), "backend=simd;math=exact");
            for (double theta : {0.0, 60.0, 85.0}) {
                // wi uniform over the hemisphere (density 1 / 2 pi).
                const int n = 200000;
                V3 view = viewAt(theta);
                std::array<std::vector<float>, 3> wi, wo, rgb;
                for (int i = 0; i < n; ++i) {
                    float z = uniform(rng), phi = 2 * float(kPi) * uniform(rng), r = std::sqrt(std::max(0.f, 1 - z * z));
                    wi[0].push_back(r * std::cos(phi)), wi[1].push_back(r * std::sin(phi)), wi[2].push_back(z);
                    wo[0].push_back(float(view.x)), wo[1].push_back(float(view.y)), wo[2].push_back(float(view.z));
                }
                for (int c = 0; c < 3; ++c) rgb[c].resize(n);
                const float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
                const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
                float* out[3] = {rgb[0].data(), rgb[1].data(), rgb[2].data()};
                REQUIRE(k->evalBatch(n, wiP, woP, nullptr, out) == 0);
                double sum = 0, sum2 = 0;
                for (int i = 0; i < n; ++i) {
                    double x = double(rgb[0][i]) * wi[2][i] * 2 * kPi;
                    sum += x, sum2 += x * x;
                }
                double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / (n - 1));
                std::string what = fmt::format("alpha {} energy {} theta_o {}: albedo {:.5f} +- {:.5f}", alpha, energy,
                                               theta, mean, se);
                MESSAGE(what);
                if (std::string(energy) == "random_walk") {
                    CHECK_MESSAGE(std::abs(mean - 1) <= 4 * se, what);
                    CHECK(se < 0.01);
                } else if (alpha == 1.0) {
                    CHECK_MESSAGE(std::abs(mean - 1) > 4 * se, what);  // the deliberately wrong case
                }
            }
        }
    }
}

TEST_CASE("F = 1: the sampled directions match the reference walk's (chi-square); the walk cut at order 1 does not") {
    std::mt19937_64 rng(10);
    std::uniform_real_distribution<float> uniform(0, 1);
    const facet::SphereGrid grid = facet::SphereGrid::equalArea(12, 24);
    for (double alpha : {0.5, 1.0}) {
        std::string text = material(fmt::format("ggx({})", alpha), "none");
        Reference ref(text);
        facet::MicrosurfaceWalk walk(ref.lobe);
        auto k = compile(text, "backend=simd;math=exact");
        for (double theta : {30.0, 75.0}) {
            const int n = 100000;
            V3 view = viewAt(theta);
            std::array<std::vector<float>, 3> wo, u, wi, weight;
            std::vector<float> pdf(n);
            for (int c = 0; c < 3; ++c) {
                wo[c].assign(n, float(c == 0 ? view.x : c == 1 ? view.y : view.z));
                for (int i = 0; i < n; ++i) u[c].push_back(std::min(uniform(rng), 1 - 0x1p-24f));
                wi[c].resize(n), weight[c].resize(n);
            }
            const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
            const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
            float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
            float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
            REQUIRE(k->sampleBatch(n, woP, uP, nullptr, wiP, pdf.data(), weightP) == 0);
            facet::CellHistogram compiled(grid), reference(grid), cut(grid);
            for (int i = 0; i < n; ++i) {
                CHECK(weight[0][i] == 1.0f);  // F = 1: every walk returns all its energy
                float w[3] = {wi[0][i], wi[1][i], wi[2][i]};
                compiled.add(grid, unit(w));
            }
            float woF[3] = {wo[0][0], wo[1][0], wo[2][0]};
            V3 o = unit(woF);
            for (int i = 0; i < n; ++i) {
                facet::WalkRandom random(1234, uint64_t(i));
                reference.add(grid, walk.sample(o, random).wi);
                facet::WalkRandom again(1234, uint64_t(i));
                facet::WalkOrders first;
                first.maxOrder = 1;
                facet::WalkSample s = walk.sample(o, again, first);
                if (s.wi.z > 0) cut.add(grid, s.wi);
            }
            // Two samples of one distribution: sum (a - b')^2 / (a + b') over
            // the cells, b' = b scaled to a's total, cells with a + b' < 10
            // pooled; chi-square with cells - 1 degrees of freedom.
            auto twoSample = [&](const facet::CellHistogram& a, const facet::CellHistogram& b) {
                double ta = 0, tb = 0;
                for (size_t c = 0; c < a.observed.size(); ++c) ta += a.observed[c], tb += b.observed[c];
                double scale = ta / tb, stat = 0, poolA = 0, poolB = 0;
                int cells = 0;
                for (size_t c = 0; c < a.observed.size(); ++c) {
                    double x = a.observed[c], y = b.observed[c] * scale;
                    if (x + y < 10) {
                        poolA += x, poolB += y;
                        continue;
                    }
                    stat += (x - y) * (x - y) / (x + y), ++cells;
                }
                if (poolA + poolB > 0) stat += (poolA - poolB) * (poolA - poolB) / (poolA + poolB), ++cells;
                return facet::chi2Survival(stat, cells - 1);
            };
            double p = twoSample(compiled, reference), pCut = twoSample(compiled, cut);
            std::string what = fmt::format("alpha {} theta_o {}: p = {:.3g} against the walk, {:.3g} against order 1",
                                           alpha, theta, p, pCut);
            MESSAGE(what);
            CHECK_MESSAGE(p > 1e-3, what);
            CHECK_MESSAGE(pCut < 1e-6, what);  // the deliberately wrong distribution
        }
    }
}

TEST_CASE("the checker's errors for what the compiled walk cannot take") {
    struct Case {
        std::string body, expect;
    };
    const Case cases[] = {
        {"ndf = beckmann(0.3); masking = smith_height_correlated; energy = random_walk;", "views below the horizon"},
        {"ndf = ggx(0.3); masking = smith_separable; energy = random_walk;", "smith_height_correlated"},
        {"ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(1.5); energy = random_walk;",
         "refracts"},
        {"ndf = ggx(0.3); masking = smith_height_correlated; diffuse = lambert(0.5); energy = random_walk;",
         "diffuse term"},
        {"lobe a { ndf = ggx(0.3); masking = smith_height_correlated; energy = random_walk; } "
         "lobe b { diffuse = lambert(0.5); } bsdf = a + b;",
         "in lobe 'a'"},
    };
    for (const Case& c : cases) {
        facet::DiagnosticEngine diags;
        facet::loadProgramText("material t {\n" + c.body + "\n}\n", "walk.mat", diags);
        INFO(c.body, "\n", diags.str());
        CHECK(diags.hasErrors());
        CHECK(diags.str().find(c.expect) != std::string::npos);
        CHECK(diags.str().find("walk.mat:2:") != std::string::npos);
    }
}

}  // TEST_SUITE
