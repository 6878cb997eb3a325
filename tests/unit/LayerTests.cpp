// Layer and mixture-sampling tests (SPEC 10; docs/design-notes/
// layer-albedo-scaling.md): the reference's layer is reciprocal, keeps a
// white Lambert base's energy (white furnace) and never creates energy over
// a white microfacet base; the reference's mixture sampler is unbiased
// (E[weight] = albedo) and its pdf integrates to 1, and the same checks
// catch a deliberately wrong pdf.
//
// Albedos and pdf integrals use this file's own quadrature over the half
// vector (not the reference's LayerAlbedo.cpp): theta_h on Gauss-Legendre
// panels graded from 0 by the narrowest lobe's alpha, the azimuth on
// uniform panels, wi = reflect(wo, h), dwi = 4 (wo.h) dwh.
#include "Checker.h"
#include "Interpreter.h"
#include "Sampling.h"
#include "../physics/PhysicsUtil.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

using namespace facet;

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

CheckedProgram checkText(const std::string& text) {
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramText(text, "layers.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    return p;
}

std::string ggxLobe(const std::string& name, double alpha, const std::string& fresnel) {
    return "    lobe " + name + " {\n        ndf = ggx(" + std::to_string(alpha) +
           ");\n        masking = smith_height_correlated;\n        fresnel = " + fresnel + ";\n    }\n";
}
const std::string kWhiteLambert = "    lobe white {\n        diffuse = lambert(1);\n    }\n";

std::string material(const std::string& lobes, const std::string& bsdf) {
    return "material m {\n" + lobes + "    bsdf = " + bsdf + ";\n}\n";
}

// Gauss-Legendre (x, w) pairs on [-1, 1]: the physics tests' rule (Newton on P_n).
std::vector<std::array<double, 2>> gauss(int n) {
    physics::GaussLegendre g(n);
    std::vector<std::array<double, 2>> out;
    for (int i = 0; i < n; ++i) out.push_back({g.x[i], g.w[i]});
    return out;
}

// Sum over half vectors h (h.z > 0, wo.h > 0) of fn(wi, measure) with
// sum fn(wi, dwi) ~ Int over the whole sphere of wi.
template <typename Fn>
void halfVectorQuadrature(const std::array<double, 3>& wo, double alphaMin, Fn&& fn) {
    static const std::vector<std::array<double, 2>> gt = gauss(8), gp = gauss(6);
    std::vector<double> br = {0};
    for (double w = alphaMin / 8; br.back() < kPi / 2;) {
        br.push_back(std::min(br.back() + w, kPi / 2));
        w = std::min(2 * w, 0.05);
    }
    const int phiPanels = 48;
    for (size_t p = 0; p + 1 < br.size(); ++p)
        for (const auto& [xt, wt] : gt) {
            double half = (br[p + 1] - br[p]) / 2, th = br[p] + half * (1 + xt), st = std::sin(th), ct = std::cos(th);
            for (int q = 0; q < phiPanels; ++q)
                for (const auto& [xp, wp] : gp) {
                    double hp = kPi / phiPanels, phi = 2 * hp * q + hp * (1 + xp);
                    std::array<double, 3> h{st * std::cos(phi), st * std::sin(phi), ct};
                    double oh = wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2];
                    if (!(oh > 0)) continue;
                    std::array<double, 3> wi{2 * oh * h[0] - wo[0], 2 * oh * h[1] - wo[1], 2 * oh * h[2] - wo[2]};
                    fn(wi, 4 * oh * st * half * wt * hp * wp);
                }
        }
}

std::array<double, 3> direction(double mu) { return {std::sqrt(std::max(0.0, 1 - mu * mu)), 0, mu}; }

// Int f(wi, wo) (n.wi) dwi, rgb, of the reference evaluation.
std::array<double, 3> albedo(const CheckedMaterial& m, double mu, double alphaMin) {
    Interpreter<double> interp(m);
    std::array<double, 3> wo = direction(mu), out{};
    halfVectorQuadrature(wo, alphaMin, [&](const std::array<double, 3>& wi, double dw) {
        if (!(wi[2] > 0)) return;
        EvalResult<double> e = interp.eval(wi.data(), wo.data(), nullptr);
        REQUIRE(e.valid);
        for (int ch = 0; ch < 3; ++ch) out[ch] += e.rgb[ch] * wi[2] * dw;
    });
    return out;
}

