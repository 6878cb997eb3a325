// LobeCombination: Interpreter::combinedBrdf, the tree of CheckedMaterial::bsdf
// evaluated by CombinationEval (LobeCombination.h). A one-lobe material is
// that lobe's brdf() unchanged.
#include "QuadMath.h"
#include "LobeCombination.h"

#include <optional>
#include <type_traits>

namespace facet {

bool hasLayer(const CheckedMaterial& m) {
    for (const BsdfNode& n : m.bsdf)
        if (n.kind == BsdfKind::Layer) return true;
    return false;
}

template <typename Real>
std::array<Real, 3> Interpreter<Real>::combinedBrdf(const ResolvedBsdf<Real>& r, const Vec3<Real>& wi,
                                                    const Vec3<Real>& wo, const Vec3<Real>& sum, const Real*) const {
    if (!material_.combinesLobes()) return r.lobes.at(size_t(material_.bsdfRoot().lobe)).brdf(wi, wo, sum);
    // The layers' tables are baked in double, from the double form of r.
    std::optional<ResolvedBsdf<double>> converted;
    const ResolvedBsdf<double>* rd = nullptr;
    if (hasLayer(material_)) {
        if constexpr (std::is_same_v<Real, double>) {
            rd = &r;
        } else {
            converted = bsdfToDouble(r);
            rd = &*converted;
        }
    }
    return CombinationEval<Real>(material_, r, rd, wi, wo, sum).node(int(material_.bsdf.size()) - 1);
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
