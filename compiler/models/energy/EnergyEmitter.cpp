// none, kulla_conty: the energy compensation as IR (the reference is the
// interpreter's, compiler/reference/KullaConty.h). f_ms = Ec(mu_i) Ec(mu_o) /
// (pi EcAvg) times F_avg^2 (1 - EcAvg) / (1 - F_avg EcAvg) per channel,
// with Ec bilinear and EcAvg linear in the material's table, which the
// kernel embeds as a constant (sqrt-spaced in alpha and mu).
#include "lowering/EnergyTableLookup.h"
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

#include "KullaConty.h"

namespace facet {
namespace {

using llvm::Value;

class NoCompensationEmitter final : public EnergyEmitter {};

// The lane's lookups in the embedded table, at the NDF's energy alpha.
EnergyTableLookup tableLookup(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n) {
    return EnergyTableLookup(lane, ndf.energyAlpha(lane, n), {lane.energyTable()});
}

// F_avg^2 (1 - EcAvg) / (1 - F_avg EcAvg) per channel, 0 where the
// denominator vanishes.
std::array<Value*, 3> fresnelTerms(LaneEmitter& lane, const FresnelEmitter& fresnel, Value* ecAvg) {
    MathEmitter& pm = lane.preciseMath();
    // The Fresnel parameters are the same expressions as in F (the
    // optimizer's CSE merges them).
    FresnelAverageArgs args = fresnel.averageArgs(lane);
    std::array<Value*, 3> out;
    for (int ch = 0; ch < 3; ++ch) {
        Value* favg = fresnel.average(lane, args, ch);
        Value* den = pm.sub(pm.c(1.0), pm.mul(favg, ecAvg));
        Value* term = pm.div(pm.mul(pm.mul(favg, favg), pm.sub(pm.c(1.0), ecAvg)), den);
        out[ch] = pm.select(pm.gt(den, pm.c(0.0)), term, pm.c(0.0));
    }
    return out;
}

class KullaContyEmitter final : public EnergyEmitter {
public:
    std::array<Value*, 3> compensation(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                       const FresnelEmitter& fresnel, Value* ci, Value* co) const override {
        MathEmitter& pm = lane.preciseMath();
        EnergyTableLookup table = tableLookup(lane, ndf, n);
        Value* ecAvg = table.ecAvg();
        Value* lobe = pm.div(pm.mul(table.ec(ci), table.ec(co)), pm.mul(pm.c(kPi), ecAvg));
        lobe = pm.select(pm.gt(ecAvg, pm.c(0.0)), lobe, pm.c(0.0));
        std::array<Value*, 3> out = fresnelTerms(lane, fresnel, ecAvg);
        for (Value*& x : out) x = pm.mul(lobe, x);
        return out;
    }

    // The compensation lobe integrates to (1 - E(n.wo)) times the Fresnel
    // term over the cosine-weighted hemisphere of wi (its wi factor 1 -
    // E(n.wi) averages to EcAvg, which the lobe divides out).
    CompensationAlbedo samplingAlbedo(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                      const FresnelEmitter& fresnel, Value* co) const override {
        MathEmitter& pm = lane.preciseMath();
        EnergyTableLookup table = tableLookup(lane, ndf, n);
        Value* ec = table.ec(co);
        std::array<Value*, 3> terms = fresnelTerms(lane, fresnel, table.ecAvg());
        Value* mean = pm.mul(pm.add(pm.add(terms[0], terms[1]), terms[2]), pm.c(1.0 / 3.0));
        return {ec, pm.mul(ec, mean)};
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_energy_EnergyEmitter() {
    static const NoCompensationEmitter& none = immortal<NoCompensationEmitter>();
    static const KullaContyEmitter& kullaConty = immortal<KullaContyEmitter>();
    // random_walk adds no closed-form term: the lane bodies walk the
    // microsurface (compiler/lowering/LaneWalk.cpp) from the NDF's and the
    // Fresnel term's emitters.
    static const NoCompensationEmitter& randomWalk = immortal<NoCompensationEmitter>();
    return {{ModelSlot::Energy, "none", &none},
            {ModelSlot::Energy, "kulla_conty", &kullaConty},
            {ModelSlot::Energy, "random_walk", &randomWalk}};
}

}  // namespace facet
