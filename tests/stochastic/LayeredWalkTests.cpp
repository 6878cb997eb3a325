// Tests of the layered random walk (compiler/reference/LayeredWalk.h, SPEC
// 13): the limits it must reach (an index-matched top is no top; a
// dielectric coat over white Lambert, smooth or rough, keeps all the energy;
// a smooth one equals the classic closed-form coating), and its two
// estimators (next events and forward walks) against each other and against
// reciprocity.
#include "../physics/PhysicsUtil.h"
#include "CosineAlbedo.h"
#include "LayeredWalk.h"
#include "WalkComparison.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace {

using facet::LayeredWalk;
using facet::WalkEstimate;
using facet::WalkRandom;
using physics::deg;
using physics::dir;
using physics::kPi;
using physics::makeMaterial;
using physics::Material;
using physics::Vec3;

// Fresnel reflectance of a dielectric boundary, eta = far / near (1 past the
// critical angle): the catalog's `dielectric` (its own g-form, not the walk's
// s and p amplitudes).
double fresnel(double c, double eta) {
    static std::map<double, Material> boundaries;
    auto it = boundaries.find(eta);
    if (it == boundaries.end()) {
        char text[64];
        std::snprintf(text, sizeof text, "%.17g", eta);
        it = boundaries.emplace(eta, makeMaterial(std::string("ndf = ggx(0.1); fresnel = dielectric(") + text + ");")).first;
    }
    return it->second.F(c, 0);
}

// The smooth coating of index eta over a Lambertian base of albedo rho
// (the diffuse part; wi and wo away from the mirror direction):
// (1 - F_i)(1 - F_o) rho / (pi eta^2 (1 - rho F_dr)), F_dr = 2 Int F(mu, 1/eta) mu dmu
// the diffuse reflectance of the boundary from inside (midpoint rule).
double smoothCoating(double muI, double muO, double eta, double rho, double extraEta2 = 1) {
    double fdr = 0;
    const int n = 200000;
    for (int k = 0; k < n; ++k) {
        double mu = (k + 0.5) / n;
        fdr += 2 * fresnel(mu, 1 / eta) * mu / n;
    }
    return (1 - fresnel(muI, eta)) * (1 - fresnel(muO, eta)) * rho / (kPi * eta * eta * extraEta2 * (1 - rho * fdr));
}

}  // namespace

TEST_CASE("the layered walk names what it cannot walk") {
    Material base = makeMaterial("lobe d { diffuse = lambert(0.5); } bsdf = d;");
    CHECK(LayeredWalk::unsupported(makeMaterial("ndf = ggx(0.1); fresnel = dielectric(1.5);"), base) == "");
    CHECK(LayeredWalk::unsupported(makeMaterial("ndf = ggx(0.1); fresnel = schlick(0.04);"), base).find("dielectric(eta)") !=
          std::string::npos);
    CHECK(LayeredWalk::unsupported(makeMaterial("ndf = gaussian(0.1); fresnel = dielectric(1.5);"), base)
              .find("the top: ") == 0);
}

TEST_CASE("an index-matched top is no top: the layered walk is its base exactly") {
    Material top = makeMaterial("ndf = ggx(0.4); fresnel = dielectric(1);");
    Material base = makeMaterial("ndf = beckmann(0.3); fresnel = conductor(eta = rgb(0.2, 1.0, 1.2), k = rgb(3.7, 2.6, 2.4));");
    LayeredWalk walk(top, base);
    for (auto [ti, to] : {std::pair{20.0, 30.0}, {60.0, 5.0}, {80.0, 70.0}}) {
        Vec3<double> wi = dir(deg(ti), 2.0), wo = dir(deg(to), 0.1);
        WalkEstimate e = walk.brdf(wi, wo, 200, 3);
        std::array<double, 3> f = base.brdf(wi, wo);
        for (int ch = 0; ch < 3; ++ch) CHECK(e.mean[ch] == doctest::Approx(f[ch]).epsilon(1e-12));
    }
}

