// abc: the ABC distribution (Church, Takacs & Leonard 1989) in the
// microfacet form of Low, Kronander, Ynnerman & Unger 2012 ("BRDF models
// for accurate and efficient rendering of glossy surfaces", ACM TOG 31(1),
// article 9):
//   D(m) = A / (1 + b (1 - mz))^c,
// with A the normalization Int D(m) mz dm = 1 (the paper fits A as a free
// scale; here it is fixed so that D is a microfacet distribution). In x = 1
// - mz and t = 1 + b x it is elementary:
//   1 / A = 2 pi N(b, c) / b^2,  N(b, c) = Int_1^(1+b) (1 + b - t) t^-c dt.
// Isotropic and not shape-invariant: its Smith Lambda is tabulated in (a,
// alpha) per constant c, alpha the equivalent roughness below. NDF sampling inverts
// the polar CDF of D(m) mz, also elementary in t but with no closed-form
// inverse, by a bracketed Newton iteration in v = ln t.
#include "QuadMath.h"
#include "Immortal.h"
#include "LambdaTable.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace facet::models {
namespace {

constexpr int kB = 0, kC = 1;
constexpr int kLogNorm = 0;  // derived: ln A
// b below 1/8 would leave N(b, c) to a difference of two terms b / N ~ 1/b
// times larger (the uniform limit b = 0 is 0/0); b = 2e8 is alpha = 1e-4
// (equivalentAlphas). c = 0 is the uniform distribution.
constexpr double kMinB = 0.125, kMaxB = 2e8, kMaxC = 10;

// expm1(y)/y, 1 at y = 0.
template <typename Real>
Real phi(Real y) {
    using std::expm1;
    return y == 0 ? Real(1) : expm1(y) / y;
}

// N(b, c) = Int_1^(1+b) (1 + b - t) t^-c dt, L = ln(1 + b):
//   ((1 + b) L phi((1 - c) L) - b) / (2 - c)   (from Int t^-c and Int t^(1-c))
//   (L phi((2 - c) L) - b) / (1 - c)           (the same, regrouped),
// the first away from c = 2, the second away from c = 1 (each exact at the
// other's pole, where a logarithm appears).
template <typename Real>
Real abcMass(Real b, Real c) {
    using std::fabs; using std::log1p;
    Real L = log1p(b);
    if (fabs(c - 2) > Real(0.5)) return ((1 + b) * L * phi((1 - c) * L) - b) / (2 - c);
    return (L * phi((2 - c) * L) - b) / (1 - c);
}

// alpha = 1 / sqrt(1 + b/2): for c = 2 the peak of D is GGX's at that
// alpha (1 + b x ~ 1 + (b/2) sin^2 against GGX's 1 + (1/alpha^2 - 1)
// sin^2), and b = 0 would be GGX's alpha = 1, the uniform distribution.
double equivalentAlpha(double b) { return 1 / std::sqrt(1 + b / 2); }

template <typename Real>
struct AbcFormulas final : NdfFormulas<Real> {
    // ln D = ln A - c ln(1 + b x), x = 1 - mz = (mx^2 + my^2) / (1 + mz)
    // (no cancellation near the pole, where a large b magnifies x).
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp; using std::log1p;
        Real x = (m.x * m.x + m.y * m.y) / (1 + m.z);
        return exp(a.derived[kLogNorm] - a[kC] * log1p(a[kB] * x));
    }
    void derive(ModelArgs<Real>& a) const override {
        using std::log;
        Real b = a[kB];
        a.derived[kLogNorm] = 2 * log(b) - log(2 * kPi<Real> * abcMass(b, a[kC]));
    }
    // The tabulated (n.v) Lambda(v) of the material's c at its equivalent
    // roughness.
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "abc"));
        double alpha = equivalentAlpha(double(a[kB]));
        return Real(tabulatedCosLambda(self, {double(a[kC])}, double(smithProjection(Real(alpha), Real(alpha), v)),
                                       double(v.z), alpha));
    }
    // The mass of D(m) mz below x = 1 - mz is, times b^2 / (2 pi A),
    //   Q = (b - (t - 1)) ln(t) phi((1 - c) ln t) + N(t - 1, c),  t = 1 + b x
    // (Int_1^t (1 + b - s) s^-c ds split at (1 + b - t) + (t - s)), with
    // dQ/dv = (b - (t - 1)) t^(1 - c) in v = ln t; Q(ln(1 + b)) = N(b, c).
    // Bracket: without its falling factor 1 + b - t the density is t^(1-c)
    // dv, whose CDF G(v) = v phi((1 - c) v) / (L phi((1 - c) L)), L = ln(1 +
    // b), inverts in closed form; the factor only moves mass to smaller v,
    // so the root lies below G^-1(u1), and (the factor being at most b)
    // above G^-1(u1 r), r = N(b, c) / (b L phi((1 - c) L)) <= 1.
    // Above the median the mass beyond t, in l = ln((1 + b)/t) = L - v,
    //   R = Int_t^(1+b) (1 + b - s) s^-c ds
    //     = (1 + b)^(2-c) l (phi(-(1 - c) l) - phi(-(2 - c) l)),
    // solves R(l) = (1 - u1) N(b, c) instead (dR/dl = Q'), so that mz =
    // (1 + b) (1 - e^-l) / b keeps its relative accuracy toward the horizon.
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::cos; using std::exp; using std::expm1; using std::log1p; using std::sin; using std::sqrt;
        Real b = a[kB], c = a[kC], L = log1p(b), k = (1 - c) * L;
        auto cdf = [&](Real v) { return (b - expm1(v)) * v * phi((1 - c) * v) + abcMass(expm1(v), c); };
        auto pdf = [&](Real v) { return (b - expm1(v)) * exp((1 - c) * v); };
        auto inverseG = [&](Real u) { return k == 0 ? u * L : L * log1p(u * expm1(k)) / k; };
        Real mass = abcMass(b, c), r = mass / (b * L * phi(k));
        Real hi = inverseG(u1), lo = inverseG(u1 * r);
        hi = hi < L ? hi : L;
        Real x, mz;
        if (u1 <= Real(0.5)) {
            Real d = expm1(invertIncreasing(cdf, pdf, u1 * mass, lo, hi));
            x = d < b ? d / b : Real(1), mz = d < b ? (b - d) / b : Real(0);
        } else {
            Real top = exp((2 - c) * L);
            auto upper = [&](Real l) { return top * l * (phi(-(1 - c) * l) - phi(-(2 - c) * l)); };
            auto upperPdf = [&](Real l) { return -(1 + b) * expm1(-l) * exp((1 - c) * (L - l)); };
            Real l = invertIncreasing(upper, upperPdf, (1 - u1) * mass, L - hi, L - lo);
            x = expm1(L - l) / b, mz = -(1 + b) * expm1(-l) / b;
        }
        Real s = sqrt(x * (2 - x)), ph = 2 * kPi<Real> * u2;
        return {s * cos(ph), s * sin(ph), mz};
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Abc() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 8, "abc", "ABC distribution (Church et al. 1989; Low et al. 2012)");
        e.canonical = {{"b", ValueType::Float, kMinB, kMaxB}, {"c", ValueType::Float, 0, kMaxC, "c", 2}};
        e.forms = {ModelForm{{{"b", ValueType::Float, {kB}}, {"c", ValueType::Float, {kC}}}}};
        e.tableShapeParams = {kC};
        e.tabulatedLambda = true;
        // The lobe (1 + b x)^-c falls over b ~ 1/c near alpha = 1: s = 2c (at
        // least 4) keeps the table within 1e-6 (1.1e-7 at c = 10); its rows
        // end where b clamps.
        e.lambdaRows = [](const std::vector<double>& shape) {
            return LambdaRows{equivalentAlpha(kMaxB), equivalentAlpha(kMinB), std::max(4.0, 2 * shape.at(0))};
        };
        e.equivalentAlphas = [](const ModelArgs<double>& a) {
            double alpha = equivalentAlpha(a[kB]);
            return std::array<double, 2>{alpha, alpha};
        };
        e.argsAtAlpha = [](double alpha, const std::vector<double>& shape) {
            ModelArgs<double> a;
            a.set(kB, std::clamp(2 * (1 / (alpha * alpha) - 1), kMinB, kMaxB));
            a.set(kC, shape.at(0));
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) { return fmt::format("b={:.6g} c={:.6g}", a[kB], a[kC]); };
        // The second example's constant c admits the Smith maskings.
        e.examples = {{"abc", "input b = 20; input c = 1.5;", "abc(b, c)", ""},
                      {"abc_c1p5", "input b = 20;", "abc(b, 1.5)", ""}};
        e.hardCases = {
            {"hcc_abc_b_min", "ndf = abc(0.125, 2); masking = cook_torrance;"},
            {"hcc_abc_b_max", "ndf = abc(2e8, 2); masking = neumann; fresnel = dielectric(1.5);"},
            {"hcc_abc_c0", "ndf = abc(50, 0); masking = none;"},
            {"hcc_abc_c_max", "ndf = abc(2e8, 10); masking = kelemen; fresnel = schlick(0.04);"},
            {"hcc_abc_c1", "ndf = abc(1000, 1); masking = schlick_smith(0.125);"},
            {"hcc_abc_near_c2", "ndf = abc(3, 2.0000001); masking = implicit;"},
            {"hcc_abc_smith_c_max", "ndf = abc(2e8, 10); masking = smith_height_correlated;"},
            {"hcc_abc_smith_b_min", "input b = 1 in 0 .. 3; ndf = abc(b, 0); masking = smith_separable; "
                                    "fresnel = dielectric(1.5);"},
            {"hcc_abc_ranged", "input b = 10 in 0 .. 1e9; input c = 1 in -1 .. 20; ndf = abc(b, c); "
                               "masking = cook_torrance;"},
        };
        e.formulas = makeFormulas<NdfFormulas, AbcFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
