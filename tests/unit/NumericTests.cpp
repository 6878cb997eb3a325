// The neutral numerical library (compiler/numeric) against integrations
// written here: the Gaussian NDF's normalization and its table, the
// slope-form Student-t tail and normalization (closed forms where nu is 1,
// 2 or 3, Simpson's rule elsewhere). (The
// Fresnel averages are checked in tests/energy, against a Simpson rule over
// the catalog's Fresnel terms.)
#include "QuadMath.h"

#include "GaussianNormalization.h"
#include "StudentT.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

namespace {

// N(alpha) = pi Int_0^{pi/2} exp(-t^2/alpha^2) sin 2t dt by composite
// Simpson in long double (not the library's Gauss-Legendre panels).
// Int_lo^hi f by composite Simpson in long double.
template <typename F>
long double simpson(const F& f, long double lo, long double hi, int intervals) {
    long double h = (hi - lo) / intervals, sum = f(lo) + f(hi);
    for (int i = 1; i < intervals; ++i) sum += f(lo + i * h) * (i % 2 ? 4 : 2);
    return sum * h / 3;
}

// Int_x^inf (1 + q^2)^(-(nu+1)/2) dq = Int_{atan x}^{pi/2} cos^(nu-1) psi dpsi,
// over the part of the interval where the integrand is above e^-1800.
long double simpsonStudentTail(long double nu, long double x) {
    const long double halfPi = 1.570796326794896619231321691639751442L;
    long double lo = std::atan(x), hi = std::min(halfPi, lo + 60 / std::sqrt(nu + 1));
    // cos^(nu-1) from sin^2: pow(cos psi, nu - 1) would amplify the rounding
    // of cos psi by nu.
    auto f = [&](long double psi) {
        long double s = std::sin(psi);
        return std::exp((nu - 1) / 2 * std::log1p(-s * s));
    };
    return simpson(f, lo, hi, 50000);
}

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

TEST_CASE("Gamma(a + 1/2) / Gamma(a) in every reference type") {
    const __float128 pi = M_PIq;
    // Closed values R(1/2) = 1/sqrt(pi), R(1) = sqrt(pi)/2, and R(a + 1) = R(a) (a + 1/2)/a
    // up to a = 150.5 and 151.
    __float128 half = 1 / sqrtq(pi), whole = sqrtq(pi) / 2;
    CHECK(std::fabs(double(facet::gammaHalfRatio<__float128>(0.5Q) / half - 1)) < 1e-32);
    CHECK(std::fabs(double(facet::gammaHalfRatio<__float128>(1.0Q) / whole - 1)) < 1e-32);
    for (int k = 0; k < 150; ++k) {
        half *= (k + 1.0Q) / (k + 0.5Q);
        whole *= (k + 1.5Q) / (k + 1.0Q);
    }
    CHECK(std::fabs(double(facet::gammaHalfRatio<__float128>(150.5Q) / half - 1)) < 1e-30);
    CHECK(std::fabs(double(facet::gammaHalfRatio<__float128>(151.0Q) / whole - 1)) < 1e-30);
    // Large a: sqrt(a) (1 - 1/(8a) + 1/(128 a^2) + O(a^-3)).
    __float128 big = 1e8Q;
    __float128 series = sqrtq(big) * (1 - 1 / (8 * big) + 1 / (128 * big * big));
    CHECK(std::fabs(double(facet::gammaHalfRatio<__float128>(big) / series - 1)) < 1e-25);
    // double and long double against __float128.
    for (double a : {1e-3, 0.7, 3.3, 39.9, 40.0, 150.5, 1e6, 1e8}) {
        CAPTURE(a);
        __float128 q = facet::gammaHalfRatio<__float128>(a);
        CHECK(std::fabs(double(facet::gammaHalfRatio<double>(a) / q - 1)) < 4e-15);
        CHECK(std::fabs(double(facet::gammaHalfRatio<long double>(a) / q - 1)) < 2e-18);
    }
}

TEST_CASE("the slope-form Student-t tail matches closed forms and quadrature") {
    // x = tan psi: s2 = sin^2 psi, c2 = cos^2 psi.
    auto tail = [](auto nu, auto x) {
        using Real = decltype(nu);
        Real c2 = 1 / (1 + x * x), s2 = x * x * c2;
        return facet::studentSlopeTail<Real>(nu, s2, c2);
    };
    const __float128 pi = M_PIq;
    for (__float128 x : {0.0Q, 1e-3Q, 0.3Q, 1.0Q, 2.5Q, 40.0Q, 1e6Q}) {
        CAPTURE(double(x));
        // nu = 1 (Cauchy), 2 (GGX alpha = 1), 3, written without cancellation:
        // pi/2 - atan x = atan(1/x), 1 - x/r = 1/(r (r + x)), and for x >= 10
        // atan y - y/(1 + y^2) = sum_k>=1 (-1)^(k+1) 2k/(2k+1) y^(2k+1), y = 1/x.
        __float128 r = sqrtq(1 + x * x), y = 1 / x;
        __float128 t1 = x == 0 ? 0.5Q : atanq(y) / pi;
        __float128 t2 = 1 / (2 * r * (r + x));
        __float128 t3 = (pi / 2 - atanq(x) - x / (1 + x * x)) / pi;
        if (x >= 10) {
            __float128 sum = 0, p = y * y * y;
            for (int k = 1; k <= 40; ++k, p *= -y * y) sum += p * (2 * k) / (2 * k + 1);
            t3 = sum / pi;
        }
        CHECK(std::fabs(double(tail(1.0Q, x) / t1 - 1)) < 1e-30);
        CHECK(std::fabs(double(tail(2.0Q, x) / t2 - 1)) < 1e-30);
        CHECK(std::fabs(double(tail(3.0Q, x) / t3 - 1)) < 1e-30);
        CHECK(tail(2.0, double(x)) == doctest::Approx(double(t2)).epsilon(1e-14));
    }
    CHECK(tail(5.0, 0.0) == 0.5);
    CHECK(facet::studentSlopeTail<double>(7.0, 1.0, 0.0) == 0);  // x = inf
    // Other nu, up to the Blinn-Phong exponent's 2e8 + 2, against Simpson:
    // the tail, and the normalization c_nu = 1 / (2 Int_0^inf (1 + q^2)^(-(nu+1)/2)).
    for (double nu : {2.7, 3.5, 10.0, 52.0, 1e3, 2e4 + 1, 1e6, 2e8 + 2}) {
        double scale = 1 / std::sqrt(nu);  // the width of p_nu
        CAPTURE(nu);
        long double half = simpsonStudentTail(nu, 0);
        CHECK(facet::studentSlopeNorm<double>(nu) == doctest::Approx(double(0.5L / half)).epsilon(1e-12));
        for (double k : {0.05, 0.7, 1.3, 2.0, 5.0}) {
            double x = k * scale;
            CAPTURE(x);
            double expected = double(simpsonStudentTail(nu, x) / (2 * half));
            CHECK(tail(nu, x) == doctest::Approx(expected).epsilon(1e-12));
            CHECK(double(tail((long double)nu, (long double)x)) == doctest::Approx(expected).epsilon(1e-12));
        }
    }
}

}  // TEST_SUITE

namespace {
struct Direction {
    double x, y, z;
};
// Out of line, so that the compiler cannot see the values it rounds.
__attribute__((noinline)) Direction unroundedDirection() { return {-0.67595424627987033, 0.123456789012345, 0.2}; }
}  // namespace

// The shape of code in which GCC 12's SLP vectorizer folded the round trip
// double -> float -> double away (top-level CMakeLists.txt turns it off):
// three conversions side by side, then the floats read back as doubles.
// The reference paths that evaluate at the float direction a kernel
// returns depend on the rounding happening.
TEST_CASE("float round trips: double -> float -> double rounds to float") {
    Direction r = unroundedDirection();
    float w[3];
    w[0] = float(r.x), w[1] = float(r.y), w[2] = float(r.z);
    const double wf[3] = {w[0], w[1], w[2]};
    CHECK(wf[0] == -0x1.5a16acp-1);
    CHECK(wf[0] != r.x);
    CHECK(wf[1] != r.y);
    CHECK(double(float(wf[1])) == wf[1]);
}
