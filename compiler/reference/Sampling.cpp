// Sampling: the reference importance sampler (see Sampling.h) and the
// interpreter's sample / pdf entry points.
#include "QuadMath.h"
#include "Sampling.h"

#include "DielectricLobe.h"
#include "KullaContyEval.h"
#include "LayerAlbedo.h"
#include "WalkLobe.h"

#include <cmath>

namespace facet {

namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

template <typename Real>
Real dot(const Vec3<Real>& a, const Vec3<Real>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

template <typename Real>
bool finite(Real x) { using std::isfinite; return isfinite(x); }

// The smallest probability either lobe gets when both are present.
constexpr double kMinLobeProbability = 0.05;

// w / |w| if w is finite and unit within kUnitTolerance (SPEC 2).
template <typename Real>
bool unitDirection(const Real w[3], Vec3<Real>& out) {
    using std::fabs; using std::sqrt;
    if (!finite(w[0]) || !finite(w[1]) || !finite(w[2])) return false;
    Real len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(fabs(len - 1) <= Real(kUnitTolerance))) return false;
    out = {w[0] / len, w[1] / len, w[2] / len};
    return true;
}

template <typename Real>
bool hasCosineLobe(const ResolvedMaterial<Real>& r) {
    return r.diffuse->present || r.energy->compensates;
}

// The cosine lobe's density, (n.wi) / pi above the horizon.
template <typename Real>
Real cosinePdf(const Vec3<Real>& wi) { return wi.z > 0 ? wi.z / kPi<Real> : Real(0); }

// The cosine lobe takes part: the material has one, or it is the technique.
template <typename Real>
bool mixesCosineLobe(const ResolvedMaterial<Real>& r, SamplingTechnique technique) {
    return hasCosineLobe(r) || technique == SamplingTechnique::Cosine;
}

// (n.wo) / G1(wo) of the visible-normal density: (n.wo) + (n.wo) Lambda(wo)
// with the Lambda exact for the NDF (NdfFormulas::visibleCosLambda), which
// need not be the masking term's.
template <typename Real>
Real visibleNormalScale(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo) {
    return wo.z + r.ndf->formulas.template get<Real>().visibleCosLambda(r.ndfArgs, wo);
}

template <typename Real>
Real mixturePdf(const ResolvedMaterial<Real>& r, SamplingTechnique technique, Real pSpec, Real spec, Real cosine) {
    return mixesCosineLobe(r, technique) ? pSpec * spec + (1 - pSpec) * cosine : spec;
}

}  // namespace

const char* samplingTechniqueName(SamplingTechnique t) {
    switch (t) {
        case SamplingTechnique::Material: return "material";
        case SamplingTechnique::VisibleNormals: return "visible normals";
        case SamplingTechnique::Normals: return "NDF";
        case SamplingTechnique::Cosine: return "cosine";
    }
    return "?";
}

template <typename Real>
Real specularProbability(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, SamplingTechnique technique) {
    if (technique == SamplingTechnique::Cosine) return 0;
    if (!hasCosineLobe(r)) return 1;
    Real c = wo.z < 1 ? wo.z : Real(1);
    Real fresnel = 0, diffuse = 0, compensation = 0;
    for (int ch = 0; ch < 3; ++ch) fresnel += r.fresnelAt(c, (1 - c) * (1 + c), ch) / 3;
    Real albedo = fresnel;  // E = 1 without a table
    if (r.energy->compensates && r.energyTable) {
        Real ec = Real(r.energyTable->ecAt(double(c), double(r.energyAlpha)));  // 1 - E(n.wo)
        albedo = fresnel * (1 - ec);
        for (int ch = 0; ch < 3; ++ch) compensation += ec * kullaContyFresnelTerm(r.favg[ch], r.ecAvg) / 3;
    }
    if (r.diffuse->present)
        for (int ch = 0; ch < 3; ++ch)
            diffuse += r.diffuse->formulas.template get<Real>().value(r.diffuseArgs, ch) * kPi<Real> / 3;
    Real total = albedo + diffuse + compensation;
    Real p = total > 0 && finite(total) ? albedo / total : Real(0.5);
    const Real lo = Real(kMinLobeProbability), hi = 1 - lo;
    return p < lo ? lo : (p > hi ? hi : p);
}

