// WholeSphereEnergy: `energy = kulla_conty` on a lobe over the whole sphere
// (SPEC 11) as IR: the compensation lobe a rough interface or a thin sheet
// adds to its single scattering, its share of the sampler's draws, its
// density and its draw.
//
// Written from the construction in compiler/reference/DielectricEnergy.h,
// which the tests compare it with. Per lane: the two tables' 1 - E at wo's
// and wi's cosines and their averages A at the lane's alpha (one stacked
// table, EnergyTableLookup), the crossing shares x_o, x_i from the plan's
// constants (LoweringPlan::smoothCrossing, interfaceEta2, sheetCrossing)
// and the lane's averages, then
//   f_ms = (crossing ? x_s : 1 - x_s) Ec_s(mu_o) Ec_s'(mu_i) / (pi A_s')
// with s wo's side and s' wi's, and eta^2 moved across a crossing pair in
// radiance transport.
#pragma once

#include "EnergyTableLookup.h"
#include "LaneEmitter.h"

namespace facet {

class WholeSphereEnergy {
public:
    using Vec = std::array<llvm::Value*, 3>;
    // At the lane's NDF parameters n (after lowerInputsAndLets).
    WholeSphereEnergy(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n);
    // f_ms(wi, wo) per channel, precise type, for unit directions off the
    // surface (in it: the caller's).
    LVal value(const Vec& wi, const Vec& wo);
    // The sampler draws from the compensation with this probability at wo
    // (its albedo from wo's side less what `scatter` drops; at most 0.9).
    llvm::Value* probability(const Vec& wo);
    // That draw's density at wi, and the draw from u (u0 already rescaled
    // to [0, 1) by the mixture's choice): a side by the kept shares, then
    // the cosine lobe there.
    llvm::Value* pdf(const Vec& wi, const Vec& wo);
    Vec sample(const Vec& wo, llvm::Value* u0, llvm::Value* u1, llvm::Value* u2);

private:
    // The shares (reflect, cross) of the draws from wo's side, the kept
    // pairs only, averaged over the channels.
    std::pair<llvm::Value*, llvm::Value*> keptShares(llvm::Value* woUp);
    // x_s of wo's side per channel.
    LVal crossing(llvm::Value* woUp);

    LaneEmitter& lane_;
    MathEmitter& pm_;
    EnergyTableLookup table_;
    llvm::Value *avgOutside_, *avgInside_;
    LVal crossOutside_, crossInside_;
};

}  // namespace facet
