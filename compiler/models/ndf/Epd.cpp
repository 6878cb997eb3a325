// epd: the exponential power distribution of slopes of Holzschuch and
// Pacanowski 2017 ("A two-scale microfacet reflectance model combining
// reflection and diffraction", ACM TOG 36(4), article 66, eq. 34-38),
// isotropic or anisotropic:
//   D(m) = p exp(-e^p) / (pi Gamma(1/p) ax ay mz^4),
//   e = (mx^2/ax^2 + my^2/ay^2) / mz^2,
// normalized in closed form for any p > 0 (the squared standard slope u has
// the density exp(-u^p) / Gamma(1 + 1/p)). p = 1 is Beckmann; a small p has
// a sharp peak and a long tail, a large p flattens toward a uniform disk of
// slopes. Shape-invariant: its Smith Lambda (finite for every p, all the
// slope moments are) is tabulated per constant p (LambdaTable.h). NDF
// sampling inverts the radial CDF: y = u^p is Gamma(1/p)-distributed, so
// P(1/p, y) = u1, solved by a bracketed Newton iteration on log y over the
// regularized incomplete gamma function (series below 1/p + 1, Legendre's
// continued fraction above), the paper's eq. 49-50. No visible-normal
// sampler: that would need the visible slope CDF, which has no closed form.
#include "QuadMath.h"
#include "Immortal.h"
#include "LambdaTable.h"
#include "models/ModelMath.h"
#include "models/NdfSampling.h"

#include <fmt/format.h>

#include <limits>

namespace facet::models {
namespace {

constexpr int kP = 2;         // after alpha_x, alpha_y (kAlphaX, kAlphaY)
constexpr int kLogNorm = 0;   // derived: log(p / (pi Gamma(1/p)))
constexpr double kMinP = 0.25, kMaxP = 4;

// log P(a, y) and log Q(a, y), the regularized incomplete gamma functions,
// and log(y^a e^-y / Gamma(a)) (y times the Gamma(a) density), at y = e^v,
// given lgamma(a). The series y^a e^-y / Gamma(a + 1) Sum y^n / ((a + 1)
// ... (a + n)) gives P below y = a + 1, Legendre's continued fraction gives
// Q above it, each to the resolution of Real; the other from its
// complement (at least about 0.1 there, so nothing cancels).
template <typename Real>
struct GammaTails {
    Real logP, logQ, logPre;
};

template <typename Real>
GammaTails<Real> gammaTails(Real a, Real lgammaA, Real v) {
    using std::exp; using std::fabs; using std::log; using std::log1p;
    const Real eps = std::numeric_limits<Real>::epsilon();
    Real y = exp(v);
    GammaTails<Real> t;
    t.logPre = a * v - y - lgammaA;
    if (y < a + 1) {
        Real term = 1, sum = 1;
        for (int n = 1; n < 2000 && term > eps * sum; ++n) {
            term *= y / (a + n);
            sum += term;
        }
        t.logP = t.logPre + log(sum / a);
        t.logQ = log1p(-exp(t.logP));
    } else {
        t.logQ = t.logPre + log(upperGammaFraction(a, y));
        t.logP = log1p(-exp(t.logQ));
    }
    return t;
}

template <typename Real>
struct EpdFormulas final : NdfFormulas<Real> {
    // In log form: mz^4 underflows toward the horizon while e^p overflows,
    // and Gamma(1/p) is large for a small p. log mz^4 is 4 log|mz|, so that
    // a tiny mz^2 cannot underflow.
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::abs; using std::exp; using std::log;
        Real ax = a[kAlphaX], ay = a[kAlphaY], p = a[kP];
        Real s = m.x * m.x / sq(ax) + m.y * m.y / sq(ay);
        Real logZ = log(abs(m.z));
        Real tail = s > 0 ? exp(p * (log(s) - 2 * logZ)) : Real(0);
        return exp(a.derived[kLogNorm] - tail - 4 * logZ - log(ax) - log(ay));
    }
    void derive(ModelArgs<Real>& a) const override {
        using std::lgamma; using std::log;
        Real p = a[kP];
        a.derived[kLogNorm] = log(p / kPi<Real>) - lgamma(1 / p);
    }
    // The tabulated (n.v) Lambda(v) of the material's p (stretched: a
    // depends on alpha(v) only through proj).
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "epd"));
        return Real(tabulatedCosLambda(self, {double(a[kP])}, double(smithProjection(a[kAlphaX], a[kAlphaY], v)),
                                       double(v.z)));
    }
    // The squared standard slope is u = y^(1/p), y ~ Gamma(1/p): y from
    // P(1/p, y) = u1 below the median (Newton on log P against log y), from
    // Q(1/p, y) = 1 - u1 above it (on -log Q), so that both tails keep their
    // relative accuracy. Brackets: P(a, y) <= y^a / Gamma(a + 1) puts the
    // root above (log u1 + lgamma(a + 1)) / a; the median is below a + 1;
    // Q(a, y) < 1 - u1 at y = 2 ln(1/(1 - u1)) + 4 a + 10 for a <= 4.
    Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const override {
        using std::exp; using std::lgamma; using std::log; using std::log1p;
        if (!(u1 > 0)) return {0, 0, 1};
        Real shape = 1 / a[kP], lgA = lgamma(shape), lgA1 = lgA + log(shape);
        bool lower = u1 < Real(0.5);
        Real rest = 1 - u1;
        Real logTarget = lower ? log(u1) : -log(rest);
        // invertIncreasing asks for the pdf where it has just asked for the
        // cdf: both from one evaluation.
        Real lastV = std::numeric_limits<Real>::quiet_NaN();
        GammaTails<Real> last{};
        auto tails = [&](Real v) -> const GammaTails<Real>& {
            if (!(v == lastV)) last = gammaTails(shape, lgA, v), lastV = v;
            return last;
        };
        auto cdf = [&](Real v) { return lower ? tails(v).logP : -tails(v).logQ; };
        auto pdf = [&](Real v) {
            const GammaTails<Real>& t = tails(v);
            return exp(t.logPre - (lower ? t.logP : t.logQ));
        };
        Real lo = ((lower ? log(u1) : log(Real(0.5))) + lgA1) / shape - 2;
        Real hi = lower ? log(shape + 1) : log(-2 * log(rest) + 4 * shape + 10);
        Real v = invertIncreasing(cdf, pdf, logTarget, lo, hi);
        return stretchedSlopeNormal(a[kAlphaX], a[kAlphaY], exp(shape * v), u2);
    }
};