// The estimator of the albedo from n samples: mean and standard error of
// channel 0. `wrongPdf`: the sampler's mixture density is replaced by the
// chosen leaf's share of it, p_k pdf_k(wi) (a classic bug).
std::array<double, 2> estimate(const CheckedMaterial& m, double mu, int n, bool wrongPdf) {
    Interpreter<double> interp(m);
    std::array<double, 3> wo = direction(mu);
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> uni(0, 1);
    ResolvedBsdf<double> r = interp.resolveAll(nullptr);
    std::vector<LeafChoice> leaves = leafProbabilities(m, r, r, mu);
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        double u[3] = {(i + uni(rng)) / n, uni(rng), uni(rng)};  // u0 stratified
        double w = 0;
        if (!wrongPdf) {
            SampleResult<double> s = interp.sample(wo.data(), u, nullptr);
            REQUIRE(s.valid);
            w = s.weight[0];
        } else {
            size_t k = 0;
            double below = 0;
            while (k + 1 < leaves.size() && u[0] >= below + leaves[k].p) below += leaves[k++].p;
            const ResolvedMaterial<double>& lobe = r.lobes.at(size_t(leaves[k].lobe));
            Vec3<double> o{wo[0], wo[1], wo[2]};
            SampleResult<double> s = sampleBrdf(lobe, o, {std::min((u[0] - below) / leaves[k].p, 0.999999), u[1], u[2]});
            double pdf = leaves[k].p * brdfPdf(lobe, s.wi, o);
            if (pdf > 0 && s.wi.z > 0) {
                double wi[3] = {s.wi.x, s.wi.y, s.wi.z};
                w = interp.eval(wi, wo.data(), nullptr).rgb[0] * s.wi.z / pdf;
            }
        }
        sum += w, sum2 += w * w;
    }
    double mean = sum / n, var = std::max(0.0, sum2 / n - mean * mean);
    return {mean, std::sqrt(var / n)};
}

// Does the sampler's estimate agree with the quadrature albedo (5 standard errors + 2e-3)?
bool unbiased(const CheckedMaterial& m, double mu, double alphaMin, bool wrongPdf) {
    double want = albedo(m, mu, alphaMin)[0];
    auto [mean, se] = estimate(m, mu, 20000, wrongPdf);
    MESSAGE("mu_o " << mu << ": albedo " << want << ", E[weight] " << mean << " +- " << se
                    << std::string(wrongPdf ? " (wrong pdf)" : ""));
    return std::abs(mean - want) <= 5 * se + 2e-3;
}

// Int pdf(wi) dwi over the whole sphere.
double pdfIntegral(const CheckedMaterial& m, double mu, double alphaMin) {
    Interpreter<double> interp(m);
    std::array<double, 3> wo = direction(mu);
    double total = 0;
    halfVectorQuadrature(wo, alphaMin, [&](const std::array<double, 3>& wi, double dw) {
        double len = std::sqrt(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
        double unit[3] = {wi[0] / len, wi[1] / len, wi[2] / len};
        PdfResult<double> p = interp.pdf(unit, wo.data(), nullptr);
        REQUIRE(p.valid);
        total += p.pdf * dw;
    });
    return total;
}

const std::string kMixLobes = ggxLobe("a", 0.1, "schlick(0.9)") + ggxLobe("b", 0.5, "dielectric(eta = 1.5)");
const std::string kLayerLobes = ggxLobe("coat", 0.1, "dielectric(eta = 1.5)") + ggxLobe("metal", 0.4, "schlick(0.8)");

}  // namespace

