// CombinationEmitter: one lane body of a material that combines lobes
// (SPEC 10) -- each lobe by the one-lobe LaneEmitter over the lobe alone
// (LoweringPlan::lobes), then the tree of CheckedMaterial::bsdf over their
// values: weights, sums, mixes and layers, a layer's g(mu_i) g(mu_o) read
// from the table the plan baked (LoweringPlan::layerG).
//
// The reference's counterpart is compiler/reference/LobeCombination.h;
// the two are written independently (the reference bakes its own tables on
// demand, per resolved parameter set).
#pragma once

#include "Lowering.h"

#include <llvm/IR/IRBuilder.h>

#include <array>
#include <string>
#include <vector>

namespace facet {

struct CombinationLanes {
    std::array<llvm::Value*, 3> rgb;  // float lanes, 0 where invalid
    llvm::Value* invalid;
};

// f of the combination at (wi, wo) for lanes of type `laneType`, in each
// lobe's scalar body (`scalar`) or batch body. Tables are named
// `tablePrefix`.layerN (covered by the cache key through the material's
// text and the codegen sources).
CombinationLanes emitCombination(const CheckedMaterial& material, const LoweringPlan& plan,
                                 const LoweringOptions& options, bool scalar, llvm::IRBuilder<>& builder,
                                 llvm::Type* laneType, llvm::Module& module, const std::array<llvm::Value*, 3>& wi,
                                 const std::array<llvm::Value*, 3>& wo, const std::vector<llvm::Value*>& slots,
                                 const std::string& tablePrefix);

}  // namespace facet
