// StudentSlopeEmitter: the Student-t slope distribution P22(x, y) = (nu/(2
// pi)) (1 + x^2 + y^2)^(-(nu + 2)/2) as IR (the reference is in
// models/NdfSampling.h): its exact Smith Lambda and its visible normals, for
// a per-lane nu > 1, in double, for unit directions in P22's frame. Shared
// by the emitters of blinn_phong (nu = e + 2) and student_t (nu = 2 gamma
// - 2, stretched); written in BlinnPhongEmitter.cpp.
#pragma once

#include "lowering/LaneEmitter.h"

namespace facet {

// (n.v) Lambda(v) of P22: c_nu sin^nu theta / (nu - 1) - cos theta
// T_nu(cot theta), at least 0; v, nu and the result in double.
llvm::Value* studentSlopeCosLambda(MathEmitter& dm, llvm::Value* nu, const std::array<llvm::Value*, 3>& v);

// A visible normal of P22 for the unit wo (double), from u1, u2 (double).
std::array<llvm::Value*, 3> studentSlopeVisibleNormal(LaneEmitter& lane, llvm::Value* nu,
                                                      const std::array<llvm::Value*, 3>& wo, llvm::Value* u1,
                                                      llvm::Value* u2);

}  // namespace facet
