// blinn_phong: the normalized Blinn-Phong NDF (e + 2)/(2 pi) mz^e. Its Smith
// Lambda is Beckmann's at the equivalent roughness alpha = sqrt(2/(e + 2))
// (SPEC 3), which is also the roughness its tables and previews use.
//
// Visible normals come from its own slope distribution (Heitz & d'Eon
// 2014): P22(x, y) = (e + 2)/(2 pi) (1 + x^2 + y^2)^(-(e + 4)/2), whose
// marginal is the slope-form Student-t p_nu, nu = e + 2 (numeric/StudentT.h,
// models/NdfSampling.h). The exact Smith Lambda of this D normalizes them;
// the BRDF's masking keeps the Beckmann one.
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

namespace facet::models {
namespace {

constexpr int kExponent = 0;

template <typename Real>
Real equivalentAlpha(Real exponent) {
    using std::sqrt;
    return sqrt(2 / (exponent + 2));
}

template <typename Real>
struct BlinnPhongFormulas final : NdfFormulas<Real> {
    // (e + 2)/(2 pi) mz^e. Near mz = 1, mz^e = exp(e/2 log1p(-(mx^2 + my^2))):
    // pow(mz, e) would carry the rounding of mz (1e-16 absolute) amplified by
    // e (1e6 and more) where the lobe is; sin^2 from the components does not.
    // Near mz = 0 (grazing h) 1 - sin^2 cancels instead and pow(mz, e) is the
    // accurate form.
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp; using std::log1p; using std::pow;
        Real e = a[kExponent];
        Real s2 = m.x * m.x + m.y * m.y;
        Real p = e == 0 ? Real(1) : m.z * m.z < Real(0.5) ? pow(m.z, e) : exp(e / 2 * log1p(-s2));
        return (e + 2) / (2 * kPi<Real>) * p;
    }
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        Real alpha = equivalentAlpha(a[kExponent]);
        Real proj = smithProjection(alpha, alpha, v);
        if (proj == 0) return 0;  // v = n: nothing is masked
        return beckmannCosLambda(proj, v.z);
    }
    // D(m) (n.m) has the polar CDF 1 - mz^(e + 2), so mz^2 = (1 - u)^(2/(e + 2)),
    // and sin^2 = -expm1(2 log1p(-u) / (e + 2)) keeps narrow lobes accurate.
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::expm1; using std::log1p;
        return normalFromPolar(-expm1(2 * log1p(-u1) / (a[kExponent] + 2)), u2);
    }
    // The exact Lambda of D and its visible normals: those of its slope
    // distribution (NdfSampling.h), nu = e + 2.
    Real visibleCosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        return studentSlopeCosLambda(a[kExponent] + 2, v);
    }
    Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const override {
        return studentSlopeVisibleNormal(a[kExponent] + 2, wo, u1, u2);
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_BlinnPhong() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 2, "blinn_phong", "normalized Blinn-Phong NDF");
        e.canonical = {{"exponent", ValueType::Float, 0, kMaxPhongExponent}};
        e.forms = {ModelForm{{{"exponent", ValueType::Float, {kExponent}}}}};
        e.smith = true;
        e.visibleNormals = true;
        e.lambdaNote = "blinn_phong uses the Beckmann Lambda (SPEC 3)";
        e.equivalentAlphas = [](const ModelArgs<double>& a) {
            double alpha = std::sqrt(2 / (a[kExponent] + 2));
            return std::array<double, 2>{alpha, alpha};
        };
        // The exponent whose equivalent roughness is alpha: the language's
        // beckmann_to_phong(alpha) = 2/alpha^2 - 2, clamped to the domain.
        e.argsAtAlpha = [](double alpha, const std::vector<double>&) {
            ModelArgs<double> a;
            a.set(kExponent, std::min(std::max(2 / (alpha * alpha) - 2, 0.0), kMaxPhongExponent));
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) { return fmt::format("exponent={:.6g}", a[kExponent]); };
        e.examples = {{"blinn_phong", "input exponent = 50;", "blinn_phong(exponent)"}};
        e.hardCases = {
            {"hcc_blinn_1e6", "ndf = blinn_phong(1e6); masking = smith_height_correlated;"},
            {"hcc_blinn_max", "ndf = blinn_phong(2e8); masking = implicit; fresnel = schlick(0.04);"},
            {"hcc_blinn_0", "ndf = blinn_phong(0); masking = smith_separable;"},
            {"hcc_blinn_phong_exponent_r0", "ndf = blinn_phong(phong_exponent(0)); masking = cook_torrance;"},
            {"hcc_blinn_phong_exponent_input",
             "input r = 0.5 in 0 .. 1; ndf = blinn_phong(phong_exponent(r)); masking = smith_height_correlated;"},
            {"hcc_blinn_beckmann_to_phong_input",
             "input a = 0.5 in 0 .. 2; ndf = blinn_phong(beckmann_to_phong(a)); masking = implicit;"},
        };
        e.formulas = makeFormulas<NdfFormulas, BlinnPhongFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
