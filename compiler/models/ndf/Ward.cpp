// ward: the whole anisotropic Ward (1992) lobe,
// exp(-tan^2(theta_h)(cos^2(phi_h)/ax^2 + sin^2(phi_h)/ay^2)) / (4 pi ax ay sqrt(ci co)),
// times F. It carries its own normalization, so it takes no masking term.
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

namespace facet::models {
namespace {

template <typename Real>
struct WardFormulas final : NdfFormulas<Real> {
    Real D(const ModelArgs<Real>&, const Vec3<Real>&) const override {
        internal_error << "D() called for ward, a whole BRDF lobe without a microfacet distribution";
    }
    Real wholeLobe(const ModelArgs<Real>& a, const Vec3<Real>& h, Real ci, Real co) const override {
        using std::exp; using std::sqrt;
        Real ax = a[kAlphaX], ay = a[kAlphaY];
        Real e = (sq(h.x / ax) + sq(h.y / ay)) / sq(h.z);
        return exp(-e) / (4 * kPi<Real> * ax * ay * sqrt(ci) * sqrt(co));
    }
    // Walter 2005: the half vector is drawn from the Beckmann NDF with the
    // lobe's exponent, exp(-e) / (pi ax ay mz^4) times mz.
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::log1p;
        return stretchedSlopeNormal(a[kAlphaX], a[kAlphaY], -log1p(-u1), u2);
    }
    Real normalPdf(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp;
        if (!(m.z > 0)) return 0;
        Real num = exp(-(sq(m.x / a[kAlphaX]) + sq(m.y / a[kAlphaY])) / sq(m.z));
        if (num == 0) return 0;  // the tail underflowed (mz^3 may have too: no 0/0)
        return num / (kPi<Real> * a[kAlphaX] * a[kAlphaY] * m.z * m.z * m.z);
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Ward() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = alphaXYNdf(5, "ward", "whole anisotropic Ward (1992) lobe");
        e.wholeLobe = true;
        e.energyNote = "ward's lobe has its own approximate normalization, not a microfacet energy bound";
        e.hardCases = {{"hcc_ward_aniso_1e4", "ndf = ward(alpha_x = 1e-4, alpha_y = 1);"}};
        e.formulas = makeFormulas<NdfFormulas, WardFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
