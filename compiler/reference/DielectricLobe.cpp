// DielectricLobe: the reference BSDF, sampler and density of a whole-sphere
// lobe (see DielectricLobe.h for the formulas and conventions).
#include "QuadMath.h"
#include "DielectricLobe.h"

#include "DielectricEnergy.h"

#include "Diagnostics.h"

#include <algorithm>
#include <cmath>

namespace facet {
namespace {

template <typename Real>
Real dot(const Vec3<Real>& a, const Vec3<Real>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// |v| without the underflow of |v|^2: the sum of two grazing directions
// that nearly cancel (1e-300 in z) still has a direction and a length.
template <typename Real>
Real length(const Vec3<Real>& v) {
    using std::abs; using std::sqrt;
    Real big = std::max({abs(v.x), abs(v.y), abs(v.z)});
    if (!(big > 0)) return big;
    Vec3<Real> u{v.x / big, v.y / big, v.z / big};
    return big * sqrt(dot(u, u));
}

template <typename Real>
Vec3<Real> withZ(const Vec3<Real>& v, Real z) { return {v.x, v.y, z}; }

// The pair in wo's frame: z multiplied by `sign` so that wo is above.
template <typename Real>
struct WoFrame {
    Real sign;
    Vec3<Real> wi, wo, sum;
};

template <typename Real>
WoFrame<Real> woFrame(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& sum) {
    Real sign = wo.z > 0 ? Real(1) : Real(-1);
    return {sign, withZ(wi, wi.z * sign), withZ(wo, wo.z * sign), withZ(sum, sum.z * sign)};
}

// The Fresnel term's arguments with the far side's index eta relative to
// the near side's (eta < 1: total internal reflection past the critical
// angle), in every channel (the refracting lobe has one eta).
template <typename Real>
ModelArgs<Real> fresnelArgsAcross(const ResolvedMaterial<Real>& r, Real eta) {
    ModelArgs<Real> a = r.fresnelArgs;
    a.value[size_t(r.fresnel->refractiveIndexParam)] = {eta, eta, eta};
    return a;
}

// F at cos c on the near side.
template <typename Real>
Real fresnelAcross(const ResolvedMaterial<Real>& r, Real eta, Real c) {
    c = c < 1 ? c : Real(1);
    return r.fresnel->formulas.template get<Real>().F(fresnelArgsAcross(r, eta), c, (1 - c) * (1 + c), 0);
}

// The transmittance 1 - F there (the catalog's form, exact at grazing).
template <typename Real>
Real transmittanceAcross(const ResolvedMaterial<Real>& r, Real eta, Real c) {
    c = c < 1 ? c : Real(1);
    return r.fresnel->formulas.template get<Real>().transmittance(fresnelArgsAcross(r, eta), c, (1 - c) * (1 + c), 0);
}

// The transmittance of a refracted pair: c on the near side, ct (> 0) on the far side.
template <typename Real>
Real pairTransmittance(const ResolvedMaterial<Real>& r, Real eta, Real c, Real ct) {
    return r.fresnel->formulas.template get<Real>().pairTransmittance(fresnelArgsAcross(r, eta), c < 1 ? c : Real(1),
                                                                       ct, 0);
}

// The interface's eta relative to wo's side (eta or 1/eta), and that minus 1
// formed without cancellation near 1.
template <typename Real>
struct RelativeEta {
    Real eta, minusOne;
};

template <typename Real>
RelativeEta<Real> relativeEta(const ResolvedMaterial<Real>& r, Real sign) {
    Real eta = clampedEta(r, 0);
    return sign > 0 ? RelativeEta<Real>{eta, eta - 1} : RelativeEta<Real>{1 / eta, (1 - eta) / eta};
}

// The facet of a transmitted pair in wo's frame (wi below, wo above):
// v = eta' wi + wo = sum + (eta' - 1) wi, m = v/|v| turned up.
template <typename Real>
struct RefractedFacet {
    Vec3<Real> m;
    Real lenSq = 0, im = 0, om = 0;
    bool valid = false;  // a facet facing both directions
};

template <typename Real>
RefractedFacet<Real> refractedFacet(const WoFrame<Real>& p, const RelativeEta<Real>& eta) {
    using std::sqrt;
    RefractedFacet<Real> out;
    Vec3<Real> v{p.sum.x + eta.minusOne * p.wi.x, p.sum.y + eta.minusOne * p.wi.y, p.sum.z + eta.minusOne * p.wi.z};
    out.lenSq = dot(v, v);
    Real len = sqrt(out.lenSq);
    if (!(len > 0)) return out;
    Real s = v.z < 0 ? -1 / len : 1 / len;
    out.m = {v.x * s, v.y * s, v.z * s};
    out.im = dot(p.wi, out.m);
    out.om = dot(p.wo, out.m);
    out.valid = out.im < 0 && out.om > 0 && out.m.z > 0;
    return out;
}

// The density of the facet normal m drawn for the view o (above).
template <typename Real>
Real facetPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& o, const Vec3<Real>& m) {
    return specularNormalPdf(r, o, m, SamplingTechnique::Material);
}

// Where the facet m (om = wo.m > 0) sends the view o (above) by reflection
// or by refraction, in wo's frame: wi, wi + wo, and the Jacobian dm/dwi (wi's
// density per unit density of m); valid is false where no direction leaves
// on the right side (below the horizon, total internal reflection).
template <typename Real>
struct FacetBranch {
    Vec3<Real> wi, sum;
    Real jacobian = 0;
    bool valid = false;
};

template <typename Real>
FacetBranch<Real> facetBranch(const Vec3<Real>& o, const Vec3<Real>& m, Real om, const RelativeEta<Real>& eta,
                              bool reflected) {
    using std::sqrt;
    FacetBranch<Real> b;
    if (reflected) {
        b.wi = {2 * om * m.x - o.x, 2 * om * m.y - o.y, 2 * om * m.z - o.z};
        b.sum = {2 * om * m.x, 2 * om * m.y, 2 * om * m.z};
        b.jacobian = 1 / (4 * om);
        b.valid = b.wi.z > 0;
        return b;
    }
    // Snell: the refracted direction's cosine with -m, ct^2 = 1 - (1 - om^2) / eta'^2.
    Real ct2 = 1 - (1 - om) * (1 + om) / (eta.eta * eta.eta);
    if (!(ct2 > 0)) return b;  // total internal reflection
    Real ct = sqrt(ct2), k = om / eta.eta - ct;
    b.wi = {-o.x / eta.eta + k * m.x, -o.y / eta.eta + k * m.y, -o.z / eta.eta + k * m.z};
    b.sum = {b.wi.x + o.x, b.wi.y + o.y, b.wi.z + o.z};
    Real denom = om - eta.eta * ct;  // eta' wi.m + wo.m
    b.jacobian = eta.eta * eta.eta * ct / (denom * denom);
    b.valid = b.wi.z < 0;
    return b;
}

// The sheet's reflectance and transmittance of channel ch at cos c:
// R' = 2F / (1 + F) and T' = (1 - F) / (1 + F) = T / (2 - T), T = 1 - F.
template <typename Real>
std::array<Real, 2> sheetWeights(const ResolvedMaterial<Real>& r, Real c, int ch) {
    c = c < 1 ? c : Real(1);
    const FresnelFormulas<Real>& fresnel = r.fresnel->formulas.template get<Real>();
    Real F = fresnel.F(r.fresnelArgs, c, (1 - c) * (1 + c), ch);
    Real T = fresnel.transmittance(r.fresnelArgs, c, (1 - c) * (1 + c), ch);
    return {2 * F / (1 + F), T / (2 - T)};
}

// The sheet's unnormalized probabilities of reflecting and transmitting at
// cos c: R' and T' summed over the channels, 0 for what `scatter` drops.
template <typename Real>
std::array<Real, 2> sheetChoice(const ResolvedMaterial<Real>& r, Real c) {
    Real pr = 0, pt = 0;
    for (int ch = 0; ch < 3; ++ch) {
        std::array<Real, 2> w = sheetWeights(r, c, ch);
        pr += keepsPair(r, true) ? w[0] : Real(0);
        pt += keepsPair(r, false) ? w[1] : Real(0);
    }
    return {pr, pt};
}

template <typename Real>
std::array<Real, 3> thinSheetBsdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                                  const Vec3<Real>& sum) {
    using std::abs; using std::sqrt;
    std::array<Real, 3> out{};
    bool reflected = (wi.z > 0) == (wo.z > 0);
    if (!keepsPair(r, reflected)) return out;
    Vec3<Real> i = withZ(wi, abs(wi.z)), o = withZ(wo, abs(wo.z));
    // Mirrored above, the pair's sum: no cancellation in z either way.
    Vec3<Real> s = reflected ? withZ(sum, abs(sum.z)) : Vec3<Real>{sum.x, sum.y, i.z + o.z};
    Real len = length(s);
    if (!(len > 0)) return out;
    Vec3<Real> h{s.x / len, s.y / len, s.z / len};
    Real c = len / 2 < 1 ? len / 2 : Real(1);
    // D w G / (4 ci co) with the largest channel's weight w in the scale (as
    // ResolvedMaterial::brdf does with F): a tiny T' at a grazing facet and
    // a huge G / (ci co) at grazing directions meet in range.
    std::array<Real, 3> w;
    Real wMax = 0;
    for (int ch = 0; ch < 3; ++ch) {
        w[size_t(ch)] = sheetWeights(r, c, ch)[reflected ? 0 : 1];
        wMax = std::max(wMax, w[size_t(ch)]);
    }
    Real lobe = wMax > 0 ? r.GOverCosines(i, o, h, c, r.D(h) * wMax / 4) : Real(0);
    for (int ch = 0; ch < 3; ++ch) out[size_t(ch)] = w[size_t(ch)] == wMax ? lobe : w[size_t(ch)] / wMax * lobe;
    return out;
}

}  // namespace

