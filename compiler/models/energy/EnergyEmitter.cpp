// none, kulla_conty: the energy compensation as IR (the reference is the
// interpreter's, compiler/KullaConty.h). f_ms = Ec(mu_i) Ec(mu_o) /
// (pi EcAvg) times F_avg^2 (1 - EcAvg) / (1 - F_avg EcAvg) per channel,
// with Ec bilinear and EcAvg linear in the material's table, which the
// kernel embeds as a constant (sqrt-spaced in alpha and mu).
#include "lowering/LaneEmitter.h"

#include "KullaConty.h"

namespace facet {
namespace {

using llvm::Value;

class NoCompensationEmitter final : public EnergyEmitter {};

class KullaContyEmitter final : public EnergyEmitter {
public:
    std::array<Value*, 3> compensation(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                       const FresnelEmitter& fresnel, Value* ci, Value* co) const override {
        MathEmitter& pm = lane.preciseMath();
        const EnergyTable* table = lane.energyTable();
        internal_assert(table) << "energy = kulla_conty lowered without its E table";
        auto* ecTable = lane.floatTable(table->ec, "facet_energy_ec");
        auto* avgTable = lane.floatTable(table->ecAvg, "facet_energy_ecavg");
        const int M = table->muCount;
        Value* alpha = pm.minnum(pm.maxnum(ndf.energyAlpha(lane, n), pm.c(table->alphaMin)), pm.c(table->alphaMax));
        Value* v = pm.fma(pm.sqrt(alpha), pm.c(table->alphaScale()), pm.c(table->alphaOffset()));
        v = pm.minnum(pm.maxnum(v, pm.c(0.0)), pm.c(table->alphaCount - 1.0));
        Value* row = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, v), pm.c(table->alphaCount - 2.0));
        Value* tRow = pm.sub(v, row);
        auto ec = [&](Value* c) {
            Value* cc = pm.minnum(pm.maxnum(pm.convert(c, pm.type()), pm.c(0.0)), pm.c(1.0));
            Value* u = pm.mul(pm.sqrt(cc), pm.c(M - 1.0));
            Value* col = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, u), pm.c(M - 2.0));
            return lane.bilerpFetch(ecTable, M, row, col, tRow, pm.sub(u, col));
        };
        Value* ecAvg = lane.lerpFetch(avgTable, row, tRow);
        Value* lobe = pm.div(pm.mul(ec(ci), ec(co)), pm.mul(pm.c(kPi), ecAvg));
        lobe = pm.select(pm.gt(ecAvg, pm.c(0.0)), lobe, pm.c(0.0));

        // The Fresnel parameters are the same expressions as in F (the
        // optimizer's CSE merges them).
        FresnelAverageArgs args = fresnel.averageArgs(lane);
        std::array<Value*, 3> out;
        for (int ch = 0; ch < 3; ++ch) {
            Value* favg = fresnel.average(lane, args, ch);
            Value* den = pm.sub(pm.c(1.0), pm.mul(favg, ecAvg));
            Value* term = pm.div(pm.mul(pm.mul(favg, favg), pm.sub(pm.c(1.0), ecAvg)), den);
            term = pm.select(pm.gt(den, pm.c(0.0)), term, pm.c(0.0));
            out[ch] = pm.mul(lobe, term);
        }
        return out;
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_energy_EnergyEmitter() {
    static const NoCompensationEmitter none;
    static const KullaContyEmitter kullaConty;
    return {{ModelSlot::Energy, "none", &none}, {ModelSlot::Energy, "kulla_conty", &kullaConty}};
}

}  // namespace facet
