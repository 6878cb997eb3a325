// The neutral numerical library (compiler/numeric) against integrations
// written here: the Gaussian NDF's normalization and its table. (The
// Fresnel averages are checked in tests/energy, against a Simpson rule over
// the catalog's Fresnel terms.)
#include "GaussianNormalization.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

namespace {

// N(alpha) = pi Int_0^{pi/2} exp(-t^2/alpha^2) sin 2t dt by composite
// Simpson in long double (not the library's Gauss-Legendre panels).
long double simpsonNorm(long double alpha, int intervals) {
    const long double pi = 3.141592653589793238462643383279502884L, b = pi / 2;
    auto f = [&](long double t) { return std::exp(-t * t / (alpha * alpha)) * std::sin(2 * t); };
    long double h = b / intervals, sum = f(0) + f(b);
    for (int i = 1; i < intervals; ++i) sum += f(i * h) * (i % 2 ? 4 : 2);
    return pi * sum * h / 3;
}

}  // namespace

TEST_SUITE("numeric") {

TEST_CASE("the Gaussian normalization matches an independent integration") {
    for (double alpha : {1e-3, 0.01, 0.1, 0.3, 0.5, 1.0, 3.0, 100.0}) {
        CAPTURE(alpha);
        double expected = double(simpsonNorm(alpha, 400000));
        CHECK(facet::gaussianNdfNorm<double>(alpha) == doctest::Approx(expected).epsilon(1e-11));
        CHECK(double(facet::gaussianNdfNorm<long double>(alpha)) == doctest::Approx(expected).epsilon(1e-11));
    }
    // Small alpha: the integrand lives near t = 0, where sin 2t ~ 2t, so
    // N -> 2 pi Int_0^inf exp(-t^2/alpha^2) t dt = pi alpha^2 (1 - 2 alpha^2/3 + ...).
    for (double alpha : {1e-4, 1e-3}) {
        double limit = M_PI * alpha * alpha * (1 - 2 * alpha * alpha / 3);
        CHECK(facet::gaussianNdfNorm<double>(alpha) == doctest::Approx(limit).epsilon(1e-9));
    }
    // Large alpha: exp(..) -> 1 and N -> pi Int_0^{pi/2} sin 2t dt = pi.
    CHECK(facet::gaussianNdfNorm<double>(1e4) == doctest::Approx(M_PI).epsilon(1e-7));
}

TEST_CASE("the Gaussian normalization table interpolates within 2e-8") {
    const facet::GaussianNormTable& table = facet::gaussianNormTable();
    REQUIRE(table.q.size() == size_t(facet::GaussianNormTable::kSize));
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> logAlpha(std::log(1e-4), std::log(1e4));
    double worst = 0;
    for (int i = 0; i < 2000; ++i) {
        double alpha = std::exp(logAlpha(rng));
        double exact = facet::gaussianNdfNorm<double>(alpha);
        worst = std::max(worst, std::abs(table.interpolate(alpha) / exact - 1));
    }
    CHECK(worst < 2e-8);
    CHECK(worst > 0);  // an interpolation, not a copy of the nodes
    // Outside the table the end values hold.
    CHECK(table.interpolate(1e-6) == doctest::Approx(std::exp(table.q.front())).epsilon(1e-12));
}

}  // TEST_SUITE
