// TabulatedLambdaEmitter: the Smith Lambda of an NDF from the plan's
// LambdaTable (LambdaTable.h) as IR, on either of its axes (a alone, or a
// and alpha), and the hook that embeds that table in the kernel. Shared by
// the emitters of the NDFs whose entry has tabulatedLambda (student_t, epd,
// gtr, gaussian, abc, sgd); written in StudentTEmitter.cpp.
#pragma once

#include "lowering/LaneEmitter.h"

namespace facet {

// (n.v) Lambda(v), float, from the table the plan carries (an internal
// error without one).
llvm::Value* tabulatedCosLambda(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                const std::array<llvm::Value*, 3>& v);

// TermEmitterEntry::tables: the material's Lambda table under a Smith
// masking, nothing otherwise.
std::vector<EmbeddedTable> lambdaTableEmbedding(const CheckedMaterial& material);

}  // namespace facet
