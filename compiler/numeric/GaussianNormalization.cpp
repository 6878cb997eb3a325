// GaussianNormalization: N(alpha) by Gauss-Legendre quadrature, and its
// log-log table (GaussianNormalization.h).
#include "QuadMath.h"  // before any std-math template (see QuadMath.h)
#include "GaussianNormalization.h"
#include "Immortal.h"

#include "Quadrature.h"

#include <algorithm>
#include <cmath>

namespace facet {

template <typename Real>
Real gaussianNdfNorm(Real alpha) {
    using std::cos; using std::exp; using std::min; using std::sin;
    const Real pi = Real(3.141592653589793238462643383279502884L);
    // A small memo per thread: the interpreter resolves the parameters for
    // every evaluation and a sample mostly shares a few alphas, while the
    // quadrature costs 512 exp/cos/sin (milliseconds in __float128).
    constexpr int kMemo = 4;
    thread_local Real memoAlpha[kMemo] = {-1, -1, -1, -1}, memoNorm[kMemo] = {};
    thread_local int memoNext = 0;
    for (int i = 0; i < kMemo; ++i)
        if (memoAlpha[i] == alpha) return memoNorm[i];
    // The integrand is negligible beyond 8 alpha (exp(-64)).
    Real upper = min(pi / 2, 8 * alpha);
    auto f = [&](Real t) { return exp(-t * t / (alpha * alpha)) * cos(t) * sin(t); };
    static const quadrature::GaussLegendre<Real>& gl8 = quadrature::gaussLegendre<Real>(8);
    Real norm = 2 * pi * quadrature::integrateUniform(f, Real(0), upper, 64, gl8);
    memoAlpha[memoNext] = alpha;
    memoNorm[memoNext] = norm;
    memoNext = (memoNext + 1) % kMemo;
    return norm;
}

template float gaussianNdfNorm<float>(float);
template double gaussianNdfNorm<double>(double);
template long double gaussianNdfNorm<long double>(long double);
template __float128 gaussianNdfNorm<__float128>(__float128);

const GaussianNormTable& gaussianNormTable() {
    static const GaussianNormTable& table = immortal<GaussianNormTable>([] {  // immutable data, built once per process
        GaussianNormTable t;
        t.q.resize(GaussianNormTable::kSize);
        for (int i = 0; i < GaussianNormTable::kSize; ++i) {
            double x = GaussianNormTable::kX0 + (GaussianNormTable::kX1 - GaussianNormTable::kX0) * i /
                                                    (GaussianNormTable::kSize - 1);
            t.q[i] = std::log(gaussianNdfNorm<double>(std::exp(x)));
        }
        return t;
    }());
    return table;
}

double GaussianNormTable::interpolate(double alpha) const {
    // The stencil a kernel uses: u clamped to the table, i in [1, size - 3],
    // s = u - i in [-1, 2].
    double h = (kX1 - kX0) / (kSize - 1);
    double u = std::clamp((std::log(alpha) - kX0) / h, 0.0, kSize - 1.0);
    int i = int(std::clamp(std::floor(u), 1.0, kSize - 3.0));
    double s = u - i;
    double l0 = -s * (s - 1) * (s - 2) / 6, l1 = (s + 1) * (s - 1) * (s - 2) / 2;
    double l2 = -(s + 1) * s * (s - 2) / 2, l3 = (s + 1) * s * (s - 1) / 6;
    return std::exp(l0 * q[i - 1] + l1 * q[i] + l2 * q[i + 1] + l3 * q[i + 2]);
}

}  // namespace facet
