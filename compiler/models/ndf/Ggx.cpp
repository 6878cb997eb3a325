// ggx / trowbridge_reitz: the GGX (Trowbridge-Reitz) NDF of Walter et al.
// 2007, isotropic or anisotropic, with its closed-form Smith Lambda.
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

namespace facet::models {
namespace {

template <typename Real>
struct GgxFormulas final : NdfFormulas<Real> {
    // 1 / (pi ax ay (mx^2/ax^2 + my^2/ay^2 + mz^2)^2)
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        Real ax = a[kAlphaX], ay = a[kAlphaY];
        Real t = m.x * m.x / sq(ax) + m.y * m.y / sq(ay) + m.z * m.z;
        return 1 / (kPi<Real> * ax * ay * t * t);
    }
    // Lambda = (-1 + sqrt(1 + x)) / 2 = x / (2 (1 + sqrt(1 + x))), x = proj / vz^2
    // (no cancellation for small x); times vz.
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        using std::sqrt;
        Real proj = smithProjection(a[kAlphaX], a[kAlphaY], v);
        if (proj == 0) return 0;  // v = n: nothing is masked
        return proj / (2 * (v.z + sqrt(sq(v.z) + proj)));
    }
    // The standard GGX slopes have the radial CDF r^2 / (1 + r^2): r^2 = u / (1 - u).
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        return stretchedSlopeNormal(a[kAlphaX], a[kAlphaY], u1 / (1 - u1), u2);
    }
    // Spherical caps (Dupuy & Benyoub 2023): stretched to alpha = 1, the
    // visible normals are h = c + wo', wo' the stretched view direction and c
    // uniform on the unit sphere's cap c.z >= -wo'.z; unstretching h gives m.
    Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const override {
        using std::cos; using std::sin; using std::sqrt;
        Real ax = a[kAlphaX], ay = a[kAlphaY];
        Vec3<Real> s{ax * wo.x, ay * wo.y, wo.z};
        Real inv = 1 / sqrt(s.x * s.x + s.y * s.y + s.z * s.z);
        s = {s.x * inv, s.y * inv, s.z * inv};
        Real phi = 2 * kPi<Real> * u1;
        Real z = (1 - u2) * (1 + s.z) - s.z;
        Real r2 = (1 - z) * (1 + z);
        Real r = sqrt(r2 > 0 ? r2 : Real(0));
        Vec3<Real> h{r * cos(phi) + s.x, r * sin(phi) + s.y, z + s.z};
        Vec3<Real> m{ax * h.x, ay * h.y, h.z > 0 ? h.z : Real(0)};
        Real len = sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
        if (!(len > 0)) return {0, 0, 1};  // h = 0: only where wo' is the cap's pole, a null set
        return {m.x / len, m.y / len, m.z / len};
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Ggx() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = alphaXYNdf(0, "ggx", "GGX / Trowbridge-Reitz (Walter et al. 2007)");
        e.aliases = {"trowbridge_reitz"};
        e.smith = true;
        e.shapeInvariant = true;
        e.visibleNormals = true;
        e.compiledWalk = true;  // the spherical cap holds for any view
        e.representative = true;
        e.hardCases = {
            {"hcc_ggx_alpha_min", "ndf = ggx(1e-4); masking = smith_height_correlated;"},
            {"hcc_ggx_alpha_below_clamp", "ndf = ggx(1e-6); masking = smith_separable; fresnel = schlick(0.04);"},
            {"hcc_ggx_aniso_1e4", "ndf = ggx(alpha_x = 1e-4, alpha_y = 1); masking = smith_height_correlated; "
                                  "fresnel = conductor(eta = rgb(0.14, 0.43, 1.38), k = rgb(3.697, 2.455, 1.914));"},
            {"hcc_ggx_alpha_2", "ndf = ggx(2); masking = smith_height_direction_correlated;"},
            {"hcc_ranged_roughness",
             "input roughness = 0.5 in 0 .. 1; input tint = rgb(1, 0.5, 0.25) in 0 .. 1; let alpha = roughness * "
             "roughness; ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = tint); "
             "diffuse = lambert(tint);"},
        };
        e.formulas = makeFormulas<NdfFormulas, GgxFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
