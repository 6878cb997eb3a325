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

class SeparableSmith final : public MaskingEmitter {  // G1(v) / (n.v) = 1 / ((n.v) (1 + Lambda(v)))
    Value* overCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n, const LaneGeometry& geo,
                       Value* D) const override {
        SmithSums s = smithSums(lane, ndf, n, geo);
        return lane.overProduct(D, s.ai, s.ao);
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
