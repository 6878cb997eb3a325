// KernelCode: a compiled kernel's entry points and the dylibs that hold
// their code (internal to the runtime; Kernel.h is the public face).
//
// One KernelCode is shared by the Kernel, a tier-up still pending for it
// (which replaces the eval entry points) and the lazily linked sampler
// (which fills the sampling ones). The entry points are atomics because a
// tier-up replaces them while other threads may be evaluating; every dylib
// stays loaded until the last owner lets go, so that a call already running
// on replaced code finishes on it.
#pragma once

#include "Jit.h"
#include "Kernel.h"

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace llvm::orc { class JITDylib; }

namespace facet {

struct KernelCode {
    std::shared_ptr<FacetJit> jit;
    std::atomic<ScalarStatusFn> scalarStatus{nullptr};
    std::atomic<BatchKernelFn> batch{nullptr};
    // The sampler's (null where the kernel has none: the reference samples).
    std::atomic<SampleScalarFn> sampleScalar{nullptr};
    std::atomic<PdfScalarFn> pdfScalar{nullptr};
    std::atomic<SampleBatchFn> sampleBatch{nullptr};
    std::atomic<PdfBatchFn> pdfBatch{nullptr};
    std::once_flag samplerOnce;
    std::string samplerOrigin;  // set once, inside samplerOnce (Kernel::samplerOrigin)
    std::string samplerError;   // set once, inside samplerOnce (Kernel::samplerError)

    mutable std::mutex mutex;  // guards the members below
    mutable std::condition_variable settled;
    std::vector<llvm::orc::JITDylib*> dylibs;
    bool optimized = false;
    bool tierUpPending = false;
    std::string tierUpError;
    double tierUpMillis = 0;

    ~KernelCode();
    // Ends a pending tier-up: optimized unless `error` says why not.
    void settle(std::string error, double millis);
    // Links `object` into a fresh dylib of `jit`, named `name`, that stays
    // loaded as long as this code. Throws where LLVM cannot link it.
    llvm::orc::JITDylib& addObject(const std::string& object, const std::string& name);
    // Points `entry` at `symbol` of `dylib`, for calls that start from now
    // on. Throws where the symbol is missing.
    template <typename Fn>
    void install(std::atomic<Fn>& entry, llvm::orc::JITDylib& dylib, const std::string& symbol) {
        entry.store(reinterpret_cast<Fn>(jit->lookup(dylib, symbol)), std::memory_order_release);
    }
};

// The entry point `member` of `code` as it is now; null where there is no
// code (an interpreter kernel) or no such entry.
template <typename Fn>
Fn entryPoint(const std::shared_ptr<KernelCode>& code, std::atomic<Fn> KernelCode::*member) {
    return code ? ((*code).*member).load(std::memory_order_acquire) : nullptr;
}

}  // namespace facet