TEST_SUITE("layers") {

TEST_CASE("a layer is reciprocal") {
    const std::string coat = ggxLobe("coat", 0.2, "dielectric(eta = 1.5)");
    const std::string metal = ggxLobe("metal", 0.3, "conductor(eta = rgb(0.2, 0.4, 1.4), k = rgb(4, 2.4, 1.6))");
    const std::string pigment = "    lobe pigment {\n        diffuse = lambert(rgb(0.5, 0.2, 0.1));\n    }\n";
    const std::pair<std::string, std::string> cases[] = {
        {coat + metal, "layer(coat, metal)"},
        {coat + pigment, "layer(coat, pigment, weight = rgb(0.2, 0.5, 1))"},
        {coat + metal + pigment, "layer(coat, 0.4 * metal + 0.6 * pigment, weight = 0.7)"},
        {coat + metal + pigment, "mix(layer(coat, layer(coat, metal)), pigment, 0.3)"}};
    for (const auto& [lobes, bsdf] : cases) {
        CheckedProgram p = checkText(material(lobes, bsdf));
        Interpreter<double> interp(p.materials.at(0));
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> uni(0, 1);
        double worst = 0;
        for (int i = 0; i < 200; ++i) {
            auto dir = [&] {
                double mu = std::max(uni(rng), 1e-3), phi = 2 * kPi * uni(rng), s = std::sqrt(1 - mu * mu);
                return std::array<double, 3>{s * std::cos(phi), s * std::sin(phi), mu};
            };
            std::array<double, 3> a = dir(), b = dir();
            EvalResult<double> ab = interp.eval(a.data(), b.data(), nullptr), ba = interp.eval(b.data(), a.data(), nullptr);
            REQUIRE(ab.valid);
            REQUIRE(ba.valid);
            for (int ch = 0; ch < 3; ++ch) {
                double scale = std::max(std::abs(ab.rgb[ch]), std::abs(ba.rgb[ch]));
                if (scale > 0) worst = std::max(worst, std::abs(ab.rgb[ch] - ba.rgb[ch]) / scale);
                CHECK(std::isfinite(ab.rgb[ch]));
                CHECK(ab.rgb[ch] >= 0);
            }
        }
        MESSAGE(bsdf << ": worst relative reciprocity error " << worst);
        CHECK(worst <= 1e-10);
    }
}

TEST_CASE("white furnace: a dielectric coat over white Lambert keeps all the energy") {
    for (double alpha : {0.05, 0.3, 1.0}) {
        CheckedProgram p = checkText(material(ggxLobe("coat", alpha, "dielectric(eta = 1.5)") + kWhiteLambert,
                                              "layer(coat, white)"));
        for (double mu : {0.02, 0.1, 0.3, 0.6, 1.0}) {
            double total = albedo(p.materials.at(0), mu, alpha)[0];
            MESSAGE("alpha " << alpha << " mu_o " << mu << ": total albedo " << total);
            CHECK(std::abs(total - 1) <= 1e-3);
        }
    }
}

TEST_CASE("a coat over a white microfacet base creates no energy") {
    // The balance makes total = E_top + (1 - E_top) A_b exactly (up to the
    // tables): checked against the two one-lobe albedos, and <= 1.
    const std::string coat = ggxLobe("coat", 0.1, "dielectric(eta = 1.5)");
    for (double alphaBase : {0.01, 0.1, 0.3, 1.0}) {
        const std::string mirror = ggxLobe("mirror", alphaBase, "none");
        CheckedProgram p = checkText(material(coat + mirror, "layer(coat, mirror)"));
        CheckedProgram top = checkText(material(coat, "coat")), base = checkText(material(mirror, "mirror"));
        const double alphaMin = std::min(alphaBase, 0.1);
        for (double mu : {0.05, 0.3, 0.7, 1.0}) {
            double total = albedo(p.materials.at(0), mu, alphaMin)[0];
            double eTop = albedo(top.materials.at(0), mu, alphaMin)[0], aBase = albedo(base.materials.at(0), mu, alphaMin)[0];
            MESSAGE("alpha_base " << alphaBase << " mu_o " << mu << ": total albedo " << total << ", E_top + u A_b "
                                  << eTop + (1 - eTop) * aBase);
            CHECK(total <= 1 + 1e-3);
            CHECK(std::abs(total - (eTop + (1 - eTop) * aBase)) <= 1e-3);
        }
    }
}

TEST_CASE("the mixture sampler is unbiased and its pdf integrates to 1; a wrong pdf is caught") {
    for (const auto& [lobes, bsdf] : {std::pair{kMixLobes, std::string("mix(a, b, 0.4)")},
                                      std::pair{kLayerLobes, std::string("layer(coat, metal, weight = 0.8)")}}) {
        CheckedProgram p = checkText(material(lobes, bsdf));
        const CheckedMaterial& m = p.materials.at(0);
        for (double mu : {0.3, 0.9}) {
            CHECK_MESSAGE(unbiased(m, mu, 0.1, false), bsdf);
            double integral = pdfIntegral(m, mu, 0.1);
            MESSAGE(bsdf << " mu_o " << mu << ": Int pdf - 1 = " << integral - 1);
            CHECK(std::abs(integral - 1) <= 2e-3);
            // The chosen leaf's share of the density alone: the same check fails.
            CHECK_MESSAGE(!unbiased(m, mu, 0.1, true), bsdf);
        }
    }
}

}  // TEST_SUITE

TEST_SUITE("layers") {

TEST_CASE("a lone diffuse lobe samples its cosine lobe (no ndf to sample)") {
    CheckedProgram p = checkText(material("    lobe grey {\n        diffuse = lambert(0.5);\n    }\n", "grey"));
    const CheckedMaterial& m = p.materials.at(0);
    for (double mu : {0.2, 1.0}) {
        CHECK(unbiased(m, mu, 0.1, false));
        CHECK(std::abs(pdfIntegral(m, mu, 0.1) - 1) <= 2e-3);
    }
    CHECK(compiledBackendsRefuse(m).empty());  // the compiled backends take it (tests/jit: its kernels)
}

}  // TEST_SUITE
