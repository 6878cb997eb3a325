// LaneDielectricSampling: the sample and pdf bodies of a lobe over the whole
// sphere (SPEC 11; plan.wholeSphere), written from the sampler's
// definition in compiler/reference/DielectricLobe.h, against which the
// tests compare it.
//
// In wo's frame (z times the sign of n.wo, wo above): a facet normal m drawn
// for wo (visible normals where the catalog has them, else the NDF's), then
//   - the rough interface: reflection with probability F(wo.m, eta') (0 for
//     scatter = transmit), else refraction (Snell about m; none past the
//     critical angle, where F = 1);
//   - the thin sheet: the reflection of wo about m, kept on wo's side with
//     probability R' and mirrored to the far side with T' (channel sums).
// pdf = P(branch) p_m(m) J, J = 1 / (4 wo.m) for a reflection and
// eta'^2 |wi.m| / (eta' wi.m + wo.m)^2 for a refraction; a draw that gives
// no direction (below the horizon, total internal reflection) is no sample,
// as in the reference and pbrt-v4. weight = f |n.wi| / pdf, f from eval's
// own wholeSphereValue.
#include "LaneEmitter.h"
#include "WholeSphereEnergy.h"

#include <optional>
#include <tuple>

namespace facet {

using llvm::Value;
using Vec = std::array<Value*, 3>;

// The branch probabilities at cos c (the facet's wo.m) of the interface or
// the sheet: what the reference's sampler weighs its choice with.
struct BranchWeights {
    Value *reflect, *transmit;
};

static BranchWeights branchWeights(LaneEmitter& lane, const FresnelEmitter& fresnel, const LVal& eta, Value* etaRel,
                                   Value* c) {
    MathEmitter& pm = lane.preciseMath();
    const bool keepsReflection = lane.plan.keepsReflection, keepsTransmission = lane.plan.keepsTransmission;
    if (!lane.plan.thinSheet) {
        Value* pr = keepsReflection ? fresnel.reflectanceAcross(lane, etaRel, c) : pm.c(0.0);
        return {pr, fresnel.transmittanceAcross(lane, etaRel, c)};
    }
    // The sheet: R' and T' summed over the channels.
    Value *pr = pm.c(0.0), *pt = pm.c(0.0);
    for (int ch = 0; ch < 3; ++ch) {
        Value* n = eta.c[ch];
        if (keepsReflection) {
            pr = pm.add(pr, lane.sheetReflectance(fresnel.reflectanceAcross(lane, n, c)));
        }
        if (keepsTransmission) {
            pt = pm.add(pt, lane.sheetTransmittance(fresnel.transmittanceAcross(lane, n, c)));
        }
    }
    return {pr, pt};
}

// A branch's share of the draws, part / total: 0 where no branch has
// weight (past the critical angle of scatter = transmit).
static Value* branchShare(MathEmitter& pm, Value* part, Value* total) {
    return pm.select(pm.gt(total, pm.c(0.0)), pm.div(part, total), pm.c(0.0));
}

// The density of the drawn normal m for the view o (above, unit): visible
// normals 4 (o.m) D(m) / smithDen, smithDen = 4 (n.o)(1 + Lambda(o)); else
// the NDF's normalPdf. 0 where o.m <= 0.
static Value* facetDensity(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const Vec& o, const Vec& m,
                           Value* om) {
    MathEmitter& fm = lane.floatMath();
    MathEmitter& pm = lane.preciseMath();
    LaneGeometry atM{};
    for (int i = 0; i < 3; ++i) atM.h[i] = fm.convert(m[i], fm.type());
    atM.hD = m;
    atM.slopeH = m;  // unit: slopeHLen2 stays null
    Value* density;
    if (lane.plan.sampling.specular == SpecularSampling::VisibleNormals) {
        Value* smithDen = pm.mul(pm.c(4.0), ndf.visibleSmithSum(lane, n, o));
        density = pm.div(pm.mul(pm.mul(pm.c(4.0), om), ndf.D(lane, n, atM)), smithDen);
    } else {
        density = ndf.normalPdf(lane, n, atM);
    }
    return pm.select(lane.builder.CreateAnd(pm.gt(om, pm.c(0.0)), pm.gt(m[2], pm.c(0.0))), density, pm.c(0.0));
}

LaneEmitter::SampleResult LaneEmitter::emitWholeSphereSample(const Vec& woArg, const Vec& u,
                                                             const std::vector<Value*>& slots) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const NdfEmitter& ndf = emitters_.ndf;
    Vec unusedF;
    const Vec wo = unitDirection(readDirection(woArg), unusedF);
    for (Value* x : u)
        rejectInput([&] { return b.CreateNot(b.CreateAnd(fm.ge(x, fm.c(0.0)), fm.lt(x, fm.c(1.0)))); });
    lowerInputsAndLets(slots);
    WholeSphereTerms t = wholeSphereTerms();
    Value* zero = pm.c(0.0);
    Value *u0 = pm.convert(u[0], pm.type()), *u1 = pm.convert(u[1], pm.type()), *u2 = pm.convert(u[2], pm.type());
    // With compensation, u0 below its probability p draws from it (u0 / p
    // reused for its side); above, the single scattering's draw takes
    // (u0 - p) / (1 - p).
    std::optional<WholeSphereEnergy> energy;
    Value *p = zero, *uSingle = u0;
    if (plan.compensatesEnergy) {
        energy.emplace(*this, ndf, t.n);
        p = energy->probability(wo);
        uSingle = pm.select(pm.gt(p, zero), pm.div(pm.sub(u0, p), pm.sub(pm.c(1.0), p)), u0);
    }

