// GaussianNorm: the normalization of the Gaussian NDF,
// N(alpha) = 2 pi Int_0^{pi/2} exp(-t^2/alpha^2) cos t sin t dt, by quadrature
// (instantiated for double, long double and __float128).
#pragma once

namespace facet {

template <typename Real>
Real gaussianNdfNorm(Real alpha);

}  // namespace facet
