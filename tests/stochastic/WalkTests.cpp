// Tests of the random walk on the microsurface (compiler/reference/
// MicrosurfaceWalk.h, SPEC 13): what it must conserve, what its first order
// must equal, and that its two estimators (the walk's exit directions and
// next-event estimation) estimate the same BSDF.
//
// Every comparison is "within k standard errors" of a seeded Monte Carlo
// estimate, so each is deterministic for its seed; k = 4 for the many
// (NDF, alpha, wo) cells at once. A deliberately wrong reference (the
// separable Smith masking in place of the height-correlated one the
// microsurface has) must be told apart by the same comparison, so that the
// tolerance is shown to be tight enough to mean something.
#include "../physics/PhysicsUtil.h"
#include "CosineAlbedo.h"
#include "MicrosurfaceWalk.h"
#include "WalkComparison.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using facet::MicrosurfaceWalk;
using facet::WalkEstimate;
using facet::WalkOrders;
using facet::WalkRandom;
using physics::deg;
using physics::dir;
using physics::kPi;
using physics::makeMaterial;
using physics::Material;

// The NDFs the walk supports (those with an exact Lambda and visible-normal
// sampler), each with one shape, isotropic and anisotropic GGX.
struct WalkNdf {
    const char* name;
    std::string (*source)(double alpha);
};
const std::vector<WalkNdf>& walkNdfs() {
    static const std::vector<WalkNdf> ndfs = {
        {"ggx", [](double a) { return "ndf = ggx(" + std::to_string(a) + ");"; }},
        {"ggx aniso", [](double a) { return "ndf = ggx(alpha_x = " + std::to_string(a) + ", alpha_y = " + std::to_string(a / 3) + ");"; }},
        {"beckmann", [](double a) { return "ndf = beckmann(" + std::to_string(a) + ");"; }},
        {"blinn_phong", [](double a) { return "ndf = blinn_phong(" + std::to_string(2 / (a * a) - 2) + ");"; }},
        {"student_t", [](double a) { return "ndf = student_t(" + std::to_string(a) + ", 3);"; }},
    };
    return ndfs;
}

// The white furnace of the walk through next-event estimation: Int f (n.wi)
// dwi with wi drawn from the cosine lobe, one walk per wi. With F = 1 it is 1
// (the walk loses no energy), which no single-scattering lobe reaches.
WalkEstimate neeAlbedo(const MicrosurfaceWalk& walk, const physics::Vec3<double>& wo, int64_t paths, uint64_t seed,
                       WalkOrders orders = {}) {
    return stochastic::cosineAlbedo(paths, seed, [&](const physics::Vec3<double>& wi, WalkRandom& random) {
        return walk.pathBrdfCos(wi, wo, random, orders);
    });
}