TEST_CASE("a dielectric coat over white Lambert keeps the energy, smooth or rough, and a smooth one is the "
          "closed-form coating") {
    // The boundary is the dielectric microsurface walk: no energy is lost
    // however rough the coat (a single-scattering boundary would lose a
    // quarter of it at alpha 0.3).
    Material white = makeMaterial("lobe d { diffuse = lambert(1); } bsdf = d;");
    for (const char* coat : {"ggx(0.001)", "ggx(0.3)", "beckmann(0.8)"}) {
        Material rough = makeMaterial(std::string("ndf = ") + coat + "; fresnel = dielectric(1.5);");
        LayeredWalk walk(rough, white);
        for (double theta : {0.0, 45.0, 75.0}) {
            WalkEstimate a = walk.albedo(dir(deg(theta), 0.2), 40000, 17);
            INFO("coat ", std::string(coat), " theta_o ", theta, " albedo ", a.mean[0], " +- ", a.stdError[0]);
            CHECK(std::abs(a.mean[0] - 1) <= 4 * a.stdError[0] + 1e-9);
            CHECK(a.abandoned == 0);
        }
        // The forward walks keep weight 1 by construction; next events over
        // cosine-drawn wi must find the same total (not for the smooth coat,
        // whose mirror peak cosine-drawn wi all but never meet).
        if (std::string(coat) == "ggx(0.001)") continue;
        Vec3<double> wo = dir(deg(50), 0.2);
        WalkEstimate e = stochastic::cosineAlbedo(40000, 19, [&](const Vec3<double>& wi, WalkRandom& random) {
            std::array<double, 3> f = walk.pathBrdf(wi, wo, random);
            for (double& v : f) v *= wi.z;
            return f;
        });
        INFO("coat ", std::string(coat), " next events: albedo ", e.mean[0], " +- ", e.stdError[0]);
        CHECK(std::abs(e.mean[0] - 1) <= 4 * e.stdError[0]);
    }
    Material top = makeMaterial("ndf = ggx(0.001); fresnel = dielectric(1.5);");
    Material grey = makeMaterial("lobe d { diffuse = lambert(0.8); } bsdf = d;");
    LayeredWalk coated(top, grey);
    for (auto [ti, to] : {std::pair{10.0, 40.0}, {50.0, 20.0}, {70.0, 65.0}}) {
        Vec3<double> wi = dir(deg(ti), 1.0), wo = dir(deg(to), 0.0);
        WalkEstimate e = coated.brdf(wi, wo, 40000, 29);
        double exact = smoothCoating(wi.z, wo.z, 1.5, 0.8);
        double wrong = smoothCoating(wi.z, wo.z, 1.5, 0.8, 1 / (1.5 * 1.5));  // without the 1/eta^2 of radiance
        INFO("theta_i ", ti, " theta_o ", to, " walk ", e.mean[0], " +- ", e.stdError[0], " closed form ", exact);
        CHECK(std::abs(e.mean[0] - exact) <= 4 * e.stdError[0] + 1e-3 * exact);
        CHECK(std::abs(e.mean[0] - wrong) > 4 * e.stdError[0] + 1e-3 * exact);
    }
}

TEST_CASE("the layered walk's next events and forward walks agree, and it is reciprocal") {
    // A rough coat with absorption over a rough coloured conductor.
    Material top = makeMaterial("ndf = ggx(0.3); fresnel = dielectric(1.5);");
    Material base = makeMaterial("ndf = ggx(0.4); fresnel = conductor(eta = rgb(0.2, 1.0, 1.2), k = rgb(3.7, 2.6, 2.4));");
    facet::LayerAbsorption absorption;
    absorption.sigma = {0.1, 0.5, 1.0};
    LayeredWalk walk(top, base, absorption);
    for (double theta : {15.0, 65.0}) {
        Vec3<double> wo = dir(deg(theta), 0.5);
        WalkEstimate forward = walk.albedo(wo, 40000, 41);
        // Next events over wi drawn from the cosine lobe.
        WalkEstimate e = stochastic::cosineAlbedo(40000, 43, [&](const Vec3<double>& wi, WalkRandom& random) {
            std::array<double, 3> f = walk.pathBrdf(wi, wo, random);
            for (double& v : f) v *= wi.z;
            return f;
        });
        for (int ch = 0; ch < 3; ++ch) {
            INFO("theta_o ", theta, " channel ", ch, " forward ", forward.mean[ch], " +- ", forward.stdError[ch],
                 " next events ", e.mean[ch], " +- ", e.stdError[ch]);
            CHECK(std::abs(forward.mean[ch] - e.mean[ch]) <= 4 * std::hypot(forward.stdError[ch], e.stdError[ch]));
        }
        CHECK(forward.mean[0] > forward.mean[2]);  // less absorbed, and the conductor's red
    }
    for (auto [ti, to] : {std::pair{20.0, 50.0}, {70.0, 10.0}}) {
        Vec3<double> a = dir(deg(ti), 0.4), b = dir(deg(to), 2.5);
        WalkEstimate ab = walk.brdf(a, b, 40000, 51), ba = walk.brdf(b, a, 40000, 53);
        for (int ch = 0; ch < 3; ++ch) {
            INFO("theta ", ti, " / ", to, " channel ", ch, ": f(a, b) ", ab.mean[ch], " +- ", ab.stdError[ch],
                 ", f(b, a) ", ba.mean[ch], " +- ", ba.stdError[ch]);
            CHECK(std::abs(ab.mean[ch] - ba.mean[ch]) <= 4 * std::hypot(ab.stdError[ch], ba.stdError[ch]));
        }
    }
}

