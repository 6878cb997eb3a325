// gtr: the generalized Trowbridge-Reitz NDF of Burley 2012,
// c / (1 + (alpha^2 - 1) mz^2)^gamma. gamma = 2 is GGX and gamma = 1 Berry's
// distribution. No closed-form Smith Lambda for a general gamma, and not
// shape-invariant: Lambda is tabulated in (a, alpha) per constant gamma.
#include "QuadMath.h"
#include "Immortal.h"
#include "LambdaTable.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

#include <algorithm>

namespace facet::models {
namespace {

constexpr int kAlpha = 0, kGamma = 1;
constexpr double kMaxTabulatedGamma = 10;  // with a Smith masking (lambdaShapeError)

// expm1(y)/y, continuous through y = 0 (where it is 1).
template <typename Real>
Real expm1OverX(Real y) {
    using std::expm1;
    if (y == 0) return 1;
    return expm1(y) / y;
}

// log(expm1(y)/y) without overflow for large y (the normalization at large
// gamma: expm1((1 - gamma) ln a^2) overflows long before the normalized D
// does).
template <typename Real>
Real logExpm1OverX(Real y) {
    using std::expm1; using std::log;
    if (y > 1) return y + log(-expm1(-y)) - log(y);
    return log(expm1OverX(y));
}

template <typename Real>
struct GtrFormulas final : NdfFormulas<Real> {
    // c / (1 + (a^2 - 1) mz^2)^gamma with c = (g-1)(a^2-1) / (pi (1 - (a^2)^(1-g))),
    // rewritten as c = phi(L) / (pi phi((1-g) L)), L = ln a^2,
    // phi(y) = expm1(y)/y, which is exact at the limits g = 1 and a = 1.
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp; using std::expm1; using std::log; using std::log1p;
        Real gamma = a[kGamma];
        Real x2 = m.x * m.x, y2 = m.y * m.y, z2 = m.z * m.z;
        Real a2 = sq(a[kAlpha]);
        Real L = log(a2);
        // In log form: for large gamma, phi((1-g) L) and t^gamma overflow or
        // underflow while their ratio is moderate.
        Real yy = (1 - gamma) * L;
        Real logD;
        if (yy > 1) {
            // log phi(yy) = yy + log(-expm1(-yy)) - log(yy), and yy - gamma log t
            // = -L - gamma log(t / a^2) with t / a^2 = 1 + s2 (1 - a^2) / a^2:
            // the two terms of size gamma L cancel analytically, not in rounding
            // (at the peak the exponent is then exact for any gamma).
            logD = logExpm1OverX(L) - L - log(-expm1(-yy)) + log(yy) - gamma * log1p((x2 + y2) * ((1 - a2) / a2));
        } else {
            Real t = a2 * z2 + x2 + y2;  // = 1 + (a^2 - 1) mz^2 for a unit m
            logD = logExpm1OverX(L) - logExpm1OverX(yy) - gamma * log(t);
        }
        return exp(logD) / kPi<Real>;
    }
    // The tabulated (n.v) Lambda(v) of the material's gamma at its alpha.
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "gtr"));
        return Real(tabulatedCosLambda(self, {double(a[kGamma])}, double(smithProjection(a[kAlpha], a[kAlpha], v)),
                                       double(v.z), double(a[kAlpha])));
    }
    // Burley 2012's inversion, in s = sin^2 theta: the density of D(m) (n.m)
    // in s is proportional to (1 + b s)^(-gamma), b = 1/a^2 - 1, whose CDF
    // inverts to ln(1 + b s) = -L g, L = ln a^2, k = (gamma - 1) L,
    // g = log1p(u expm1(k)) / k (g = u at k = 0: gamma = 1 or a = 1), so
    // s = expm1(-L g) / expm1(-L) (s = u at a = 1).
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::exp; using std::expm1; using std::log; using std::log1p;
        Real L = 2 * log(a[kAlpha]), k = (a[kGamma] - 1) * L;
        Real g = u1;
        if (k > 30) g = (k + log(u1 + (1 - u1) * exp(-k))) / k;  // expm1(k) would overflow for large gamma
        else if (k != 0) g = log1p(u1 * expm1(k)) / k;
        Real s = L == 0 ? u1 : expm1(-L * g) / expm1(-L);
        return normalFromPolar(s, u2);
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Gtr() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 3, "gtr", "generalized Trowbridge-Reitz (Burley 2012)");
        e.canonical = {{"alpha", ValueType::Float, kMinAlpha}, {"gamma", ValueType::Float, 0, INFINITY, "g", 2}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlpha}}, {"gamma", ValueType::Float, {kGamma}}}}};
        e.tabulatedLambda = true;
        // Near alpha = 1 the lobe (1 + b sin^2)^-gamma, b = 1/alpha^2 - 1,
        // changes over b ~ 1/gamma: rows with s = 2 gamma (at least 4, which
        // small gammas need too). Across mid-roughness rows Lambda changes
        // faster as gamma grows (rows 1/8 apart: 2e-7 at gamma = 5, 1.4e-6
        // at 10), so beyond 5 they are 1/16 apart (2.3e-7 at 10).
        e.lambdaRows = [](const std::vector<double>& shape) {
            double gamma = shape.at(0);
            return LambdaRows{kMinAlpha, 1, std::max(4.0, 2 * gamma), gamma > 5 ? 1.0 / 16 : 1.0 / 8};
        };
        e.lambdaShapeError = [](const std::vector<double>& shape) -> std::string {
            if (shape.at(0) <= kMaxTabulatedGamma) return "";
            return fmt::format("its Smith Lambda is tabulated for gamma <= {} only, got {}", kMaxTabulatedGamma,
                               shape.at(0));
        };
        e.tableShapeParams = {kGamma};
        e.equivalentAlphas = [](const ModelArgs<double>& a) { return std::array<double, 2>{a[kAlpha], a[kAlpha]}; };
        e.argsAtAlpha = [](double alpha, const std::vector<double>& shape) {
            ModelArgs<double> a;
            a.set(kAlpha, alpha);
            a.set(kGamma, shape.at(0));
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) {
            return fmt::format("alpha={:.6g} gamma={:.6g}", a[kAlpha], a[kGamma]);
        };
        // The second example's constant gamma admits the Smith maskings.
        e.examples = {{"gtr", "input alpha = 0.3; input gamma = 1.5;", "gtr(alpha, gamma)"},
                      {"gtr_g1p5", "input alpha = 0.3;", "gtr(alpha, 1.5)"}};
        e.hardCases = {
            {"hcc_gtr_g1_a1", "ndf = gtr(1, 1); masking = cook_torrance;"},
            {"hcc_gtr_g1", "ndf = gtr(0.1, 1); masking = schlick_smith(0.125); fresnel = schlick(0.04);"},
            {"hcc_gtr_a1", "ndf = gtr(1, 2.5); masking = kelemen;"},
            {"hcc_gtr_near_g1", "ndf = gtr(0.3, 1.0000001); masking = neumann;"},
            {"hcc_gtr_near_a1", "ndf = gtr(0.9999999, 2); masking = implicit;"},
            {"hcc_gtr_g0", "ndf = gtr(0.5, 0); masking = none;"},
            {"hcc_gtr_ranged", "input alpha = 0.5 in 0 .. 2; input gamma = 1 in 0 .. 10; ndf = gtr(alpha, gamma); "
                               "masking = cook_torrance;"},
            {"hcc_gtr_smith_g0", "input alpha = 0.5 in 0 .. 2; ndf = gtr(alpha, 0); masking = smith_height_correlated;"},
            {"hcc_gtr_smith_g10", "input alpha = 0.5 in 0 .. 3; ndf = gtr(alpha, 10); "
                                 "masking = smith_direction_correlated;"},
        };
        e.formulas = makeFormulas<NdfFormulas, GtrFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
