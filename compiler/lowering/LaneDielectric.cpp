// LaneDielectric: the lane body of a lobe that scatters over the whole
// sphere (SPEC 11; LoweringPlan::wholeSphere): a rough dielectric interface
// (Walter et al. 2007) or a thin-walled sheet.
//
// Written from the formulas of compiler/reference/DielectricLobe.h, not
// from its code (the differential tests compare the two). Everything is in
// wo's frame: z is multiplied by the sign of n.wo, so that wo is above and
// the far side has the relative index eta' = eta (wo outside) or 1/eta.
// Three facets come out of that frame:
//   - the mirrored pair's: i = (wi.x, wi.y, |wi.z|), o = (wo.x, wo.y,
//     |wo.z|), h = (i + o)/|i + o|. It is the reflected pair's half vector
//     (both directions on wo's side, so i + o is wi + wo there) and the thin
//     sheet's for either pair (nothing bends in a sheet: the transmitted
//     lobe is the reflected one mirrored);
//   - the refracted pair's (interface only): v = eta' wi + wo = (wi + wo) +
//     (eta' - 1) wi, m = v/|v| turned up, kept where the facet faces both
//     directions (wi.m < 0 < wo.m).
// The model terms come from the catalog's emitters: D at either facet, the
// masking's reflection form on the mirrored pair and its transmission form
// (transmittedOverCosines) on the refracted one with wi mirrored above, the
// Fresnel term's reflectance and transmittance across the interface.
#include "LaneEmitter.h"
#include "WholeSphereEnergy.h"

#include "reference/DielectricLobe.h"