    // wo's frame; a view in the surface has no sample (it computes with n).
    Value* woUp = pm.gt(wo[2], zero);
    Value* view = b.CreateNot(pm.eq(wo[2], zero));
    Value* sign = pm.select(woUp, pm.c(1.0), pm.c(-1.0));
    const Vec o = selectVec(pm, view, Vec{wo[0], wo[1], pm.abs(wo[2])}, constantVec(pm, 0, 0, 1));
    const Vec m = plan.sampling.specular == SpecularSampling::VisibleNormals
                      ? ndf.sampleVisibleNormal(*this, t.n, o, u1, u2)
                      : ndf.sampleNormal(*this, t.n, u1, u2);
    Value* om = dot(pm, o, m);
    Value* c = pm.minnum(pm.maxnum(om, zero), pm.c(1.0));
    Value *etaRel = nullptr, *etaMinusOne = nullptr;
    if (!plan.thinSheet) std::tie(etaRel, etaMinusOne) = relativeEta(t, woUp);
    BranchWeights w = branchWeights(*this, emitters_.fresnel, t.eta, etaRel, c);
    Value* total = pm.add(w.reflect, w.transmit);
    Value* reflect = pm.lt(pm.mul(uSingle, total), w.reflect);

    // The reflection of o about m (wi + wo = 2 (wo.m) m), and its Jacobian.
    Value* twoOm = pm.add(om, om);
    const Vec iR = {pm.fma(twoOm, m[0], pm.neg(o[0])), pm.fma(twoOm, m[1], pm.neg(o[1])),
                    pm.fma(twoOm, m[2], pm.neg(o[2]))};
    Value* jacR = pm.div(pm.c(0.25), om);
    Vec iT;
    Value *jacT, *validT;
    if (plan.thinSheet) {
        // Through the sheet: the reflection's mirror image on the far side.
        iT = {iR[0], iR[1], pm.neg(iR[2])};
        jacT = jacR;
        validT = pm.gt(iR[2], zero);
    } else {
        // Snell about m: cos theta_t = sqrt(1 - (1 - om^2) / eta'^2) on the
        // far side, wi = -o / eta' + (om / eta' - ct) m.
        Value* inv = pm.div(pm.c(1.0), etaRel);
        Value* ct2 = pm.sub(pm.c(1.0), pm.mul(pm.mul(pm.sub(pm.c(1.0), om), pm.add(pm.c(1.0), om)), pm.mul(inv, inv)));
        Value* ct = pm.sqrt(pm.maxnum(ct2, zero));
        Value* k = pm.sub(pm.mul(om, inv), ct);
        for (int i = 0; i < 3; ++i) iT[i] = pm.fma(k, m[i], pm.neg(pm.mul(o[i], inv)));
        Value* denom = pm.sub(om, pm.mul(etaRel, ct));  // eta' wi.m + wo.m
        jacT = pm.div(pm.mul(pm.mul(etaRel, etaRel), ct), pm.mul(denom, denom));
        validT = b.CreateAnd(pm.gt(ct2, zero), pm.lt(iT[2], zero));
    }
    const Vec i = selectVec(pm, reflect, iR, iT);
    Value* branchValid = b.CreateOr(b.CreateAnd(reflect, pm.gt(iR[2], zero)), b.CreateAnd(b.CreateNot(reflect), validT));
    Value* share = branchShare(pm, pm.select(reflect, w.reflect, w.transmit), total);
    Value* pdf = pm.mul(pm.mul(share, facetDensity(*this, ndf, t.n, o, m, om)), pm.select(reflect, jacR, jacT));
    // Back from wo's frame.
    Vec wi = {i[0], i[1], pm.mul(i[2], sign)};
    Value* sampled = b.CreateAnd(b.CreateAnd(view, branchValid),
                                 b.CreateAnd(pm.gt(total, zero), pm.gt(pdf, zero)));
    if (energy) {
        // The compensation's draw where u0 < p; the density is the
        // mixture's at whichever wi came out (as the pdf entry's).
        Value* fromCompensation = pm.lt(u0, p);
        const Vec wiC = energy->sample(wo, pm.div(u0, p), u1, u2);
        Value* drawnC = b.CreateAnd(view, b.CreateNot(pm.eq(wiC[2], zero)));
        wi = selectVec(pm, fromCompensation, wiC, wi);
        sampled = b.CreateSelect(fromCompensation, drawnC, sampled);
        pdf = pm.add(pm.mul(pm.sub(pm.c(1.0), p), singleScatteringPdf(wi, wo, t)), pm.mul(p, energy->pdf(wi, wo)));
    }

