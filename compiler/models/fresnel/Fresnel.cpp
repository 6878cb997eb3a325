// The Fresnel terms: none, Schlick's approximation (from f0 or from eta),
// and the exact unpolarized dielectric and conductor terms. The exact forms
// are the SPEC's formulas rearranged so that nothing cancels near eta = 1
// (F -> 0 exactly there) or at c -> 1 (s2 = 1 - c^2 comes from the
// directions' difference).
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"

#include <complex>

namespace facet::models {
namespace {

template <typename Real>
struct NoFresnel final : FresnelFormulas<Real> {
    Real F(const ModelArgs<Real>&, Real, Real, int) const override { return 1; }
    std::optional<Real> closedFormAverage(const ModelArgs<Real>&, int) const override { return Real(1); }
};

constexpr int kF0 = 0, kSchlickEta = 1;  // schlick: exactly one is given

template <typename Real>
struct SchlickFresnel final : FresnelFormulas<Real> {
    static Real f0(const ModelArgs<Real>& a, int ch) {
        if (a.given[kF0]) return a.channel(kF0, ch);
        Real eta = a.channel(kSchlickEta, ch);
        return sq((eta - 1) / (eta + 1));
    }
    Real F(const ModelArgs<Real>& a, Real c, Real s2, int ch) const override {
        using std::pow;
        Real r0 = f0(a, ch);
        Real q = s2 / (1 + c);  // 1 - c
        return r0 + (1 - r0) * pow(q, 5);
    }
    // 2 Int (f0 + (1 - f0)(1 - mu)^5) mu dmu = (20 f0 + 1)/21
    std::optional<Real> closedFormAverage(const ModelArgs<Real>& a, int ch) const override {
        Real r0 = a.channel(kF0, ch);
        if (!a.given[kF0]) {
            Real q = (a.channel(kSchlickEta, ch) - 1) / (a.channel(kSchlickEta, ch) + 1);
            r0 = q * q;
        }
        return (20 * r0 + 1) / 21;
    }
};

constexpr int kEta = 0, kK = 1;

template <typename Real>
struct DielectricFresnel final : FresnelFormulas<Real> {
    // g = eta cos(theta_t) = sqrt(eta^2 - sin^2) = sqrt(e + c^2), e = eta^2 - 1.
    // Snell: past sin^2 = eta^2 (g^2 <= 0) the light is totally reflected.
    // rs = (c - g)/(c + g) = -e / (c + g)^2          (c^2 - g^2 = -e)
    // rp = (eta^2 c - g)/(eta^2 c + g) = e ((eta^2 + 1) c^2 - 1) / (eta^2 c + g)^2
    //    = e (eta^2 c^2 - s2) / (eta^2 c + g)^2   (no cancellation as eta -> 0)
    // g^2 from whichever form loses less: eta^2 - s2 near normal incidence
    // (eta -> 0), e + c^2 near grazing and for eta -> 1.
    Real F(const ModelArgs<Real>& a, Real c, Real s2, int ch) const override {
        using std::abs; using std::sqrt;
        Real n = a.channel(kEta, ch);
        Real e = (n - 1) * (n + 1);
        Real g2 = n * n + s2 < abs(e) + c * c ? n * n - s2 : e + c * c;
        if (g2 <= 0) return 1;
        Real g = sqrt(g2), n2 = n * n;
        Real rs = -e / sq(c + g);
        Real rp = e * (n2 * (c * c) - s2) / sq(n2 * c + g);
        return (rs * rs + rp * rp) / 2;
    }
    // 1 - rs^2 = 4 c g / (c + g)^2 and 1 - rp^2 = 4 eta^2 c g / (eta^2 c + g)^2:
    // T = 2 c g (1 / (c + g)^2 + eta^2 / (eta^2 c + g)^2), every term
    // positive, so T keeps its relative precision where F -> 1 (grazing).
    Real transmittance(const ModelArgs<Real>& a, Real c, Real s2, int ch) const override {
        using std::abs; using std::sqrt;
        Real n = a.channel(kEta, ch);
        Real e = (n - 1) * (n + 1);
        Real g2 = n * n + s2 < abs(e) + c * c ? n * n - s2 : e + c * c;
        if (g2 <= 0 || c <= 0) return 0;
        Real g = sqrt(g2), n2 = n * n;
        return 2 * c * g * (1 / sq(c + g) + n2 / sq(n2 * c + g));
    }
    // g = eta cos(theta_t) from the refracted direction itself.
    Real pairTransmittance(const ModelArgs<Real>& a, Real c, Real ct, int ch) const override {
        Real n = a.channel(kEta, ch), n2 = n * n, g = n * ct;
        if (c <= 0 || !(g > 0)) return 0;
        return 2 * c * g * (1 / sq(c + g) + n2 / sq(n2 * c + g));
    }
};

template <typename Real>
struct ConductorFresnel final : FresnelFormulas<Real> {
    // Complex index N = eta + i k; the dielectric forms with complex
    // e = N^2 - 1 and g = N cos(theta_t) = sqrt(N^2 - sin^2) = sqrt(e + c^2)
    // (principal root: the transmitted wave decays into the metal).
    Real F(const ModelArgs<Real>& a, Real c, Real s2, int ch) const override {
        using std::abs; using std::norm; using std::sqrt;
        std::complex<Real> N(a.channel(kEta, ch), a.channel(kK, ch));
        std::complex<Real> e = (N - Real(1)) * (N + Real(1));
        std::complex<Real> N2 = N * N;
        std::complex<Real> g = sqrt(abs(N2) + s2 < abs(e) + c * c ? N2 - s2 : e + c * c);
        std::complex<Real> rs = -e / ((c + g) * (c + g));
        std::complex<Real> rp = e * (N2 * (c * c) - s2) / ((N2 * c + g) * (N2 * c + g));
        return (norm(rs) + norm(rp)) / 2;
    }
};

constexpr ValueType C = ValueType::Rgb;

}  // namespace

std::vector<const ModelInfo*> facetModels_fresnel_Fresnel() {
    static const FresnelEntry& none = immortal<FresnelEntry>([] {
        FresnelEntry e = makeEntry<FresnelEntry>(ModelSlot::Fresnel, 0, "none", "F = 1");
        e.examples = {{"none", "", "none"}};
        e.representative = true;
        e.formulas = makeFormulas<FresnelFormulas, NoFresnel>();
        return e;
    }());
    static const FresnelEntry& schlick = immortal<FresnelEntry>([] {
        FresnelEntry e = makeEntry<FresnelEntry>(ModelSlot::Fresnel, 1, "schlick", "Schlick 1994 approximation");
        e.canonical = {{"f0", C, 0, 1}, {"eta", C, kMinEta}};
        e.forms = {ModelForm{{{"f0", C, {kF0}}}}, ModelForm{{{"eta", C, {kSchlickEta}}}}};
        // schlick(f0) carries the Lambert base (albedo input) as well;
        // schlick(eta) differs from it only in how f0 is computed.
        e.examples = {{"schlick_f0", "input f0 = rgb(0.04, 0.5, 0.9); input albedo = rgb(0.5, 0.25, 0.1);",
                       "schlick(f0 = f0)", "diffuse = lambert(albedo);"},
                      {"schlick_eta", "input eta = rgb(1.5, 1.0, 0.7);", "schlick(eta = eta)", "", true}};
        e.hardCases = {{"hcc_schlick_eta1", "ndf = ggx(0.3); masking = smith_separable; fresnel = schlick(eta = 1);"}};
        e.formulas = makeFormulas<FresnelFormulas, SchlickFresnel>();
        return e;
    }());
    static const FresnelEntry& dielectric = immortal<FresnelEntry>([] {
        FresnelEntry e = makeEntry<FresnelEntry>(ModelSlot::Fresnel, 2, "dielectric", "exact dielectric Fresnel");
        e.reciprocityStep = true;
        e.refractiveIndexParam = kEta;
        e.canonical = {{"eta", C, kMinEta}};
        e.forms = {ModelForm{{{"eta", C, {kEta}}}}};
        e.examples = {{"dielectric", "input eta = rgb(1.5, 1.0, 0.7);", "dielectric(eta)"}};
        e.hardCases = {
            {"hcc_dielectric_eta1", "ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(1);"},
            {"hcc_dielectric_tir",
             "ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(rgb(0.5, 0.9, 0.6666667));"},
            {"hcc_dielectric_near1",
             "ndf = beckmann(0.3); masking = smith_separable; fresnel = dielectric(rgb(1.000001, 0.999999, 1));"},
            // Every channel above 1 also in float, too close to 1 for the
            // float term: the emitter drops its total-reflection test here.
            {"hcc_dielectric_above1",
             "ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(rgb(1.0000001, 1.000001, 1.0001));"},
        };
        e.formulas = makeFormulas<FresnelFormulas, DielectricFresnel>();
        return e;
    }());
    static const FresnelEntry& conductor = immortal<FresnelEntry>([] {
        FresnelEntry e = makeEntry<FresnelEntry>(ModelSlot::Fresnel, 3, "conductor", "exact conductor Fresnel, complex index eta + ik");
        e.canonical = {{"eta", C, kMinEta}, {"k", C, 0}};
        e.forms = {ModelForm{{{"eta", C, {kEta}}, {"k", C, {kK}}}}};
        // (kc, not k: schlick_smith's input is k)
        e.examples = {{"conductor", "input eta = rgb(0.14, 1.0, 1.38); input kc = rgb(3.7, 0.0, 1.9);",
                       "conductor(eta = eta, k = kc)"}};
        e.hardCases = {
            {"hcc_conductor_k0",
             "ndf = ggx(0.3); masking = smith_height_correlated; fresnel = conductor(eta = rgb(0.2, 1, 1.5), k = 0);"},
            {"hcc_conductor_eta1_k0", "ndf = ggx(0.3); masking = smith_separable; fresnel = conductor(eta = 1, k = 0);"},
        };
        e.formulas = makeFormulas<FresnelFormulas, ConductorFresnel>();
        return e;
    }());
    return {&none, &schlick, &dielectric, &conductor};
}

}  // namespace facet::models
