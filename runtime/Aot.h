// Aot: what `facet build` adds to the JIT's kernel pipeline to write a
// self-contained object for the host or another LLVM target.
//
// The kernel itself is lowered, optimized and emitted exactly as the JIT
// does it (Compiler::compileAot in CompilerOutputs.cpp, optimizeKernelModule and
// runKernelCodegen in Jit.h); this file supplies the three things the JIT
// does not need:
//   - a target machine for a triple, CPU and features named on the command
//     line, checked against LLVM's target registry and against what Facet
//     builds for (AotTarget.cpp);
//   - the C entry points PREFIX_eval / PREFIX_eval_batch, and where the
//     module has the sampler's entry points PREFIX_sample / _sample_batch /
//     _pdf / _pdf_batch, with the conventions of facet_eval, facet_sample
//     and the rest (facet.h), emitted in IR into the kernel's module so that
//     the object needs nothing else;
//   - writing the module as an object, assembly, IR text or bitcode.
#pragma once

#include "Lowering.h"

#include <llvm/IR/Module.h>
#include <llvm/Target/TargetMachine.h>

#include <memory>
#include <string>

namespace facet {

enum class AotOutput { Object, Assembly, LlvmIr, Bitcode };

// The target of an ahead-of-time build. Empty triple: the host, with the
// CPU and features the JIT compiles for (unless cpu is given); features
// ("+avx2,-fma") are added to the CPU's own.
struct AotTargetRequest {
    std::string triple, cpu, features;
};

struct AotTarget {
    std::unique_ptr<llvm::TargetMachine> machine;
    std::string triple, cpu, features;  // as used
    int width = 4;                      // the SIMD width the JIT would pick on this CPU (16 AVX-512F, 8 AVX2, else 4)
};

// On a user error returns a target without machine and sets `error` to
// one line: a target, CPU or feature LLVM does not know (naming the ones
// it knows), or one Facet cannot serve, refused before any code is
// generated since LLVM aborts or fails on many: an architecture other than
// x86_64 and aarch64, 32-bit pointers, an x86_64 CPU and features without
// 64-bit mode or SSE2, with soft-float, or with avx512f but neither evex512
// nor avx512vl; aarch64 without fp-armv8 or with x1-x7 reserved. cpu
// "native" is this machine's CPU and features (its architecture only).
AotTarget createAotTarget(const AotTargetRequest& request, std::string& error);

// Adds PREFIX_eval and PREFIX_eval_batch over the lowered entry points,
// and PREFIX_sample, PREFIX_sample_batch, PREFIX_pdf and PREFIX_pdf_batch
// over the sampler's where the module has them (LoweringOptions::
// emitSampling and a plan with a compiled sampler); the lowered functions
// become internal: the C entry points are the object's only symbols.
// `material` is the specialized material the module was lowered from (its
// slot defaults feed the scalar kernel's batch loops).
void addAotEntryPoints(LoweredModule& lowered, const CheckedMaterial& material, const std::string& prefix);

// The module, optimized, in the requested form.
std::string writeAotOutput(llvm::Module& module, llvm::TargetMachine& machine, AotOutput output);

}  // namespace facet