namespace facet {

namespace {

// A facet normal with the pair (both above) it is the geometry of, as the
// NDF and masking emitters read a LaneGeometry: unit h in the precise type
// (slopeH without a length: the unit h), cos = wo.h.
LaneGeometry facetGeometry(MathEmitter& fm, MathEmitter& pm, const std::array<llvm::Value*, 3>& i,
                           const std::array<llvm::Value*, 3>& o, const std::array<llvm::Value*, 3>& h, llvm::Value* cos, llvm::Value* nonZero) {
    LaneGeometry g{};
    for (int k = 0; k < 3; ++k) {
        g.wiD[k] = i[k], g.woD[k] = o[k], g.hD[k] = h[k];
        g.wi[k] = fm.convert(i[k], fm.type());
        g.wo[k] = fm.convert(o[k], fm.type());
        g.h[k] = fm.convert(h[k], fm.type());
    }
    g.slopeH = g.hD;
    g.slopeHLen2 = nullptr;
    g.cosD = cos;
    g.oneMinusCosD = pm.sub(pm.c(1.0), cos);
    g.sin2D = pm.mul(g.oneMinusCosD, pm.add(pm.c(1.0), cos));
    g.hNonZero = nonZero;
    return g;
}

}  // namespace

LaneEmitter::WholeSphereTerms LaneEmitter::wholeSphereTerms() {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    WholeSphereTerms t;
    t.n = emitters_.ndf.params(*this);
    t.eta = emitters_.fresnel.refractiveIndex(*this);
    if (!plan.thinSheet) {
        // The interface's index moved away from 1 (SPEC 11: the refracted
        // lobe of an index-matched interface is a delta).
        llvm::Value* n0 = t.eta.c[0];
        const double clamp = kEtaClampFromOne;
        n0 = pm.select(b.CreateAnd(pm.ge(n0, pm.c(1.0)), pm.lt(n0, pm.c(1.0 + clamp))), pm.c(1.0 + clamp), n0);
        n0 = pm.select(b.CreateAnd(pm.lt(n0, pm.c(1.0)), pm.gt(n0, pm.c(1.0 - clamp))), pm.c(1.0 - clamp), n0);
        t.interfaceEta = n0;
    }
    return t;
}

// eta' = eta (wo outside) or 1/eta, and eta' - 1 without cancellation near 1.
std::pair<llvm::Value*, llvm::Value*> LaneEmitter::relativeEta(const WholeSphereTerms& t, llvm::Value* woUp) {
    MathEmitter& pm = preciseMath_;
    llvm::Value* n0 = t.interfaceEta;
    return {pm.select(woUp, n0, pm.div(pm.c(1.0), n0)),
            pm.select(woUp, pm.sub(n0, pm.c(1.0)), pm.div(pm.sub(pm.c(1.0), n0), n0))};
}

LaneEmitter::MirroredPair LaneEmitter::mirroredPair(const std::array<llvm::Value*, 3>& wi,
                                                   const std::array<llvm::Value*, 3>& wo) {
    MathEmitter& pm = preciseMath_;
    MirroredPair p;
    p.i = {wi[0], wi[1], pm.abs(wi[2])};
    p.o = {wo[0], wo[1], pm.abs(wo[2])};
    p.s = {pm.add(wi[0], wo[0]), pm.add(wi[1], wo[1]), pm.add(p.i[2], p.o[2])};
    p.len = pm.sqrt(dot(pm, p.s, p.s));
    llvm::Value* inv = pm.div(pm.c(1.0), p.len);
    p.h = {pm.mul(p.s[0], inv), pm.mul(p.s[1], inv), pm.mul(p.s[2], inv)};
    p.cos = pm.minnum(pm.mul(p.len, pm.c(0.5)), pm.c(1.0));
    return p;
}

LaneEmitter::RefractedFacet LaneEmitter::refractedFacet(const MirroredPair& p, llvm::Value* etaMinusOne) {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    llvm::Value* zero = pm.c(0.0);
    RefractedFacet f;
    // In wo's frame wi is below: wi' = (wi.x, wi.y, -|wi.z|), and v =
    // (wi' + wo') + (eta' - 1) wi', whose z sum is |wo.z| - |wi.z|.
    f.wiFrame = {p.i[0], p.i[1], pm.neg(p.i[2])};
    std::array<llvm::Value*, 3> v;
    for (int k = 0; k < 3; ++k) v[k] = pm.fma(etaMinusOne, f.wiFrame[k], k < 2 ? p.s[k] : pm.sub(p.o[2], p.i[2]));
    f.lenSq = dot(pm, v, v);
    llvm::Value* up = pm.div(pm.select(pm.lt(v[2], zero), pm.c(-1.0), pm.c(1.0)), pm.sqrt(f.lenSq));
    f.m = {pm.mul(v[0], up), pm.mul(v[1], up), pm.mul(v[2], up)};
    f.im = dot(pm, f.wiFrame, f.m);  // < 0 where the facet faces wi
    f.om = dot(pm, p.o, f.m);
    f.faces = b.CreateAnd(b.CreateAnd(pm.lt(f.im, zero), pm.gt(f.om, zero)),
                          b.CreateAnd(pm.gt(f.m[2], zero), pm.gt(f.lenSq, zero)));
    return f;
}

llvm::Value* LaneEmitter::sheetReflectance(llvm::Value* F) {
    MathEmitter& pm = preciseMath_;
    return pm.div(pm.mul(F, pm.c(2.0)), pm.add(pm.c(1.0), F));
}

llvm::Value* LaneEmitter::sheetTransmittance(llvm::Value* T) {
    MathEmitter& pm = preciseMath_;
    return pm.div(T, pm.sub(pm.c(2.0), T));
}

std::array<llvm::Value*, 3> LaneEmitter::wholeSphereBsdf(const std::array<llvm::Value*, 3>& wiIn,
                                                         const std::array<llvm::Value*, 3>& woIn,
                                                         const std::vector<llvm::Value*>& slots) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    std::array<llvm::Value*, 3> unusedF;
    const std::array<llvm::Value*, 3> wi = unitDirection(wiIn, unusedF), wo = unitDirection(woIn, unusedF);
    lowerInputsAndLets(slots);
    LVal value = wholeSphereValue(wi, wo, wholeSphereTerms());
    // f = 0 where either direction lies in the surface (a valid lane).
    llvm::Value* inSurface = builder.CreateOr(pm.eq(wi[2], pm.c(0.0)), pm.eq(wo[2], pm.c(0.0)));
    return map({value}, true, [&](auto& x) {
        return fm.select(inSurface, fm.c(0.0), fm.convert(x[0], fm.type()));
    }).c;
}

