// Jit: a small wrapper around LLVM ORC's LLJIT, after Kaleidoscope's.
//
// It owns the target machine used for optimization and object emission, and
// the LLJIT that links compiled objects into this process. Each kernel gets
// its own JITDylib (so the same cached object can be loaded twice without
// symbol clashes) and is released by removing that dylib.
#pragma once

#include <llvm/ADT/SmallVector.h>
#include <llvm/ExecutionEngine/Orc/LLJIT.h>
#include <llvm/IR/LegacyPassManager.h>
#include <llvm/IR/Module.h>
#include <llvm/IR/OptBisect.h>
#include <llvm/Support/MemoryBuffer.h>
#include <llvm/Target/TargetMachine.h>

#include <memory>
#include <mutex>
#include <string>

namespace facet {

class FacetJit {
public:
    // Creates a JIT for the host CPU. Throws std::runtime_error if LLVM cannot.
    static std::unique_ptr<FacetJit> Create();
    ~FacetJit();

    // The host as the kernels are compiled for it: CPU name and features.
    const std::string& cpuName() const { return cpu_; }
    const std::string& cpuFeatures() const { return features_; }
    int hostVectorWidth() const;  // 16 with AVX-512F, 8 with AVX2, else 4

    // How object code is emitted: Optimized is the kernel as it is meant to
    // run (CodeGenOptLevel::Aggressive); Quick (CodeGenOptLevel::None: fast
    // register allocation, no machine scheduling) emits in about half the
    // time, computes the same bits and runs slower. Each level has its own
    // target machine (LLVM's caches its subtargets unlocked), pipeline and
    // lock, so a quick compile never waits for an optimized one running on
    // another thread.
    enum class Level { Quick, Optimized };
    // optimize() prepares `module` for this target and runs the short
    // function pipeline described in Jit.cpp; emitObject() returns its
    // object code. Both may be called from several threads.
    void optimize(llvm::Module& module, Level level = Level::Optimized);
    std::unique_ptr<llvm::MemoryBuffer> emitObject(llvm::Module& module, Level level = Level::Optimized);
    // Names the pipeline and codegen level: part of the kernel cache key,
    // so that a change to either never serves objects compiled before it.
    static constexpr const char* kPipelineId = "early-cse,reassociate,instcombine;codegen-O3";

    // Links an object into a fresh JITDylib; returns it. lookup() finds a
    // symbol in it; release() unloads it.
    llvm::orc::JITDylib& addObject(std::unique_ptr<llvm::MemoryBuffer> object);
    void* lookup(llvm::orc::JITDylib& dylib, const std::string& symbol);
    void release(llvm::orc::JITDylib& dylib);

private:
    FacetJit() = default;
    // Emits a small kernel-like module at both levels. This builds the two
    // codegen pipelines, and LLVM's codegen constructs its function-local
    // statics (the SelectionDAG's value-type tables) here, before any
    // Compiler owning this JIT is constructed. A static Compiler is then
    // destroyed before them, so its last tier-up, which its destructor
    // waits for, never runs on destroyed LLVM state.
    void warmUp();
    std::unique_ptr<llvm::orc::LLJIT> jit_;
    // One codegen level: its target machine, its pipeline, built on the first
    // emitObject() at that level and run on every module after it (building
    // it is ~1 ms of a compile), the stream it writes objects to, and the
    // lock that makes one optimize() or emitObject() at a time use them.
    struct Codegen {
        std::unique_ptr<llvm::TargetMachine> tm;
        std::mutex mutex;
        llvm::SmallVector<char, 0> object;
        std::unique_ptr<llvm::raw_svector_ostream> stream;
        std::unique_ptr<llvm::legacy::PassManager> passes;
    };
    Codegen quick_, optimized_;
    Codegen& codegenAt(Level level) { return level == Level::Quick ? quick_ : optimized_; }
    std::string cpu_, features_;
    std::mutex mutex_;  // LLJIT linking is not re-entrant
    uint64_t dylibCounter_ = 0;
};

// The kernel pipeline for any target machine: FacetJit runs it for the host,
// `facet build` (Aot.h) for the target it is asked for, so that both emit
// the same code from the same IR. optimizeKernelModule() sets the module's
// data layout and triple and runs the middle end of `level` (Jit.cpp);
// runKernelCodegen() runs a codegen pipeline built by the target machine
// (addPassesToEmitMC or addPassesToEmitFile) on it, skipping the passes
// that have nothing to do in a kernel.
void optimizeKernelModule(llvm::Module& module, llvm::TargetMachine& tm, FacetJit::Level level);
void runKernelCodegen(llvm::legacy::PassManager& passes, llvm::Module& module);

}  // namespace facet
