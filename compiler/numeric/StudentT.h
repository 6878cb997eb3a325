// StudentT: the Student-t distribution in slope form, for closed-form
// Smith Lambdas and visible-normal samplers of NDFs whose slopes have the
// density p_nu(x) = c_nu (1 + x^2)^(-(nu+1)/2) (x sqrt(nu) is Student-t with
// nu degrees of freedom; c_nu = Gamma((nu+1)/2) / (sqrt(pi) Gamma(nu/2))).
// The marginal of the Blinn-Phong slope distribution is one (nu = e + 2).
//
// Its upper tail is T(x) = Int_x^inf p_nu = I_z(nu/2, 1/2) / 2 for x >= 0,
// z = 1/(1 + x^2) (the regularized incomplete beta function). The caller
// passes z and 1 - z = x^2/(1 + x^2), each accurate (cos^2 and sin^2 of
// atan x), so that neither cancels. I_z is a continued fraction, on I_z(a,
// b) or 1 - I_{1-z}(b, a), whichever converges fast.
//
// A neutral numerical header, templated over the reference real types
// (include QuadMath.h first for __float128); tests/unit (suite numeric)
// checks it against quadrature.
#pragma once

#include <cmath>
#include <limits>

namespace facet {

// Gamma(a + 1/2) / Gamma(a), a > 0: shifted up to a >= 40 by R(a) = R(a +
// 1) a / (a + 1/2), then Stirling's series of ln Gamma(a + 1/2) - ln
// Gamma(a) (twelve Bernoulli terms: below 1e-35 at a = 40). a log1p(1/(2a))
// - 1/2 keeps its absolute accuracy for a up to 1e8 and beyond.
template <typename Real>
Real gammaHalfRatio(Real a) {
    using std::exp; using std::log; using std::log1p; using std::pow;
    Real scale = 1;
    while (a < 40) {
        scale *= a / (a + Real(0.5));
        a += 1;
    }
    // B_2k / (2k (2k - 1)), k = 1..12.
    static const Real coef[12] = {Real(1) / 12,          Real(-1) / 360,         Real(1) / 1260,
                                  Real(-1) / 1680,       Real(1) / 1188,         Real(-691) / 360360,
                                  Real(1) / 156,         Real(-3617) / 122400,   Real(43867) / 244188,
                                  Real(-174611) / 125400, Real(77683) / 5796,    Real(-236364091) / 1506960};
    Real b = a + Real(0.5);
    Real lnR = log(a) / 2 + (a * log1p(1 / (2 * a)) - Real(0.5));
    Real ia = 1 / a, ib = 1 / b, ia2 = ia * ia, ib2 = ib * ib;
    Real pa = ia, pb = ib;  // a^(1-2k), b^(1-2k)
    for (int k = 0; k < 12; ++k) {
        lnR += coef[k] * (pb - pa);
        pa *= ia2, pb *= ib2;
    }
    return scale * exp(lnR);
}

// The normalization c_nu of p_nu, nu > 0. The last two values per thread
// are kept: a sampler and its pdf ask for the same one or two nu per call.
template <typename Real>
Real studentSlopeNorm(Real nu) {
    using std::atan; using std::sqrt;
    static const Real rootPi = sqrt(4 * atan(Real(1)));  // to the precision of Real, __float128 included
    thread_local Real memoNu[2] = {-1, -1}, memoNorm[2] = {0, 0};
    thread_local int next = 0;
    for (int i = 0; i < 2; ++i)
        if (memoNu[i] == nu) return memoNorm[i];
    Real norm = gammaHalfRatio(nu / 2) / rootPi;
    memoNu[next] = nu, memoNorm[next] = norm;
    next ^= 1;
    return norm;
}

// The continued fraction of I_z(a, b) = z^a (1 - z)^b / (a B(a, b)) / g,
// g = 1 + d1/(1 + d2/(1 + ...)) (Abramowitz & Stegun 26.5.8), given z and
// w = 1 - z; converges fast for z < (a + 1) / (a + b + 2). In its odd
// contraction g = B0 + A1/(B1 + A2/(B2 + ...)), B_m = 1 + d_2m + d_2m+1 =
// w + z beta_m with beta_m > 0 formed without cancellation, A_m = -d_2m-1
// d_2m: the plain fraction's 1 + d_2m+1 ~ 1 - z would lose digits where z
// is near 1 (a large, the slope a few widths of p_nu out). Modified Lentz.
template <typename Real>
Real betaContinuedFraction(Real a, Real b, Real z, Real w) {
    using std::fabs;
    const Real tiny = std::numeric_limits<Real>::min() / std::numeric_limits<Real>::epsilon();
    const Real eps = std::numeric_limits<Real>::epsilon();
    auto guard = [&](Real v) { return fabs(v) < tiny ? tiny : v; };
    // d_2m+1 = -(a + m)(a + b + m) z / ((a + 2m)(a + 2m + 1)), d_2m = m (b - m) z / ((a + 2m - 1)(a + 2m)).
    auto dOdd = [&](Real m) { return -(a + m) * (a + b + m) * z / ((a + 2 * m) * (a + 2 * m + 1)); };
    auto dEven = [&](Real m) { return m * (b - m) * z / ((a + 2 * m - 1) * (a + 2 * m)); };
    // B_m = w + z (1 + d_2m / z + d_2m+1 / z), with 1 + d_2m+1 / z summed exactly:
    // (a + 2m)(a + 2m + 1) - (a + m)(a + b + m) = a (2m + 1 - b) + m (3m + 2 - b).
    auto B = [&](Real m) {
        Real beta = (a * (2 * m + 1 - b) + m * (3 * m + 2 - b)) / ((a + 2 * m) * (a + 2 * m + 1));
        if (m > 0) beta += m * (b - m) / ((a + 2 * m - 1) * (a + 2 * m));
        return w + z * beta;
    };
    Real f = guard(B(0)), c = f, d = 0;
    for (int m = 1; m <= 2000; ++m) {
        Real A = -dOdd(Real(m - 1)) * dEven(Real(m)), Bm = B(Real(m));
        d = 1 / guard(Bm + A * d);
        c = guard(Bm + A / c);
        Real del = c * d;
        f *= del;
        if (fabs(del - 1) <= eps) break;
    }
    return 1 / f;
}

// Where the tail switches from 1 - I_{1-z}(1/2, a) to I_z(a, 1/2): at x^2 nu
// = 3.5^2 (x 3.5 widths of p_nu out), where both fractions take at most
// 20 steps to converge in double for every nu >= 2 (33 for nu = 1); the
// first form's 1 - (1 - 2T) keeps T's absolute accuracy.
inline constexpr double kStudentSwitch = 12.25;

// The upper tail T(x) = Int_x^inf p_nu of p_nu at x >= 0, from s2 =
// x^2/(1 + x^2) and c2 = 1/(1 + x^2) (s2 + c2 = 1); nu > 0. T(0) = 1/2,
// T(inf) = 0 (c2 = 0).
template <typename Real>
Real studentSlopeTail(Real nu, Real s2, Real c2) {
    using std::exp; using std::log; using std::log1p; using std::sqrt;
    if (!(c2 > 0)) return 0;
    const Real a = nu / 2, b = Real(0.5);
    // z^a (1 - z)^b / B(a, b), z = c2; 1 / B(a, 1/2) = c_nu.
    Real logZ = s2 < Real(0.5) ? log1p(-s2) : log(c2);
    Real front = exp(a * logZ) * sqrt(s2) * studentSlopeNorm(nu);
    if (s2 * nu >= kStudentSwitch * c2) return front * betaContinuedFraction(a, b, c2, s2) / (2 * a);
    return (1 - front * betaContinuedFraction(b, a, s2, c2) / b) / 2;
}

}  // namespace facet
