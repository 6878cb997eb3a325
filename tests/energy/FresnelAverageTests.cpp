// F_avg = 2 Int_0^1 F(mu) mu dmu: Schlick's closed form, the graded
// quadrature of the exact dielectric and conductor Fresnel (library and
// interpreter), and the accuracy of the tables the JIT uses for per-lane
// eta / k. Reference: composite Simpson in this test (2e5 intervals in
// s = sqrt(mu), and split at the critical angle when eta < 1).
#include "EnergyTestUtil.h"

#include <cstdio>
#include <random>

using namespace energy;

namespace {

// A material with only the Fresnel term `model` and the named parameters.
template <typename Real = double>
facet::ResolvedMaterial<Real> fresnelOnly(const char* model, std::initializer_list<std::pair<const char*, Real>> args) {
    facet::ResolvedMaterial<Real> r;
    r.fresnel = &facet::fresnelEntry(facet::modelNamed(facet::ModelSlot::Fresnel, model));
    for (auto [name, value] : args) {
        int p = facet::paramIndex(*r.fresnel, name);
        REQUIRE(p >= 0);
        r.fresnelArgs.set(p, value);
    }
    return r;
}

double simpson(const std::function<double(double)>& f, double a, double b, int n) {
    if (!(b > a)) return 0;
    if (n % 2) ++n;
    double h = (b - a) / n, sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4 : 2);
    return sum * h / 3;
}

// 2 Int F mu dmu with mu = s^2: 4 Int F(s^2) s^3 ds, split at the critical angle.
double referenceAverage(const facet::ResolvedMaterial<double>& r) {
    auto f = [&](double s) { return s == 0 ? 0.0 : r.F(s * s, 0) * 4 * s * s * s; };
    double n = r.fresnelArgs[facet::paramIndex(*r.fresnel, "eta")];
    if (n < 1) {
        double sc = std::sqrt(std::sqrt((1 - n) * (1 + n)));
        return simpson(f, 0, sc, 100000) + simpson(f, sc, 1, 100000);
    }
    return simpson(f, 0, 1, 200000);
}

}  // namespace

