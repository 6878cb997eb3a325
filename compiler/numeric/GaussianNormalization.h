// GaussianNormalization: the normalization of the Gaussian NDF,
// N(alpha) = 2 pi Int_0^{pi/2} exp(-t^2/alpha^2) cos t sin t dt, by
// quadrature, and the table of ln N over ln alpha that kernels with a
// per-lane alpha interpolate.
//
// A neutral numerical library: the interpreter's Gaussian NDF
// (models/ndf/Gaussian.cpp) and its emitter (GaussianEmitter.cpp) both take
// N from here; tests/unit (suite numeric) checks it against an independent
// integration.
#pragma once

#include <vector>

namespace facet {

// Instantiated for double, long double and __float128.
template <typename Real>
Real gaussianNdfNorm(Real alpha);

// q[i] = ln N(e^x_i), x_i uniform over [kX0, kX1] = [ln 1e-4, ln 1e4].
// Cubic (4-point Lagrange) interpolation keeps the relative error of N
// below 2e-8 (1.1e-8 measured over 2000 random alphas, tests/unit).
// Immutable, built on first use.
struct GaussianNormTable {
    static constexpr int kSize = 1024;
    static constexpr double kX0 = -9.210340371976184;  // ln 1e-4
    static constexpr double kX1 = 9.210340371976184;   // ln 1e4
    std::vector<double> q;
    // N(alpha) by the interpolation a kernel performs (alphas outside the
    // table take its end values).
    double interpolate(double alpha) const;
};
const GaussianNormTable& gaussianNormTable();

}  // namespace facet
