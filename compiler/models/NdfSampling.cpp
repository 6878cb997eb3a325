// NdfSampling: the default samplers of NdfFormulas (ModelCatalog.h): NDF
// sampling by numerical inversion of the polar CDF, for isotropic NDFs
// without a closed-form inversion (gaussian), and the refusal of
// visible-normal sampling for NDFs that have none.
#include "QuadMath.h"
#include "models/NdfSampling.h"

#include "Quadrature.h"

#include <vector>

namespace facet {

namespace {

using models::kPi;

// The polar CDF of one NDF's arguments: P(theta) = 2 pi Int_0^theta
// D(t) cos t sin t dt at the break points of a fixed grid, graded toward
// the pole (first panel 1e-6 rad, so that alpha = 1e-4 peaks are resolved)
// and at most 0.02 rad wide elsewhere, whatever the NDF's roughness; 16
// Gauss-Legendre points per panel. The doubling panels are as wide as
// 2.6 alpha where a gaussian(alpha = 0.006) peak lies, and the samples
// need the CDF to 1e-12: above u = 1 - 2^-24 lies 6e-8 of the mass, and
// 8 points per panel left 1e-9 there (3e-6 rad in theta).
template <typename Real>
struct PolarCdf {
    const NdfFormulas<Real>* ndf = nullptr;
    ModelArgs<Real> args;
    std::vector<Real> breaks, cumulative;
};

template <typename Real>
bool sameArgs(const ModelArgs<Real>& a, const ModelArgs<Real>& b) {
    for (int p = 0; p < kMaxModelParams; ++p)
        for (int ch = 0; ch < 3; ++ch)
            if (!(a.value[p][ch] == b.value[p][ch])) return false;
    return a.derived == b.derived;
}

template <typename Real>
Real polarDensity(const NdfFormulas<Real>& ndf, const ModelArgs<Real>& a, Real theta) {
    using std::cos; using std::sin;
    Real s = sin(theta), c = cos(theta);
    if (!(c > 0)) return 0;
    return 2 * kPi<Real> * ndf.D(a, Vec3<Real>{s, 0, c}) * c * s;
}

template <typename Real>
const quadrature::GaussLegendre<Real>& glPanel() {
    static const quadrature::GaussLegendre<Real>& g = quadrature::gaussLegendre<Real>(16);
    return g;
}

// The table of (ndf, a), from a small per-thread memo: the sampler is
// called per sample and a test or render mostly reuses a few argument sets.
template <typename Real>
const PolarCdf<Real>& polarCdf(const NdfFormulas<Real>& ndf, const ModelArgs<Real>& a) {
    constexpr int kMemo = 4;
    thread_local PolarCdf<Real> memo[kMemo];
    thread_local int next = 0;
    for (const PolarCdf<Real>& m : memo)
        if (m.ndf == &ndf && sameArgs(m.args, a)) return m;
    PolarCdf<Real>& t = memo[next];
    next = (next + 1) % kMemo;
    t.ndf = &ndf;
    t.args = a;
    std::vector<double> br = quadrature::gradedBreaks(0, double(kPi<Real>) / 2, {{0, 1e-6}}, 0.02);
    t.breaks.assign(br.begin(), br.end());
    t.breaks.back() = kPi<Real> / 2;
    t.cumulative.assign(1, Real(0));
    auto f = [&](Real theta) { return polarDensity(ndf, a, theta); };
    for (size_t i = 0; i + 1 < t.breaks.size(); ++i) {
        Real lo = t.breaks[i], hi = t.breaks[i + 1];
        t.cumulative.push_back(t.cumulative.back() + quadrature::panel(f, (lo + hi) / 2, (hi - lo) / 2, glPanel<Real>()));
    }
    return t;
}

}  // namespace

template <typename Real>
Vec3<Real> NdfFormulas<Real>::sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const {
    const PolarCdf<Real>& t = polarCdf(*this, a);
    Real target = u1 * t.cumulative.back();
    size_t k = 0;
    while (k + 2 < t.cumulative.size() && t.cumulative[k + 1] <= target) ++k;
    Real lo = t.breaks[k], hi = t.breaks[k + 1], rest = target - t.cumulative[k];
    auto f = [&](Real theta) { return polarDensity(*this, a, theta); };
    // Within the panel, the partial integral by the same 16-point rule on
    // [lo, x]: accurate because the panel is small against the density's scale.
    auto cdf = [&](Real x) { return x > lo ? quadrature::panel(f, (lo + x) / 2, (x - lo) / 2, glPanel<Real>()) : Real(0); };
    // Newton starts where the panel's mass would put theta if the density
    // were flat across it: the panels are narrow against the density's
    // scale, so this start is close and saves the first steps from the
    // middle (each step integrates the panel's part anew).
    Real mass = t.cumulative[k + 1] - t.cumulative[k];
    Real start = mass > 0 ? lo + (hi - lo) * (rest / mass) : (lo + hi) / 2;
    Real theta = models::invertIncreasing(cdf, f, rest, lo, hi, start);
    using std::sin;
    Real s = sin(theta);
    return models::normalFromPolar(s * s, u2);
}

template <typename Real>
Vec3<Real> NdfFormulas<Real>::sampleVisibleNormal(const ModelArgs<Real>&, const Vec3<Real>&, Real, Real) const {
    internal_error << "visible-normal sampling requested for an NDF without an exact visible-normal sampler";
}

#define FACET_NDF_SAMPLING(Real)                                                                         \
    template Vec3<Real> NdfFormulas<Real>::sampleNormal(const ModelArgs<Real>&, Real, Real) const;       \
    template Vec3<Real> NdfFormulas<Real>::sampleVisibleNormal(const ModelArgs<Real>&, const Vec3<Real>&, \
                                                               Real, Real) const;
FACET_NDF_SAMPLING(float)
FACET_NDF_SAMPLING(double)
FACET_NDF_SAMPLING(long double)
FACET_NDF_SAMPLING(__float128)
#undef FACET_NDF_SAMPLING

}  // namespace facet
