// sgd: the shifted gamma distribution of Bagher, Soler & Holzschuch 2012
// ("Accurate fitting of measured reflectances using a Shifted Gamma
// micro-facet distribution", Computer Graphics Forum 31(4)), isotropic:
//   D(m) = exp(-w) w^-p / (pi N cos^4 theta),  w = alpha + tan^2 theta / alpha,
// a gamma density of w shifted to start at alpha (the paper fits a free
// scale K in front; here it is the normalization). With dw = d(tan^2)/alpha,
// Int D(m) mz dm = pi Int P22 d(tan^2) / pi gives
//   N = alpha Gamma(1 - p, alpha),
// the upper incomplete gamma function, finite for every p at alpha > 0.
// p = 0 is Beckmann with alpha_B^2 = alpha; p > 0 sharpens the peak (the
// factor w^-p, GGX-like for small alpha). Not shape-invariant: its Smith
// Lambda is tabulated in (a, alpha) per constant p, alpha the equivalent
// roughness below. NDF sampling draws w from its truncated gamma density, Gamma(1 -
// p, w) = (1 - u1) Gamma(1 - p, alpha), by a bracketed Newton iteration.
#include "QuadMath.h"
#include "Immortal.h"
#include "LambdaTable.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace facet::models {
namespace {

constexpr int kAlpha = 0, kP = 1;
constexpr int kLogNorm = 0;    // derived: -ln(pi N)
constexpr int kLogGammaA = 1;  // derived: ln Gamma(1 - p, alpha)
// p in [0, 2]: the peak stays at the pole (p >= 0) and the incomplete gamma
// function's order 1 - p in [-1, 1]. alpha in [2e-4, 10] keeps the
// equivalent roughness alpha / sqrt(alpha + p) within [1.4e-4, 3].
constexpr double kMinAlpha = 2e-4, kMaxAlpha = 10, kMaxP = 2;

// ln Gamma(a, x) for a in [-1, 1], x > 0. From x = 2 up, Legendre's
// continued fraction (upperGammaFraction). Below,
// Gamma(a, 2) plus Int_x^2 t^(a-1) e^-t dt, the exponential's series
// integrated term by term: sum (-1)^n / n! (2^(a+n) - x^(a+n)) / (a + n),
// whose first two terms (where a + n may be 0 or negative) are taken as
// 2^k L phi(-k L), L = ln(2/x), phi(y) = expm1(y)/y.
template <typename Real>
Real logGammaByFraction(Real a, Real y) {
    using std::log;
    return a * log(y) - y + log(upperGammaFraction(a, y));
}

// logGammaAt2 = ln Gamma(a, 2), which a caller evaluating many x keeps.
template <typename Real>
Real logUpperGamma(Real a, Real x, Real logGammaAt2) {
    using std::exp; using std::expm1; using std::fabs; using std::log; using std::pow;
    const Real eps = std::numeric_limits<Real>::epsilon();
    const Real x0 = 2;
    if (x >= x0) return logGammaByFraction(a, x);
    Real L = log(x0 / x);
    auto phi = [](Real y) { return y == 0 ? Real(1) : expm1(y) / y; };
    Real sum = pow(x0, a) * L * phi(-a * L) - pow(x0, a + 1) * L * phi(-(a + 1) * L);
    Real termX0 = pow(x0, a + 1), termX = pow(x, a + 1), fact = 1;
    for (int n = 2; n < 200; ++n) {
        termX0 *= x0, termX *= x, fact *= n;
        Real t = (termX0 - termX) / ((a + n) * fact);
        sum += n % 2 ? -t : t;
        if (fabs(t) <= eps * fabs(sum)) break;
    }
    return log(exp(logGammaAt2) + sum);
}

// The Beckmann-sense roughness: ln P22 falls like -tan^2 (alpha + p) /
// alpha^2 at the pole, Beckmann's like -tan^2 / alpha_B^2.
double equivalentAlpha(double alpha, double p) { return alpha / std::sqrt(alpha + p); }

template <typename Real>
struct SgdFormulas final : NdfFormulas<Real> {
    // ln D = -w - p ln w - ln(pi N) - 4 ln mz: exp(-w) and cos^-4 do not
    // overflow toward the horizon, where tan^2 grows without bound (beyond
    // w = 1e30 D is 0 in every type, and p ln w would be 0 inf at p = 0
    // once tan^2 overflows).
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::exp; using std::log;
        Real alpha = a[kAlpha], p = a[kP];
        Real w = alpha + (m.x * m.x + m.y * m.y) / (m.z * m.z) / alpha;
        if (!(w <= Real(1e30))) return 0;
        return exp(a.derived[kLogNorm] - w - p * log(w) - 4 * log(m.z));
    }
    void derive(ModelArgs<Real>& a) const override {
        using std::log;
        Real alpha = a[kAlpha];
        a.derived[kLogGammaA] = logUpperGamma(1 - a[kP], alpha, logGammaByFraction(1 - a[kP], Real(2)));
        a.derived[kLogNorm] = -log(kPi<Real> * alpha) - a.derived[kLogGammaA];
    }
    // The tabulated (n.v) Lambda(v) of the material's p at its equivalent
    // roughness.
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "sgd"));
        double alpha = equivalentAlpha(double(a[kAlpha]), double(a[kP]));
        return Real(tabulatedCosLambda(self, {double(a[kP])}, double(smithProjection(Real(alpha), Real(alpha), v)),
                                       double(v.z), alpha));
    }
    // w from ln Gamma(1 - p, w) = ln(1 - u1) + ln Gamma(1 - p, alpha), by
    // Newton's method on -ln Gamma(1 - p, e^v) (slope w^(1 - p) e^-w /
    // Gamma(1 - p, w)). Brackets: the density is at most alpha^-p e^-alpha,
    // so the mass below w is at most (w - alpha) times that (w above
    // alpha + u1 Gamma(1 - p, alpha) alpha^p e^alpha); for w >= 1, Gamma(1 -
    // p, w) <= w^-p e^-w <= e^-w (w below max(1, T) + 1, T = -ln((1 - u1)
    // Gamma(1 - p, alpha))). tan^2 theta = alpha (w - alpha).
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::cos; using std::exp; using std::log; using std::log1p; using std::sin; using std::sqrt;
        if (!(u1 > 0)) return {0, 0, 1};  // w = alpha exactly, not to the resolution of ln w
        Real alpha = a[kAlpha], p = a[kP], order = 1 - p, logGammaA = a.derived[kLogGammaA];
        Real target = logGammaA + log1p(-u1);
        Real logGammaAt2 = logGammaByFraction(order, Real(2));
        // invertIncreasing asks for the pdf where it has just asked for the
        // cdf: one incomplete gamma function for both.
        Real lastV = std::numeric_limits<Real>::quiet_NaN(), lastLog = 0;
        auto logGamma = [&](Real v) {
            if (!(v == lastV)) lastLog = logUpperGamma(order, exp(v), logGammaAt2), lastV = v;
            return lastLog;
        };
        auto cdf = [&](Real v) { return -logGamma(v); };
        auto pdf = [&](Real v) { return exp(order * v - exp(v) - logGamma(v)); };
        Real head = alpha + u1 * exp(logGammaA + p * log(alpha) + alpha);
        Real tail = std::max({Real(1), alpha, -target}) + 1;
        // Below the median from the lower bracket, the first-order root;
        // above from the tail's asymptote Gamma(a, w) ~ w^-p e^-w.
        Real lo = log(head), hi = log(tail), T = -target;
        Real tailStart = T - p * log(T > 1 ? T : Real(1));
        Real w = exp(invertIncreasing(cdf, pdf, -target, lo, hi,
                                      u1 < Real(0.5) ? lo : log(tailStart > 0 ? tailStart : head)));
        Real tan2 = alpha * (w > alpha ? w - alpha : Real(0));
        Real c = 1 / sqrt(1 + tan2), s = sqrt(tan2) * c, ph = 2 * kPi<Real> * u2;
        return {s * cos(ph), s * sin(ph), c};
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Sgd() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 9, "sgd",
                                         "shifted gamma distribution (Bagher, Soler & Holzschuch 2012)");
        e.canonical = {{"alpha", ValueType::Float, kMinAlpha, kMaxAlpha}, {"p", ValueType::Float, 0, kMaxP, "p", 0.6}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlpha}}, {"p", ValueType::Float, {kP}}}}};
        e.tableShapeParams = {kP};
        e.tabulatedLambda = true;
        // The rows span the equivalent roughnesses of alpha in [kMinAlpha,
        // kMaxAlpha] (to 3.2 at p = 0); within 1e-6 with s = 4 (1e-7 for p
        // in [0, 2]).
        e.lambdaRows = [](const std::vector<double>& shape) {
            double p = shape.at(0);
            return LambdaRows{equivalentAlpha(kMinAlpha, p), equivalentAlpha(kMaxAlpha, p), 4};
        };
        e.equivalentAlphas = [](const ModelArgs<double>& a) {
            double alpha = equivalentAlpha(a[kAlpha], a[kP]);
            return std::array<double, 2>{alpha, alpha};
        };
        // The inverse: alpha^2 - q^2 alpha - q^2 p = 0 for the roughness q.
        e.argsAtAlpha = [](double q, const std::vector<double>& shape) {
            double p = shape.at(0), q2 = q * q;
            ModelArgs<double> a;
            a.set(kAlpha, std::clamp((q2 + std::sqrt(q2 * q2 + 4 * q2 * p)) / 2, kMinAlpha, kMaxAlpha));
            a.set(kP, p);
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) {
            return fmt::format("alpha={:.6g} p={:.6g}", a[kAlpha], a[kP]);
        };
        // The second example's constant p admits the Smith maskings.
        e.examples = {{"sgd", "input alpha = 0.1; input p = 0.6;", "sgd(alpha, p)", ""},
                      {"sgd_p0p6", "input alpha = 0.1;", "sgd(alpha, 0.6)", ""}};
        e.hardCases = {
            {"hcc_sgd_alpha_min", "ndf = sgd(2e-4, 2); masking = cook_torrance;"},
            {"hcc_sgd_alpha_min_p0", "ndf = sgd(2e-4, 0); masking = neumann; fresnel = dielectric(1.5);"},
            {"hcc_sgd_alpha_max", "ndf = sgd(10, 2); masking = kelemen; fresnel = schlick(0.04);"},
            {"hcc_sgd_p1", "ndf = sgd(0.05, 1); masking = schlick_smith(0.125);"},
            {"hcc_sgd_near_p1", "ndf = sgd(0.3, 1.0000001); masking = implicit;"},
            {"hcc_sgd_smith_alpha_min", "ndf = sgd(2e-4, 2); masking = smith_direction_correlated;"},
            {"hcc_sgd_smith_p0", "input alpha = 1 in 0 .. 20; ndf = sgd(alpha, 0); "
                                 "masking = smith_height_direction_correlated;"},
            {"hcc_sgd_ranged", "input alpha = 0.1 in 0 .. 20; input p = 1 in -1 .. 3; ndf = sgd(alpha, p); "
                               "masking = none;"},
        };
        e.formulas = makeFormulas<NdfFormulas, SgdFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
