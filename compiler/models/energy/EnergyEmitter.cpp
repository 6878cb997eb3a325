// none, kulla_conty: the energy compensation as IR (the reference is the
// interpreter's, compiler/reference/KullaConty.h). f_ms = Ec(mu_i) Ec(mu_o) /
// (pi EcAvg) times F_avg^2 (1 - EcAvg) / (1 - F_avg EcAvg) per channel,
// with Ec bilinear and EcAvg linear in the material's table, which the
// kernel embeds as a constant (sqrt-spaced in alpha and mu).
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

#include "KullaConty.h"

namespace facet {
namespace {

using llvm::Value;

class NoCompensationEmitter final : public EnergyEmitter {};

// The lane's lookups in the embedded table: the alpha row (once) and Ec at
// any cosine.
class EnergyTableLookup {
public:
    EnergyTableLookup(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n) : lane_(lane), pm_(lane.preciseMath()) {
        const EnergyTable* table = lane.energyTable();
        internal_assert(table) << "energy = kulla_conty lowered without its E table";
        table_ = table;
        ecTable_ = lane.floatTable(table->ec, "facet_energy_ec");
        auto* avgTable = lane.floatTable(table->ecAvg, "facet_energy_ecavg");
        MathEmitter& pm = pm_;
        Value* alpha = pm.minnum(pm.maxnum(ndf.energyAlpha(lane, n), pm.c(table->alphaMin)), pm.c(table->alphaMax));
        Value* v = pm.fma(pm.sqrt(alpha), pm.c(table->alphaScale()), pm.c(table->alphaOffset()));
        v = pm.minnum(pm.maxnum(v, pm.c(0.0)), pm.c(table->alphaCount - 1.0));
        row_ = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, v), pm.c(table->alphaCount - 2.0));
        tRow_ = pm.sub(v, row_);
        ecAvg = lane.lerpFetch(avgTable, row_, tRow_);
    }
    // 1 - E(c), bilinear in (sqrt alpha, sqrt c).
    Value* ec(Value* c) {
        MathEmitter& pm = pm_;
        const int M = table_->muCount;
        Value* cc = pm.minnum(pm.maxnum(pm.convert(c, pm.type()), pm.c(0.0)), pm.c(1.0));
        Value* u = pm.mul(pm.sqrt(cc), pm.c(M - 1.0));
        Value* col = pm.minnum(lane_.intrinsic(llvm::Intrinsic::floor, u), pm.c(M - 2.0));
        return lane_.bilerpFetch(ecTable_, M, row_, col, tRow_, pm.sub(u, col));
    }
    Value* ecAvg;

private:
    LaneEmitter& lane_;
    MathEmitter& pm_;
    const EnergyTable* table_;
    llvm::GlobalVariable* ecTable_;
    Value *row_, *tRow_;
};

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
        EnergyTableLookup table(lane, ndf, n);
        Value* lobe = pm.div(pm.mul(table.ec(ci), table.ec(co)), pm.mul(pm.c(kPi), table.ecAvg));
        lobe = pm.select(pm.gt(table.ecAvg, pm.c(0.0)), lobe, pm.c(0.0));
        std::array<Value*, 3> out = fresnelTerms(lane, fresnel, table.ecAvg);
        for (Value*& x : out) x = pm.mul(lobe, x);
        return out;
    }

    // The compensation lobe integrates to (1 - E(n.wo)) times the Fresnel
    // term over the cosine-weighted hemisphere of wi (its wi factor 1 -
    // E(n.wi) averages to EcAvg, which the lobe divides out).
    CompensationAlbedo samplingAlbedo(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                      const FresnelEmitter& fresnel, Value* co) const override {
        MathEmitter& pm = lane.preciseMath();
        EnergyTableLookup table(lane, ndf, n);
        Value* ec = table.ec(co);
        std::array<Value*, 3> terms = fresnelTerms(lane, fresnel, table.ecAvg);
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
