// ReferenceModels: hand-written ahead-of-time C++ of three reference BRDFs.
//
// These are the baseline `facet bench` times the JIT against (SPEC section 6):
// what a good engineer writes by hand for speed in plain C++ — float, std::
// math, branch-free loops over SoA arrays that the compiler vectorizes — built
// with -O3 -march=native (see bench/CMakeLists.txt). Each function has the
// calling convention of the JIT batch kernel (runtime/Kernel.h BatchKernelFn)
// and its conventions (SPEC section 2): a lane whose directions are not finite
// or not unit within 1e-3, or whose inputs are not finite, yields 0 and is
// counted; valid directions are renormalized; below the horizon f = 0.
//
// The matching material files live in bench/models/ (same constants, same
// inputs and defaults, and a `// aot: NAME` line that ties them to a model
// here). tests/bench/AotReferenceTests.cpp checks both against the
// interpreter.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace facet::aot {

// n lanes, SoA: wi[0..2], wo[0..2], rgb[0..2] each point to n floats; inputs
// is null (all defaults) or inputs[s] points to n floats (or is null: that
// slot's default). Returns the number of invalid lanes.
using BatchFn = int64_t (*)(int64_t n, const float* const wi[3], const float* const wo[3],
                            const float* const* inputs, float* const rgb[3]);

struct ReferenceModel {
    const char* name;         // the `// aot: NAME` tag
    const char* modelFile;    // bench/models/<modelFile>, relative to the source tree
    const char* description;  // one line: ndf + masking + fresnel
    std::vector<const char*> inputs;  // slot names, in slot order (as Kernel::inputName)
    BatchFn batch;
};

// (a) isotropic GGX + Smith height-correlated + Schlick with an rgb f0.
// Input: roughness (alpha = roughness^2).
int64_t ggxSchlick(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]);
// (b) isotropic Beckmann + Smith separable + conductor (complex eta + ik, rgb).
// Input: roughness (alpha = roughness^2).
int64_t beckmannConductor(int64_t n, const float* const wi[3], const float* const wo[3],
                          const float* const* inputs, float* const rgb[3]);
// (c) anisotropic GGX + Smith height-correlated + exact dielectric (rgb eta).
// Inputs: roughness_x, roughness_y (alpha_x,y = roughness_x,y^2).
int64_t anisoGgxDielectric(int64_t n, const float* const wi[3], const float* const wo[3],
                           const float* const* inputs, float* const rgb[3]);

// All three, in the order above.
const std::vector<ReferenceModel>& referenceModels();
// The model tagged `name`, or null.
const ReferenceModel* findReferenceModel(std::string_view name);

}  // namespace facet::aot
