// SamplingSetup: what `facet sample` and `facet render --plot pdf` share:
// the --wo view direction and the reference sampler of a material.
#pragma once

#include "Checker.h"
#include "Interpreter.h"

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <string>

namespace facet {

// Parses "X,Y,Z" (three finite numbers forming a unit vector within
// kUnitTolerance) into `view`. Returns "" or the reason, naming the option
// `option`.
std::string parseViewDirection(const std::string& option, const std::string& text, std::array<double, 3>& view);
// Whether `view` is on a side of the surface `material` is seen from: above
// (z > 0), or either side (z != 0) for a lobe that scatters below the
// surface (SPEC 11). Returns "" or the reason.
std::string viewSideProblem(const std::string& option, const std::string& text, const std::array<double, 3>& view,
                            const CheckedMaterial& material);

// The uniform numbers of `facet sample` and `facet render --plot pdf`: a
// 64-bit Mersenne Twister seeded with `seed`, 53 bits per number, in [0, 1),
// so that a seed draws the same samples on every platform.
class SampleUniforms {
public:
    explicit SampleUniforms(uint64_t seed) : rng_(seed) {}
    double next() { return double(rng_() >> 11) * 0x1p-53; }

private:
    std::mt19937_64 rng_;
};

// --seed S: a whole number from 0 to 2^64 - 1, written in decimal. ""
// with the value in `seed`, or the error message (a value beyond 2^64 - 1
// is an error, never saturated).
std::string parseSeed(const std::string& option, const std::string& text, uint64_t& seed);

// The double interpreter of `material` as the commands' interp backend runs
// it: its Kulla-Conty table and its tabulated Lambda, where it has them,
// come from the table cache, as a compiled kernel's do (a cache that cannot
// be used is reported on stderr, once, and the tables built in memory).
std::unique_ptr<Interpreter<double>> referenceInterpreter(const CheckedMaterial& material);

}  // namespace facet
