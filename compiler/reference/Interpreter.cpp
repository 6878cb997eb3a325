// Interpreter: the reference formulas (SPEC section 3), one term at a time.
// QuadMath.h first: the __float128 math overloads must be declared before
// any template that calls them (Builtins.h, <complex>); see QuadMath.h.
#include "QuadMath.h"
#include "Interpreter.h"
#include "DielectricEnergy.h"
#include "DielectricLobe.h"
#include "WalkLobe.h"

#include "Diagnostics.h"
#include "KullaContyEval.h"
#include "Quadrature.h"

#include <cmath>
#include <complex>
#include <limits>

namespace facet {

namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

template <typename Real>
Real sq(Real x) { return x * x; }

template <typename Real>
bool finite(Real x) { using std::isfinite; return isfinite(x); }

// cos of the half angle, wi.h = wo.h = |wi + wo| / 2 for unit vectors (at most 1).
template <typename Real>
Real halfAngleCos(const Vec3<Real>& wi, const Vec3<Real>& wo) {
    using std::sqrt;
    Real len = sqrt(sq(wi.x + wo.x) + sq(wi.y + wo.y) + sq(wi.z + wo.z));
    return len / 2 < 1 ? len / 2 : Real(1);
}

// sin^2 of the half angle, 1 - (wi.h)^2 = |wi - wo|^2 / 4 for unit vectors:
// from the difference of the directions, so that it keeps its relative
// accuracy near wi = wo, where 1 - c^2 computed from c cancels (hard cases).
template <typename Real>
Real halfAngleSin2(const Vec3<Real>& wi, const Vec3<Real>& wo) {
    Real s2 = (sq(wi.x - wo.x) + sq(wi.y - wo.y) + sq(wi.z - wo.z)) / 4;
    return s2 < 1 ? s2 : Real(1);
}

// ---- double-Real arithmetic for the directions ----
//
// eval() takes directions that are unit only within 1e-3 (float inputs are
// off by ~1e-8) and normalizes them. The normalized components carry a
// rounding error of 1 ulp, which is harmless except in wi + wo when the two
// are nearly opposite: that error, along the directions, is perpendicular to
// their small sum and turns h by ulp / |wi + wo| (1e-12 rad at |wi + wo| =
// 1e-4, a 1e-9 relative error in D for alpha = 1e-4). So the normalization
// and the sum are computed as unevaluated sums hi + lo (Dekker / Knuth
// error-free transformations with fma), and rounded once at the end.
template <typename Real>
struct DD {
    Real hi, lo;
};
template <typename Real>
DD<Real> twoSum(Real a, Real b) {
    Real s = a + b, bb = s - a;
    return {s, (a - (s - bb)) + (b - bb)};
}
template <typename Real>
DD<Real> twoProd(Real a, Real b) {
    using std::fma;
    Real p = a * b;
    return {p, fma(a, b, -p)};
}
template <typename Real>
DD<Real> ddAdd(DD<Real> a, DD<Real> b) {
    DD<Real> s = twoSum(a.hi, b.hi);
    Real lo = s.lo + a.lo + b.lo;
    return twoSum(s.hi, lo);
}

// w / |w| for both directions, as Real, and their sum, rounded once.
template <typename Real>
void normalizedPair(const Real wi[3], const Real wo[3], Vec3<Real>& ui, Vec3<Real>& uo, Vec3<Real>& sum) {
    using std::fma; using std::sqrt;
    if constexpr (std::numeric_limits<Real>::digits >= 2 * std::numeric_limits<double>::digits) {
        // __float128: w.w of double inputs is exact and one rounding is
        // 2^-113, so the plain normalization is already 1e-30 accurate where
        // wi + wo is 1e-4 long. (libquadmath's fmaq is software, ~900 ns a
        // call: the pair's 16 of them were a third of the hard-case test's
        // __float128 reference.)
        Vec3<Real> u[2];
        const Real* ws[2] = {wi, wo};
        for (int d = 0; d < 2; ++d) {
            const Real* w = ws[d];
            Real len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            u[d] = {w[0] / len, w[1] / len, w[2] / len};
        }
        ui = u[0], uo = u[1];
        sum = {u[0].x + u[1].x, u[0].y + u[1].y, u[0].z + u[1].z};
        return;
    }
    DD<Real> unit[2][3];
    const Real* ws[2] = {wi, wo};
    for (int d = 0; d < 2; ++d) {
        const Real* w = ws[d];
        DD<Real> s2{0, 0};
        for (int k = 0; k < 3; ++k) s2 = ddAdd(s2, twoProd(w[k], w[k]));
        // len = sqrt(s2) to double-Real: one Newton correction of sqrt(hi).
        Real l0 = sqrt(s2.hi);
        Real l1 = (fma(-l0, l0, s2.hi) + s2.lo) / (2 * l0);
        // 1 / len: q0 = 1 / l0 corrected for both the division's rounding and l1.
        Real q0 = 1 / l0;
        Real q1 = q0 * (fma(-q0, l0, Real(1)) - q0 * l1);
        for (int k = 0; k < 3; ++k) {
            DD<Real> p = twoProd(w[k], q0);
            unit[d][k] = twoSum(p.hi, p.lo + w[k] * q1);
        }
    }
    Real* outI[3] = {&ui.x, &ui.y, &ui.z};
    Real* outO[3] = {&uo.x, &uo.y, &uo.z};
    Real* outS[3] = {&sum.x, &sum.y, &sum.z};
    for (int k = 0; k < 3; ++k) {
        *outI[k] = unit[0][k].hi + unit[0][k].lo;
        *outO[k] = unit[1][k].hi + unit[1][k].lo;
        DD<Real> s = ddAdd(unit[0][k], unit[1][k]);
        *outS[k] = s.hi + s.lo;
    }
}

}  // namespace

