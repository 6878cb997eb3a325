// BsdfCombination: checks the expression of `bsdf = EXPR;` (SPEC 10) and
// turns it into the plain combination tree of CheckedMaterial::bsdf.
//
// The parser reads the right-hand side with the ordinary expression grammar,
// so this is where lobes are told from numbers: a name of a lobe, `X + Y`,
// `W * X` / `X * W`, `mix(X, Y, T)` and `layer(TOP, BASE [, weight = W])`
// are combinations; everything else is a weight, typed by the caller's
// expression checker (float or rgb, names resolved as anywhere else).
#pragma once

#include "Diagnostics.h"
#include "Material.h"

#include <functional>
#include <string_view>
#include <vector>

namespace facet {

struct BsdfCheckContext {
    // The index of the lobe called `name` in CheckedMaterial::lobes, or -1.
    std::function<int(std::string_view name)> findLobe;
    // Types a weight expression, reporting its own errors (Unknown then).
    std::function<ValueType(Expr& weight)> typeWeight;
    // The lobe names, for the message of an unknown one.
    std::vector<std::string> lobeNames;
    DiagnosticEngine& diags;
};

// Appends the nodes of `expr` to `nodes` (children first) and returns the
// index of its root, or -1 after reporting an error.
int buildBsdfTree(Expr& expr, const BsdfCheckContext& context, std::vector<BsdfNode>& nodes);

}  // namespace facet
