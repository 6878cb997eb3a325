// EnergyTableLookup: a lane's lookups in the energy tables a kernel embeds
// (compiler/reference/KullaConty.h's EnergyTable, interpolated as its ecAt
// and ecAvgAt are): the alpha row once, then 1 - E at any cosine.
//
// One table for a lobe above the surface (kulla_conty); two for a lobe over
// the whole sphere, whose compensation reads the table of wo's side and the
// table of wi's (DielectricEnergy.h). The two share their grid, so they are
// embedded as one table of stacked rows and a lane picks its side by a row
// offset rather than by looking up both and selecting.
#pragma once

#include "LaneEmitter.h"

#include <vector>

namespace facet {

class EnergyTableLookup {
public:
    // `tables`: one, or the outside's and the inside's (the same grid);
    // alpha in the precise type (clamped to the grid here).
    EnergyTableLookup(LaneEmitter& lane, llvm::Value* alpha, const std::vector<const EnergyTable*>& tables);
    // 1 - E(c), bilinear in (sqrt alpha, sqrt c), of the table `inside`
    // picks per lane (i1; null: the first table).
    llvm::Value* ec(llvm::Value* c, llvm::Value* inside = nullptr);
    // 1 - E_avg, linear in sqrt alpha.
    llvm::Value* ecAvg(llvm::Value* inside = nullptr);
    // 1 - E_avg of table k (0: the first).
    llvm::Value* ecAvgOfTable(int k);

private:
    llvm::Value* row(llvm::Value* inside);
    llvm::Value* rowOfTable(int k);

    LaneEmitter& lane_;
    MathEmitter& pm_;
    const EnergyTable* table_;
    int tableCount_;
    llvm::GlobalVariable *ecTable_, *avgTable_;
    llvm::Value *row_, *tRow_;
};

}  // namespace facet