template <typename Real>
ResolvedMaterial<Real> ResolvedMaterial<Real>::specularLobe() const {
    ResolvedMaterial<Real> r = *this;
    r.fresnel = &fresnelEntry(*findModel(ModelSlot::Fresnel, "none"));
    r.diffuse = &diffuseEntry(*findModel(ModelSlot::Diffuse, "none"));
    return r.withoutEnergy();
}

template <typename Real>
ResolvedMaterial<Real> ResolvedMaterial<Real>::withoutEnergy() const {
    ResolvedMaterial<Real> r = *this;
    r.energy = &energyEntry(*findModel(ModelSlot::Energy, "none"));
    return r;
}

ResolvedMaterial<double> lobeAtAlpha(const NdfEntry& ndf, const MaskingEntry& masking, double alpha,
                                     const std::vector<double>& shape) {
    ResolvedMaterial<double> r;
    r.ndf = &ndf;
    r.masking = &masking;
    r = r.specularLobe();
    size_t ndfShapes = ndf.tableShapeParams.size();
    internal_assert(shape.size() == ndfShapes + masking.tableShapeParams.size())
        << "lobe of " << ndf.name << " x " << masking.name << " with " << shape.size() << " shape values";
    r.ndfArgs = ndf.argsAtAlpha(std::max(alpha, kMinAlpha), std::vector<double>(shape.begin(), shape.begin() + ndfShapes));
    ndf.formulas.get<double>().derive(r.ndfArgs);
    for (size_t i = 0; i < masking.tableShapeParams.size(); ++i)
        r.maskingArgs.set(masking.tableShapeParams[i], shape[ndfShapes + i]);
    return r;
}

template <typename Real>
Real ResolvedMaterial<Real>::D(const Vec3<Real>& m) const {
    if (m.z <= 0) return 0;
    return ndf->formulas.template get<Real>().D(ndfArgs, m);
}

template <typename Real>
Real ResolvedMaterial<Real>::lambda(const Vec3<Real>& v) const {
    // Lambda = ((n.v) Lambda) / (n.v): at grazing Lambda grows like 1/(n.v)
    // and overflows to +Inf (G1 = 0, the right limit), never to NaN.
    Real cl = cosLambda(v);
    return cl == 0 ? Real(0) : cl / v.z;
}

template <typename Real>
Real ResolvedMaterial<Real>::cosLambda(const Vec3<Real>& v) const {
    return ndf->formulas.template get<Real>().cosLambda(ndfArgs, v);
}

template <typename Real>
Real ResolvedMaterial<Real>::smithG1(const Vec3<Real>& v, const Vec3<Real>& m) const {
    if (v.x * m.x + v.y * m.y + v.z * m.z <= 0) return 0;
    return 1 / (1 + lambda(v));
}

template <typename Real>
Real ResolvedMaterial<Real>::G(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real cosHalf) const {
    // For the half vector, wi.h = wo.h = |wi + wo| / 2 (cosHalf). Using that
    // one value for both keeps f exactly reciprocal; the two dot products
    // differ by rounding amplified by 1/|wi + wo| when the directions are
    // nearly opposite.
    Real ih = cosHalf >= 0 ? cosHalf : wi.x * h.x + wi.y * h.y + wi.z * h.z;
    Real oh = cosHalf >= 0 ? cosHalf : wo.x * h.x + wo.y * h.y + wo.z * h.z;
    if (masking->smith && (ih <= 0 || oh <= 0)) return 0;  // chi+(wi.h) chi+(wo.h)
    return masking->formulas.template get<Real>().G(*this, {wi, wo, h, ih, oh});
}