TEST_CASE("verify's layer report: an index-matched coat is its base on both sides; albedo scaling over a smooth coat "
          "keeps the light that internal reflection returns to the base") {
    auto report = [](const std::string& coat, double theta) {
        facet::DiagnosticEngine diags;
        facet::CheckedProgram program = facet::loadProgramText(
            "material t { lobe coat { ndf = ggx(0.05); masking = smith_height_correlated; fresnel = dielectric(" + coat +
                "); } lobe base { diffuse = lambert(0.8); } bsdf = layer(coat, base); }",
            "layer.mat", diags);
        REQUIRE_FALSE(diags.hasErrors());
        const facet::CheckedMaterial& m = *program.find("t");
        facet::Interpreter<double> interp(m);
        facet::ResolvedBsdf<double> r = interp.resolveAll(nullptr);
        REQUIRE(facet::layerWalkUnsupported(m, r) == "");
        facet::WalkComparisonOptions options;
        options.thetas = {theta};
        options.gridTheta = 6, options.gridPhi = 12;
        return facet::compareLayerWithWalk(interp, r, options).at(0);
    };
    facet::WalkComparisonRow matched = report("1", 30);
    INFO("matched: layer ", matched.modelAlbedo[0], " walk ", matched.walkAlbedo[0], " shape ", matched.modelShapeError);
    CHECK(matched.modelAlbedo[0] == doctest::Approx(0.8).epsilon(1e-3));
    CHECK(matched.walkAlbedo[0] == doctest::Approx(0.8).epsilon(1e-12));
    CHECK(matched.modelShapeError < 1e-3);
    // Eta 1.5 at normal incidence: the walk's albedo is F_o + (1 - F_o) rho
    // (1 - F_dr) / (1 - rho F_dr), F_dr ~ 0.6 the boundary's diffuse
    // reflectance from inside (0.63), the layer's E_top + (1 - E_top) rho
    // (0.81): brighter by far more than the walk's noise.
    facet::WalkComparisonRow coated = report("1.5", 0);
    INFO("coated: layer ", coated.modelAlbedo[0], " walk ", coated.walkAlbedo[0], " +- ", coated.walkAlbedoError[0]);
    CHECK(coated.modelAlbedo[0] > coated.walkAlbedo[0] + 0.1);
    CHECK(coated.walkAlbedo[0] == doctest::Approx(0.04 + 0.96 * 0.8 * 0.4 / (1 - 0.8 * 0.6)).epsilon(0.05));
}

TEST_CASE("a dispersive coat walks each eta once: channels that share an eta get the same walk") {
    // eta (1.5, 1.4, 1.5): red and blue are one walk, green its own; with a
    // grey base, red and blue must come out identical, green not.
    Material top = makeMaterial("ndf = ggx(0.3); fresnel = dielectric(rgb(1.5, 1.4, 1.5));");
    Material grey = makeMaterial("lobe d { diffuse = lambert(0.6); } bsdf = d;");
    LayeredWalk walk(top, grey);
    Vec3<double> wi = dir(deg(30), 1.0), wo = dir(deg(50), 0.0);
    WalkEstimate f = walk.brdf(wi, wo, 2000, 83);
    CHECK(f.mean[0] == f.mean[2]);
    CHECK(f.mean[1] != f.mean[0]);
    WalkEstimate a = walk.albedo(wo, 2000, 89);
    CHECK(a.mean[0] == a.mean[2]);
    CHECK(a.mean[1] != a.mean[0]);
}
