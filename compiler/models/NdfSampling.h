// NdfSampling: helpers the NDF entries' reference samplers share (SPEC 8):
// normals from slopes or polar angles, the radial slope sampling of
// shape-invariant NDFs stretched by (alpha_x, alpha_y), and a safeguarded
// Newton inversion of a monotone CDF for samplers without a closed form.
// Templates over the reference real types; include QuadMath.h before this
// header where they are instantiated for __float128.
#pragma once

#include "models/ModelMath.h"

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
// with derivative pdf: Newton steps, falling back to bisection whenever a
// step leaves the bracket; stops at the resolution of Real.
template <typename Real, typename Cdf, typename Pdf>
Real invertIncreasing(const Cdf& cdf, const Pdf& pdf, Real target, Real lo, Real hi) {
    using std::fabs;
    Real x = (lo + hi) / 2;
    for (int it = 0; it < 200; ++it) {
        Real f = cdf(x) - target;
        if (f == 0) return x;
        if (f > 0) hi = x;
        else lo = x;
        Real d = pdf(x);
        Real next = d > 0 ? x - f / d : (lo + hi) / 2;
        if (!(next > lo && next < hi)) next = (lo + hi) / 2;
        if (next == x || hi - lo <= std::numeric_limits<Real>::epsilon() * (fabs(lo) + fabs(hi))) return next;
        x = next;
    }
    return x;
}

}  // namespace facet::models
