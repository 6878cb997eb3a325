// LaneSampling: the lane bodies of the sample and pdf entry points (SPEC 8,
// the plan's SamplingPlan): the lobe probability from each lobe's albedo
// estimate, the cosine lobe, the specular lobe's density through the drawn
// normal or the half vector, the one-sample mixture's pdf, and the weight
// f (n.wi) / pdf with f from eval's own assembly. The NDF-specific samplers
// are the NDF emitters' hooks (TermEmitters.h). Written independently of
// the reference sampler (compiler/reference/Sampling.cpp), against which the tests
// compare it.
#include "LaneEmitter.h"

namespace facet {

using llvm::Value;
using Vec = std::array<Value*, 3>;

namespace {

// The smallest probability either lobe gets when both are present: a poor
// albedo estimate (F = 0 at n.wo but not at other angles) must not starve
// a lobe whose f is not zero.
constexpr double kMinLobeProbability = 0.05;

Value* channelMean(MathEmitter& m, const LVal& v) {
    if (v.gray()) return v.c[0];
    return m.mul(m.add(m.add(v.c[0], v.c[1]), v.c[2]), m.c(1.0 / 3.0));
}

}  // namespace

// What the sample and pdf bodies share for one lane.
struct LaneEmitter::SamplingTerms {
    NdfParams n;
    Vec wo;                     // unit, n.wo > 0 (other lanes read (0, 0, 1)), precise type
    Value* p = nullptr;         // the specular lobe's probability
    Value* smithDen = nullptr;  // visible normals: 4 (n.wo)(1 + Lambda(wo)), precise type (visibleSmithSum)
    Value* above = nullptr;     // n.wo > 0 (else no sample and pdf 0)
};

// The NDF's parameters, the lobe probability and the Smith term of the
// lane's wo (unit, precise type), after lowerInputsAndLets.
LaneEmitter::SamplingTerms LaneEmitter::samplingTerms(const Vec& wo) {
    MathEmitter& pm = preciseMath_;
    SamplingTerms t;
    t.n = emitters_.ndf.params(*this);
    // With n.wo <= 0 the BRDF is 0 for every wi: no sample (a valid lane).
    // Those lanes compute with wo = n, so that nothing below is NaN there.
    t.above = pm.gt(wo[2], pm.c(0.0));
    t.wo = selectVec(pm, t.above, wo, constantVec(pm, 0, 0, 1));
    if (plan.sampling.specular == SpecularSampling::VisibleNormals)
        t.smithDen = pm.mul(pm.c(4.0), emitters_.ndf.visibleSmithSum(*this, t.n, t.wo));
    t.p = specularProbability(t);
    return t;
}

Vec LaneEmitter::normalFromSlopes(Value* sx, Value* sy) {
    MathEmitter& pm = preciseMath_;
    Value* inv = pm.div(pm.c(1.0), pm.sqrt(pm.fma(sx, sx, pm.fma(sy, sy, pm.c(1.0)))));
    return {pm.neg(pm.mul(sx, inv)), pm.neg(pm.mul(sy, inv)), inv};
}

Vec LaneEmitter::normalFromPolar(Value* sin2, Value* u, Value* cos2) {
    MathEmitter& pm = preciseMath_;
    Value* s2 = pm.minnum(pm.maxnum(sin2, pm.c(0.0)), pm.c(1.0));
    Value* s = pm.sqrt(s2);
    Value* c = pm.sqrt(cos2 ? pm.minnum(pm.maxnum(cos2, pm.c(0.0)), pm.c(1.0)) : pm.sub(pm.c(1.0), s2));
    auto [sinPhi, cosPhi] = pm.sinCosTurns(u);
    return {pm.mul(s, cosPhi), pm.mul(s, sinPhi), c};
}

Vec LaneEmitter::stretchedSlopeNormal(const NdfParams& n, Value* r2, Value* u) {
    MathEmitter& pm = preciseMath_;
    Value* r = pm.sqrt(r2);
    auto [sinPhi, cosPhi] = pm.sinCosTurns(u);
    return normalFromSlopes(pm.mul(n.axD, pm.mul(r, cosPhi)), pm.mul(n.ayD, pm.mul(r, sinPhi)));
}

Value* LaneEmitter::expm1(Value* y) { return preciseMath_.mul(y, expm1OverX(y)); }

Value* LaneEmitter::invertIncreasing(MathEmitter& pm, const CdfAndPdf& cdfAndPdf, Value* target, Value* lo, Value* hi,
                                     int steps) {
    auto phi = [&](Value* x) {
        auto [cdf, pdf] = cdfAndPdf(x);
        return NewtonTerms{pm.sub(cdf, target), pdf};
    };
    return bracketedNewton(pm, phi, pm.mul(pm.add(lo, hi), pm.c(0.5)), lo, hi, steps);
}

Value* LaneEmitter::bracketedNewton(MathEmitter& pm, const std::function<NewtonTerms(Value*)>& eval, Value* v0,
                                    Value* lo, Value* hi, int steps, double settledStep, double settledFloor) {
    return emitBracketedNewton(builder, pm, eval, v0, lo, hi, steps, settledStep, settledFloor);
}

// p = A_spec / (A_spec + A_other), clamped to [0.05, 0.95], with the
// albedo estimates at n.wo (channel means): A_spec = F(n.wo) E(n.wo) (E =
// 1 without a Kulla-Conty table), A_other = the Lambert albedo plus the
// compensation lobe's. 1 without a cosine lobe.
Value* LaneEmitter::specularProbability(SamplingTerms& t) {
    MathEmitter& pm = preciseMath_;
    if (!plan.sampling.cosineLobe) return pm.c(1.0);
    Value* c = pm.minnum(t.wo[2], pm.c(1.0));
    Value* q = pm.sub(pm.c(1.0), c);
    // F as a facet seen at wo's angle: the Fresnel emitters read the cosine,
    // 1 - cosine and sin^2 of a geometry.
    LaneGeometry atWo{};
    atWo.cosD = c;
    atWo.oneMinusCosD = q;
    atWo.sin2D = pm.mul(q, pm.add(pm.c(1.0), c));
    Value* albedo = channelMean(pm, emitters_.fresnel.F(*this, atWo));
    Value* other = pm.c(0.0);
    if (plan.sampling.compensationAlbedo) {
        CompensationAlbedo ca = emitters_.energy.samplingAlbedo(*this, emitters_.ndf, t.n, emitters_.fresnel, c);
        albedo = pm.mul(albedo, pm.sub(pm.c(1.0), ca.oneMinusE));
        other = ca.albedo;
    }
    if (emitters_.diffuse.present())
        other = pm.fma(channelMean(pm, emitters_.diffuse.diffuse(*this)), pm.c(kPi), other);
    Value* total = pm.add(albedo, other);
    Value* ok = builder.CreateAnd(pm.gt(total, pm.c(0.0)), pm.isFinite(total));
    Value* p = pm.select(ok, pm.div(albedo, total), pm.c(0.5));
    return pm.minnum(pm.maxnum(p, pm.c(kMinLobeProbability)), pm.c(1 - kMinLobeProbability));
}

// The specular lobe's density of wi = 2 (wo.m) m - wo, for the unit normal
// m with om = wo.m: pdf_m(m) / (4 |wo.m|), the Jacobian of the reflection.
// With visible normals pdf_m = G1(wo) (wo.m)+ D(m) / (n.wo), so the density
// is D(m) / (4 ((n.wo) + (n.wo) Lambda(wo))) where wo.m > 0.
Value* LaneEmitter::specularPdf(SamplingTerms& t, const Vec& m, Value* om) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    const NdfEmitter& ndf = emitters_.ndf;
    LaneGeometry atM{};
    for (int i = 0; i < 3; ++i) atM.h[i] = fm.convert(m[i], fm.type());
    atM.hD = m;
    atM.slopeH = m;  // unit: slopeHLen2 stays null
    Value* up = pm.gt(m[2], pm.c(0.0));
    if (plan.sampling.specular == SpecularSampling::VisibleNormals) {
        Value* ok = builder.CreateAnd(up, pm.gt(om, pm.c(0.0)));
        return pm.select(ok, pm.div(ndf.D(*this, t.n, atM), t.smithDen), pm.c(0.0));
    }
    Value* ok = builder.CreateAnd(up, builder.CreateNot(pm.eq(om, pm.c(0.0))));
    Value* pdf = pm.div(ndf.normalPdf(*this, t.n, atM), pm.mul(pm.c(4.0), pm.abs(om)));
    return pm.select(ok, pdf, pm.c(0.0));
}

