// Quadrature: the Gauss-Legendre rules and panel integration shared by the
// compiler's integrals: the Kulla-Conty albedo tables and Fresnel averages
// (KullaConty.cpp, KullaContyEval.h), the Gaussian NDF normalization
// (Interpreter.cpp) and the quadrature checks of `facet verify`
// (PhysicsChecks.cpp). tests/physics and tests/energy keep their own
// quadrature on purpose: they check these integrals independently.
//
// An integral is a sum of panels, each integrated with one n-point rule:
// the panels lie between consecutive break points (gradedBreaks makes them
// narrow near peaks and kinks of the integrand), or are n equal panels.
// Nodes, weights and sums are in Real, so that the interpreter's long double
// and __float128 instantiations integrate at their own precision; the
// templates below use arithmetic only (no std math), so any Real works here.
#pragma once

#include <cstddef>
#include <vector>

namespace facet::quadrature {

// An n-point Gauss-Legendre rule on [-1, 1].
template <typename Real>
struct GaussLegendre {
    std::vector<Real> x, w;  // nodes, weights
};

// The n-point rule, 1 <= n <= 64: Newton's method on P_n in Real, built on
// first use and kept (thread-safe). Instantiated for double, long double
// and __float128.
template <typename Real>
const GaussLegendre<Real>& gaussLegendre(int n);

// The rule on one panel given by its midpoint and half-width.
template <typename Real, typename F>
Real panel(const F& f, Real mid, Real half, const GaussLegendre<Real>& g) {
    Real s = 0;
    for (std::size_t i = 0; i < g.x.size(); ++i) s += g.w[i] * f(mid + half * g.x[i]);
    return s * half;
}

// Sum over the panels between consecutive break points (empty or reversed
// panels are skipped). Break points may be of another type (double) than Real.
template <typename Real, typename F, typename Break>
Real integratePanels(const F& f, const std::vector<Break>& breaks, const GaussLegendre<Real>& g) {
    Real sum = 0;
    for (std::size_t p = 0; p + 1 < breaks.size(); ++p) {
        Real a = Real(breaks[p]), b = Real(breaks[p + 1]);
        if (!(b > a)) continue;
        sum += panel(f, (a + b) / 2, (b - a) / 2, g);
    }
    return sum;
}

// `panels` equal panels on [a, b].
template <typename Real, typename F>
Real integrateUniform(const F& f, Real a, Real b, int panels, const GaussLegendre<Real>& g) {
    Real sum = 0, h = (b - a) / panels;
    for (int p = 0; p < panels; ++p) sum += panel(f, a + (p + Real(0.5)) * h, h / 2, g);
    return sum;
}

// A point where the integrand has a peak or a kink, and the width of the
// first panel on either side of it.
struct GradePoint {
    double at, h0;
};

// Break points of [a, b]: at each grade point inside [a, b], panels
// growing by a factor 2 away from it (first width h0; none if h0 <= 0);
// then every interval wider than maxWidth split into equal parts. Sorted,
// a and b included, points closer than 1e-14 (relative beyond 1) merged.
std::vector<double> gradedBreaks(double a, double b, const std::vector<GradePoint>& points, double maxWidth);

}  // namespace facet::quadrature
