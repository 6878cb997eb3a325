// LobeCombination: the reference BRDF of a combination of lobes (SPEC 10):
// the tree of CheckedMaterial::bsdf evaluated node by node over the
// resolved lobes. A one-lobe material is that lobe's brdf() unchanged.
#include "QuadMath.h"
#include "Interpreter.h"

#include "Diagnostics.h"

namespace facet {

namespace {

template <typename Real>
class CombinationEval {
public:
    CombinationEval(const CheckedMaterial& m, const ResolvedBsdf<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                    const Vec3<Real>& sum)
        : m_(m), r_(r), wi_(wi), wo_(wo), sum_(sum) {}

    std::array<Real, 3> node(int index) const {
        const BsdfNode& n = m_.bsdf.at(size_t(index));
        const std::array<Real, 3>& w = r_.weights.at(size_t(index));
        std::array<Real, 3> out{};
        switch (n.kind) {
            case BsdfKind::Lobe: return r_.lobes.at(size_t(n.lobe)).brdf(wi_, wo_, sum_);
            case BsdfKind::Scale: {
                std::array<Real, 3> x = node(n.a);
                for (int ch = 0; ch < 3; ++ch) out[ch] = w[ch] == 0 ? Real(0) : w[ch] * x[ch];
                return out;
            }
            case BsdfKind::Sum: {
                std::array<Real, 3> x = node(n.a), y = node(n.b);
                for (int ch = 0; ch < 3; ++ch) out[ch] = x[ch] + y[ch];
                return out;
            }
            case BsdfKind::Mix: {
                std::array<Real, 3> x = node(n.a), y = node(n.b);
                for (int ch = 0; ch < 3; ++ch) out[ch] = (1 - w[ch]) * x[ch] + w[ch] * y[ch];
                return out;
            }
            case BsdfKind::Layer: break;
        }
        internal_error << "bsdf node '" << bsdfKindName(n.kind) << "' has no reference evaluation yet";
    }

private:
    const CheckedMaterial& m_;
    const ResolvedBsdf<Real>& r_;
    const Vec3<Real>&wi_, &wo_, &sum_;
};

}  // namespace

template <typename Real>
std::array<Real, 3> Interpreter<Real>::combinedBrdf(const ResolvedBsdf<Real>& r, const Vec3<Real>& wi,
                                                    const Vec3<Real>& wo, const Vec3<Real>& sum, const Real*) const {
    return CombinationEval<Real>(material_, r, wi, wo, sum).node(int(material_.bsdf.size()) - 1);
}

#define FACET_COMBINATION(Real)                                                                                   \
    template std::array<Real, 3> Interpreter<Real>::combinedBrdf(const ResolvedBsdf<Real>&, const Vec3<Real>&, \
                                                                 const Vec3<Real>&, const Vec3<Real>&, const Real*) const;
FACET_COMBINATION(float)
FACET_COMBINATION(double)
FACET_COMBINATION(long double)
FACET_COMBINATION(__float128)
#undef FACET_COMBINATION

}  // namespace facet