template <typename Real>
Real clampedEta(const ResolvedMaterial<Real>& r, int ch) {
    internal_assert(r.fresnel->refractiveIndexParam >= 0) << "a whole-sphere lobe with fresnel " << r.fresnel->name;
    return clampedFromOne(r.fresnelArgs.value[size_t(r.fresnel->refractiveIndexParam)][size_t(ch)]);
}

namespace {

// The rough interface's single-scattering BSDF.
template <typename Real>
std::array<Real, 3> interfaceBsdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                                  const Vec3<Real>& sum) {
    using std::sqrt;
    std::array<Real, 3> out{};
    WoFrame<Real> p = woFrame(wi, wo, sum);
    bool reflected = p.wi.z > 0;
    if (!keepsPair(r, reflected)) return out;
    RelativeEta<Real> eta = relativeEta(r, p.sign);
    Real value = 0;
    if (reflected) {
        Real len = length(p.sum);
        if (!(len > 0)) return out;
        Vec3<Real> h{p.sum.x / len, p.sum.y / len, p.sum.z / len};
        Real c = len / 2 < 1 ? len / 2 : Real(1);
        Real F = fresnelAcross(r, eta.eta, c);
        value = F > 0 ? r.GOverCosines(p.wi, p.wo, h, c, r.D(h) * F / 4) : Real(0);
    } else {
        RefractedFacet<Real> f = refractedFacet(p, eta);
        if (!f.valid) return out;
        Real T = pairTransmittance(r, eta.eta, f.om, -f.im);
        Real scale = r.D(f.m) * T * (-f.im) * f.om / f.lenSq;
        if (r.transport == Transport::Importance) scale *= eta.eta * eta.eta;
        Vec3<Real> i = withZ(p.wi, -p.wi.z);  // mirrored above for the masking
        value = T > 0 && scale > 0
                    ? r.masking->formulas.template get<Real>().transmittedGOverCosines(r, {i, p.wo, f.m, -f.im, f.om},
                                                                                        scale)
                    : Real(0);
    }
    out = {value, value, value};
    return out;
}

}  // namespace

