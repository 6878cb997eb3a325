// student_t: the Student's t-distribution of slopes (STD) of Ribardiere,
// Bringier, Meneveaux and Simonot 2017, isotropic or anisotropic:
//   D(m) = (1 + e / (gamma - 1))^(-gamma) / (pi ax ay mz^4),
//   e = (mx^2/ax^2 + my^2/ay^2) / mz^2,
// a slope distribution normalized for any gamma > 1 (the paper takes gamma
// > 1.5, where the slopes have a finite mean and Smith Lambda exists). gamma
// = 2 is GGX; gamma -> infinity is Beckmann. Its Smith Lambda is tabulated
// (LambdaTable.h): the slopes' marginal is a Student-t in x / sqrt(gamma - 1)
// with 2 gamma - 2 degrees of freedom, so Lambda does have a closed form
// through the incomplete beta function (numeric/StudentT.h), but the kernel
// would need that continued fraction in IR; the table serves both
// evaluators. Lambda is finite only for gamma > 1.5 (a finite mean slope).
// Its visible normals are those of the Student-t slope distribution of
// NdfSampling.h (blinn_phong's), stretched.
#include "QuadMath.h"
#include "Immortal.h"
#include "LambdaTable.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

namespace facet::models {
namespace {

constexpr int kGamma = 2;  // after alpha_x, alpha_y (kAlphaX, kAlphaY)

template <typename Real>
struct StudentTFormulas final : NdfFormulas<Real> {
    // In log form: with gamma up to 1e4 the power over- or underflows long
    // before D does, and toward the horizon D ~ mz^(2 gamma - 4) while e
    // overflows and mz^4 underflows. Where x = e / (gamma - 1) > 1, log(1 +
    // x) = log(s / (gamma - 1)) - log(mz^2) + log1p(1/x) (s the numerator
    // of e), and the powers of mz combine to (gamma - 2) log(mz^2), taken
    // as 2 log|mz| so that a tiny mz^2 cannot underflow.
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::abs; using std::exp; using std::log; using std::log1p;
        Real ax = a[kAlphaX], ay = a[kAlphaY], g = a[kGamma];
        Real logZ2 = 2 * log(abs(m.z));
        Real s = m.x * m.x / sq(ax) + m.y * m.y / sq(ay);
        Real x = s / ((g - 1) * (m.z * m.z));
        Real logD = x > 1 ? -g * (log(s / (g - 1)) + log1p(1 / x)) + (g - 2) * logZ2 : -g * log1p(x) - 2 * logZ2;
        return exp(logD) / (kPi<Real> * ax * ay);
    }
    // The tabulated (n.v) Lambda(v) of the material's gamma (stretched: a
    // depends on alpha(v) only through proj).
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "student_t"));
        return Real(tabulatedCosLambda(self, {double(a[kGamma])}, double(smithProjection(a[kAlphaX], a[kAlphaY], v)),
                                       double(v.z)));
    }
    // The standard slopes have the radial CDF 1 - (1 + r^2/(gamma - 1))^(1 - gamma):
    // r^2 = (gamma - 1) expm1(log1p(-u) / (1 - gamma)) (Beckmann's -log1p(-u)
    // as gamma grows).
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::expm1; using std::log1p;
        Real g = a[kGamma];
        return stretchedSlopeNormal(a[kAlphaX], a[kAlphaY], (g - 1) * expm1(log1p(-u1) / (1 - g)), u2);
    }
    // Visible normals, and the Lambda that normalizes them, from the slope
    // distribution P22 of NdfSampling.h: the slopes of D are those of P22
    // with nu = 2 gamma - 2 stretched by k = sqrt(gamma - 1) (alpha_x,
    // alpha_y). A direction v maps to (kx vx, ky vy, vz) in P22's frame,
    // and (n.v) Lambda(v) = |that| times P22's at its unit direction. This
    // Lambda is exact, where cosLambda is the table's (within 1e-6): the
    // visible density must integrate to 1.
    Real visibleCosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        Real length;
        Vec3<Real> s = toSlopeFrame(a, v, length);
        return length * studentSlopeCosLambda(2 * a[kGamma] - 2, s);
    }
    // The normal of P22's visible normal m' is (kx m'x, ky m'y, m'z) up to
    // scale (the slopes scale by k).
    Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const override {
        using std::sqrt;
        Real length, k = sqrt(a[kGamma] - 1);
        Vec3<Real> m = studentSlopeVisibleNormal(2 * a[kGamma] - 2, toSlopeFrame(a, wo, length), u1, u2);
        Real mx = k * a[kAlphaX] * m.x, my = k * a[kAlphaY] * m.y;
        Real inv = 1 / sqrt(mx * mx + my * my + m.z * m.z);
        return {mx * inv, my * inv, m.z * inv};
    }

