// ComputeCost: how much code a material's own expressions become, and the
// budget the checker holds them to.
//
// Every backend compiles a material's inputs, lets and model arguments into
// each of its bodies, and LLVM's register allocation and scheduling grow
// faster than linearly with the size of one straight-line body: an rgb
// mix chain of 5000 lets took 47 s to compile for SIMD, 25 rgb exp() calls
// in a chain about 10 s, while the models themselves compile in well under
// a second. So the checker refuses a material whose expressions cost more
// than kMaxComputeCost, with a message at the statement that passes it,
// instead of handing LLVM a body it cannot compile in reasonable time or
// stack (a 100k let chain overflowed the stack in LLVM's Reassociate).
// Real materials cost tens to hundreds; the budget is about 2 s of SIMD
// compile and sampler on a slow 2-core host.
//
// The cost counts float operations per channel (an rgb value costs three),
// each builtin at its weight in the builtin table (exp and log are
// polynomials of ~30 operations in double with range reduction, and cost
// far more than their size in the register allocator), each input slot the
// material reads, and each let once, as the lowering evaluates it once.
// What the models do not read (CheckedMaterial::readByModels) is never
// lowered and costs nothing.
#pragma once

#include "Material.h"

#include <optional>
#include <string>

namespace facet {

constexpr long kMaxComputeCost = 4000;

// The cost of one expression tree (names cost nothing: a let is counted
// where it is defined).
long computeCost(const Expr& e);

struct ComputeBudgetError {
    SourceLoc loc;
    std::string message;
};
// The statement at which the material's running cost (the inputs it reads,
// then the lets, then the model arguments) passes kMaxComputeCost, or nullopt.
std::optional<ComputeBudgetError> exceedsComputeBudget(const CheckedMaterial& material);

}  // namespace facet
