// Lowering: a checked (and usually specialized) material to LLVM IR.
//
// Emits up to two entry points with a C ABI (SPEC section 4), and next to
// each the sampler's sample and pdf twins (SPEC section 8, LoweredModule;
// KernelEntries.cpp):
//   int32 <prefix>_scalar_status(const float wi[3], const float wo[3], const float* inputs, float rgb[3])
//                                (1: invalid lane; Kernel::eval, the SPEC's void entry, drops it)
//   int64 <prefix>_batch(int64 n, const float* const wi[3], const float* const wo[3],
//                        const float* const* inputs, float* const rgb[3], uint8_t* status)
//                        (status: NULL, or n bytes: 1 for an invalid lane, 0 for a valid one)
// The batch kernel works on explicit LLVM vectors of `width` lanes (a main
// loop over full vectors, then one masked remainder step) and returns the
// number of invalid lanes. Both entry points are generated from the same
// per-lane emitter, instantiated once with float and once with <W x float>,
// so scalar and SIMD compute the same formulas -- except that a batch kernel
// may have two bodies (MathVariant::floatFirst): exact, a guarded float body
// for the well-conditioned lanes and the precise body for the others; fast
// (isotropic GGX), a guarded body with unscaled Smith forms and the plain
// fast body for the lanes its range guards reject. planLowering() decides
// which (LoweringPlan.h).
//
// The per-lane formulas follow SPEC section 3 but are written for float:
// sin^2 from components, Lambda forms that do not cancel, pow and the GTR
// normalization through double-precision log/exp, and no libm calls.
#pragma once

#include "LoweringPlan.h"

#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/Module.h>

#include <memory>
#include <string>
#include <vector>

namespace facet {

class EnergyTable;

struct LoweringOptions {
    // energy = kulla_conty: the E table of the material's NDF x masking,
    // embedded in the module as constant arrays (required for such materials).
    const EnergyTable* energyTable = nullptr;
    // and, for a lobe over the whole sphere, the table from inside
    // (insideTableKey of energyTable's key; the same table for a thin sheet).
    const EnergyTable* energyTableInside = nullptr;
    // A combination of lobes: the table of each compensating lobe (per lobe,
    // in CheckedMaterial::lobes order; null for the others).
    std::vector<const EnergyTable*> lobeEnergyTables;
    MathMode math = MathMode::Exact;
    MathVariant variant = MathVariant::exact();
    int width = 16;  // lanes of the batch kernel: 4, 8 or 16
    bool emitScalar = true;
    bool emitBatch = true;
    // Which entry points: eval's, and the sampler's sample and pdf (where
    // the plan has a JIT sampler for the material: LoweringPlan::sampling),
    // scalar and/or batch as above. JIT kernels compile the sampler in a
    // module of its own on first use (runtime/Kernel.h), so that eval-only
    // hosts do not pay for it.
    bool emitEval = true;
    bool emitSampling = false;
    // The host's promise of valid inputs (assume=unit; LoweringPlan::trustInputs).
    bool trustInputs = false;
    // The transport a refracting lobe's kernel is for (SPEC 11; LoweringPlan::transport).
    Transport transport = Transport::Radiance;
    // Each batch entry gets its lane body at one lane too, which its one-lane
    // calls run (LoweringPlan::oneLaneBody): optimized code only, as it
    // costs about a third more compile time.
    bool oneLaneBodies = false;
};

struct LoweredModule {
    std::unique_ptr<llvm::Module> module;
    LoweringPlan plan;  // the decisions the module was lowered with
    // int32 <prefix>_scalar_status(wi[3], wo[3], inputs, rgb[3]) (1: invalid
    // lane) and the batch entry point; empty when not emitted.
    std::string scalarSymbol, batchSymbol;
    // The sampler's (empty when not emitted):
    //   int32 <prefix>_sample_scalar(const float wo[3], const float u[3], const float* inputs,
    //                                float wi[3], float* pdf, float weight[3])   (1: invalid lane)
    //   int32 <prefix>_pdf_scalar(const float wi[3], const float wo[3], const float* inputs, float* pdf)
    //   int64 <prefix>_sample_batch(int64 n, const float* const wo[3], const float* const u[3],
    //                               const float* const* inputs, float* const wi[3], float* pdf,
    //                               float* const weight[3])   (the number of invalid lanes)
    //   int64 <prefix>_pdf_batch(int64 n, const float* const wi[3], const float* const wo[3],
    //                            const float* const* inputs, float* pdf)
    std::string sampleScalarSymbol, pdfScalarSymbol, sampleBatchSymbol, pdfBatchSymbol;
};

// `material` must be checked (and is usually specialized); `plan` is
// planLowering(material, options.variant, options.trustInputs). Throws
// InternalError on a lowering bug (the module is verified before it is
// returned). runKernelPipeline (runtime/Pipeline.h) is the caller.
LoweredModule lowerMaterial(const CheckedMaterial& material, const LoweringPlan& plan, const LoweringOptions& options,
                            llvm::LLVMContext& context, const std::string& symbolPrefix);

}  // namespace facet
