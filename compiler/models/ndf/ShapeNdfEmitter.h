// ShapeNdfEmitter: what the emitters of the isotropic NDFs written in
// their own two shape parameters instead of alpha (abc's b and c, sgd's
// alpha and p) share: their parameters for a lane, and (e^y - 1)/y in
// double to its last bits for the closed forms of their normalizations and
// CDFs, which divide a difference of powers by its exponent
// (LaneEmitter::expm1OverX serves the precise type and keeps about 1e-11
// from |y| = 1e-5 up, too little once such differences cancel). Written in
// AbcEmitter.cpp.
#pragma once

#include "lowering/LaneEmitter.h"

namespace facet {

// NdfParams of an isotropic NDF without alphas: own[0], own[1] the clamped
// parameters p0, p1 in the precise type, and their double values.
struct ShapeParams {
    NdfParams n;
    llvm::Value *first = nullptr, *second = nullptr;  // double
};
ShapeParams shapeParams(LaneEmitter& lane, int p0, int p1);

// (e^y - 1)/y, 1 at y = 0; y and the result in double.
llvm::Value* expm1OverXDouble(MathEmitter& dm, llvm::Value* y);

}  // namespace facet