std::array<double, 2> equivalentAlphas(const ModelArgs<double>& a) { return {a[kAlphaX], a[kAlphaY]}; }

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Epd() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 7, "epd",
                                         "exponential power distribution of slopes (Holzschuch & Pacanowski 2017)");
        e.canonical = {{"alpha_x", ValueType::Float, kMinAlpha},
                       {"alpha_y", ValueType::Float, kMinAlpha},
                       {"p", ValueType::Float, kMinP, kMaxP, "p", 0.7}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlphaX, kAlphaY}}, {"p", ValueType::Float, {kP}}}},
                   ModelForm{{{"alpha_x", ValueType::Float, {kAlphaX}},
                              {"alpha_y", ValueType::Float, {kAlphaY}},
                              {"p", ValueType::Float, {kP}}}}};
        e.shapeInvariant = true;
        e.tabulatedLambda = true;
        e.tableShapeParams = {kP};
        e.equivalentAlphas = equivalentAlphas;
        e.argsAtAlpha = [](double alpha, const std::vector<double>& shape) {
            ModelArgs<double> a;
            a.set(kAlphaX, alpha);
            a.set(kAlphaY, alpha);
            a.set(kP, shape.at(0));
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) {
            return fmt::format("alpha=({:.6g},{:.6g}) p={:.6g}", a[kAlphaX], a[kAlphaY], a[kP]);
        };
        // The isotropic example with p as an input is sparse: the Fresnel
        // terms and the non-Smith maskings do not read p, so the
        // representative ones suffice (each combination costs the hard-case
        // test about a second). The anisotropic one, with a constant p, meets
        // every masking (the Smith forms through the Lambda table) and Fresnel
        // model.
        e.examples = {{"epd", "input alpha = 0.3; input p = 0.6;", "epd(alpha, p)", "", true},
                      {"epd_aniso", "input alpha_x = 0.05; input alpha_y = 0.5;",
                       "epd(alpha_x = alpha_x, alpha_y = alpha_y, p = 1.7)", ""}};
        e.hardCases = {
            {"hcc_epd_p_min", "ndf = epd(0.3, 0.25); masking = smith_height_correlated;"},
            {"hcc_epd_p_max", "ndf = epd(0.3, 4); masking = none; fresnel = schlick(0.04);"},
            {"hcc_epd_alpha_min", "ndf = epd(1e-4, 0.5); masking = neumann; fresnel = dielectric(1.5);"},
            {"hcc_epd_alpha_1", "ndf = epd(1, 0.25); masking = smith_separable;"},
            {"hcc_epd_aniso", "ndf = epd(alpha_x = 1, alpha_y = 1e-4, p = 4); masking = smith_height_correlated;"},
        };
        e.formulas = makeFormulas<NdfFormulas, EpdFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
