// NewtonLoop: the root of an increasing phi(v) in a bracket, per lane, by
// Newton's (or Halley's) steps in a loop of the IR; the samplers invert
// their CDFs with it (LaneEmitter::bracketedNewton, invertIncreasing).
//
// Why a loop that ends early rather than a fixed count of unrolled steps:
// each step holds a whole CDF evaluation (gaussian: a 12-point quadrature),
// so unrolling multiplies the module's size and its compile time, and most
// vectors settle in fewer steps than the worst lane needs. Why each lane
// keeps the value of the step that settled it: a lane's result must not
// depend on the lanes beside it (a one-lane call gets the bits it gets in a
// long batch), and further steps would move it by a rounding-sized amount.
#pragma once

#include "VectorMath.h"

#include <functional>

namespace facet {

// phi(v), phi'(v), and phi''(v) for Halley's step where `curvature` is set.
struct NewtonTerms {
    llvm::Value *phi, *slope;
    llvm::Value* curvature = nullptr;
};

// The root of phi, increasing in v, in [lo, hi], per lane in the type of
// `math`. At most `steps` steps from v0: each sign of phi narrows the
// bracket, and a step that would leave it (or is not a number: phi
// infinite or its slope 0) bisects it instead. A lane stops at the Newton
// (or Halley) step that moved it by at most `settledStep` max(|v|,
// settledFloor) (settledStep 0: 2^-40 in double, 2^-20 in float; Newton's
// error is then of the order of that step squared, Halley's of its cube)
// or left it not a number, and keeps that value. The loop ends when every
// lane has stopped. `eval` emits the terms at v.
llvm::Value* emitBracketedNewton(llvm::IRBuilder<>& builder, MathEmitter& math,
                                 const std::function<NewtonTerms(llvm::Value*)>& eval, llvm::Value* v0,
                                 llvm::Value* lo, llvm::Value* hi, int steps, double settledStep = 0,
                                 double settledFloor = 0);

// Marks the loop whose back edge is `back` as not to be unrolled: its trip
// count is the lanes' (a constant bound invites full unrolling, which
// would bring the compile time back). The walk's loop uses it too.
void keepLoopRolled(llvm::BranchInst* back);

}  // namespace facet