template <typename Real>
Real specularNormalPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const Vec3<Real>& m,
                       SamplingTechnique technique) {
    if (!(m.z > 0)) return 0;
    if (visibleNormalSampling(r, technique)) {
        // G1(wo) (wo.m)+ D(m) / (n.wo) with G1 = (n.wo) / ((n.wo) + (n.wo) Lambda(wo)).
        Real om = dot(wo, m);
        if (!(om > 0)) return 0;
        return r.D(m) * om / visibleNormalScale(r, wo);
    }
    return r.ndf->formulas.template get<Real>().normalPdf(r.ndfArgs, m);
}

template <typename Real>
Real specularPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                 SamplingTechnique technique) {
    using std::sqrt;
    Vec3<Real> s{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    Real len = sqrt(dot(s, s));
    if (!(len > 0)) return 0;
    // wi is the reflection of wo about m = +-h, wo.m = +-|wi + wo| / 2; the
    // sampler's normals have m.z > 0.
    Vec3<Real> m{s.x / len, s.y / len, s.z / len};
    if (m.z < 0) m = {-m.x, -m.y, -m.z};
    if (visibleNormalSampling(r, technique)) {
        // pdf_m / (4 wo.m) = D(m) / (4 ((n.wo) + (n.wo) Lambda(wo))) for
        // wo.m > 0, which holds for m = h (and fails for m = -h).
        if (!(s.z > 0)) return 0;
        return r.D(m) / (4 * visibleNormalScale(r, wo));
    }
    return specularNormalPdf(r, wo, m, technique) / (2 * len);
}

template <typename Real>
Real brdfPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo, SamplingTechnique technique) {
    if (r.wholeSphere()) return dielectricLobePdf(r, wi, wo);  // DielectricLobe.h
    if (!(wo.z > 0)) return 0;
    if (r.energy->walks && technique == SamplingTechnique::Material) return walkLobePdf(r, wi, wo);
    return mixturePdf(r, technique, specularProbability(r, wo, technique), specularPdf(r, wi, wo, technique),
                      cosinePdf(wi));
}