LVal LaneEmitter::wholeSphereValue(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                                   const WholeSphereTerms& t) {
    MathEmitter& fm = floatMath_;
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const NdfEmitter& ndf = emitters_.ndf;
    const MaskingEmitter& masking = emitters_.masking;
    const FresnelEmitter& fresnel = emitters_.fresnel;
    const NdfParams& n = t.n;
    llvm::Value* zero = pm.c(0.0);
    llvm::Value* woUp = pm.gt(wo[2], zero);
    llvm::Value* sameSide = b.CreateICmpEQ(pm.gt(wi[2], zero), woUp);

    // The mirrored pair and its half vector.
    const MirroredPair p = mirroredPair(wi, wo);
    llvm::Value* c = p.cos;
    LaneGeometry mirrored = facetGeometry(fm, pm, p.i, p.o, p.h, c, pm.gt(p.len, zero));
    // D G / (4 |n.wi| |n.wo|) of the mirrored pair.
    llvm::Value* lobe = masking.overCosines(*this, ndf, n, mirrored, pm.mul(ndf.D(*this, n, mirrored), pm.c(0.25)));
    lobe = pm.select(mirrored.hNonZero, lobe, zero);

    LVal value;
    if (plan.thinSheet) {
        // The sheet's reflectance R' and transmittance T' per channel at wo.h.
        value = map({t.eta}, true, [&](auto& x) {
            llvm::Value* w = zero;
            if (plan.keepsReflection) {
                llvm::Value* F = fresnel.reflectanceAcross(*this, x[0], c);
                w = pm.select(sameSide, sheetReflectance(F), zero);
            }
            if (plan.keepsTransmission) {
                llvm::Value* T = fresnel.transmittanceAcross(*this, x[0], c);
                w = pm.select(sameSide, w, sheetTransmittance(T));
            }
            // w = 0 is 0 even where the lobe overflowed.
            return pm.select(pm.eq(w, zero), zero, pm.mul(w, lobe));
        });
    } else {
        auto [etaRel, etaMinusOne] = relativeEta(t, woUp);
        llvm::Value* reflected = zero;
        if (plan.keepsReflection) {
            llvm::Value* F = fresnel.reflectanceAcross(*this, etaRel, c);
            reflected = pm.select(pm.eq(F, zero), zero, pm.mul(F, lobe));
        }
        llvm::Value* transmitted = zero;
        if (plan.keepsTransmission) {
            const RefractedFacet f = refractedFacet(p, etaMinusOne);
            llvm::Value* T = fresnel.pairTransmittance(*this, etaRel, pm.minnum(f.om, pm.c(1.0)), pm.neg(f.im));
            LaneGeometry refracted = facetGeometry(fm, pm, p.i, p.o, f.m, f.om, f.faces);
            // D T |wi.m| |wo.m| / |v|^2 (radiance transport), times eta'^2
            // for importance transport (Veach 1997, 5.14).
            llvm::Value* scale =
                pm.div(pm.mul(pm.mul(ndf.D(*this, n, refracted), T), pm.mul(pm.neg(f.im), f.om)), f.lenSq);
            if (plan.transport == Transport::Importance) scale = pm.mul(scale, pm.mul(etaRel, etaRel));
            llvm::Value* lobeT = masking.transmittedOverCosines(*this, ndf, n, refracted, scale);
            transmitted = pm.select(b.CreateAnd(f.faces, pm.gt(scale, zero)), lobeT, zero);
        }
        value = LVal::scalar(pm.select(sameSide, reflected, transmitted));
    }
    if (plan.compensatesEnergy) {
        // energy = kulla_conty: the lobe the single scattering loses, from
        // both sides (WholeSphereEnergy.h).
        LVal ms = WholeSphereEnergy(*this, ndf, n).value(wi, wo);
        value = map({value, ms}, value.rgb || ms.rgb, [&](auto& x) { return pm.add(x[0], x[1]); });
    }
    return value;
}

}  // namespace facet