TEST_SUITE("fresnel_average") {

TEST_CASE("Schlick: (20 f0 + 1) / 21") {
    for (double f0 : {0.0, 0.04, 0.5, 0.95, 1.0}) {
        auto r = fresnelOnly("schlick", {{"f0", f0}});
        CHECK(facet::fresnelAverage(r, 0) == doctest::Approx((20 * f0 + 1) / 21).epsilon(1e-15));
        CHECK(referenceAverage(r) == doctest::Approx((20 * f0 + 1) / 21).epsilon(1e-9));
    }
    // From eta: f0 = ((eta - 1)/(eta + 1))^2.
    auto r = fresnelOnly("schlick", {{"eta", 1.5}});
    CHECK(facet::fresnelAverage(r, 1) == doctest::Approx((20 * 0.04 + 1) / 21).epsilon(1e-12));
}

TEST_CASE("dielectric and conductor quadrature against Simpson") {
    double worst = 0;
    for (double eta : {1e-4, 0.05, 0.3, 0.667, 0.95, 1.0, 1.0001, 1.33, 1.5, 2.4, 10.0, 68.0, 1e4}) {
        auto r = fresnelOnly("dielectric", {{"eta", eta}});
        double ref = referenceAverage(r);
        INFO("dielectric eta=", eta, " reference ", ref);
        CHECK(facet::fresnelAverageDielectric(eta) == doctest::Approx(ref).epsilon(1e-7).scale(1));
        CHECK(facet::fresnelAverage(r, 0) == doctest::Approx(ref).epsilon(1e-7).scale(1));
        worst = std::max(worst, std::abs(facet::fresnelAverageDielectric(eta) - ref));
    }
    for (double eta : {0.05, 0.14, 0.43, 1.0, 1.38, 3.0, 20.0})
        for (double k : {0.0, 0.01, 0.5, 1.914, 3.697, 10.0, 100.0}) {
            auto r = fresnelOnly("conductor", {{"eta", eta}, {"k", k}});
            double ref = referenceAverage(r);
            INFO("conductor eta=", eta, " k=", k, " reference ", ref);
            CHECK(facet::fresnelAverageConductor(eta, k) == doctest::Approx(ref).epsilon(1e-7).scale(1));
            CHECK(facet::fresnelAverage(r, 0) == doctest::Approx(ref).epsilon(1e-7).scale(1));
            worst = std::max(worst, std::abs(facet::fresnelAverageConductor(eta, k) - ref));
        }
    MESSAGE("F_avg quadrature vs Simpson: max |difference| = ", worst);
    // Glass: the hemispherical reflectance of n = 1.5 is 0.0918 (a textbook value).
    CHECK(facet::fresnelAverageDielectric(1.5) == doctest::Approx(0.0918).epsilon(2e-3));
    // k = 0 conductor = dielectric.
    CHECK(facet::fresnelAverageConductor(1.5, 0) == doctest::Approx(facet::fresnelAverageDielectric(1.5)).epsilon(1e-12));
    // Long double interpreter agrees.
    facet::ResolvedMaterial<long double> rl = fresnelOnly<long double>("conductor", {});
    rl.fresnelArgs.value[0] = {0.14L, 0.43L, 1.38L};
    rl.fresnelArgs.value[1] = {3.697L, 2.455L, 1.914L};
    rl.fresnelArgs.given = {true, true};
    CHECK(double(facet::fresnelAverage(rl, 2)) == doctest::Approx(facet::fresnelAverageConductor(1.38, 1.914)).epsilon(1e-12));
}

TEST_CASE("dielectric reciprocity: 1 - F_avg(1/eta) = eta^2 (1 - F_avg(eta))") {
    for (double eta : {1.1, 1.33, 1.5, 2.0, 4.0}) {
        double inside = facet::fresnelAverageDielectric(1 / eta), outside = facet::fresnelAverageDielectric(eta);
        INFO("eta=", eta);
        CHECK(1 - inside == doctest::Approx((1 - outside) / (eta * eta)).epsilon(1e-9));
    }
}

TEST_CASE("F_avg tables for per-lane eta and k: accuracy") {
    const facet::FresnelAverageTables& t = facet::fresnelAverageTables();
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    // Dielectric: eta log-uniform in [1e-3, 1e3], plus the physical range [1, 3].
    double worstD = 0, worstDPhys = 0;
    for (int i = 0; i < 4000; ++i) {
        double eta = std::pow(10.0, -3 + 6 * u(rng));
        double err = std::abs(t.dielectricAt(eta) - facet::fresnelAverageDielectric(eta));
        worstD = std::max(worstD, err);
        double e2 = 1 + 2 * u(rng);
        worstDPhys = std::max(worstDPhys, std::abs(t.dielectricAt(e2) - facet::fresnelAverageDielectric(e2)));
    }
    // Conductor: metals (eta in [0.01, 10], k in [0.5, 10]), weakly absorbing (k < 0.5, near the
    // total-internal-reflection kink at eta = 1, k = 0), and log-uniform over [1e-3, 1e3]^2.
    double worstMetal = 0, worstWeak = 0, worstC = 0;
    for (int i = 0; i < 3000; ++i) {
        double eta = 0.01 + 9.99 * u(rng), k = 0.5 + 9.5 * u(rng);
        worstMetal = std::max(worstMetal, std::abs(t.conductorAt(eta, k) - facet::fresnelAverageConductor(eta, k)));
        double e1 = 0.01 + 9.99 * u(rng), k1 = 0.5 * u(rng);
        worstWeak = std::max(worstWeak, std::abs(t.conductorAt(e1, k1) - facet::fresnelAverageConductor(e1, k1)));
        double e2 = std::pow(10.0, -3 + 6 * u(rng)), k2 = std::pow(10.0, -3 + 6 * u(rng));
        worstC = std::max(worstC, std::abs(t.conductorAt(e2, k2) - facet::fresnelAverageConductor(e2, k2)));
    }
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "F_avg tables, max |table - quadrature|: dielectric (%d nodes) %.2e for eta in [1, 3], %.2e over "
                  "[1e-3, 1e3]; conductor (%d^2 nodes) %.2e for metals (eta in [0.01, 10], k in [0.5, 10]), %.2e "
                  "for k < 0.5, %.2e over [1e-3, 1e3]^2",
                  facet::FresnelAverageTables::kDielectricCount, worstDPhys, worstD,
                  facet::FresnelAverageTables::kConductorCount, worstMetal, worstWeak, worstC);
    MESSAGE(buf);
    CHECK(worstDPhys < 5e-6);
    CHECK(worstD < 5e-6);
    CHECK(worstMetal < 1e-4);
    CHECK(worstWeak < 1.5e-3);
    CHECK(worstC < 5e-3);
    // Limits.
    CHECK(t.dielectricAt(1.0) == doctest::Approx(0).scale(1).epsilon(1e-7));
    CHECK(t.conductorAt(1e30, 0) == doctest::Approx(1).epsilon(1e-6));
}

// Near eta = 1 F_avg ~ (2/3) s, s = (eta - 1)/(eta + 1), and the
// integrand F(mu) mu peaks at mu ~ sqrt(eta^2 - 1): the quadrature must
// resolve that peak, and the table must be accurate relative to F_avg
// itself (kulla_conty's Fresnel term is ~F_avg^2). Simpson in sqrt(mu)
// resolves it (checked against an independent tanh-sinh quadrature:
// F_avg / s = 0.666664, 0.666643, 0.666475, 0.665208, 0.656655 at s = 1e-7,
// 1e-6, 1e-5, 1e-4, 1e-3).
TEST_CASE("dielectric near eta = 1: relative to F_avg itself") {
    const facet::FresnelAverageTables& t = facet::fresnelAverageTables();
    const double expected[] = {0.6666638263802097, 0.6666428689220888, 0.6664747367322303, 0.665207548202776,
                               0.6566553400710399};
    int i = 0;
    for (double s : {1e-7, 1e-6, 1e-5, 1e-4, 1e-3}) {
        double eta = (1 + s) / (1 - s);
        auto r = fresnelOnly("dielectric", {{"eta", eta}});
        INFO("s=", s, " eta=", eta);
        CHECK(referenceAverage(r) / s == doctest::Approx(expected[i]).epsilon(1e-6));
        CHECK(facet::fresnelAverageDielectric(eta) / s == doctest::Approx(expected[i]).epsilon(1e-8));
        CHECK(facet::fresnelAverage(r, 0) / s == doctest::Approx(expected[i]).epsilon(1e-8));
        CHECK(t.dielectricAt(eta) / s == doctest::Approx(expected[i]).epsilon(1e-5));
        // Below 1, by reciprocity: 1 - F_avg(1/eta) = eta^2 (1 - F_avg(eta)).
        double inside = facet::fresnelAverageDielectric(1 / eta);
        CHECK(t.dielectricAt(1 / eta) == doctest::Approx(inside).epsilon(1e-6));
        ++i;
    }
}

}  // TEST_SUITE
