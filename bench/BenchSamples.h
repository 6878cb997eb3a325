// BenchSamples: the inputs `facet bench` times and measures error on.
//
// Two samples per material, both SoA float arrays (the very same floats go
// to the kernels and, widened to double, to the reference interpreter):
// - the regular sample: directions as a renderer produces them (uniform
//   over the upper hemisphere, a few below the horizon) and inputs uniform
//   in their declared ranges; it is also the batch that is timed;
// - the hard-case sample (SPEC section 7) of the shared generator
//   compiler/HardCases.h (also used by `facet verify` and the hard-case
//   tests): grazing, mirror, retro-reflected and nearly opposite directions,
//   extreme inputs, and invalid lanes.
#pragma once

#include "Material.h"

#include <cstdint>
#include <string>
#include <vector>

namespace facet::bench {

struct Sample {
    std::vector<float> dir[6];              // wi_x, wi_y, wi_z, wo_x, wo_y, wo_z
    std::vector<std::vector<float>> slots;  // one column per input slot of the material
    size_t size() const { return dir[0].size(); }
    // Appends one lane (slots.size() values in `inputs`).
    void push(const double wi[3], const double wo[3], const std::vector<double>& inputs);
    // Pointers in the layout of Kernel::evalBatch: wi[3], wo[3], inputs[slots].
    const float* const* wi() const { return wiPtr_; }
    const float* const* wo() const { return woPtr_; }
    const float* const* inputs() const { return inPtr_.empty() ? nullptr : inPtr_.data(); }
    void finish();  // refreshes the pointers once the columns are complete

private:
    const float* wiPtr_[3] = {};
    const float* woPtr_[3] = {};
    std::vector<const float*> inPtr_;
};

// n lanes: directions uniform over the upper hemisphere (5% of them below the
// horizon), inputs uniform in their declared ranges (or [0, 2 default] when
// unranged). Deterministic in `seed`.
Sample regularSample(const CheckedMaterial& material, size_t n, uint64_t seed);

// The hard-case sample of SPEC section 7 for this material (HardCases.h).
Sample hardCaseSample(const CheckedMaterial& material);
// One line describing how the hard-case sample is made (for the reports).
std::string hardCaseSampleDescription();

}  // namespace facet::bench