template <typename Real>
SampleResult<Real> sampleBrdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u,
                              SamplingTechnique technique) {
    using std::cos; using std::sin; using std::sqrt;
    if (r.energy->walks && technique == SamplingTechnique::Material) return sampleWalkLobe(r, wo, u);  // WalkLobe.h
    if (r.wholeSphere()) return sampleDielectricLobe(r, wo, u);                                       // DielectricLobe.h
    SampleResult<Real> out;
    if (!(wo.z > 0)) return out;
    Real pSpec = specularProbability(r, wo, technique);
    Real spec, cosine;
    Vec3<Real> wi, sum;
    if (u[0] < pSpec) {
        const NdfFormulas<Real>& ndf = r.ndf->formulas.template get<Real>();
        Vec3<Real> m = visibleNormalSampling(r, technique) ? ndf.sampleVisibleNormal(r.ndfArgs, wo, u[1], u[2])
                                                : ndf.sampleNormal(r.ndfArgs, u[1], u[2]);
        Real om = dot(wo, m);
        wi = {2 * om * m.x - wo.x, 2 * om * m.y - wo.y, 2 * om * m.z - wo.z};
        // wi + wo along the drawn normal: where wi is nearly -wo, the sum of
        // the rounded directions would turn the half vector (and D) away
        // from m.
        sum = {2 * om * m.x, 2 * om * m.y, 2 * om * m.z};
        // From the drawn normal (pdf() finds it again as the half vector).
        spec = om != 0 ? specularNormalPdf(r, wo, m, technique) / (4 * (om > 0 ? om : -om)) : Real(0);
        cosine = cosinePdf(wi);
    } else {
        Real radius = sqrt(u[1]), phi = 2 * kPi<Real> * u[2];
        wi = {radius * cos(phi), radius * sin(phi), sqrt(1 - u[1])};
        cosine = cosinePdf(wi);
        spec = specularPdf(r, wi, wo, technique);
        sum = {wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    }
    out.wi = wi;
    out.pdf = mixturePdf(r, technique, pSpec, spec, cosine);
    if (out.pdf > 0 && wi.z > 0) {
        std::array<Real, 3> f = r.brdf(wi, wo, sum);
        for (int ch = 0; ch < 3; ++ch) out.weight[ch] = f[ch] * wi.z / out.pdf;
    }
    return out;
}

template <typename Real>
SampleResult<Real> Interpreter<Real>::sample(const Real wo[3], const Real u[3], const Real* slots) const {
    SampleResult<Real> invalid;
    invalid.valid = false;
    Vec3<Real> o;
    if (!unitDirection(wo, o)) return invalid;
    std::array<Real, 3> uu{};
    for (int k = 0; k < 3; ++k) {
        if (!(u[k] >= 0 && u[k] < 1)) return invalid;  // NaN fails too
        uu[k] = u[k];
    }
    SampleResult<Real> out;
    if (material_.combinesLobes() || !material_.singleLobe().hasNdf()) {  // a lone diffuse lobe: the cosine leaf
        ResolvedBsdf<Real> all = resolveAll(slots);
        if (!all.valid) return invalid;
        out = sampleCombination(*this, all, o, uu);
    } else {
        ResolvedMaterial<Real> r = resolve(slots);
        if (!r.valid) return invalid;
        out = sampleBrdf(r, o, uu);
    }
    // As in eval: a result beyond the reference's range is an invalid lane.
    bool ok = finite(out.pdf) && out.pdf >= 0 && finite(out.wi.x) && finite(out.wi.y) && finite(out.wi.z);
    for (Real w : out.weight) ok = ok && finite(w) && w >= 0;
    return ok ? out : invalid;
}

template <typename Real>
PdfResult<Real> Interpreter<Real>::pdf(const Real wi[3], const Real wo[3], const Real* slots) const {
    PdfResult<Real> invalid;
    invalid.valid = false;
    Vec3<Real> i, o;
    if (!unitDirection(wi, i) || !unitDirection(wo, o)) return invalid;
    PdfResult<Real> out;
    if (material_.combinesLobes() || !material_.singleLobe().hasNdf()) {  // a lone diffuse lobe: the cosine leaf
        ResolvedBsdf<Real> all = resolveAll(slots);
        if (!all.valid) return invalid;
        if (o.z > 0)
            out.pdf = combinationPdf(material_, all, leafProbabilities(material_, bsdfToDouble(all), resolvedDefaults(), double(o.z)), i, o);
    } else {
        ResolvedMaterial<Real> r = resolve(slots);
        if (!r.valid) return invalid;
        out.pdf = brdfPdf(r, i, o);
    }
    return finite(out.pdf) && out.pdf >= 0 ? out : invalid;
}

template <typename Real>
const ResolvedBsdf<double>& Interpreter<Real>::resolvedDefaults() const {
    std::call_once(defaults_->once, [&] { defaults_->value = bsdfToDouble(resolveAll(nullptr)); });
    return defaults_->value;
}

#define FACET_SAMPLING(Real)                                                                                 \
    template const ResolvedBsdf<double>& Interpreter<Real>::resolvedDefaults() const;                        \
    template Real specularProbability(const ResolvedMaterial<Real>&, const Vec3<Real>&, SamplingTechnique);  \
    template Real specularNormalPdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&,     \
                                    SamplingTechnique);                                                      \
    template Real specularPdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&,           \
                              SamplingTechnique);                                                            \
    template Real brdfPdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&,               \
                          SamplingTechnique);                                                                \
    template SampleResult<Real> sampleBrdf(const ResolvedMaterial<Real>&, const Vec3<Real>&,                 \
                                           const std::array<Real, 3>&, SamplingTechnique);                   \
    template SampleResult<Real> Interpreter<Real>::sample(const Real[3], const Real[3], const Real*) const;  \
    template PdfResult<Real> Interpreter<Real>::pdf(const Real[3], const Real[3], const Real*) const;
FACET_SAMPLING(double)
FACET_SAMPLING(long double)
FACET_SAMPLING(__float128)
#undef FACET_SAMPLING

}  // namespace facet
