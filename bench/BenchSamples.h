// BenchSamples: the inputs `facet bench` times and measures error on.
//
// Two samples per material, both LaneBatch SoA float arrays (the very same
// floats go to the kernels and, widened to double, to the reference
// interpreter):
// - the regular sample: directions as a renderer produces them (uniform
//   over the upper hemisphere, a few below the horizon) and inputs uniform
//   in their declared ranges; it is also the batch that is timed;
// - the hard-case sample (SPEC section 7) of the shared generator
//   compiler/hardcases/HardCases.h (also used by `facet verify` and the hard-case
//   tests): grazing, mirror, retro-reflected and nearly opposite directions,
//   extreme inputs, and invalid lanes.
#pragma once

#include "LaneBatch.h"
#include "Material.h"

#include <cstdint>
#include <string>
#include <vector>

namespace facet::bench {

// n lanes: directions uniform over the upper hemisphere (5% of them below the
// horizon), inputs uniform in their declared ranges (or [0, 2 default] when
// unranged). Deterministic in `seed`.
LaneBatch regularSample(const CheckedMaterial& material, size_t n, uint64_t seed);

// The hard-case sample of SPEC section 7 for this material (HardCases.h).
LaneBatch hardCaseSample(const CheckedMaterial& material);
// One line describing how the hard-case sample is made (for the reports).
std::string hardCaseSampleDescription();

}  // namespace facet::bench
