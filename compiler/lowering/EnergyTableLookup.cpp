// EnergyTableLookup: see EnergyTableLookup.h.
#include "EnergyTableLookup.h"

#include "Diagnostics.h"
#include "KullaConty.h"

namespace facet {

using llvm::Value;

EnergyTableLookup::EnergyTableLookup(LaneEmitter& lane, Value* alpha, const std::vector<const EnergyTable*>& tables)
    : lane_(lane), pm_(lane.preciseMath()), tableCount_(int(tables.size())) {
    internal_assert(!tables.empty() && tables[0]) << "energy compensation lowered without its E table";
    table_ = tables[0];
    std::vector<float> ec, avg;
    for (const EnergyTable* t : tables) {
        internal_assert(t && t->muCount == table_->muCount && t->alphaCount == table_->alphaCount &&
                        t->alphaMin == table_->alphaMin && t->alphaMax == table_->alphaMax)
            << "stacked energy tables on different grids";
        ec.insert(ec.end(), t->ec.begin(), t->ec.end());
        avg.insert(avg.end(), t->ecAvg.begin(), t->ecAvg.end());
    }
    // Named by the table's key: the lobes of a combination each embed
    // their own (a module's tables are shared by name).
    const std::string id = table_->key.name() + (tableCount_ == 1 ? "" : ".sides");
    ecTable_ = lane.floatTable(ec, "facet_energy_ec." + id);
    avgTable_ = lane.floatTable(avg, "facet_energy_ecavg." + id);
    MathEmitter& pm = pm_;
    const EnergyTable& t = *table_;
    Value* a = pm.minnum(pm.maxnum(alpha, pm.c(t.alphaMin)), pm.c(t.alphaMax));
    Value* v = pm.fma(pm.sqrt(a), pm.c(t.alphaScale()), pm.c(t.alphaOffset()));
    v = pm.minnum(pm.maxnum(v, pm.c(0.0)), pm.c(t.alphaCount - 1.0));
    row_ = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, v), pm.c(t.alphaCount - 2.0));
    tRow_ = pm.sub(v, row_);
}

// The row of the lane's table: the inside's rows follow the outside's.
Value* EnergyTableLookup::row(Value* inside) {
    if (!inside || tableCount_ == 1) return row_;
    return pm_.select(inside, rowOfTable(1), row_);
}

Value* EnergyTableLookup::rowOfTable(int k) {
    internal_assert(k >= 0 && k < tableCount_) << "energy table " << k << " of " << tableCount_;
    return k == 0 ? row_ : pm_.add(row_, pm_.c(double(k * table_->alphaCount)));
}

Value* EnergyTableLookup::ec(Value* c, Value* inside) {
    MathEmitter& pm = pm_;
    const int M = table_->muCount;
    Value* cc = pm.minnum(pm.maxnum(pm.convert(c, pm.type()), pm.c(0.0)), pm.c(1.0));
    Value* u = pm.mul(pm.sqrt(cc), pm.c(M - 1.0));
    Value* col = pm.minnum(lane_.intrinsic(llvm::Intrinsic::floor, u), pm.c(M - 2.0));
    return lane_.bilerpFetch(ecTable_, M, row(inside), col, tRow_, pm.sub(u, col));
}

Value* EnergyTableLookup::ecAvg(Value* inside) { return lane_.lerpFetch(avgTable_, row(inside), tRow_); }

Value* EnergyTableLookup::ecAvgOfTable(int k) { return lane_.lerpFetch(avgTable_, rowOfTable(k), tRow_); }

}  // namespace facet
