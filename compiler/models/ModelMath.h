// ModelMath: small helpers the reference formulas of several entries share
// (pi in any real type, squares, the Smith projection, the Beckmann Lambda
// that shape-invariant NDFs built on the Beckmann profile reuse).
//
// Include QuadMath.h before this header in a file that instantiates the
// formulas for __float128.
#pragma once

#include "Diagnostics.h"
#include "models/ModelCatalog.h"

#include <cmath>

namespace facet::models {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

template <typename Real>
Real sq(Real x) { return x * x; }

// alpha(v)^2 sin^2(theta_v) = (vx ax)^2 + (vy ay)^2: the Smith argument of a
// shape-invariant NDF (a = n.v / sqrt of it).
template <typename Real>
Real smithProjection(Real ax, Real ay, const Vec3<Real>& v) {
    return sq(v.x * ax) + sq(v.y * ay);
}

// (n.v) Lambda(v) of the Beckmann profile for proj = smithProjection > 0.
// Walter et al. 2007: Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)),
// a = cot(theta_v) / alpha_v = vz / s, s = sqrt(proj), written with erfc so
// that it does not cancel for large a; times vz, using vz / a = s.
template <typename Real>
Real beckmannCosLambda(Real proj, Real vz) {
    using std::erfc; using std::exp; using std::sqrt;
    Real s = sqrt(proj), a = vz / s;
    return (s * exp(-a * a) / sqrt(kPi<Real>) - vz * erfc(a)) / 2;
}

// The alpha canonical parameters of an NDF written ndf(alpha) or
// ndf(alpha_x, alpha_y) (ggx, beckmann, ward): indices 0 and 1.
constexpr int kAlphaX = 0, kAlphaY = 1;
// Such an entry with its parameters, forms, roughness hooks and examples
// (isotropic and 10:1 anisotropic) filled in.
NdfEntry alphaXYNdf(int id, const char* name, const char* summary);

}  // namespace facet::models