// G / ((n.wi)(n.wo)): the factor of the BRDF, D G / (4 ci co), formed
// without G and the product of the cosines. At grazing both go to zero
// together (implicit: G = ci co exactly; Smith: G ~ ci / Lambda-terms), and
// the quotient of the two underflowed values is 0/0 or 0 * Inf; each entry
// forms its own quotient.
template <typename Real>
Real ResolvedMaterial<Real>::GOverCosines(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real oh,
                                          Real scale) const {
    if (masking->smith && oh <= 0) return 0;  // chi+(wi.h) chi+(wo.h)
    if (scale == 0) return 0;                 // D underflowed: no 0 * Inf
    return masking->formulas.template get<Real>().GOverCosines(*this, {wi, wo, h, oh, oh}, scale);
}

template <typename Real>
Real ResolvedMaterial<Real>::F(Real c, int ch) const {
    return fresnelAt(c, (1 - c) * (1 + c), ch);
}

// Fresnel at c = wi.h, given s2 = 1 - c^2 as well (the BRDF passes it from
// the directions' difference: accurate where c -> 1).
template <typename Real>
Real ResolvedMaterial<Real>::fresnelAt(Real c, Real s2, int ch) const {
    return fresnel->formulas.template get<Real>().F(fresnelArgs, c, s2, ch);
}

