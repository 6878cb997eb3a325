// blinn_phong: the normalized Blinn-Phong NDF (e + 2)/(2 pi) mz^e. Its Smith
// Lambda is Beckmann's at the equivalent roughness alpha = sqrt(2/(e + 2))
// (SPEC 3), which is also the roughness its tables and previews use.
//
// Visible normals come from its own slope distribution (Heitz & d'Eon
// 2014): P22(x, y) = (e + 2)/(2 pi) (1 + x^2 + y^2)^(-(e + 4)/2), whose
// marginal is the slope-form Student-t p_nu, nu = e + 2 (numeric/StudentT.h).
// The exact Smith Lambda of this D, (1/mu) Int_mu^inf (q - mu) p_nu(q) dq at
// mu = cot theta, normalizes them; the BRDF's masking keeps the Beckmann one.
#include "QuadMath.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include "StudentT.h"

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
    // The exact Lambda: with (1 + mu^2)^(-1/2) = sin theta and Int_mu^inf q
    // p_nu(q) dq = c_nu (1 + mu^2)^(-(nu-1)/2) / (nu - 1),
    // (n.v) Lambda = c_nu sin^nu theta / (nu - 1) - cos theta T_nu(mu), T_nu
    // the tail of p_nu at mu = cot theta. (e = 0 gives GGX's at alpha = 1.)
    Real visibleCosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        Real nu = a[kExponent] + 2;
        Real s2 = v.x * v.x + v.y * v.y, c2 = v.z * v.z;
        if (s2 == 0) return 0;  // v = n: nothing is masked
        Real cl = studentSlopeNorm(nu) * powSin(s2, c2, nu) / (nu - 1) - v.z * studentSlopeTail(nu, c2, s2);
        return cl > 0 ? cl : Real(0);
    }
    // In the frame turned about n so that wo' = (sin t, 0, cos t), the
    // visible slopes (x, y) have the density (1 - x tan t)+ P22(x, y) up to
    // a constant. With x = tan psi, cos t times the CDF of psi is
    //   G(psi) = cos t F(tan psi) + sin t c_nu cos^(nu-1) psi / (nu - 1),
    // F = 1 - T_nu, with G' = c_nu cos^e psi sin(psi_max - psi) on (-pi/2,
    // psi_max], psi_max = pi/2 - t, and G(psi_max) = cos t + (n.wo)
    // Lambda(wo). Given x, y = sqrt(1 + x^2) tan chi, where tan chi has the
    // density p_(e+3) (from (1 + x^2 + y^2) = (1 + x^2)(1 + tan^2 chi)).
    // Both angles by Newton's method; the normal of the slopes (x, y) is
    // (-sin psi cos chi, -sin chi, cos psi cos chi), turned back.
    Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const override {
        using std::atan2; using std::cos; using std::sin; using std::sqrt;
        const Real e = a[kExponent], nu = e + 2, halfPi = kPi<Real> / 2;
        Real sxy = sqrt(wo.x * wo.x + wo.y * wo.y);
        Real cosPhi = sxy > 0 ? wo.x / sxy : Real(1), sinPhi = sxy > 0 ? wo.y / sxy : Real(0);
        Real norm = studentSlopeNorm(nu);
        auto cdfPsi = [&](Real psi) {
            Real s = sin(psi), c = cos(psi), s2 = s * s, c2 = c * c;
            Real tail = studentSlopeTail(nu, s2, c2);
            Real F = psi >= 0 ? 1 - tail : tail;
            return wo.z * F + sxy * norm * powSin(c2, s2, nu - 1) / (nu - 1);
        };
        auto pdfPsi = [&](Real psi) {
            Real s = sin(psi), c = cos(psi);
            Real d = wo.z * c - sxy * s;
            return d > 0 ? norm * powSin(c * c, s * s, e) * d : Real(0);
        };
        Real psiMax = atan2(wo.z, sxy);
        // Quantiles below 2^-32 (u = 0 in float) are taken at 2^-32: the
        // limit u = 0 is the horizon, where the CDF underflows for large e
        // (the inversion could stop anywhere there) and where m.z = 0 would
        // make the sample's pdf ill-conditioned.
        const Real floorU = Real(0x1p-32);
        Real psi = invertIncreasing(cdfPsi, pdfPsi, (u1 > floorU ? u1 : floorU) * cdfPsi(psiMax), -halfPi, psiMax);
        // tan chi from its tail q = min(u2, 1 - u2), the sign from the side.
        Real nuY = e + 3, normY = studentSlopeNorm(nuY), q = u2 < Real(0.5) ? u2 : 1 - u2;
        auto minusTail = [&](Real chi) {
            Real s = sin(chi), c = cos(chi);
            return -studentSlopeTail(nuY, s * s, c * c);
        };
        auto pdfChi = [&](Real chi) {
            Real s = sin(chi), c = cos(chi);
            return normY * powSin(c * c, s * s, nuY - 1);
        };
        Real chi = invertIncreasing(minusTail, pdfChi, -(q > floorU ? q : floorU), Real(0), halfPi);
        if (u2 < Real(0.5)) chi = -chi;
        Real mx = -sin(psi) * cos(chi), my = -sin(chi), mz = cos(psi) * cos(chi);
        return {cosPhi * mx - sinPhi * my, sinPhi * mx + cosPhi * my, mz};
    }

private:
    // sqrt(s2)^p for s2 + c2 = 1 (sin^p from sin^2 and cos^2): through
    // log1p(-c2) where c2 is small, so that a large p keeps its accuracy.
    static Real powSin(Real s2, Real c2, Real p) {
        using std::exp; using std::log; using std::log1p;
        if (p == 0) return 1;
        if (!(s2 > 0)) return 0;
        return exp(p / 2 * (c2 < Real(0.5) ? log1p(-c2) : log(s2)));
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_BlinnPhong() {
    static const NdfEntry entry = [] {
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
    }();
    return {&entry};
}

}  // namespace facet::models
