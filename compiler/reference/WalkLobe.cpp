// WalkLobe: the random-walk lobe's eval term, sampler and MIS density in the
// reference (see WalkLobe.h), on MicrosurfaceWalk's walk.
#include "QuadMath.h"
#include "WalkLobe.h"

#include "LayerAlbedo.h"

#include <bit>
#include <cmath>

namespace facet {
namespace {

// The cosine lobe's share of the MIS density stays within [0.05, 0.95], as
// a sampled mixture's lobe probabilities do (Sampling.cpp).
constexpr double kMinCosineShare = 0.05;

// A direction component on the seed's grid: floor(x 2^16 + 0.3183) as a
// 32-bit word. The offset keeps the cell edges off 0, +-1, 1/2 and the
// other round values hard cases use, where the kernel's and the reference's
// normalizations could round to either side.
uint32_t gridCell(double x) { return uint32_t(int32_t(std::floor(x * 65536.0 + 0.3183))); }

Vec3<double> toDouble(const Vec3<double>& v) { return v; }
template <typename Real>
Vec3<double> toDouble(const Vec3<Real>& v) { return {double(v.x), double(v.y), double(v.z)}; }

}  // namespace

uint32_t evalWalkSeed(const Vec3<double>& wi, const Vec3<double>& wo) {
    uint32_t s = 0x5bd1e995u;
    for (double x : {wi.x, wi.y, wi.z, wo.x, wo.y, wo.z}) s = WalkRandom::walkHash(s ^ gridCell(x));
    return s;
}

uint32_t sampleWalkSeed(const std::array<float, 3>& u) {
    uint32_t s = WalkRandom::walkHash(std::bit_cast<uint32_t>(u[0]));
    s = WalkRandom::walkHash(s ^ std::bit_cast<uint32_t>(u[1]));
    return WalkRandom::walkHash(s ^ std::bit_cast<uint32_t>(u[2]));
}

template <typename Real>
std::array<Real, 3> walkMultipleScattering(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi,
                                           const Vec3<Real>& wo) {
    std::array<Real, 3> out{};
    if (!(wi.z > 0) || !(wo.z > 0)) return out;
    const ResolvedMaterial<double> lobe = lobeToDouble(r);
    const MicrosurfaceWalk walk(lobe);
    const Vec3<double> i = toDouble(wi), o = toDouble(wo);
    WalkRandom random = WalkRandom::counterStream(evalWalkSeed(i, o));
    WalkOrders orders;
    orders.minOrder = 2;
    orders.maxOrder = kLaneWalkMaxOrder;
    std::array<double, 3> sum = walk.pathBrdfCos(i, o, random, orders);
    for (int ch = 0; ch < 3; ++ch) out[ch] = Real(sum[ch] / i.z);
    return out;
}

template <typename Real>
SampleResult<Real> sampleWalkLobe(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u) {
    SampleResult<Real> out;
    if (!(wo.z > 0)) return out;
    const ResolvedMaterial<double> lobe = lobeToDouble(r);
    const MicrosurfaceWalk walk(lobe);
    WalkRandom random = WalkRandom::counterStream(sampleWalkSeed({float(u[0]), float(u[1]), float(u[2])}));
    WalkOrders orders;
    orders.maxOrder = kLaneWalkMaxOrder;
    WalkSample s = walk.sample(toDouble(wo), random, orders);
    if (!(s.wi.z > 0)) return out;  // cut (or, at double's resolution, grazing)
    out.wi = {Real(s.wi.x), Real(s.wi.y), Real(s.wi.z)};
    out.pdf = walkLobePdf(r, out.wi, wo);
    for (int ch = 0; ch < 3; ++ch) out.weight[ch] = Real(s.weight[ch]);
    return out;
}

template <typename Real>
Real walkLobePdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    if (!(wo.z > 0)) return 0;
    Real cosLambda = r.ndf->formulas.template get<Real>().visibleCosLambda(r.ndfArgs, wo);
    Real q = cosLambda / (wo.z + cosLambda);  // Lambda / (1 + Lambda)
    const Real lo = Real(kMinCosineShare), hi = 1 - lo;
    q = q < lo ? lo : (q > hi ? hi : q);
    Real single = specularPdf(r, wi, wo, SamplingTechnique::VisibleNormals);
    Real cosine = wi.z > 0 ? wi.z / Real(3.141592653589793238462643383279502884L) : Real(0);
    return (1 - q) * single + q * cosine;
}

#define FACET_WALK_LOBE(Real)                                                                                     \
    template std::array<Real, 3> walkMultipleScattering(const ResolvedMaterial<Real>&, const Vec3<Real>&,         \
                                                        const Vec3<Real>&);
FACET_WALK_LOBE(float)
FACET_WALK_LOBE(double)
FACET_WALK_LOBE(long double)
FACET_WALK_LOBE(__float128)
#undef FACET_WALK_LOBE
#define FACET_WALK_SAMPLER(Real)                                                                                \
    template SampleResult<Real> sampleWalkLobe(const ResolvedMaterial<Real>&, const Vec3<Real>&,                \
                                               const std::array<Real, 3>&);                                     \
    template Real walkLobePdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&);
FACET_WALK_SAMPLER(double)
FACET_WALK_SAMPLER(long double)
FACET_WALK_SAMPLER(__float128)
#undef FACET_WALK_SAMPLER

}  // namespace facet
