// beckmann: the Beckmann NDF (Cook & Torrance 1982, Walter et al. 2007),
// isotropic or anisotropic, with its closed-form Smith Lambda.
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

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
    // The standard Beckmann slopes have the radial CDF 1 - exp(-r^2).
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::log1p;
        return stretchedSlopeNormal(a[kAlphaX], a[kAlphaY], -log1p(-u1), u2);
    }
    // Heitz & d'Eon 2014: stretched to alpha = 1 and turned so that wo' =
    // (sin t, 0, cos t), the visible slopes (x, y) have the density
    // (1 - x tan t)+ exp(-x^2 - y^2) / pi up to a constant: x from the CDF
    // C(x) = erfc(-x)/2 + tan t exp(-x^2) / (2 sqrt(pi)) (C(cot t) = 1 + Lambda),
    // y independently from erfc(-y)/2, both by Newton's method; then turned
    // back and unstretched.
    Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const override {
        using std::erfc; using std::exp; using std::sqrt;
        Real ax = a[kAlphaX], ay = a[kAlphaY];
        Real sx = ax * wo.x, sy = ay * wo.y, sxy = sqrt(sx * sx + sy * sy);
        Real cosPhi = sxy > 0 ? sx / sxy : Real(1), sinPhi = sxy > 0 ? sy / sxy : Real(0);
        const Real tail = 8, rootPi = sqrt(kPi<Real>);  // C(-8) < 1e-28 C(cot t)
        auto gauss = [&](Real x) { return exp(-x * x) / rootPi; };
        Real x;
        if (wo.z > 0) {
            Real tanT = sxy / wo.z;
            auto cdfX = [&](Real x) { return erfc(-x) / 2 + tanT * exp(-x * x) / (2 * rootPi); };
            Real hi = sxy > 0 && wo.z / sxy < tail ? wo.z / sxy : tail;
            x = invertIncreasing(cdfX, [&](Real t) { return (1 - t * tanT) * gauss(t); }, u1 * cdfX(hi), -tail, hi);
        } else {
            // Below the horizon (the random walk's rays going up,
            // MicrosurfaceWalk.h): the density is (cos t - x sin t)+ exp(-x^2),
            // on x < cot t < 0, and cos t C(x) above, undivided (cos t < 0),
            // is its CDF. Where cot t underflows the mass (stretched wo within
            // 2 degrees of -n) no ray can meet the surface: Lambda(-wo) = 0.
            auto cdfX = [&](Real x) { return wo.z * erfc(-x) / 2 + sxy * exp(-x * x) / (2 * rootPi); };
            Real hi = sxy > 0 ? wo.z / sxy : -tail;
            x = invertIncreasing(cdfX, [&](Real t) { return (wo.z - t * sxy) * gauss(t); }, u1 * cdfX(hi), hi - tail, hi);
        }
        Real y = invertIncreasing([&](Real t) { return erfc(-t) / 2; }, gauss, u2, -tail, tail);
        return normalFromSlopes(ax * (cosPhi * x - sinPhi * y), ay * (sinPhi * x + cosPhi * y));
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Beckmann() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = alphaXYNdf(1, "beckmann", "Beckmann (Cook & Torrance 1982, Walter et al. 2007)");
        e.smith = true;
        e.shapeInvariant = true;
        e.visibleNormals = true;
        e.hardCases = {
            {"hcc_beckmann_alpha_min", "ndf = beckmann(1e-4); masking = smith_height_correlated; fresnel = dielectric(1.5);"},
            {"hcc_beckmann_aniso_1e4", "ndf = beckmann(alpha_x = 1, alpha_y = 1e-4); masking = smith_direction_correlated;"},
            {"hcc_beckmann_alpha_2", "ndf = beckmann(2); masking = smith_separable;"},
        };
        e.formulas = makeFormulas<NdfFormulas, BeckmannFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