// The single-scattering lobe with F = 1 that the walk's first order is,
// D G2 / (4 ci co), written here from the NDF's D and exact Lambda
// (visibleCosLambda: the masking models' Lambda is an approximation for
// blinn_phong), with the height-correlated G2 = 1 / (1 + Li + Lo) or, as
// the deliberately wrong reference, the separable 1 / ((1 + Li)(1 + Lo)).
double smithSingle(const Material& r, const physics::Vec3<double>& wi, const physics::Vec3<double>& wo, bool separable) {
    if (!(wi.z > 0 && wo.z > 0)) return 0;
    physics::Vec3<double> h = physics::normalize({wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
    if (physics::dot(wi, h) <= 0) return 0;
    const auto& ndf = r.ndf->formulas.get<double>();
    double li = ndf.visibleCosLambda(r.ndfArgs, wi) / wi.z, lo = ndf.visibleCosLambda(r.ndfArgs, wo) / wo.z;
    double g2 = separable ? 1 / ((1 + li) * (1 + lo)) : 1 / (1 + li + lo);
    return r.D(h) * g2 / (4 * wi.z * wo.z);
}

// Its albedo by a cosine-lobe Monte Carlo (its error is small against the
// walk's).
double singleAlbedo(const Material& r, const physics::Vec3<double>& wo, int64_t n, uint64_t seed, bool separable,
                    double* stdError) {
    WalkEstimate e = stochastic::cosineAlbedo(n, seed, [&](const physics::Vec3<double>& wi, WalkRandom&) {
        double fCos = smithSingle(r, wi, wo, separable) * wi.z;
        return std::array<double, 3>{fCos, fCos, fCos};
    });
    *stdError = e.stdError[0];
    return e.mean[0];
}

}  // namespace

TEST_CASE("the walk supports the NDFs with an exact Lambda and visible normals, and says why not the others") {
    for (const WalkNdf& ndf : walkNdfs()) CHECK(MicrosurfaceWalk::unsupported(makeMaterial(ndf.source(0.3))) == "");
    CHECK(MicrosurfaceWalk::unsupported(makeMaterial("ndf = gaussian(0.3);")).find("visible-normal") != std::string::npos);
    CHECK(MicrosurfaceWalk::unsupported(makeMaterial("ndf = ward(0.3);")).find("whole lobe") != std::string::npos);
}

// A visible normal of v below the horizon by rejection, independent of the
// catalog's own sampler there: drawn from the visible normals of v mirrored
// above the horizon, (v.x, v.y, -v.z), and kept with probability <v, m> /
// <v+, m> (<= 1 for every m above the horizon).
physics::Vec3<double> rejectionVisibleNormal(const Material& r, const physics::Vec3<double>& v, WalkRandom& random) {
    const auto& ndf = r.ndf->formulas.get<double>();
    physics::Vec3<double> up{v.x, v.y, -v.z};
    for (;;) {
        double u1 = random.next(), u2 = random.next(), u3 = random.next();
        physics::Vec3<double> m = ndf.sampleVisibleNormal(r.ndfArgs, up, u1, u2);
        double along = physics::dot(v, m);
        if (along > 0 && u3 * physics::dot(up, m) < along) return m;
    }
}

TEST_CASE("visible normals below the horizon: the catalog's samplers against rejection from above") {
    // The walk's rays going up meet facets through the catalog's samplers
    // called with a direction below the horizon. Their moments (m.x, m.y,
    // m.z, m.z^2) against those of the rejection sampler.
    for (const WalkNdf& ndf : walkNdfs()) {
        for (auto [alpha, theta] : {std::pair{0.6, 95.0}, {0.6, 120.0}, {1.0, 140.0}}) {
            Material r = makeMaterial(ndf.source(alpha));
            const auto& formulas = r.ndf->formulas.get<double>();
            physics::Vec3<double> v = dir(deg(theta), 0.7);
            std::array<std::array<double, 4>, 2> sum{}, sum2{};
            const int64_t n[2] = {40000, 6000};
            for (int which = 0; which < 2; ++which)
                for (int64_t k = 0; k < n[which]; ++k) {
                    WalkRandom random(which == 0 ? 3 : 5, uint64_t(k));
                    physics::Vec3<double> m;
                    if (which == 0) {
                        double u1 = random.next(), u2 = random.next();
                        m = formulas.sampleVisibleNormal(r.ndfArgs, v, u1, u2);
                    } else {
                        m = rejectionVisibleNormal(r, v, random);
                    }
                    std::array<double, 4> x{m.x, m.y, m.z, m.z * m.z};
                    for (int i = 0; i < 4; ++i) sum[which][i] += x[i], sum2[which][i] += x[i] * x[i];
                }
            for (int i = 0; i < 4; ++i) {
                double mean[2], se2[2];
                for (int w = 0; w < 2; ++w) {
                    mean[w] = sum[w][i] / double(n[w]);
                    se2[w] = std::max(0.0, sum2[w][i] / double(n[w]) - mean[w] * mean[w]) / double(n[w]);
                }
                INFO(std::string(ndf.name), " alpha ", alpha, " theta_v ", theta, " moment ", i, " catalog ", mean[0],
                     " rejection ", mean[1]);
                CHECK(std::abs(mean[0] - mean[1]) <= 4 * std::sqrt(se2[0] + se2[1]));
            }
        }
    }
}

TEST_CASE("projected area: A(v) - A(-v) = n.v, the weak white furnace from both sides") {
    // Int <v, m> D(m) dm = n.v for a normalized D (projected area of the
    // macrosurface), and <v, m>+ - <-v, m>+ = <v, m>.
    for (const WalkNdf& ndf : walkNdfs()) {
        Material r = makeMaterial(ndf.source(0.6));
        MicrosurfaceWalk walk(r);
        for (double theta : {0.0, 30.0, 75.0, 89.0}) {
            physics::Vec3<double> v = dir(deg(theta), 0.4);
            INFO(std::string(ndf.name), " theta ", theta);
            CHECK(walk.projectedArea(v) - walk.projectedArea({-v.x, -v.y, -v.z}) == doctest::Approx(v.z).epsilon(1e-12));
        }
    }
}

TEST_CASE("with F = 1 the walk conserves energy, and its first order is the height-correlated Smith lobe") {
    int cells = 0;
    for (const WalkNdf& ndf : walkNdfs()) {
        for (double alpha : {0.2, 0.6, 1.0}) {
            Material r = makeMaterial(ndf.source(alpha));
            MicrosurfaceWalk walk(r);
            for (double theta : {0.0, 60.0, 85.0}) {
                physics::Vec3<double> wo = dir(deg(theta), 0.3);
                INFO(std::string(ndf.name), " alpha ", alpha, " theta_o ", theta);
                ++cells;
                // Next-event estimation over all orders: albedo 1.
                WalkEstimate total = neeAlbedo(walk, wo, 20000, 11 + cells);
                CHECK(std::abs(total.mean[0] - 1) <= 4 * total.stdError[0] + 1e-9);
                // The walk's exits: every walk leaves, weight 1.
                WalkEstimate exits = walk.albedo(wo, 2000, 23 + cells);
                CHECK(exits.mean[0] == 1.0);
                CHECK(exits.abandoned == 0);
                // Order 1, by the exits and by next events, against the lobe
                // with height-correlated Smith masking (and not separable).
                WalkEstimate first = walk.albedo(wo, 40000, 37 + cells, WalkOrders{.onlyOrder = 1});
                WalkEstimate firstNee = neeAlbedo(walk, wo, 40000, 41 + cells, WalkOrders{.onlyOrder = 1});
                double singleError = 0, separableError = 0;
                double single = singleAlbedo(r, wo, 400000, 53 + cells, false, &singleError);
                double wrong = singleAlbedo(r, wo, 400000, 53 + cells, true, &separableError);
                double tolerance = 4 * std::hypot(first.stdError[0], singleError);
                CHECK(std::abs(first.mean[0] - single) <= tolerance);
                CHECK(std::abs(firstNee.mean[0] - single) <= 4 * std::hypot(firstNee.stdError[0], singleError));
                // The separable masking differs most at grazing wo: that is
                // where the comparison must see it.
                if (theta == 85.0 && alpha >= 0.6) CHECK(std::abs(first.mean[0] - wrong) > tolerance);
            }
        }
    }
    CHECK(cells == 45);
}

TEST_CASE("order 1 of next-event estimation equals the single-scattering BRDF at given directions") {
    for (const WalkNdf& ndf : walkNdfs()) {
        Material r = makeMaterial(ndf.source(0.5) + " fresnel = conductor(eta = rgb(0.2, 1.0, 1.2), k = rgb(3.7, 2.6, 2.4));");
        MicrosurfaceWalk walk(r);
        int pair = 0;
        for (auto [ti, to, dphi] : {std::array<double, 3>{20, 40, 2.0}, {70, 10, 0.5}, {80, 80, 3.0}, {45, 45, 0.0}}) {
            physics::Vec3<double> wi = dir(deg(ti), 0.3 + dphi), wo = dir(deg(to), 0.3);
            WalkEstimate e = walk.brdf(wi, wo, 50000, 100 + ++pair, WalkOrders{.onlyOrder = 1});
            physics::Vec3<double> h = physics::normalize({wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
            std::array<double, 3> exact;
            for (int ch = 0; ch < 3; ++ch) exact[ch] = smithSingle(r, wi, wo, false) * r.F(physics::dot(wi, h), ch);
            for (int ch = 0; ch < 3; ++ch) {
                INFO(std::string(ndf.name), " theta_i ", ti, " theta_o ", to, " channel ", ch, " walk ", e.mean[ch], " +- ",
                     e.stdError[ch], " exact ", exact[ch]);
                CHECK(std::abs(e.mean[ch] - exact[ch]) <= 4 * e.stdError[ch] + 1e-12 * exact[ch]);
            }
        }
    }
}

TEST_CASE("the walk's exits and its next events estimate the same coloured albedo") {
    // Two independent estimators of Int f (n.wi) dwi for a coloured
    // conductor: the mean weight of the walk's exits (Fresnel at every
    // reflection) and next-event estimation over cosine-drawn wi.
    for (const WalkNdf& ndf : walkNdfs()) {
        Material r = makeMaterial(ndf.source(0.8) + " fresnel = conductor(eta = rgb(0.2, 1.0, 1.2), k = rgb(3.7, 2.6, 2.4));");
        MicrosurfaceWalk walk(r);
        for (double theta : {10.0, 70.0}) {
            physics::Vec3<double> wo = dir(deg(theta), 1.1);
            WalkEstimate exits = walk.albedo(wo, 40000, 7);
            WalkEstimate nee = neeAlbedo(walk, wo, 40000, 9);
            for (int ch = 0; ch < 3; ++ch) {
                INFO(std::string(ndf.name), " theta_o ", theta, " channel ", ch, " exits ", exits.mean[ch], " nee ", nee.mean[ch]);
                CHECK(std::abs(exits.mean[ch] - nee.mean[ch]) <= 4 * std::hypot(exits.stdError[ch], nee.stdError[ch]));
                CHECK(exits.mean[ch] < 1);
            }
            CHECK(exits.mean[0] > exits.mean[2]);  // copper-like: red reflects the most
        }
    }
}

TEST_CASE("a cut walk keeps its orders: the orders' albedos add up to the whole") {
    Material r = makeMaterial("ndf = ggx(0.9);");
    MicrosurfaceWalk walk(r);
    physics::Vec3<double> wo = dir(deg(70), 0);
    WalkEstimate upTo2 = walk.albedo(wo, 100000, 5, WalkOrders{.maxOrder = 2});
    WalkEstimate o1 = walk.albedo(wo, 100000, 5, WalkOrders{.onlyOrder = 1});
    WalkEstimate o2 = walk.albedo(wo, 100000, 5, WalkOrders{.onlyOrder = 2});
    // Same seed, same walks: the counts add exactly.
    CHECK(upTo2.mean[0] == doctest::Approx(o1.mean[0] + o2.mean[0]).epsilon(1e-12));
    CHECK(o2.mean[0] > 0.02);  // rough GGX at 70 degrees: a few percent leave after two reflections
    CHECK(upTo2.mean[0] < 1);
}

TEST_CASE("Kulla-Conty against the walk: energy restored, and the lobe's shape closer than single scattering's") {
    // A white rough GGX lobe: the single-scattering lobe loses up to ~40%
    // of the energy at alpha = 1; Kulla-Conty gives it back (its furnace
    // bound is 1%), and its compensation lobe brings f closer to the walk's
    // multiple scattering than the single-scattering lobe is.
    Material r = makeMaterial("ndf = ggx(1.0); masking = smith_height_correlated; energy = kulla_conty;");
    facet::WalkComparisonOptions options;
    options.thetas = {0, 60, 85};
    for (const facet::WalkComparisonRow& row : facet::compareWithWalk(r, options)) {
        INFO("theta_o ", row.thetaO, " single ", row.singleAlbedo[0], " model ", row.modelAlbedo[0], " walk ",
             row.walkAlbedo[0], " shape: single ", row.singleShapeError, " model ", row.modelShapeError, " noise ",
             row.shapeNoise);
        CHECK(row.walkAlbedo[0] == 1.0);
        CHECK(row.abandoned == 0);
        CHECK(row.singleAlbedo[0] < 0.9);
        CHECK(std::abs(row.modelAlbedo[0] - 1) < 0.01);
        CHECK(row.modelShapeError < 0.7 * row.singleShapeError);
        CHECK(row.shapeNoise < 0.5 * row.singleShapeError);
    }
}

TEST_CASE("the walk's scattering orders against the independent Python walk (scripts/reference_walk.py)") {
    // tests/stochastic/walk_orders.txt: the fraction of walks leaving after
    // 1, 2 and >= 3 reflections (F = 1), from a second implementation with
    // Gaussian heights, the paper's signed height formula and other
    // visible-normal samplers. Each fraction within 4 combined standard errors.
    std::FILE* file = std::fopen(FACET_WALK_ORDERS, "r");
    REQUIRE(file != nullptr);
    char line[512];
    int cells = 0;
    while (std::fgets(line, sizeof line, file)) {
        if (line[0] == '#') continue;
        char ndf[32];
        double alpha, theta, e[3], se[3];
        long long paths;
        int n = std::sscanf(line, "%31s %lf %lf %lld %lf %lf %lf %lf %lf %lf", ndf, &alpha, &theta, &paths, &e[0], &se[0],
                            &e[1], &se[1], &e[2], &se[2]);
        REQUIRE(n == 10);
        Material r = makeMaterial("ndf = " + std::string(ndf) + "(" + std::to_string(alpha) + ");");
        MicrosurfaceWalk walk(r);
        physics::Vec3<double> wo = dir(deg(theta), 0);
        WalkEstimate o1 = walk.albedo(wo, 100000, 71 + cells, WalkOrders{.onlyOrder = 1});
        WalkEstimate o2 = walk.albedo(wo, 100000, 71 + cells, WalkOrders{.onlyOrder = 2});
        WalkEstimate upTo2 = walk.albedo(wo, 100000, 71 + cells, WalkOrders{.maxOrder = 2});
        double mine[3] = {o1.mean[0], o2.mean[0], 1 - upTo2.mean[0]};
        double mySe[3] = {o1.stdError[0], o2.stdError[0], upTo2.stdError[0]};
        for (int k = 0; k < 3; ++k) {
            INFO(ndf, " alpha ", alpha, " theta_o ", theta, " order ", k + 1, (k == 2 ? "+" : ""), ": C++ ", mine[k],
                 " +- ", mySe[k], ", Python ", e[k], " +- ", se[k]);
            CHECK(std::abs(mine[k] - e[k]) <= 4 * std::hypot(mySe[k], se[k]) + 1e-12);
        }
        ++cells;
    }
    std::fclose(file);
    CHECK(cells == 18);
}

TEST_CASE("a dielectric microsurface: order 1 is the single-scattering lobe, next events from both sides agree with "
          "the exits, and a smooth one is Fresnel's") {
    // eta 1 / 1.5 (seen from inside glass): light refracted below bends
    // toward the horizon and often meets the surface again from below,
    // which is where the lower side's next events matter.
    for (const WalkNdf& ndf : walkNdfs()) {
        for (auto [alpha, eta] : {std::pair{0.3, "1.5"}, {1.0, "1.5"}, {0.6, "0.6666667"}}) {
            Material r = makeMaterial(ndf.source(alpha) + " fresnel = dielectric(" + eta + ");");
            MicrosurfaceWalk walk(r);
            REQUIRE(walk.dielectric());
            // Order 1 at given directions: D F G2 / (4 ci co).
            physics::Vec3<double> wi = dir(deg(35), 2.5), wo = dir(deg(60), 0.3);
            physics::Vec3<double> h = physics::normalize({wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
            WalkEstimate first = walk.brdf(wi, wo, 40000, 61, WalkOrders{.onlyOrder = 1});
            double exact = smithSingle(r, wi, wo, false) * r.F(physics::dot(wi, h), 0);
            INFO(std::string(ndf.name), " alpha ", alpha, " eta ", std::string(eta), " order 1: walk ", first.mean[0], " +- ", first.stdError[0],
                 " exact ", exact);
            CHECK(std::abs(first.mean[0] - exact) <= 4 * first.stdError[0] + 1e-12 * exact);
            // All orders: the walks that leave upward against next events
            // (those from the lower side refract up through a facet).
            for (double theta : {20.0, 75.0}) {
                physics::Vec3<double> v = dir(deg(theta), 0.9);
                WalkEstimate exits = walk.albedo(v, 40000, 67);
                WalkEstimate nee = neeAlbedo(walk, v, 40000, 71);
                WalkEstimate neeFirst = neeAlbedo(walk, v, 40000, 71, WalkOrders{.onlyOrder = 1});
                INFO("theta_o ", theta, " exits ", exits.mean[0], " +- ", exits.stdError[0], " next events ", nee.mean[0],
                     " +- ", nee.stdError[0], " order 1 ", neeFirst.mean[0]);
                CHECK(std::abs(exits.mean[0] - nee.mean[0]) <= 4 * std::hypot(exits.stdError[0], nee.stdError[0]));
                CHECK(exits.abandoned == 0);
                if (alpha == 1.0) CHECK(nee.mean[0] > neeFirst.mean[0] + 4 * nee.stdError[0]);  // light comes back out
            }
        }
    }
    // Smooth: the reflected fraction is the Fresnel reflectance at n.wo.
    Material smooth = makeMaterial("ndf = ggx(0.001); fresnel = dielectric(1.5);");
    MicrosurfaceWalk walk(smooth);
    for (double theta : {0.0, 60.0, 85.0}) {
        WalkEstimate exits = walk.albedo(dir(deg(theta), 0), 40000, 73);
        double fresnel = smooth.F(std::cos(deg(theta)), 0);
        INFO("theta_o ", theta, " reflected ", exits.mean[0], " +- ", exits.stdError[0], " Fresnel ", fresnel);
        CHECK(std::abs(exits.mean[0] - fresnel) <= 4 * exits.stdError[0] + 2e-3);
    }
}
