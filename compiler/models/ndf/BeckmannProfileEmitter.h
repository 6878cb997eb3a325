// BeckmannProfileEmitter: the Smith Lambda of NDFs with the Beckmann slope
// profile (beckmann, and blinn_phong through its equivalent alpha) as IR,
// shared by their emitters (BeckmannEmitter.cpp, BlinnPhongEmitter.cpp).
#pragma once

#include "lowering/LaneEmitter.h"

namespace facet {

class BeckmannProfileEmitter : public NdfEmitter {
public:
    BeckmannProfileEmitter() { traits.beckmannProfileLambda = true; }
    llvm::Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<llvm::Value*, 3>& v) const override;
};

}  // namespace facet
