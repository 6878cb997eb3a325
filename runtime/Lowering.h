// Lowering: a checked (and usually specialized) material to LLVM IR.
//
// Emits up to two entry points with a C ABI (SPEC section 4):
//   void  <prefix>_scalar(const float wi[3], const float wo[3], const float* inputs, float rgb[3])
//   int64 <prefix>_batch(int64 n, const float* const wi[3], const float* const wo[3],
//                        const float* const* inputs, float* const rgb[3])
// The batch kernel works on explicit LLVM vectors of `width` lanes (a main
// loop over full vectors, then one masked remainder step) and returns the
// number of invalid lanes. Both entry points are generated from the same
// per-lane emitter, instantiated once with float and once with <W x float>,
// so scalar and SIMD compute the same formulas -- except that a batch kernel
// may have two bodies (MathVariant::floatFirst): exact, a guarded float body
// for the well-conditioned lanes and the precise body for the others; fast
// (isotropic GGX), a guarded body with unscaled Smith forms and the plain
// fast body for the lanes its range guards reject.
//
// The per-lane formulas follow SPEC section 3 but are written for float:
// sin^2 from components, Lambda forms that do not cancel, pow and the GTR
// normalization through double-precision log/exp, and no libm calls.
#pragma once

#include "Material.h"

#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/Module.h>

#include <memory>
#include <string>
#include <string>

namespace facet {

enum class MathMode { Exact, Fast };
const char* mathModeName(MathMode m);

// Which approximations a kernel uses. `exact` keeps every term at full float
// accuracy (double where float rounding would be amplified); `fast` computes
// everything in float with shorter polynomials and lets the backend use
// estimates refined by one Newton step where it can (see `estimates`). The
// two model substitutions change the model the user named, so only a
// tolerance may enable them.
struct MathVariant {
    bool precise = true;            // geometry, exponents, exact Fresnel, parameters in double
    bool estimates = false;         // x/sqrt(y) by an rsqrt estimate + 1 Newton step (Lowering.cpp)
    bool shortPolynomials = false;  // exp/log/atan2 polynomials for ~1e-6 instead of 1 ulp
    bool walterLambda = false;      // Beckmann / Blinn-Phong Smith Lambda: Walter et al. 2007 rational fit
    bool schlickDielectric = false; // dielectric(eta) evaluated as Schlick with f0 from eta
    // With `precise`: evaluate each lane first in float (IEEE division and
    // sqrt, the exact polynomials) and keep that value only where the lane is
    // well-conditioned (guards below); every other lane is recomputed in the
    // precise body. Applies to the materials floatFirstApplies() accepts.
    // Without `precise` (fast): evaluate each lane first with the unscaled
    // Smith forms and D G / (4 ci co) as one fraction (two divisions
    // instead of six), keep that value where the range guards show that no
    // intermediate left float's normal range, and recompute the other lanes
    // in the plain fast body, whose Smith forms are scaled. Applies to the
    // materials guardedFastApplies() accepts.
    bool floatFirst = true;

    static MathVariant exact() { return {}; }
    static MathVariant fast() { return {false, true, true, false, false}; }
    std::string name() const;  // e.g. "exact", "fast", "fast+walter"
    bool operator==(const MathVariant&) const = default;
};

class EnergyTable;

// Whether a kernel of `variant` for `material` is built float-first: GGX
// (isotropic or anisotropic) with any masking, no Fresnel, Schlick with f0,
// or a dielectric/conductor with well-conditioned constant parameters, and
// no energy compensation. (The material's expressions are evaluated in
// double in both bodies, unless they only multiply: see exprEmitter.)
bool floatFirstApplies(const CheckedMaterial& material, const MathVariant& variant);
// Whether a fast SIMD kernel of `variant` is built with the guarded fast
// body (MathVariant::floatFirst): isotropic GGX, no energy compensation.
bool guardedFastApplies(const CheckedMaterial& material, const MathVariant& variant);

// Whether the model substitutions of MathVariant can change this material:
// a Smith masking on a Beckmann-profile Lambda (beckmann, blinn_phong) for
// walterLambda, a dielectric Fresnel term for schlickDielectric.
bool walterLambdaApplies(const CheckedMaterial& material);
bool schlickDielectricApplies(const CheckedMaterial& material);

struct LoweringOptions {
    // energy = kulla_conty: the E table of the material's NDF x masking,
    // embedded in the module as constant arrays (required for such materials).
    const EnergyTable* energyTable = nullptr;
    MathMode math = MathMode::Exact;
    MathVariant variant = MathVariant::exact();
    int width = 16;  // lanes of the batch kernel: 4, 8 or 16
    bool emitScalar = true;
    bool emitBatch = true;
    // Whether the target is x86, whose MXCSR fast kernels set to flush
    // subnormals (Lowering.cpp, DenormalFlush). The host's by default; an
    // ahead-of-time build for another target sets its own.
#if defined(__x86_64__) || defined(__i386__)
    bool x86Target = true;
#else
    bool x86Target = false;
#endif
};

struct LoweredModule {
    std::unique_ptr<llvm::Module> module;
    std::string scalarSymbol, batchSymbol;  // empty when not emitted
};

// `material` must be checked. Throws InternalError on a lowering bug (the
// module is verified before it is returned).
LoweredModule lowerMaterial(const CheckedMaterial& material, const LoweringOptions& options,
                            llvm::LLVMContext& context, const std::string& symbolPrefix);

}  // namespace facet
