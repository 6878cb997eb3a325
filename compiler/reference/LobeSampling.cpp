// LobeSampling: the reference sampler of a combination of lobes (SPEC 10):
// a one-sample mixture over the leaf lobes of CheckedMaterial::bsdf.
//
// Each leaf is picked with a probability proportional to its share of the
// directional albedo at wo (channel mean): the leaf's own albedo (the
// reference's quadrature, LayerAlbedo.h) at the material's default inputs
// (an estimate: one table per leaf, not one per lane's parameters; the
// compiled sampler makes the same choice) times the weight the tree gives it
// (scale weights multiply; mix gives (1 - T) and T; a layer gives its top W
// and its base 1 - W + W u(n.wo), u = 1 - E_top, which makes the base's
// estimate (1 - W + W u) A_b exact by the balance of the design note). The
// chosen leaf draws wi with the one-lobe sampler (Sampling.h; a diffuse
// lobe draws from the cosine lobe). The reported pdf is the mixture's,
// sum_k p_k pdf_k(wi), and weight = f(wi, wo) (n.wi) / pdf with f the whole
// combination, so the estimator is unbiased whatever the p_k are.
#include "QuadMath.h"
#include "Sampling.h"

#include "LayerAlbedo.h"

#include <cmath>

namespace facet {

namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

// A leaf keeps at least this fraction of the largest leaf's share, so that
// a poor estimate cannot starve a lobe whose f is not zero.
constexpr double kMinShare = 0.01;

using Rgb = std::array<double, 3>;

// The albedo of the sub-expression `node` at muO from the estimates' tables
// (1 where the estimates are not valid: the factors alone).
Rgb estimate(const CheckedMaterial& m, const ResolvedBsdf<double>& est, int node, double muO) {
    return est.valid ? albedoTable(m, est, node)->at(muO) : Rgb{1, 1, 1};
}

void collect(const CheckedMaterial& m, const ResolvedBsdf<double>& r, const ResolvedBsdf<double>& est, int node,
             const Rgb& factor, double muO, std::vector<LeafChoice>& out) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    const Rgb& w = r.weights.at(size_t(node));
    auto times = [&](const Rgb& a) { return Rgb{factor[0] * a[0], factor[1] * a[1], factor[2] * a[2]}; };
    switch (n.kind) {
        case BsdfKind::Lobe: {
            if (factor[0] <= 0 && factor[1] <= 0 && factor[2] <= 0) return;
            Rgb a = estimate(m, est, node, muO);
            double share = 0;
            for (int ch = 0; ch < 3; ++ch) share += factor[ch] * std::max(a[ch], 0.0) / 3;
            out.push_back({n.lobe, std::isfinite(share) ? share : 0.0});
            return;
        }
        case BsdfKind::Scale: collect(m, r, est, n.a, times(w), muO, out); return;
        case BsdfKind::Sum:
            collect(m, r, est, n.a, factor, muO, out);
            collect(m, r, est, n.b, factor, muO, out);
            return;
        case BsdfKind::Mix:
            collect(m, r, est, n.a, times({1 - w[0], 1 - w[1], 1 - w[2]}), muO, out);
            collect(m, r, est, n.b, times(w), muO, out);
            return;
        case BsdfKind::Layer: {
            collect(m, r, est, n.a, times(w), muO, out);
            Rgb base = {1 - w[0], 1 - w[1], 1 - w[2]};
            if (w[0] > 0 || w[1] > 0 || w[2] > 0) {
                Rgb eTop = estimate(m, est, n.a, muO);
                for (int ch = 0; ch < 3; ++ch) base[ch] += w[ch] * std::max(0.0, 1 - eTop[ch]);
            }
            collect(m, r, est, n.b, times(base), muO, out);
            return;
        }
    }
}

// One leaf lobe's density of wi.
template <typename Real>
Real leafPdf(const ResolvedMaterial<Real>& lobe, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    if (lobe.ndf) return brdfPdf(lobe, wi, wo);
    return wi.z > 0 ? wi.z / kPi<Real> : Real(0);
}

}  // namespace

