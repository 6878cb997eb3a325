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

    // optimize() prepares `module` for this target and runs the short
    // function pipeline described in Jit.cpp; emitObject() returns its
    // object code.
    void optimize(llvm::Module& module);
    std::unique_ptr<llvm::MemoryBuffer> emitObject(llvm::Module& module);
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
    std::unique_ptr<llvm::orc::LLJIT> jit_;
    std::unique_ptr<llvm::TargetMachine> tm_;
    // The codegen pipeline, built on the first emitObject() and run on every
    // module after it (building it is ~1 ms of a compile), and the stream it
    // writes objects to.
    struct Codegen {
        llvm::SmallVector<char, 0> object;
        std::unique_ptr<llvm::raw_svector_ostream> stream;
        llvm::legacy::PassManager passes;
    };
    std::unique_ptr<Codegen> codegen_;
    // Skips the codegen passes that have nothing to do in a kernel (see
    // Jit.cpp); set on the module's own LLVMContext only while it is emitted.
    struct SkipPasses : llvm::OptPassGate {
        bool isEnabled() const override { return true; }
        bool shouldRunPass(llvm::StringRef pass, llvm::StringRef) override;
    };
    SkipPasses skipPasses_;
    std::string cpu_, features_;
    std::mutex mutex_;  // LLJIT linking and TargetMachine emission are not re-entrant
    uint64_t dylibCounter_ = 0;
};

}  // namespace facet