// p pdf_spec + (1 - p) (n.wi)+ / pi, or pdf_spec without a cosine lobe.
Value* LaneEmitter::mixturePdf(SamplingTerms& t, Value* spec, const Vec& wi) {
    MathEmitter& pm = preciseMath_;
    if (!plan.sampling.cosineLobe) return spec;
    Value* cosine = pm.select(pm.gt(wi[2], pm.c(0.0)), pm.mul(wi[2], pm.c(1.0 / kPi)), pm.c(0.0));
    return pm.fma(t.p, spec, pm.mul(pm.sub(pm.c(1.0), t.p), cosine));
}

namespace {

// The unit half vector of wi and wo turned to the upper hemisphere, its
// wo.m, and whether it exists (wi + wo not 0).
struct HalfNormal {
    Vec m, sum;  // sum: wi + wo
    Value *om, *exists;
};

HalfNormal halfNormal(MathEmitter& pm, const Vec& wi, const Vec& wo) {
    Vec s = {pm.add(wi[0], wo[0]), pm.add(wi[1], wo[1]), pm.add(wi[2], wo[2])};
    Value* len2 = dot(pm, s, s);
    // The sampler's normals have m.z > 0: m = -h where h points down.
    Value* inv = pm.div(pm.c(1.0), pm.sqrt(len2));
    inv = pm.select(pm.lt(s[2], pm.c(0.0)), pm.neg(inv), inv);
    Vec m = {pm.mul(s[0], inv), pm.mul(s[1], inv), pm.mul(s[2], inv)};
    // wo.m = wi.m = +-|wi + wo| / 2 for unit wi and wo, as the reference
    // computes it. The dot product itself would take the rounding of the
    // directions' near-cancelling components for the answer where wi is
    // nearly -wo (a grazing mirror pair: wo.m of 1e-40 where it is 2e-24).
    // (inv carries m's sign.)
    Value* om = pm.mul(pm.c(0.5), pm.mul(len2, inv));
    return {m, s, om, pm.gt(len2, pm.c(0.0))};
}

}  // namespace

