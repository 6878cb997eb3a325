// The four Smith forms as IR (the reference is Smith.cpp), from the NDF's
// Lambda: D G / (ci co) written with ai = ci (1 + Li) and ao = co (1 + Lo),
// sums of positive terms, either from the NDF's root form R(v) (the plan's
// LambdaForm::RootSums) or from (n.v) Lambda(v).
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

namespace facet {
namespace {

using llvm::Value;

// ci (1 + Li), co (1 + Lo), and what they were made of.
struct SmithSums {
    Value *ai, *ao;
    Value *rootI = nullptr, *rootO = nullptr;  // RootSums
    Value *li = nullptr, *lo = nullptr;        // otherwise: (n.v) Lambda(v)
};

SmithSums smithSums(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo) {
    MathEmitter& pm = lane.preciseMath();
    Value *ci = geo.wiD[2], *co = geo.woD[2];
    SmithSums s;
    if (lane.plan.lambda == LambdaForm::RootSums) {
        // R(v) = (n.v)(1 + 2 Lambda(v)): (n.v)(1 + Lambda) = ((n.v) + R)/2.
        // R is a norm of v, so where the body normalized the inputs itself
        // R(w/|w|) = R(w) / |w|: the square roots start from the loaded
        // inputs instead of waiting for the renormalization, which is the
        // head of a one-lane body's chain; there both take one instruction.
        MathEmitter& fm = lane.floatMath();
        const bool fromInputs = geo.wiInvLen != nullptr;
        auto [rootI, rootO] = fm.sqrtBoth(ndf.smithRootSquared(lane, n, fromInputs ? geo.wiIn : geo.wi, !fromInputs),
                                          ndf.smithRootSquared(lane, n, fromInputs ? geo.woIn : geo.wo, !fromInputs));
        s.rootI = pm.convert(rootI, pm.type());
        s.rootO = pm.convert(rootO, pm.type());
        if (fromInputs) {
            s.rootI = pm.mul(s.rootI, geo.wiInvLen);
            s.rootO = pm.mul(s.rootO, geo.woInvLen);
        }
        s.ai = pm.mul(pm.add(ci, s.rootI), pm.c(0.5));
        s.ao = pm.mul(pm.add(co, s.rootO), pm.c(0.5));
    } else {
        // (n.v) Lambda(v), computed in float: it enters sums with n.v.
        s.li = pm.convert(ndf.cosLambda(lane, n, geo.wi), pm.type());
        s.lo = pm.convert(ndf.cosLambda(lane, n, geo.wo), pm.type());
        s.ai = pm.add(ci, s.li);
        s.ao = pm.add(co, s.lo);
    }
    return s;
}

// ln Gamma(x) for x >= 1, double: Stirling's series at z = x + 6 >= 7 to
// the z^-7 term (the next is below 1 / (1188 z^9) = 2.1e-11), less the
// logarithm of x (x + 1) ... (x + 5), taken as two products of three so
// that neither overflows for any x a Lambda can reach (the cosines are
// floats: Lambda < 1e46).
Value* logGamma(MathEmitter& dm, Value* x) {
    Value* z = dm.add(x, dm.c(6.0));
    Value* w = dm.div(dm.c(1.0), z);
    Value* series = dm.mul(w, dm.poly(dm.mul(w, w), {1.0 / 12, -1.0 / 360, 1.0 / 1260, -1.0 / 1680}));
    Value* stirling = dm.add(dm.fma(dm.sub(z, dm.c(0.5)), dm.log(z), dm.sub(dm.c(0.91893853320467274178), z)), series);
    Value* low = dm.mul(x, dm.mul(dm.add(x, dm.c(1.0)), dm.add(x, dm.c(2.0))));
    Value* high = dm.mul(dm.add(x, dm.c(3.0)), dm.mul(dm.add(x, dm.c(4.0)), dm.add(x, dm.c(5.0))));
    return dm.sub(stirling, dm.add(dm.log(low), dm.log(high)));
}

// Heitz 2014's transmission form of the height-correlated masking (the
// reference is Smith.cpp's heightCorrelatedTransmission): scale B(1 + Li, 1
// + Lo) / (ci co), formed in logarithms and in double in every body: the
// log-gammas grow like L ln L at grazing and cancel to the small log B,
// which float would lose. Lambda from the sums: ai = ci (1 + Li).
Value* betaOverCosines(LaneEmitter& lane, const SmithSums& s, Value* ci, Value* co, Value* scale) {
    MathEmitter& dm = lane.doubleMath();
    MathEmitter& pm = lane.preciseMath();
    auto wide = [&](Value* v) { return dm.convert(v, dm.type()); };
    Value *cid = wide(ci), *cod = wide(co);
    Value* li = dm.div(dm.sub(wide(s.ai), cid), cid);
    Value* lo = dm.div(dm.sub(wide(s.ao), cod), cod);
    li = dm.maxnum(li, dm.c(0.0)), lo = dm.maxnum(lo, dm.c(0.0));
    Value* logB = dm.sub(dm.add(logGamma(dm, dm.add(li, dm.c(1.0))), logGamma(dm, dm.add(lo, dm.c(1.0)))),
                         logGamma(dm, dm.add(dm.add(li, lo), dm.c(2.0))));
    Value* g = dm.exp(dm.sub(logB, dm.add(dm.log(cid), dm.log(cod))));
    return pm.convert(dm.mul(wide(scale), g), pm.type());
}

// The separable form, x G1(wi) G1(wo) / (ci co) = x / (ai ao).
Value* separableOverCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                            Value* x) {
    SmithSums s = smithSums(lane, ndf, n, geo);
    return lane.overProduct(x, s.ai, s.ao);
}

class SeparableSmith final : public MaskingEmitter {  // G1(v) / (n.v) = 1 / ((n.v) (1 + Lambda(v)))
    Value* overCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                       Value* D) const override {
        return separableOverCosines(lane, ndf, n, geo, D);
    }
    // Uncorrelated heights: the same either way.
    Value* transmittedOverCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                                  Value* scale) const override {
        return separableOverCosines(lane, ndf, n, geo, scale);
    }
};

