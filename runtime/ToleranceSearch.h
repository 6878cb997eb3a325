// ToleranceSearch: how a tolerance=X compile chooses its math variant
// (internal to the runtime). Compiler::searchVariants compiles the
// candidate variants, fastest first, and keeps the first whose error,
// measured against the double interpreter (measureKernelError), meets the
// tolerance; exact is the last candidate and is kept even if it does not.
#pragma once

#include "Kernel.h"

#include <optional>
#include <string>

namespace facet {

// The math variant a cached record names: the compile's own, or for a
// tolerance build one of the candidates the search tries (named as the
// search names them); nullopt for any other name (a record that is not
// this compile's: recompiled).
std::optional<MathVariant> cachedVariant(const CheckedMaterial& material, const MathVariant& variant, bool tolerance,
                                         const std::string& name);

}  // namespace facet
