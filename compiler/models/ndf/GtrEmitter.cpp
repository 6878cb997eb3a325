// gtr: Burley's generalized Trowbridge-Reitz NDF as IR (the reference is
// Gtr.cpp), in log form in the precise type.
#include "lowering/LaneEmitter.h"

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlpha = 0, kGamma = 1;
constexpr int kOwnGamma = 0;  // NdfParams::own: the clamped gamma, precise type

class GtrEmitter final : public NdfEmitter {
public:
    GtrEmitter() { traits.isotropicOnly = true; }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.ndf, kAlpha, kAlpha, {kGamma});  // own[kOwnGamma]
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
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_GtrEmitter() {
    static const GtrEmitter emitter;
    return {{ModelSlot::Ndf, "gtr", &emitter}};
}

}  // namespace facet
