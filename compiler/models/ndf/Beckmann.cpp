// beckmann: the Beckmann NDF (Cook & Torrance 1982, Walter et al. 2007),
// isotropic or anisotropic, with its closed-form Smith Lambda.
#include "QuadMath.h"
#include "models/ModelMath.h"

namespace facet::models {
namespace {

template <typename Real>
struct BeckmannFormulas final : NdfFormulas<Real> {
    // exp(-(mx^2/ax^2 + my^2/ay^2)/mz^2) / (pi ax ay mz^4)
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp;
        Real ax = a[kAlphaX], ay = a[kAlphaY], z2 = m.z * m.z;
        Real e = (m.x * m.x / sq(ax) + m.y * m.y / sq(ay)) / z2;
        Real num = exp(-e);
        if (num == 0) return 0;  // the tail underflowed (mz^4 may have too: no 0/0)
        return num / (kPi<Real> * ax * ay * z2 * z2);
    }
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        Real proj = smithProjection(a[kAlphaX], a[kAlphaY], v);
        if (proj == 0) return 0;  // v = n: nothing is masked
        return beckmannCosLambda(proj, v.z);
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Beckmann() {
    static const NdfEntry entry = [] {
        NdfEntry e = alphaXYNdf(1, "beckmann", "Beckmann (Cook & Torrance 1982, Walter et al. 2007)");
        e.smith = true;
        e.shapeInvariant = true;
        e.hardCases = {
            {"hcc_beckmann_alpha_min", "ndf = beckmann(1e-4); masking = smith_height_correlated; fresnel = dielectric(1.5);"},
            {"hcc_beckmann_aniso_1e4", "ndf = beckmann(alpha_x = 1, alpha_y = 1e-4); masking = smith_direction_correlated;"},
            {"hcc_beckmann_alpha_2", "ndf = beckmann(2); masking = smith_separable;"},
        };
        e.formulas = makeFormulas<NdfFormulas, BeckmannFormulas>();
        return e;
    }();
    return {&entry};
}

}  // namespace facet::models
