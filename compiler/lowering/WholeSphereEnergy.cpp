// WholeSphereEnergy: see WholeSphereEnergy.h.
#include "WholeSphereEnergy.h"

#include "Diagnostics.h"
#include "KullaConty.h"

namespace facet {

using llvm::Value;

namespace {

// As the reference: the single-scattering sampler keeps at least 10% of
// the draws.
constexpr double kMaxCompensationProbability = 0.9;

std::vector<const EnergyTable*> sideTables(const LaneEmitter& lane) {
    // A thin sheet's two sides are the same table.
    if (lane.plan.thinSheet) return {lane.energyTable()};
    internal_assert(lane.energyTableInside()) << "whole-sphere compensation lowered without its inside table";
    return {lane.energyTable(), lane.energyTableInside()};
}

}  // namespace

WholeSphereEnergy::WholeSphereEnergy(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n)
    : lane_(lane), pm_(lane.preciseMath()), table_(lane, ndf.energyAlpha(lane, n), sideTables(lane)) {
    MathEmitter& pm = pm_;
    const LoweringPlan& plan = lane.plan;
    avgOutside_ = table_.ecAvg();
    avgInside_ = plan.thinSheet ? avgOutside_ : table_.ecAvgOfTable(1);
    if (plan.thinSheet) {
        // The sheet's share, the same from both sides.
        const std::array<double, 3>& x = plan.sheetCrossing;
        crossOutside_ = {{pm.c(x[0]), pm.c(x[1]), pm.c(x[2])}, true};
        if (x[0] == x[1] && x[1] == x[2]) crossOutside_ = LVal::scalar(crossOutside_.c[0]);
        crossInside_ = crossOutside_;
        return;
    }
    // x_o = 1 - F_avg, lowered to eta^2 A_i / A_o where x_i would pass 1;
    // x_i = x_o A_o / (eta^2 A_i) (generalized reciprocity).
    Value *ao = avgOutside_, *ai = avgInside_, *zero = pm.c(0.0);
    Value *x0 = pm.c(plan.smoothCrossing), *eta2Ai = pm.mul(pm.c(plan.interfaceEta2), ai);
    Value* limited = lane.builder.CreateAnd(pm.gt(ao, zero), pm.lt(eta2Ai, pm.mul(x0, ao)));
    Value* xo = pm.select(limited, pm.div(eta2Ai, ao), x0);
    Value* xi = pm.select(pm.gt(ai, zero), pm.minnum(pm.div(pm.mul(xo, ao), eta2Ai), pm.c(1.0)), zero);
    crossOutside_ = LVal::scalar(xo);
    crossInside_ = LVal::scalar(xi);
}

LVal WholeSphereEnergy::crossing(Value* woUp) {
    MathEmitter& pm = pm_;
    return lane_.map({crossOutside_, crossInside_}, crossOutside_.rgb,
                     [&](auto& x) { return pm.select(woUp, x[0], x[1]); });
}

LVal WholeSphereEnergy::value(const Vec& wi, const Vec& wo) {
    MathEmitter& pm = pm_;
    llvm::IRBuilder<>& b = lane_.builder;
    const LoweringPlan& plan = lane_.plan;
    Value* zero = pm.c(0.0);
    Value *woUp = pm.gt(wo[2], zero), *wiUp = pm.gt(wi[2], zero);
    Value* crosses = b.CreateXor(woUp, wiUp);
    // Ec of wo's side at |n.wo| times Ec of wi's side at |n.wi|, over pi A
    // of wi's side.
    Value* a = pm.select(wiUp, avgOutside_, avgInside_);
    Value* ecO = table_.ec(pm.abs(wo[2]), b.CreateNot(woUp));
    Value* ecI = table_.ec(pm.abs(wi[2]), b.CreateNot(wiUp));
    Value* lobe = pm.select(pm.gt(a, zero), pm.div(pm.mul(ecO, ecI), pm.mul(pm.c(kPi), a)), zero);
    if (!plan.thinSheet && plan.transport == Transport::Radiance) {
        // eta_o^2 / eta_i^2 times the importance form across the surface:
        // 1 / eta^2 going in (wo outside), eta^2 going out.
        Value* eta2 = pm.c(plan.interfaceEta2);
        lobe = pm.select(crosses, pm.select(woUp, pm.div(lobe, eta2), pm.mul(lobe, eta2)), lobe);
    }
    return lane_.map({crossing(woUp)}, crossOutside_.rgb, [&](auto& x) {
        Value* share = pm.select(crosses, x[0], pm.sub(pm.c(1.0), x[0]));
        if (!plan.keepsReflection) share = pm.select(crosses, share, zero);
        if (!plan.keepsTransmission) share = pm.select(crosses, zero, share);
        return pm.mul(share, lobe);
    });
}

std::pair<Value*, Value*> WholeSphereEnergy::keptShares(Value* woUp) {
    MathEmitter& pm = pm_;
    LVal x = crossing(woUp);
    Value* cross = x.gray() ? x.c[0] : pm.mul(pm.add(pm.add(x.c[0], x.c[1]), x.c[2]), pm.c(1.0 / 3.0));
    return {lane_.plan.keepsReflection ? pm.sub(pm.c(1.0), cross) : pm.c(0.0),
            lane_.plan.keepsTransmission ? cross : pm.c(0.0)};
}

Value* WholeSphereEnergy::probability(const Vec& wo) {
    MathEmitter& pm = pm_;
    Value* woUp = pm.gt(wo[2], pm.c(0.0));
    auto [reflect, cross] = keptShares(woUp);
    Value* p = pm.mul(table_.ec(pm.abs(wo[2]), lane_.builder.CreateNot(woUp)), pm.add(reflect, cross));
    p = pm.minnum(pm.maxnum(p, pm.c(0.0)), pm.c(kMaxCompensationProbability));
    return pm.select(pm.eq(wo[2], pm.c(0.0)), pm.c(0.0), p);
}

Value* WholeSphereEnergy::pdf(const Vec& wi, const Vec& wo) {
    MathEmitter& pm = pm_;
    Value* zero = pm.c(0.0);
    Value* woUp = pm.gt(wo[2], zero);
    auto [reflect, cross] = keptShares(woUp);
    Value* total = pm.add(reflect, cross);
    Value* crosses = lane_.builder.CreateXor(woUp, pm.gt(wi[2], zero));
    Value* share = pm.div(pm.select(crosses, cross, reflect), total);
    Value* density = pm.mul(share, pm.mul(pm.abs(wi[2]), pm.c(1.0 / kPi)));
    return pm.select(pm.gt(total, zero), density, zero);
}

WholeSphereEnergy::Vec WholeSphereEnergy::sample(const Vec& wo, Value* u0, Value* u1, Value* u2) {
    MathEmitter& pm = pm_;
    llvm::IRBuilder<>& b = lane_.builder;
    Value* zero = pm.c(0.0);
    Value* woUp = pm.gt(wo[2], zero);
    auto [reflect, cross] = keptShares(woUp);
    Value* crosses = pm.ge(pm.mul(u0, pm.add(reflect, cross)), reflect);
    // The cosine lobe on the chosen side: radius sqrt(u1), azimuth 2 pi u2.
    Vec w = lane_.normalFromPolar(u1, u2);
    Value* up = b.CreateXor(woUp, crosses);
    return {w[0], w[1], pm.select(up, w[2], pm.neg(w[2]))};
}

}  // namespace facet