    LVal f = wholeSphereValue(wi, wo, t);
    SampleResult r;
    r.pdf = fm.convert(pdf, fm.type());
    Value* weighted = b.CreateAnd(sampled, fm.gt(r.pdf, fm.c(0.0)));
    Value* cosOverPdf = pm.div(pm.abs(wi[2]), pdf);
    for (int ch = 0; ch < 3; ++ch)
        r.weight[ch] = fm.convert(pm.select(weighted, pm.mul(f.c[ch], cosOverPdf), zero), fm.type());
    for (int k = 0; k < 3; ++k) r.wi[k] = fm.convert(wi[k], fm.type());
    finishSample(r, b.CreateNot(weighted));
    return r;
}

LaneEmitter::PdfResult LaneEmitter::emitWholeSpherePdf(const Vec& wiIn, const Vec& woIn,
                                                       const std::vector<Value*>& slots) {
    MathEmitter& pm = preciseMath_;
    Vec unusedF;
    const Vec wi = unitDirection(readDirection(wiIn), unusedF), wo = unitDirection(readDirection(woIn), unusedF);
    lowerInputsAndLets(slots);
    WholeSphereTerms t = wholeSphereTerms();
    Value* zero = pm.c(0.0);
    Value* pdf = singleScatteringPdf(wi, wo, t);
    if (plan.compensatesEnergy) {
        // The mixture's: (1 - p) single + p compensation.
        WholeSphereEnergy energy(*this, emitters_.ndf, t.n);
        Value* p = energy.probability(wo);
        pdf = pm.add(pm.mul(pm.sub(pm.c(1.0), p), pdf), pm.mul(p, energy.pdf(wi, wo)));
    }
    Value* inSurface = builder.CreateOr(pm.eq(wi[2], zero), pm.eq(wo[2], zero));
    return finishPdf(pm.select(inSurface, zero, pdf));
}

Value* LaneEmitter::singleScatteringPdf(const Vec& wi, const Vec& wo, const WholeSphereTerms& t) {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const NdfEmitter& ndf = emitters_.ndf;
    const FresnelEmitter& fresnel = emitters_.fresnel;
    Value* zero = pm.c(0.0);
    Value* woUp = pm.gt(wo[2], zero);
    Value* sameSide = b.CreateICmpEQ(pm.gt(wi[2], zero), woUp);
    // The mirrored pair (both above) and its half vector: the reflected
    // pair's facet, and the sheet's for either pair.
    const MirroredPair p = mirroredPair(wi, wo);
    Value* c = p.cos;
    Value* pdfMirrored = pm.mul(facetDensity(*this, ndf, t.n, p.o, p.h, c), pm.div(pm.c(0.25), c));
    pdfMirrored = pm.select(pm.gt(p.len, zero), pdfMirrored, zero);
    // (branchWeights leaves out what `scatter` drops: its share is 0.)
    Value* pdf;
    if (plan.thinSheet) {
        BranchWeights w = branchWeights(*this, fresnel, t.eta, nullptr, c);
        pdf = pm.mul(branchShare(pm, pm.select(sameSide, w.reflect, w.transmit), pm.add(w.reflect, w.transmit)), pdfMirrored);
    } else {
        auto [etaRel, etaMinusOne] = relativeEta(t, woUp);
        BranchWeights w = branchWeights(*this, fresnel, t.eta, etaRel, c);
        Value* reflected = pm.mul(branchShare(pm, w.reflect, pm.add(w.reflect, w.transmit)), pdfMirrored);
        Value* transmitted = zero;
        if (plan.keepsTransmission) {
            // The refracted pair's facet (as eval forms it), P_T from the
            // pair's own transmittance, J = eta'^2 |wi.m| / |v|^2.
            const RefractedFacet f = refractedFacet(p, etaMinusOne);
            Value* cm = pm.minnum(f.om, pm.c(1.0));
            Value* pr = plan.keepsReflection ? fresnel.reflectanceAcross(*this, etaRel, cm) : zero;
            Value* pt = fresnel.pairTransmittance(*this, etaRel, cm, pm.neg(f.im));
            Value* jac = pm.div(pm.mul(pm.mul(etaRel, etaRel), pm.neg(f.im)), f.lenSq);
            Value* density = pm.mul(branchShare(pm, pt, pm.add(pr, pt)), facetDensity(*this, ndf, t.n, p.o, f.m, f.om));
            transmitted = pm.select(f.faces, pm.mul(density, jac), zero);
        }
        pdf = pm.select(sameSide, reflected, transmitted);
    }
    return pdf;
}

}  // namespace facet
