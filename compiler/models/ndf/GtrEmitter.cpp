// gtr: Burley's generalized Trowbridge-Reitz NDF as IR (the reference is
// Gtr.cpp), in log form in the precise type.
#include "TabulatedLambdaEmitter.h"
#include "Immortal.h"
#include "lowering/LaneEmitter.h"

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlpha = 0, kGamma = 1;
constexpr int kOwnGamma = 0;  // NdfParams::own: the clamped gamma, precise type

class GtrEmitter final : public NdfEmitter {
public:
    GtrEmitter() {
        traits.isotropicOnly = true;
        traits.samplesNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.singleLobe().ndf, kAlpha, kAlpha, {kGamma});  // own[kOwnGamma]
    }

    // D = c / t^gamma, c = phi(L) / (pi phi((1 - gamma) L)), L = ln a^2,
    // phi(y) = expm1(y)/y, t = a^2 mz^2 + mx^2 + my^2; in log form: for
    // large gamma phi((1 - gamma) L) overflows while t^gamma underflows.
    // With y = (1 - gamma) L > 1, log phi(y) = y + log(1 - e^-y) - log y,
    // and y - gamma log t = -L - gamma log1p(s2 (1 - a^2)/a^2): the two terms
    // of size gamma L cancel analytically instead of in rounding.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& hD = geo.hD;
        Value* A2 = pm.mul(n.axD, n.axD);
        Value* L = pm.log(A2);
        Value* G = n.own[kOwnGamma];
        Value* logPhiL = pm.log(lane.expm1OverX(L));
        Value* y = pm.mul(pm.sub(pm.c(1.0), G), L);
        Value* s2 = pm.fma(hD[0], hD[0], pm.mul(hD[1], hD[1]));
        Value* yBig = pm.maxnum(y, pm.c(1.0));  // keeps the unused lanes finite
        Value* big = pm.sub(pm.add(pm.sub(pm.sub(logPhiL, L), pm.log(pm.sub(pm.c(1.0), pm.exp(pm.neg(yBig))))), pm.log(yBig)),
                            pm.mul(G, pm.log1p(pm.mul(s2, pm.div(pm.sub(pm.c(1.0), A2), A2)))));
        Value* t = pm.fma(A2, pm.mul(hD[2], hD[2]), s2);
        Value* small = pm.sub(pm.sub(logPhiL, pm.log(lane.expm1OverX(pm.minnum(y, pm.c(1.0))))), pm.mul(G, pm.log(t)));
        Value* logD = pm.select(pm.gt(y, pm.c(1.0)), big, small);
        return pm.mul(pm.exp(logD), pm.c(1.0 / kPi));
    }

    // Its Smith Lambda from the plan's table in (a, alpha) (TabulatedLambdaEmitter.h).
    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // In s = sin^2 theta, D(m) (n.m) is proportional to (1 + b s)^-gamma with
    // b = 1/a^2 - 1. Its CDF inverts to s = expm1(-L g) / expm1(-L), L = ln
    // a^2, where g = log1p(u expm1(k)) / k, k = (gamma - 1) L (g = u at k =
    // 0, s = u at L = 0). For u > 1/2 (and k > -30, where expm1(-k) stays
    // finite) the same is g = 1 + log1p(v expm1(-k)) / k with v = 1 - u
    // exact, which keeps 1 - g, and so cos^2 theta = 1 - s = e^(-L g)
    // expm1(-L (1 - g)) / expm1(-L), accurate toward the horizon, where s
    // rounds to 1 in float; it also serves k > 30, where expm1(k) could
    // overflow.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* L = pm.mul(pm.c(2.0), pm.log(n.axD));
        Value* k = pm.mul(pm.sub(n.own[kOwnGamma], pm.c(1.0)), L);
        Value* kZero = pm.eq(k, pm.c(0.0));
        Value* kSafe = pm.select(kZero, pm.c(1.0), k);
        Value* v = pm.sub(pm.c(1.0), u1);
        Value* upper = lane.builder.CreateAnd(pm.gt(u1, pm.c(0.5)), pm.gt(k, pm.c(-30.0)));
        upper = lane.builder.CreateOr(upper, pm.gt(k, pm.c(30.0)));
        Value* gLower = pm.div(pm.log1p(pm.mul(u1, lane.expm1(pm.minnum(kSafe, pm.c(30.0))))), kSafe);
        Value* oneMinusGUpper =
            pm.div(pm.neg(pm.log1p(pm.mul(v, lane.expm1(pm.neg(pm.maxnum(kSafe, pm.c(-30.0))))))), kSafe);
        Value* g = pm.select(upper, pm.sub(pm.c(1.0), oneMinusGUpper), gLower);
        Value* oneMinusG = pm.select(upper, oneMinusGUpper, pm.sub(pm.c(1.0), gLower));
        g = pm.select(kZero, u1, g);
        oneMinusG = pm.select(kZero, v, oneMinusG);
        Value* LZero = pm.eq(L, pm.c(0.0));
        Value* LSafe = pm.select(LZero, pm.c(1.0), L);
        Value* den = lane.expm1(pm.neg(LSafe));
        Value* s = pm.select(LZero, u1, pm.div(lane.expm1(pm.neg(pm.mul(LSafe, g))), den));
        Value* c2 = pm.div(pm.mul(pm.exp(pm.neg(pm.mul(LSafe, g))), lane.expm1(pm.neg(pm.mul(LSafe, oneMinusG)))), den);
        c2 = pm.select(LZero, v, c2);
        return lane.normalFromPolar(s, u2, c2);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_GtrEmitter() {
    static const GtrEmitter& emitter = immortal<GtrEmitter>();
    return {{ModelSlot::Ndf, "gtr", &emitter, lambdaTableEmbedding}};
}

}  // namespace facet
