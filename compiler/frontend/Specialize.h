// Specialize: bind inputs to constants and fold everything that becomes
// constant ("model only what the scene needs").
//
// Given values for some inputs (`--set NAME=VALUE`, `set.NAME=VALUE`), the
// pass removes those inputs (the remaining inputs get new, dense slots),
// replaces their uses by the clamped constant, and folds constant
// subexpressions in double precision, so that lets and model arguments that
// no longer depend on any input become plain numbers. Lowering then sees
// constants and can drop work (a constant F0 is computed once, not per lane),
// and the combination's constant weights fold (BsdfFolding.h: a lobe whose
// weight is 0 is dropped, a weight of 1 disappears).
#pragma once

#include "Diagnostics.h"
#include "Material.h"

#include <map>
#include <string>
#include <vector>

namespace facet {

// Input bindings by name: one value for a float input, one (gray) or three for an rgb input.
using InputBindings = std::map<std::string, std::vector<double>>;

// Returns the specialized material. An unknown input name or a wrong value
// count is reported in diags (at the material's location).
CheckedMaterial specializeMaterial(const CheckedMaterial& material, const InputBindings& bindings,
                                   DiagnosticEngine& diags);

// True if `e` is a number or rgb(number, number, number).
bool isConstantExpr(const Expr& e);
// The constant value of such an expression (channels equal for a float).
std::array<double, 3> constantValue(const Expr& e);

// Prints a checked material back in source syntax (for `facet ir --stages`).
std::string printMaterial(const CheckedMaterial& material);

}  // namespace facet