LaneEmitter::SampleResult LaneEmitter::emitSample(const Vec& woArg, const Vec& u, const std::vector<Value*>& slots) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const SamplingPlan& sp = plan.sampling;
    internal_assert(sp.specular != SpecularSampling::None) << "a sampler without a specular technique";
    if (sp.walk) return emitWalkSample(woArg, u, slots);
    if (plan.wholeSphere) return emitWholeSphereSample(woArg, u, slots);  // LaneDielectricSampling.cpp
    const Vec woIn = readDirection(woArg);
    Vec wo;
    if (body.correctedSums) {
        Value* corr = unitCorrection(woIn);
        for (int i = 0; i < 3; ++i) wo[i] = fm.fma(woIn[i], corr, woIn[i]);
    } else {
        Vec woF{};
        wo = unitDirection(woIn, woF);
    }
    for (Value* x : u)
        rejectInput([&] { return b.CreateNot(b.CreateAnd(fm.ge(x, fm.c(0.0)), fm.lt(x, fm.c(1.0)))); });
    lowerInputsAndLets(slots);

    SamplingTerms t = samplingTerms(wo);
    const bool visible = sp.specular == SpecularSampling::VisibleNormals;
    Value* u0 = pm.convert(u[0], pm.type());
    Value* u1 = pm.convert(u[1], pm.type());
    Value* u2 = pm.convert(u[2], pm.type());

    // The specular lobe: wi is the reflection of wo about the drawn m.
    Vec m = visible ? emitters_.ndf.sampleVisibleNormal(*this, t.n, t.wo, u1, u2)
                    : emitters_.ndf.sampleNormal(*this, t.n, u1, u2);
    Value* om = dot(pm, t.wo, m);
    Value* twoOm = pm.add(om, om);
    Vec sum = {pm.mul(twoOm, m[0]), pm.mul(twoOm, m[1]), pm.mul(twoOm, m[2])};  // wi + wo
    Vec wi = {pm.sub(sum[0], t.wo[0]), pm.sub(sum[1], t.wo[1]), pm.sub(sum[2], t.wo[2])};
    Value* specular = nullptr;
    Vec mPdf = m, cosineSum{};
    Value *omPdf = om, *pdfExists = pm.c(1.0);
    if (sp.cosineLobe) {
        // The cosine lobe: sqrt(u1) in the unit disk at azimuth 2 pi u2,
        // lifted to the hemisphere. Its specular density is through the
        // half vector.
        specular = pm.lt(u0, t.p);
        Value* r = pm.sqrt(u1);
        auto [sinPhi, cosPhi] = pm.sinCosTurns(u2);
        Vec wiCos = {pm.mul(r, cosPhi), pm.mul(r, sinPhi), pm.sqrt(pm.sub(pm.c(1.0), u1))};
        HalfNormal h = halfNormal(pm, wiCos, t.wo);
        cosineSum = h.sum;
        wi = selectVec(pm, specular, wi, wiCos);
        mPdf = selectVec(pm, specular, m, h.m);
        omPdf = pm.select(specular, om, h.om);
        pdfExists = pm.select(b.CreateOr(specular, h.exists), pm.c(1.0), pm.c(0.0));
    }
    if (body.guarded()) {
        // A float body keeps the lanes whose density and f it computes to
        // float accuracy: wo.m, in float a few ulp off absolutely, enters F
        // and the maskings that divide by wo.h relative to itself, so |wo.m|
        // >= 1e-2 (with visible normals the density of m is proportional to
        // wo.m: such lanes are rare); a cosine sample's half vector is the
        // sum wi + wo, exact to a few ulp absolutely, so |wi + wo|^2 >= 1e-2
        // keeps D of it within ~1e-6.
        Value* badSpecular = pm.lt(pm.abs(om), pm.c(1e-2));
        distrust(sp.cosineLobe ? pm.select(specular, badSpecular, pm.lt(dot(pm, cosineSum, cosineSum), pm.c(1e-2)))
                               : badSpecular);
    }
    Value* spec = pm.mul(specularPdf(t, mPdf, omPdf), pdfExists);
    Value* pdf = mixturePdf(t, spec, wi);

    // f at the sample from eval's assembly. For a specular sample the half
    // vector is the drawn normal (and wi + wo its multiple), not the sum of
    // the rounded directions: near wi = -wo that sum would turn h away from
    // m, and D(h) would no longer cancel the density's D(m).
    Vec wiLane;
    for (int i = 0; i < 3; ++i) wiLane[i] = fm.convert(wi[i], fm.type());
    Vec wiEval = selectVec(fm, t.above, wiLane, constantVec(fm, 0, 0, 1));
    LaneGeometry geo = geometry(wiEval, woIn, true);
    if (!pm.isDouble()) {
        // A float body's eval reads wo as the sampler does (n for a lane
        // below the horizon, whose weight is 0 below): the same values, so
        // that the terms of wo both take (the Smith root) are computed once.
        geo.wo = t.wo;
        geo.woD = t.wo;
    }
    Value* fromDrawn = sp.cosineLobe ? specular : llvm::Constant::getAllOnesValue(boolType());
    if (geo.hD[0])  // null where the plan keeps the half angle in float (no consumer of the unit h)
        for (int i = 0; i < 3; ++i) {
            geo.hD[i] = pm.select(fromDrawn, m[i], geo.hD[i]);
            geo.h[i] = fm.select(fromDrawn, fm.convert(m[i], fm.type()), geo.h[i]);
        }
    if (geo.slopeHLen2) {
        // wi + wo up to scale: the drawn normal's multiple.
        for (int i = 0; i < 3; ++i) geo.slopeH[i] = pm.select(fromDrawn, sum[i], geo.slopeH[i]);
        geo.slopeHLen2 = pm.select(fromDrawn, dot(pm, sum, sum), geo.slopeHLen2);
    } else {
        for (int i = 0; i < 3; ++i) geo.slopeH[i] = pm.select(fromDrawn, m[i], geo.slopeH[i]);
    }
    // wo.h of the drawn normal too (h = m, or -m where wo.m < 0): the
    // masking and Fresnel terms that read it (Kelemen's (wo.h)^2, F(wo.h))
    // would otherwise take |wi + wo| / 2 of the rounded directions, which at
    // grazing mirror pairs (wi + wo of size n.wo) is off by several percent
    // while the density uses the exact wo.m. 1 - wo.h = |wo - h|^2 / 2
    // without cancellation near wo = h.
    {
        Value* sign = pm.select(pm.lt(om, pm.c(0.0)), pm.c(-1.0), pm.c(1.0));
        Vec d = {pm.sub(t.wo[0], pm.mul(sign, m[0])), pm.sub(t.wo[1], pm.mul(sign, m[1])),
                 pm.sub(t.wo[2], pm.mul(sign, m[2]))};
        Value* cosM = pm.minnum(pm.abs(om), pm.c(1.0));
        Value* oneMinusCosM = pm.minnum(pm.mul(dot(pm, d, d), pm.c(0.5)), pm.c(1.0));
        geo.cosD = pm.select(fromDrawn, cosM, geo.cosD);
        geo.oneMinusCosD = pm.select(fromDrawn, oneMinusCosM, geo.oneMinusCosD);
        geo.sin2D = pm.select(fromDrawn, pm.mul(oneMinusCosM, pm.add(pm.c(1.0), cosM)), geo.sin2D);
    }
    Value* fValid = nullptr;
    Vec f = brdfPrecise(geo, fValid);

    SampleResult r;
    // Below the horizon f is 0 (the lane's eval there may have read n for
    // wo). A density that underflows float is no density a renderer can
    // divide by: pdf 0 means weight 0.
    r.pdf = fm.convert(pdf, fm.type());
    Value* weighted = b.CreateAnd(b.CreateAnd(fValid, t.above), fm.gt(r.pdf, fm.c(0.0)));
    Value* cosOverPdf = pm.div(wi[2], pdf);
    for (int ch = 0; ch < 3; ++ch) {
        Value* w = pm.select(weighted, pm.mul(f[ch], cosOverPdf), pm.c(0.0));
        r.weight[ch] = fm.convert(w, fm.type());
    }
    r.wi = wiLane;
    finishSample(r, b.CreateNot(t.above));
    return r;
}