template <typename Real>
std::array<Real, 3> dielectricBsdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                                   const Vec3<Real>& sum) {
    if (!r.ndf || wi.z == 0 || wo.z == 0) return {};
    std::array<Real, 3> f = r.thin ? thinSheetBsdf(r, wi, wo, sum) : interfaceBsdf(r, wi, wo, sum);
    if (r.energyTable) {
        std::array<Real, 3> ms = wholeSphereCompensation(r, wi, wo);  // DielectricEnergy.h
        for (int ch = 0; ch < 3; ++ch) f[ch] += ms[ch];
    }
    return f;
}

namespace {

// The single-scattering sampler's density (DielectricLobe.h).
template <typename Real>
Real singleScatteringPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    using std::abs; using std::sqrt;
    Vec3<Real> sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    if (r.thin) {
        bool reflected = (wi.z > 0) == (wo.z > 0);
        if (!keepsPair(r, reflected)) return 0;
        Vec3<Real> i = withZ(wi, abs(wi.z)), o = withZ(wo, abs(wo.z));
        Vec3<Real> s = reflected ? withZ(sum, abs(sum.z)) : Vec3<Real>{sum.x, sum.y, i.z + o.z};
        Real len = length(s);
        if (!(len > 0)) return 0;
        Vec3<Real> h{s.x / len, s.y / len, s.z / len};
        Real c = len / 2;
        auto [pr, pt] = sheetChoice(r, c);
        if (!(pr + pt > 0)) return 0;
        return (reflected ? pr : pt) / (pr + pt) * facetPdf(r, o, h) / (4 * c);
    }
    WoFrame<Real> p = woFrame(wi, wo, sum);
    bool reflected = p.wi.z > 0;
    if (!keepsPair(r, reflected)) return 0;
    RelativeEta<Real> eta = relativeEta(r, p.sign);
    Vec3<Real> m;
    Real om, jacobian, refractedCos = 0;  // dm/dwi; |wi.m| of a refracted pair
    if (reflected) {
        Real len = length(p.sum);
        if (!(len > 0)) return 0;
        m = {p.sum.x / len, p.sum.y / len, p.sum.z / len};
        om = len / 2;
        jacobian = 1 / (4 * om);
    } else {
        RefractedFacet<Real> f = refractedFacet(p, eta);
        if (!f.valid) return 0;
        m = f.m;
        om = f.om;
        refractedCos = -f.im;
        jacobian = eta.eta * eta.eta * -f.im / f.lenSq;
    }
    // P_T = 1 - F at wo.m (of the refracted pair itself where wi is one).
    Real pr = keepsPair(r, true) ? fresnelAcross(r, eta.eta, om) : Real(0);
    Real pt = reflected ? transmittanceAcross(r, eta.eta, om) : pairTransmittance(r, eta.eta, om, refractedCos);
    if (!(pr + pt > 0)) return 0;
    return (reflected ? pr : pt) / (pr + pt) * facetPdf(r, p.wo, m) * jacobian;
}

