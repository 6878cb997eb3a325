// DiffHarness: compares compiled kernels against the double interpreter.
//
// Shared by the differential tests over shipped/corpus materials and the
// random-material test. Directions are drawn in float (both sides see the
// very same float inputs); the reference runs in double. Error bounds:
// 99.9% of finite reference values within 1e-5
// relative, every value within 2e-3 relative or 1e-30 absolute, no NaN, Inf
// or negative output, and scalar/SIMD agreement within 4 ulp.
#pragma once

#include "Interpreter.h"
#include "Kernel.h"
#include "LaneBatch.h"
#include "ReferenceComparison.h"

#include <optional>
#include <random>
#include <string>
#include <vector>

namespace facet::test {

// n random pairs: directions uniform over the sphere's upper hemisphere
// (10% below the horizon), inputs uniform in their ranges (5% outside).
LaneBatch randomSample(const CheckedMaterial& m, size_t n, uint64_t seed);
// Hand-made hard directions: normal, grazing, mirror, retro, near-opposite.
LaneBatch hardSample(const CheckedMaterial& m);

struct DiffStats {
    size_t compared = 0, finiteRef = 0, within1e5 = 0, beyond2e3 = 0, nonFinite = 0, negative = 0,
           invalidMismatch = 0, ulpViolations = 0;
    double maxRel = 0, maxUlpScalarSimd = 0;
    std::string worst;  // the worst case, printable
    bool ok(std::string& why) const;
};

// Evaluates `kernel` on `s` (whose slot columns are those of `reference`, the
// unspecialized material) and compares with the reference interpreter of the
// kernel's own material, in which inputs bound by the options are folded
// (ReferenceComparison.h defines the error).
// `shared`, when given, holds the reference values of `s` across calls: the
// first call computes them, later ones (kernels of the same material, inputs
// and tables: other backends, widths, bodies) reuse them instead of running
// the interpreter over the sample again.
void compare(const Kernel& kernel, const CheckedMaterial& reference, const LaneBatch& s, DiffStats& stats,
             std::optional<ReferenceValues>* shared = nullptr);
// Scalar vs SIMD on the same sample: max ulp distance.
void compareUlp(const Kernel& scalar, const Kernel& simd, const LaneBatch& s, DiffStats& stats);

std::string readFile(const std::string& path);

}  // namespace facet::test