// As in eval: a result float cannot hold is an invalid lane. Invalid lanes
// and those of `noSample` return wi = 0, pdf = 0 and weight = 0.
void LaneEmitter::finishSample(SampleResult& r, Value* noSample) {
    MathEmitter& fm = floatMath_;
    llvm::IRBuilder<>& b = builder;
    markInvalid(fm.anyNanInfOrNegative({r.pdf, r.weight[0], r.weight[1], r.weight[2]}));
    for (Value* x : r.wi) markInvalid(b.CreateNot(fm.isFinite(x)));
    Value* zero = b.CreateOr(invalid_, noSample);
    for (Value*& x : r.wi) x = fm.select(zero, fm.c(0.0), x);
    r.pdf = fm.select(zero, fm.c(0.0), r.pdf);
    for (Value*& x : r.weight) x = fm.select(zero, fm.c(0.0), x);
    r.invalid = invalid_;
    r.untrusted = b.CreateOr(untrusted_, invalid_);
}

LaneEmitter::PdfResult LaneEmitter::emitPdf(const Vec& wiIn, const Vec& woIn, const std::vector<Value*>& slots) {
    MathEmitter& pm = preciseMath_;
    internal_assert(plan.sampling.specular != SpecularSampling::None) << "a pdf without a specular technique";
    if (plan.wholeSphere) return emitWholeSpherePdf(wiIn, woIn, slots);  // LaneDielectricSampling.cpp
    Vec wiF{}, woF{};
    Vec wi = unitDirection(readDirection(wiIn), wiF);
    Vec wo = unitDirection(readDirection(woIn), woF);
    lowerInputsAndLets(slots);

    SamplingTerms t = samplingTerms(wo);
    Value* pdf;
    if (plan.sampling.walk) {
        pdf = pm.select(t.above, walkPdf(t, wi), pm.c(0.0));
    } else {
        HalfNormal h = halfNormal(pm, wi, t.wo);
        Value* spec = pm.select(h.exists, specularPdf(t, h.m, h.om), pm.c(0.0));
        pdf = pm.select(t.above, mixturePdf(t, spec, wi), pm.c(0.0));
    }
    return finishPdf(pdf);
}