template <typename Real>
std::array<Real, 3> ResolvedMaterial<Real>::brdf(const Vec3<Real>& wi, const Vec3<Real>& wo) const {
    return brdf(wi, wo, Vec3<Real>{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
}

template <typename Real>
std::array<Real, 3> ResolvedMaterial<Real>::brdf(const Vec3<Real>& wi, const Vec3<Real>& wo,
                                                 const Vec3<Real>& sum) const {
    using std::exp; using std::sqrt;
    if (wholeSphere()) return dielectricBsdf(*this, wi, wo, sum);  // DielectricLobe.h
    std::array<Real, 3> out{};
    Real ci = wi.z, co = wo.z;
    if (ci <= 0 || co <= 0) return out;
    Vec3<Real> h = sum;
    Real len = sqrt(h.x * h.x + h.y * h.y + h.z * h.z);
    if (len == 0) return out;
    h = {h.x / len, h.y / len, h.z / len};
    // c = wi.h = wo.h = |wi + wo| / 2 (see G); from the given sum, which
    // eval() computes without the rounding of the normalized directions.
    Real c = len / 2 < 1 ? len / 2 : Real(1);
    Real s2 = halfAngleSin2(wi, wo);  // 1 - c^2, accurate near wi = wo
    if (!ndf) {
        // A diffuse lobe: no specular term.
    } else if (ndf->wholeLobe) {
        Real lobe = ndf->formulas.template get<Real>().wholeLobe(ndfArgs, h, ci, co);
        for (int ch = 0; ch < 3; ++ch) out[ch] = fresnelAt(c, s2, ch) * lobe;
    } else {
        // D F G / (4 ci co) as (D F_max / 4) (G / (ci co)) (F / F_max): no 0 *
        // Inf or 0/0 at grazing, and G / (ci co), which grows like 1/(n.w),
        // scaled by the whole rest of the largest channel before it can
        // overflow where that channel does not.
        std::array<Real, 3> f;
        Real fMax = 0;
        for (int ch = 0; ch < 3; ++ch) f[ch] = fresnelAt(c, s2, ch), fMax = f[ch] > fMax ? f[ch] : fMax;
        Real dg = fMax > 0 ? GOverCosines(wi, wo, h, c, D(h) * fMax / 4) : Real(0);
        // F = 0 (eta = 1): no 0 * Inf; a NaN F stays NaN.
        for (int ch = 0; ch < 3; ++ch) out[ch] = f[ch] == 0 ? Real(0) : f[ch] == fMax ? dg : f[ch] / fMax * dg;
    }
    if (energy->compensates) {
        std::array<Real, 3> ms = kullaContyBrdf(*this, ci, co);
        for (int ch = 0; ch < 3; ++ch) out[ch] += ms[ch];
    }
    if (energy->walks) {
        std::array<Real, 3> ms = walkMultipleScattering(*this, wi, wo);  // WalkLobe.h
        for (int ch = 0; ch < 3; ++ch) out[ch] += ms[ch];
    }
    if (diffuse->present)
        for (int ch = 0; ch < 3; ++ch) out[ch] += diffuse->formulas.template get<Real>().value(diffuseArgs, ch);
    return out;
}

template <typename Real>
Interpreter<Real>::Interpreter(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> energyTable)
    : material_(material), read_(material.readByModels()) {
    for (const CheckedLobe& lobe : material.lobes)
        energy_.push_back(lobe.compensatesEnergy()
                              ? std::make_shared<EnergyTableSlot>(energyTableKey(material, lobe),
                                                                  material.combinesLobes() ? nullptr : energyTable)
                              : nullptr);
    addInsideTables();
}

template <typename Real>
void Interpreter<Real>::addInsideTables() {
    for (size_t l = 0; l < material_.lobes.size(); ++l) {
        const CheckedLobe& lobe = material_.lobes[l];
        bool both = lobe.compensatesEnergy() && lobe.wholeSphere();
        // A thin sheet's tables are the same on both sides.
        energyInside_.push_back(!both      ? nullptr
                                : lobe.thin ? energy_[l]
                                            : std::make_shared<EnergyTableSlot>(
                                                  insideTableKey(energyTableKey(material_, lobe)), nullptr));
    }
}

template <typename Real>
Interpreter<Real>::Interpreter(const CheckedMaterial& material,
                               const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables)
    : material_(material), read_(material.readByModels()) {
    for (size_t l = 0; l < material.lobes.size(); ++l) {
        const CheckedLobe& lobe = material.lobes[l];
        energy_.push_back(lobe.compensatesEnergy()
                              ? std::make_shared<EnergyTableSlot>(energyTableKey(material, lobe),
                                                                  l < lobeTables.size() ? lobeTables[l] : nullptr)
                              : nullptr);
    }
    addInsideTables();
}

template <typename Real>
ResolvedMaterial<Real> Interpreter<Real>::resolve(const Real* slots) const {
    internal_assert(!material_.combinesLobes()) << "resolve() of material '" << material_.name
                                                << "', which combines lobes: use resolveAll()";
    ResolvedBsdf<Real> all = resolveAll(slots);
    ResolvedMaterial<Real> r = std::move(all.lobes.at(size_t(material_.bsdfRoot().lobe)));
    r.valid = all.valid;
    return r;
}

template <typename Real>
ResolvedBsdf<Real> Interpreter<Real>::resolveAll(const Real* slots) const {
    using std::isnan;
    const CheckedMaterial& m = material_;
    ResolvedBsdf<Real> r;

    // Inputs: given or default, clamped to the declared range.
    std::vector<Value<Real>> inputs(m.inputs.size());
    for (size_t i = 0; i < m.inputs.size(); ++i) {
        const CheckedInput& in = m.inputs[i];
        Value<Real>& v = inputs[i];
        v.rgb = in.type == ValueType::Rgb;
        for (int ch = 0; ch < in.slotCount(); ++ch) {
            Real x = slots ? slots[in.firstSlot + ch] : Real(in.defaultValue[ch]);
            if (!finite(x) && read_.inputs[i]) r.valid = false;
            if (in.hasRange) x = x < Real(in.lo) ? Real(in.lo) : (x > Real(in.hi) ? Real(in.hi) : x);
            v.c[ch] = x;
        }
        if (!v.rgb) v.c[1] = v.c[2] = v.c[0];
    }
    std::vector<Value<Real>> lets;
    lets.reserve(m.lets.size());
    auto lookup = [&](const NameExpr& n) -> Value<Real> {
        internal_assert(n.binding != BindingKind::Unresolved) << "unresolved name " << n.name;
        return n.binding == BindingKind::Input ? inputs.at(n.index) : lets.at(n.index);
    };
    for (size_t i = 0; i < m.lets.size(); ++i)
        lets.push_back(read_.lets[i] ? evaluateExpr<Real>(*m.lets[i].value, lookup) : Value<Real>{});

    // A model argument, clamped to its catalog domain: NaN is invalid;
    // clamping happens before the finiteness test so that e.g.
    // phong_exponent(0) = inf clamps to the largest exponent instead of
    // failing.
    auto clamped = [&](Real x, Real lo, Real hi) {
        if (isnan(x)) {
            r.valid = false;
            return Real(0);
        }
        x = x < lo ? lo : (x > hi ? hi : x);
        if (!finite(x)) r.valid = false;
        return x;
    };
    for (size_t l = 0; l < m.lobes.size(); ++l) {
        const CheckedLobe& lobe = m.lobes[l];
        ResolvedMaterial<Real>& out = r.lobes.emplace_back();
        out.ndf = lobe.ndf.model ? &ndfEntry(*lobe.ndf.model) : nullptr;
        out.masking = &maskingEntry(*lobe.masking.model);
        out.fresnel = &fresnelEntry(*lobe.fresnel.model);
        out.energy = &energyEntry(*lobe.energy.model);
        out.diffuse = &diffuseEntry(*lobe.diffuse.model);
        out.scatter = lobe.scatter;
        out.thin = lobe.thin;
        out.transport = transport_;
        auto resolveArgs = [&](const ModelUse& use, ModelArgs<Real>& args) {
            if (!use.model) return;
            for (size_t p = 0; p < use.model->canonical.size(); ++p) {
                if (!use.has(int(p))) continue;
                const ModelParam& param = use.model->canonical[p];
                Value<Real> v = evaluateExpr<Real>(*use.args[p], lookup);
                args.given[p] = true;
                for (int ch = 0; ch < (param.type == ValueType::Rgb ? 3 : 1); ++ch)
                    args.value[p][ch] = clamped(param.type == ValueType::Rgb ? v.channel(ch) : v.c[0],
                                                Real(param.lo), Real(param.hi));
                if (param.type != ValueType::Rgb) args.value[p][1] = args.value[p][2] = args.value[p][0];
            }
        };
        resolveArgs(lobe.ndf, out.ndfArgs);
        if (r.valid && out.ndf) out.ndf->formulas.template get<Real>().derive(out.ndfArgs);
        resolveArgs(lobe.masking, out.maskingArgs);
        resolveArgs(lobe.fresnel, out.fresnelArgs);
        resolveArgs(lobe.diffuse, out.diffuseArgs);
        if (energy_[l] && r.valid) {
            if (energyInside_[l])
                resolveWholeSphereCompensation(out, energy_[l]->get(), energyInside_[l]->get());  // DielectricEnergy.h
            else
                resolveKullaConty(out, energy_[l]->get());
        }
    }
    // The combination's weights (SPEC 10): a scale is clamped to >= 0, a
    // mix's and a layer's to [0, 1].
    for (const BsdfNode& node : m.bsdf) {
        std::array<Real, 3>& w = r.weights.emplace_back(std::array<Real, 3>{1, 1, 1});
        if (!node.weight) continue;
        Value<Real> v = evaluateExpr<Real>(*node.weight, lookup);
        Real hi = node.kind == BsdfKind::Scale ? Real(INFINITY) : Real(1);
        for (int ch = 0; ch < 3; ++ch) {
            w[ch] = clamped(v.channel(ch), Real(0), hi);
        }
    }
    for (ResolvedMaterial<Real>& lobe : r.lobes) lobe.valid = r.valid;
    return r;
}

template <typename Real>
EvalResult<Real> Interpreter<Real>::eval(const Real wi[3], const Real wo[3], const Real* slots) const {
    using std::abs; using std::sqrt;
    EvalResult<Real> out;
    Vec3<Real> dirs[2];
    const Real* given[2] = {wi, wo};
    for (int d = 0; d < 2; ++d) {
        const Real* w = given[d];
        if (!finite(w[0]) || !finite(w[1]) || !finite(w[2])) {
            out.valid = false;
            return out;
        }
        Real len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (!(abs(len - 1) <= Real(kUnitTolerance))) {
            out.valid = false;
            return out;
        }
    }
    // Unit directions and wi + wo in double-Real arithmetic (see
    // normalizedPair): when wi and wo are nearly opposite, h is decided by
    // the last bits of the normalized directions.
    Vec3<Real> sum;
    normalizedPair(wi, wo, dirs[0], dirs[1], sum);
    ResolvedBsdf<Real> r = resolveAll(slots);
    if (!r.valid) {
        out.valid = false;
        return out;
    }
    out.rgb = combinedBrdf(r, dirs[0], dirs[1], sum, slots);
    // A value that overflows even the reference's range (parameters far
    // outside any physical use) is reported as an invalid lane, never as Inf.
    for (Real v : out.rgb)
        if (!finite(v) || v < 0) {
            out = {};
            out.valid = false;
        }
    return out;
}

template class Interpreter<float>;
template class Interpreter<double>;
template class Interpreter<long double>;
template struct ResolvedMaterial<float>;
template struct ResolvedMaterial<double>;
template struct ResolvedMaterial<long double>;
// __float128: the high-precision reference of the hard-case checks (QuadMath.h).
template class Interpreter<__float128>;
template struct ResolvedMaterial<__float128>;

}  // namespace facet
