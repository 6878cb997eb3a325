// BsdfFolding: the combination's constant weights folded away (SPEC 10,
// "Specialization"): a lobe whose weight is 0 is not compiled, a weight of
// 1 is no multiplication.
//
// Run by specializeMaterial() once the bound inputs are constants, so that
// `set.coat=0` on `layer(clearcoat, flakes, weight = coat)` leaves the flakes
// lobe alone, a one-lobe material that lowers exactly as that lobe written
// alone would. Each rewrite gives the same value as the tree it replaces
// (the evaluators clamp the weights the same way, SPEC 10):
//   w * X with w <= 0 in every channel      -> nothing (0)
//   w * X with w = 1 in every channel       -> X
//   X + nothing, nothing + X                -> X
//   mix(X, Y, t), t <= 0 / t >= 1           -> X / Y
//   layer(T, B, weight = w), w <= 0         -> B (the base unattenuated)
//   layer(T, B, weight = w), w >= 1         -> layer(T, B)
// A node some other rewrite cannot express (mix or layer with one child
// that is nothing, and a weight that is not constant) keeps that child as
// written. A combination that folds to nothing at all is left as written
// (its value, 0, needs some lobe to evaluate). Lobes no node refers to any
// more are dropped, the others renumbered in source order.
#pragma once

#include "Material.h"

namespace facet {

// Rewrites material.bsdf and material.lobes in place; true if anything changed.
bool foldBsdfWeights(CheckedMaterial& material);

}  // namespace facet