private:
    // v in P22's frame, unit, and the length it had.
    static Vec3<Real> toSlopeFrame(const ModelArgs<Real>& a, const Vec3<Real>& v, Real& length) {
        using std::sqrt;
        Real k = sqrt(a[kGamma] - 1);
        Real x = k * a[kAlphaX] * v.x, y = k * a[kAlphaY] * v.y;
        length = sqrt(x * x + y * y + v.z * v.z);
        return {x / length, y / length, v.z / length};
    }
};

std::array<double, 2> equivalentAlphas(const ModelArgs<double>& a) { return {a[kAlphaX], a[kAlphaY]}; }

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_StudentT() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 6, "student_t",
                                         "Student's t-distribution of slopes (Ribardiere et al. 2017)");
        e.canonical = {{"alpha_x", ValueType::Float, kMinAlpha},
                       {"alpha_y", ValueType::Float, kMinAlpha},
                       {"gamma", ValueType::Float, 1.5, 1e4, "g", 2}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlphaX, kAlphaY}}, {"gamma", ValueType::Float, {kGamma}}}},
                   ModelForm{{{"alpha_x", ValueType::Float, {kAlphaX}},
                              {"alpha_y", ValueType::Float, {kAlphaY}},
                              {"gamma", ValueType::Float, {kGamma}}}}};
        e.shapeInvariant = true;
        e.tabulatedLambda = true;
        e.visibleNormals = true;
        e.lambdaShapeError = [](const std::vector<double>& shape) -> std::string {
            if (shape.at(0) > 1.5) return "";
            return "its Smith Lambda needs gamma > 1.5 (at 1.5 the mean slope and Lambda are infinite)";
        };
        e.tableShapeParams = {kGamma};
        e.equivalentAlphas = equivalentAlphas;
        e.argsAtAlpha = [](double alpha, const std::vector<double>& shape) {
            ModelArgs<double> a;
            a.set(kAlphaX, alpha);
            a.set(kAlphaY, alpha);
            a.set(kGamma, shape.at(0));
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) {
            return fmt::format("alpha=({:.6g},{:.6g}) gamma={:.6g}", a[kAlphaX], a[kAlphaY], a[kGamma]);
        };
        e.examples = {{"student_t", "input alpha = 0.3; input gamma = 3;", "student_t(alpha, gamma)", ""},
                      {"student_t_aniso", "input alpha_x = 0.05; input alpha_y = 0.5;",
                       "student_t(alpha_x = alpha_x, alpha_y = alpha_y, gamma = 1.8)", ""}};
        e.hardCases = {
            {"hcc_student_t_gamma_min", "ndf = student_t(0.3, 1.5); masking = cook_torrance;"},
            {"hcc_student_t_gamma_max", "ndf = student_t(0.3, 1e4); masking = none; fresnel = schlick(0.04);"},
            {"hcc_student_t_alpha_min", "ndf = student_t(1e-4, 2); masking = neumann; fresnel = dielectric(1.5);"},
            {"hcc_student_t_aniso", "ndf = student_t(alpha_x = 1, alpha_y = 1e-4, gamma = 1.6); masking = kelemen;"},
            {"hcc_student_t_smith_heavy", "ndf = student_t(alpha_x = 1, alpha_y = 1e-3, gamma = 1.55); "
                                          "masking = smith_height_direction_correlated;"},
            {"hcc_student_t_smith_beckmann_like", "ndf = student_t(1e-3, 1e4); masking = smith_separable; "
                                                  "fresnel = dielectric(1.5);"},
        };
        e.formulas = makeFormulas<NdfFormulas, StudentTFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