// The single-scattering sampler: out.wi and out.pdf (its own density),
// and wi + wo in `sum`, formed accurately; out.pdf = 0 without a sample.
template <typename Real>
SampleResult<Real> sampleSingleScattering(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo,
                                          const std::array<Real, 3>& u, Vec3<Real>& sum) {
    using std::abs; using std::sqrt;
    SampleResult<Real> out;
    Real sign = wo.z > 0 ? Real(1) : Real(-1);
    Vec3<Real> o = withZ(wo, abs(wo.z));
    const NdfFormulas<Real>& ndf = r.ndf->formulas.template get<Real>();
    Vec3<Real> m = visibleNormalSampling(r) ? ndf.sampleVisibleNormal(r.ndfArgs, o, u[1], u[2])
                                            : ndf.sampleNormal(r.ndfArgs, u[1], u[2]);
    Real om = dot(o, m);
    if (!(om > 0)) return out;
    Vec3<Real> i, s;  // wi and wi + wo in wo's frame (for the sheet: mirrored above)
    bool reflected;
    Real pdf;
    if (r.thin) {
        auto [pr, pt] = sheetChoice(r, om);
        if (!(pr + pt > 0)) return out;
        reflected = u[0] * (pr + pt) < pr;
        i = {2 * om * m.x - o.x, 2 * om * m.y - o.y, 2 * om * m.z - o.z};
        if (!(i.z > 0)) return out;
        pdf = (reflected ? pr : pt) / (pr + pt) * facetPdf(r, o, m) / (4 * om);
        // Back to the directions: the reflection on wo's side, the
        // transmission its mirror image on the far side.
        out.wi = withZ(i, reflected ? i.z * sign : -i.z * sign);
        // wi + wo along the drawn normal (thinSheetBsdf reads x and y of a
        // transmitted pair's sum, which mirrored above is the same 2 (wo.m) m).
        s = {2 * om * m.x, 2 * om * m.y, reflected ? 2 * om * m.z * sign : out.wi.z + wo.z};
    } else {
        RelativeEta<Real> eta = relativeEta(r, sign);
        Real pr = keepsPair(r, true) ? fresnelAcross(r, eta.eta, om) : Real(0);
        Real pt = transmittanceAcross(r, eta.eta, om);
        if (!(pr + pt > 0)) return out;
        reflected = u[0] * (pr + pt) < pr;
        FacetBranch<Real> b = facetBranch(o, m, om, eta, reflected);
        if (!b.valid) return out;  // (total internal reflection has pt = 0)
        i = b.wi;
        s = b.sum;
        pdf = (reflected ? pr : pt) / (pr + pt) * facetPdf(r, o, m) * b.jacobian;
        out.wi = withZ(i, i.z * sign);
        s = withZ(s, s.z * sign);
    }
    out.pdf = pdf;
    sum = s;
    return out;
}

}  // namespace

template <typename Real>
Real dielectricLobePdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    if (!r.ndf || wi.z == 0 || wo.z == 0) return 0;
    Real p = compensationProbability(r, wo);  // DielectricEnergy.h; 0 without compensation
    Real single = singleScatteringPdf(r, wi, wo);
    return p > 0 ? (1 - p) * single + p * compensationPdf(r, wi, wo) : single;
}