// The density in float; as in eval, one float cannot hold is an invalid
// lane, and an invalid lane's density is 0.
LaneEmitter::PdfResult LaneEmitter::finishPdf(Value* pdf) {
    MathEmitter& fm = floatMath_;
    PdfResult r;
    r.pdf = fm.convert(pdf, fm.type());
    markInvalid(fm.isNanInfOrNegative(r.pdf));
    r.pdf = fm.select(invalid_, fm.c(0.0), r.pdf);
    r.invalid = invalid_;
    return r;
}

// energy = random_walk (LaneWalk.cpp): the walk from wo; wi is where it
// leaves and the weight the product of the Fresnel terms met, which is f
// (n.wi) over the walk's own density; pdf is walkPdf's, for MIS.
LaneEmitter::SampleResult LaneEmitter::emitWalkSample(const Vec& woArg, const Vec& u, const std::vector<Value*>& slots) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    Vec woF{};
    Vec wo = unitDirection(readDirection(woArg), woF);
    for (Value* x : u)
        rejectInput([&] { return b.CreateNot(b.CreateAnd(fm.ge(x, fm.c(0.0)), fm.lt(x, fm.c(1.0)))); });
    lowerInputsAndLets(slots);
    SamplingTerms t = samplingTerms(wo);
    WalkExit exit = walkFromView(t.wo, t.above, u);
    Value* left = pm.gt(exit.wi[2], pm.c(0.0));  // not cut
    Value* pdf = pm.select(left, walkPdf(t, exit.wi), pm.c(0.0));

    SampleResult r;
    r.pdf = fm.convert(pdf, fm.type());
    for (int i = 0; i < 3; ++i) r.wi[i] = fm.convert(exit.wi[i], fm.type());
    for (int ch = 0; ch < 3; ++ch) r.weight[ch] = fm.convert(pm.select(left, exit.weight[ch], pm.c(0.0)), fm.type());
    finishSample(r, b.CreateNot(b.CreateAnd(t.above, left)));
    return r;
}

// The random-walk lobe's density for MIS (compiler/reference/WalkLobe.h):
// (1 - q) p_ss(wi) + q (n.wi)+ / pi, p_ss the reflection of a visible normal
// of wo and q = Lambda(wo) / (1 + Lambda(wo)) in [0.05, 0.95].
Value* LaneEmitter::walkPdf(SamplingTerms& t, const Vec& wi) {
    MathEmitter& pm = preciseMath_;
    HalfNormal h = halfNormal(pm, wi, t.wo);
    Value* single = pm.select(h.exists, specularPdf(t, h.m, h.om), pm.c(0.0));
    Value* cl = emitters_.ndf.visibleCosLambda(*this, t.n, t.wo);
    Value* q = pm.div(cl, pm.add(t.wo[2], cl));
    q = pm.minnum(pm.maxnum(q, pm.c(kMinLobeProbability)), pm.c(1 - kMinLobeProbability));
    Value* cosine = pm.select(pm.gt(wi[2], pm.c(0.0)), pm.mul(wi[2], pm.c(1.0 / kPi)), pm.c(0.0));
    return pm.fma(pm.sub(pm.c(1.0), q), single, pm.mul(q, cosine));
}

}  // namespace facet