std::vector<LeafChoice> leafProbabilities(const CheckedMaterial& m, const ResolvedBsdf<double>& r,
                                          const ResolvedBsdf<double>& estimates, double muO) {
    std::vector<LeafChoice> out;
    collect(m, r, estimates, int(m.bsdf.size()) - 1, {1, 1, 1}, muO, out);
    double top = 0, sum = 0;
    for (const LeafChoice& c : out) top = std::max(top, c.p);
    for (LeafChoice& c : out) sum += (c.p = top > 0 ? std::max(c.p, kMinShare * top) : 1.0);
    for (LeafChoice& c : out) c.p /= sum;
    return out;
}

template <typename Real>
Real combinationPdf(const CheckedMaterial& m, const ResolvedBsdf<Real>& r, const std::vector<LeafChoice>& leaves,
                    const Vec3<Real>& wi, const Vec3<Real>& wo) {
    (void)m;
    Real pdf = 0;
    for (const LeafChoice& c : leaves) pdf += Real(c.p) * leafPdf(r.lobes.at(size_t(c.lobe)), wi, wo);
    return pdf;
}

template <typename Real>
SampleResult<Real> sampleCombination(const Interpreter<Real>& in, const ResolvedBsdf<Real>& r, const Vec3<Real>& wo,
                                     const std::array<Real, 3>& u) {
    using std::cos; using std::sin; using std::sqrt;
    SampleResult<Real> out;
    if (!(wo.z > 0)) return out;
    const CheckedMaterial& m = in.material();
    std::vector<LeafChoice> leaves =
        leafProbabilities(m, bsdfToDouble(r), in.resolvedDefaults(), double(wo.z));
    if (leaves.empty()) return out;
    // Pick the leaf with u0 and rescale u0 to [0, 1) within its interval
    // (the one-lobe sampler reads u0 again to choose its own technique).
    size_t k = 0;
    double u0 = double(u[0]), below = 0;
    while (k + 1 < leaves.size() && u0 >= below + leaves[k].p) below += leaves[k++].p;
    double rescaled = leaves[k].p > 0 ? (u0 - below) / leaves[k].p : 0.0;
    rescaled = rescaled < 0 ? 0.0 : (rescaled < 1 ? rescaled : std::nextafter(1.0, 0.0));
    const ResolvedMaterial<Real>& lobe = r.lobes.at(size_t(leaves[k].lobe));
    Vec3<Real> wi;
    if (lobe.ndf) {
        wi = sampleBrdf(lobe, wo, {Real(rescaled), u[1], u[2]}).wi;
    } else {
        Real radius = sqrt(u[1]), phi = 2 * kPi<Real> * u[2];
        wi = {radius * cos(phi), radius * sin(phi), sqrt(1 - u[1])};
    }
    out.wi = wi;
    out.pdf = combinationPdf(m, r, leaves, wi, wo);
    if (out.pdf > 0 && wi.z > 0) {
        Vec3<Real> sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
        std::array<Real, 3> f = in.combinedBrdf(r, wi, wo, sum, nullptr);
        for (int ch = 0; ch < 3; ++ch) out.weight[ch] = f[ch] * wi.z / out.pdf;
    }
    return out;
}

#define FACET_LOBE_SAMPLING(Real)                                                                               \
    template Real combinationPdf(const CheckedMaterial&, const ResolvedBsdf<Real>&, const std::vector<LeafChoice>&, \
                                 const Vec3<Real>&, const Vec3<Real>&);                                         \
    template SampleResult<Real> sampleCombination(const Interpreter<Real>&, const ResolvedBsdf<Real>&,          \
                                                  const Vec3<Real>&, const std::array<Real, 3>&);
FACET_LOBE_SAMPLING(double)
FACET_LOBE_SAMPLING(long double)
FACET_LOBE_SAMPLING(__float128)
#undef FACET_LOBE_SAMPLING

}  // namespace facet