// A mixture of the single-scattering sampler and, with probability p, the
// compensation's (u[0] picks, then is reused rescaled).
template <typename Real>
SampleResult<Real> sampleDielectricLobe(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo,
                                        const std::array<Real, 3>& u) {
    using std::abs;
    SampleResult<Real> out;
    if (!r.ndf || wo.z == 0) return out;
    Real p = compensationProbability(r, wo);
    Vec3<Real> sum;
    if (p > 0 && u[0] < p) {
        out.wi = sampleCompensation(r, wo, {u[0] / p, u[1], u[2]});
        if (out.wi.z == 0) return SampleResult<Real>{};
        sum = {out.wi.x + wo.x, out.wi.y + wo.y, out.wi.z + wo.z};
    } else {
        Real u0 = p > 0 ? (u[0] - p) / (1 - p) : u[0];  // (1 by rounding only chooses refraction)
        out = sampleSingleScattering(r, wo, {u0, u[1], u[2]}, sum);
        if (!(out.pdf > 0)) return SampleResult<Real>{};
    }
    // The mixture's density (dielectricLobePdf's, with p already known).
    if (p > 0) out.pdf = (1 - p) * singleScatteringPdf(r, out.wi, wo) + p * compensationPdf(r, out.wi, wo);
    if (out.pdf > 0) {
        std::array<Real, 3> f = dielectricBsdf(r, out.wi, wo, sum);
        for (int ch = 0; ch < 3; ++ch) out.weight[size_t(ch)] = f[size_t(ch)] * abs(out.wi.z) / out.pdf;
    }
    return out;
}

double interfaceAlbedo(const ResolvedMaterial<double>& r, double mu, int grid) {
    using std::sqrt;
    internal_assert(!r.thin && r.scatter == Scatter::Both && r.transport == Transport::Importance)
        << "interfaceAlbedo of a lobe that is not a whole interface in importance transport";
    const Vec3<double> o{sqrt((1 - mu) * (1 + mu)), 0, mu};
    const RelativeEta<double> eta = relativeEta(r, 1.0);
    const NdfFormulas<double>& ndf = r.ndf->formulas.get<double>();
    const bool visible = visibleNormalSampling(r);
    double total = 0;
    for (int a = 0; a < grid; ++a)
        for (int b = 0; b < grid; ++b) {
            double u1 = (a + 0.5) / grid, u2 = (b + 0.5) / grid;
            Vec3<double> m = visible ? ndf.sampleVisibleNormal(r.ndfArgs, o, u1, u2) : ndf.sampleNormal(r.ndfArgs, u1, u2);
            double om = dot(o, m), pm = om > 0 ? facetPdf(r, o, m) : 0.0;
            if (!(pm > 0)) continue;
            // Both branches of the facet: f |n.wi| over wi's density given m.
            for (bool reflected : {true, false}) {
                FacetBranch<double> fb = facetBranch(o, m, om, eta, reflected);
                if (!fb.valid) continue;
                double f = dielectricBsdf(r, fb.wi, o, fb.sum)[0];
                double term = f * std::abs(fb.wi.z) / (pm * fb.jacobian);
                if (std::isfinite(term)) total += term;
            }
        }
    return total / (double(grid) * grid);
}

#define FACET_DIELECTRIC_LOBE(Real)                                                                               \
    template Real clampedEta(const ResolvedMaterial<Real>&, int);                                                \
    template std::array<Real, 3> dielectricBsdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&, \
                                                const Vec3<Real>&);
#define FACET_DIELECTRIC_SAMPLING(Real)                                                                           \
    template Real dielectricLobePdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&);         \
    template SampleResult<Real> sampleDielectricLobe(const ResolvedMaterial<Real>&, const Vec3<Real>&,            \
                                                     const std::array<Real, 3>&);
FACET_DIELECTRIC_LOBE(float)
FACET_DIELECTRIC_LOBE(double)
FACET_DIELECTRIC_LOBE(long double)
FACET_DIELECTRIC_LOBE(__float128)
// Sampling in the reference sampler's types (Sampling.cpp).
FACET_DIELECTRIC_SAMPLING(double)
FACET_DIELECTRIC_SAMPLING(long double)
FACET_DIELECTRIC_SAMPLING(__float128)
#undef FACET_DIELECTRIC_LOBE
#undef FACET_DIELECTRIC_SAMPLING

}  // namespace facet
