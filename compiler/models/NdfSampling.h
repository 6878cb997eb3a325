// NdfSampling: helpers the NDF entries' reference samplers share (SPEC 8):
// normals from slopes or polar angles, the radial slope sampling of
// shape-invariant NDFs stretched by (alpha_x, alpha_y), and a safeguarded
// Newton inversion of a monotone CDF for samplers without a closed form.
// Templates over the reference real types; include QuadMath.h before this
// header where they are instantiated for __float128.
#pragma once

#include "models/ModelMath.h"

#include "StudentT.h"

#include <cmath>
#include <limits>

namespace facet::models {

// The unit normal of the microfacet with slopes (sx, sy): (-sx, -sy, 1) / |.|.
template <typename Real>
Vec3<Real> normalFromSlopes(Real sx, Real sy) {
    using std::sqrt;
    Real inv = 1 / sqrt(1 + sx * sx + sy * sy);
    return {-sx * inv, -sy * inv, inv};
}

// The unit normal at polar angle theta (given sin^2 theta, so that small
// angles keep their relative accuracy) and azimuth 2 pi u.
template <typename Real>
Vec3<Real> normalFromPolar(Real sin2, Real u) {
    using std::cos; using std::sin; using std::sqrt;
    Real s = sqrt(sin2 < 1 ? sin2 : Real(1)), c = sqrt(sin2 < 1 ? 1 - sin2 : Real(0));
    Real phi = 2 * kPi<Real> * u;
    return {s * cos(phi), s * sin(phi), c};
}

// NDF sampling of a shape-invariant NDF (Heitz 2014): the slopes of the
// standard (alpha = 1) profile have squared radius r2 (drawn by the entry
// from the radial CDF of its profile) and a uniform azimuth 2 pi u; the
// stretch by (alpha_x, alpha_y) gives the anisotropic NDF, whose m then has
// density D(m) (n.m).
template <typename Real>
Vec3<Real> stretchedSlopeNormal(Real ax, Real ay, Real r2, Real u) {
    using std::cos; using std::sin; using std::sqrt;
    Real r = sqrt(r2), phi = 2 * kPi<Real> * u;
    return normalFromSlopes(ax * r * cos(phi), ay * r * sin(phi));
}

// x in [lo, hi] with cdf(x) = target, for a cdf increasing on [lo, hi]
// with derivative pdf: Newton steps from `start` (by default the middle),
// falling back to bisection whenever a step leaves the bracket or is more
// than half the step before the last (on a strongly curved cdf, such as a
// log cdf against log x, Newton's steps can otherwise cycle between the
// two ends of the bracket); stops at the resolution of Real.
template <typename Real, typename Cdf, typename Pdf>
Real invertIncreasing(const Cdf& cdf, const Pdf& pdf, Real target, Real lo, Real hi,
                      Real start = std::numeric_limits<Real>::quiet_NaN()) {
    using std::fabs;
    Real x = start >= lo && start <= hi ? start : (lo + hi) / 2, step = hi - lo, stepBefore = hi - lo;
    for (int it = 0; it < 200; ++it) {
        Real f = cdf(x) - target;
        if (f == 0) return x;
        if (f > 0) hi = x;
        else lo = x;
        Real d = pdf(x);
        Real next = d > 0 ? x - f / d : (lo + hi) / 2;
        if (!(next > lo && next < hi) || 2 * fabs(next - x) > fabs(stepBefore)) next = (lo + hi) / 2;
        stepBefore = step;
        step = next - x;
        if (next == x || hi - lo <= std::numeric_limits<Real>::epsilon() * (fabs(lo) + fabs(hi))) return next;
        x = next;
    }
    return x;
}

// Legendre's continued fraction of the upper incomplete gamma function,
// Gamma(a, y) = y^a e^-y h with h = 1/(y + 1 - a - 1 (1 - a)/(y + 3 - a -
// 2 (2 - a)/(y + 5 - a - ...))), by the modified Lentz method to the
// resolution of Real: h for y > 0 and any real a, converging in a few
// dozen levels once y is a little above a + 1.
template <typename Real>
Real upperGammaFraction(Real a, Real y) {
    using std::fabs;
    const Real eps = std::numeric_limits<Real>::epsilon();
    const Real tiny = std::numeric_limits<Real>::min() / eps;
    Real b = y + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 5000; ++i) {
        Real an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        Real step = d * c;
        h *= step;
        if (fabs(step - 1) <= eps) break;
    }
    return h;
}

// ---- the Student-t slope distribution ----------------------------------------
//
// P22(x, y) = (nu/(2 pi)) (1 + x^2 + y^2)^(-(nu + 2)/2), nu > 1, whose
// marginal is the slope-form Student-t p_nu (numeric/StudentT.h): the slopes
// of blinn_phong (nu = e + 2) and, stretched by sqrt(gamma - 1) alpha, of
// student_t (nu = 2 gamma - 2). Its Smith Lambda and visible normals
// (Heitz & d'Eon 2014), for unit directions in the unstretched frame.

// sqrt(s2)^p for s2 + c2 = 1 (sin^p from sin^2 and cos^2): through
// log1p(-c2) where c2 is small, so that a large p keeps its accuracy.
template <typename Real>
Real powSin(Real s2, Real c2, Real p) {
    using std::exp; using std::log; using std::log1p;
    if (p == 0) return 1;
    if (!(s2 > 0)) return 0;
    return exp(p / 2 * (c2 < Real(0.5) ? log1p(-c2) : log(s2)));
}