class DirectionCorrelatedSmith final : public MaskingEmitter {
    // w G1i G1o / (ci co) + (1 - w) min(G1i, G1o) / (ci co), with
    // G1i G1o / (ci co) = 1 / (ai ao) and min(G1i, G1o) / (ci co) = 1 / max(ai co, ao ci).
    Value* overCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                       Value* D) const override {
        MathEmitter& pm = lane.preciseMath();
        Value *ci = geo.wiD[2], *co = geo.woD[2];
        SmithSums s = smithSums(lane, ndf, n, geo);
        Value* w = lane.azimuthWeight(geo);
        Value* least = !lane.body.scaleMaskingSums
                           ? pm.div(D, pm.maxnum(pm.mul(s.ai, co), pm.mul(s.ao, ci)))
                           : pm.minnum(pm.div(pm.div(D, s.ai), co), pm.div(pm.div(D, s.ao), ci));
        return pm.fma(w, lane.overProduct(D, s.ai, s.ao), pm.mul(pm.sub(pm.c(1.0), w), least));
    }
    // Across the surface no directional correlation is left: the separable form.
    Value* transmittedOverCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                                  Value* scale) const override {
        return separableOverCosines(lane, ndf, n, geo, scale);
    }
};

// Height-correlated forms: D / (ci co (1 + Li + Lo)), and with max(Li, Lo)
// + w min(Li, Lo) for the direction-aware one. Scaled (plan) by a =
// max(ci, co): ri = ci/a, ro = co/a, one of them 1.
class HeightCorrelatedSmith final : public MaskingEmitter {
public:
    explicit HeightCorrelatedSmith(bool directionAware) : directionAware_(directionAware) {
        traits.needsSeparateLambdas = directionAware;
    }
    Value* overCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                       Value* D) const override {
        MathEmitter& pm = lane.preciseMath();
        Value *ci = geo.wiD[2], *co = geo.woD[2];
        SmithSums s = smithSums(lane, ndf, n, geo);
        Value *a = pm.c(1.0), *ri = ci, *ro = co;
        if (lane.body.scaleMaskingSums) {
            a = pm.maxnum(ci, co);
            ri = pm.div(ci, a);
            ro = pm.div(co, a);
        }
        Value* den;
        if (s.rootI) {  // (co Ri + ci Ro) / (2 a)
            den = pm.mul(pm.fma(ro, s.rootI, pm.mul(ri, s.rootO)), pm.c(0.5));
        } else {
            Value *pi = pm.mul(ro, s.li), *po = pm.mul(ri, s.lo);  // ci co Li / a, ci co Lo / a
            Value* rest = directionAware_ ? pm.fma(lane.azimuthWeight(geo), pm.minnum(pi, po), pm.maxnum(pi, po))
                                          : pm.add(pi, po);
            den = pm.fma(ci, ro, rest);
        }
        return !lane.body.scaleMaskingSums ? lane.quarterDOver(D, den) : pm.div(pm.div(D, den), a);
    }
    // Across the surface only the heights correlate (both forms): the Beta form.
    Value* transmittedOverCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                                  Value* scale) const override {
        return betaOverCosines(lane, smithSums(lane, ndf, n, geo), geo.wiD[2], geo.woD[2], scale);
    }

private:
    bool directionAware_;
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_masking_SmithEmitter() {
    static const SeparableSmith& separable = immortal<SeparableSmith>();
    static const HeightCorrelatedSmith& heightCorrelated = immortal<HeightCorrelatedSmith>(false);
    static const DirectionCorrelatedSmith& directionCorrelated = immortal<DirectionCorrelatedSmith>();
    static const HeightCorrelatedSmith& heightDirectionCorrelated = immortal<HeightCorrelatedSmith>(true);
    return {{ModelSlot::Masking, "smith_separable", &separable},
            {ModelSlot::Masking, "smith_height_correlated", &heightCorrelated},
            {ModelSlot::Masking, "smith_direction_correlated", &directionCorrelated},
            {ModelSlot::Masking, "smith_height_direction_correlated", &heightDirectionCorrelated}};
}

}  // namespace facet