// The exact (n.v) Lambda(v) of P22: with (1 + mu^2)^(-1/2) = sin theta and
// Int_mu^inf q p_nu(q) dq = c_nu (1 + mu^2)^(-(nu-1)/2) / (nu - 1),
// (n.v) Lambda = c_nu sin^nu theta / (nu - 1) - cos theta T_nu(mu), T_nu
// the tail of p_nu at mu = cot theta (nu = 2 gives GGX's at alpha = 1).
template <typename Real>
Real studentSlopeCosLambda(Real nu, const Vec3<Real>& v) {
    Real s2 = v.x * v.x + v.y * v.y, c2 = v.z * v.z;
    if (s2 == 0) return 0;  // v = n: nothing is masked
    Real cl = studentSlopeNorm(nu) * powSin(s2, c2, nu) / (nu - 1) - v.z * studentSlopeTail(nu, c2, s2);
    return cl > 0 ? cl : Real(0);
}

// The visible slope angle's floor above the horizon, in the co-angle b
// below: for nu < 2 the quantiles of b near u = 0 go like u^(1/(nu - 1)),
// beyond double's range as nu nears 1. A normal within 1e-20 of the horizon
// reflects every wo with n.wo > 1e-19 below it, so the floor moves no
// sample's direction; it keeps m.z, D(m) and the pdf finite in float.
inline constexpr double kVisibleSlopeAngleFloor = 1e-20;

// A visible normal of P22 for the unit wo. In the frame turned about n so
// that wo' = (sin t, 0, cos t), the visible slopes (x, y) have the density
// (1 - x tan t)+ P22(x, y) up to a constant. With x = tan psi = -cot b, b =
// psi + pi/2 the slope angle's co-angle (from the horizon, so that normals
// near it keep their relative accuracy), cos t times the CDF of b is
//   G(b) = cos t F(-cot b) + sin t c_nu sin^(nu-1) b / (nu - 1),
// F = 1 - T_nu, with G' = c_nu sin^(nu-2) b (cos t sin b + sin t cos b) on
// (0, pi - t], and G(pi - t) = cos t + (n.wo) Lambda(wo). G ~ b^(nu-1)
// near 0 (b^nu at t = 0): b is found by Newton's method on log G against
// log b, where the function is nearly linear. Given x, y = sqrt(1 + x^2)
// tan chi, where tan chi has the density p_(nu+1) (from (1 + x^2 + y^2) =
// (1 + x^2)(1 + tan^2 chi)), found by Newton's method on its tail. The
// normal of the slopes (x, y) is (cos b cos chi, -sin chi, sin b cos chi),
// turned back.
template <typename Real>
Vec3<Real> studentSlopeVisibleNormal(Real nu, const Vec3<Real>& wo, Real u1, Real u2) {
    using std::atan2; using std::cos; using std::exp; using std::log; using std::sin; using std::sqrt;
    const Real halfPi = kPi<Real> / 2;
    Real sxy = sqrt(wo.x * wo.x + wo.y * wo.y);
    Real cosPhi = sxy > 0 ? wo.x / sxy : Real(1), sinPhi = sxy > 0 ? wo.y / sxy : Real(0);
    Real norm = studentSlopeNorm(nu);
    auto cdf = [&](Real b) {
        Real s = sin(b), c = cos(b), s2 = s * s, c2 = c * c;
        Real tail = studentSlopeTail(nu, c2, s2);  // at |x| = |cot b|
        Real F = b >= halfPi ? 1 - tail : tail;
        return wo.z * F + sxy * norm * powSin(s2, c2, nu - 1) / (nu - 1);
    };
    auto density = [&](Real b) {
        Real s = sin(b), c = cos(b);
        Real d = wo.z * s + sxy * c;
        return d > 0 ? norm * powSin(s * s, c * c, nu - 2) * d : Real(0);
    };
    // log G(e^y) and its derivative e^y G'/G: NaN where G underflows, which
    // the inversion answers with a bisection.
    auto logCdf = [&](Real y) { return log(cdf(exp(y))); };
    auto logDensity = [&](Real y) {
        Real b = exp(y);
        return b * density(b) / cdf(b);
    };
    Real bMax = halfPi + atan2(wo.z, sxy);
    // Quantiles below 2^-32 (u = 0 in float) are taken at 2^-32: the
    // limit u = 0 is the horizon, where the CDF underflows for large nu.
    const Real floorU = Real(0x1p-32);
    Real target = (u1 > floorU ? u1 : floorU) * cdf(bMax);
    Real b = exp(invertIncreasing(logCdf, logDensity, log(target), log(Real(kVisibleSlopeAngleFloor)), log(bMax)));
    // tan chi from its tail q = min(u2, 1 - u2), the sign from the side.
    Real nuY = nu + 1, normY = studentSlopeNorm(nuY), q = u2 < Real(0.5) ? u2 : 1 - u2;
    auto minusTail = [&](Real chi) {
        Real s = sin(chi), c = cos(chi);
        return -studentSlopeTail(nuY, s * s, c * c);
    };
    auto pdfChi = [&](Real chi) {
        Real s = sin(chi), c = cos(chi);
        return normY * powSin(c * c, s * s, nuY - 1);
    };
    Real chi = invertIncreasing(minusTail, pdfChi, -(q > floorU ? q : floorU), Real(0), halfPi);
    if (u2 < Real(0.5)) chi = -chi;
    Real mx = cos(b) * cos(chi), my = -sin(chi), mz = sin(b) * cos(chi);
    return {cosPhi * mx - sinPhi * my, sinPhi * mx + cosPhi * my, mz};
}

}  // namespace facet::models
