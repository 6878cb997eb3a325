// LazySampler: a JIT kernel's sampler, got on the first call of any
// sampling function (Kernel::ensureSampler) so that hosts that only
// evaluate never pay for it, and what the kernel reports about it
// (samplerTier, samplerOrigin, samplerError).
//
// The sampler is the eval kernel's lowering with the sampling entry points
// instead of eval's: the same math variant (a tolerance search's choice
// included) and width. Its object is cached like eval's, in the caches of
// the Compiler that built the kernel (which the kernel may outlive), under
// a key of its own (KernelCacheKey::sampler). A sampler that does not
// compile, link or resolve leaves the reference sampling, and says why.
#include "Kernel.h"

#include "CacheFiles.h"
#include "Immortal.h"
#include "KernelCache.h"
#include "KernelCode.h"
#include "Pipeline.h"
#include "TableCache.h"

#include <fmt/format.h>

namespace facet {

void Kernel::ensureSampler() const {
    if (!code_ || !memoryCache_) return;  // (a tolerance search's probe kernels only evaluate)
    std::call_once(code_->samplerOnce, [this] {
        // A failure leaves the entry points null, so the reference samples,
        // and says why in samplerError.
        KernelCode& code = *code_;
        std::string origin;
        auto fail = [&code, &origin](const std::string& why) {
            code.sampleScalar.store(nullptr, std::memory_order_release);
            code.pdfScalar.store(nullptr, std::memory_order_release);
            code.sampleBatch.store(nullptr, std::memory_order_release);
            code.pdfBatch.store(nullptr, std::memory_order_release);
            code.samplerError = origin.empty() || origin == "compiled"
                                    ? "the compiled sampler failed: " + why
                                    : fmt::format("the sampler from the {} failed: {}", origin, why);
        };
        try {
            LoweringOptions lowering = samplerLowering_;
            lowering.emitEval = false;
            lowering.emitSampling = true;
            if (!hasCompiledSampler(material_)) return;
            std::optional<CachedKernel> cached =
                lookUpCaches(*memoryCache_, *diskCache_, samplerKey_, samplerCachePath_, samplerCache_, origin);
            if (!cached) {
                PipelineRun run = PipelineRun::fromSpecialized(material_, energyTable_);
                run.energyTableInside = energyTableInside_;
                // A combination's lobes' tables too: the eval compile's own
                // objects, not tables built again (~0.3 s each) in the empty
                // cache below.
                if (material_.combinesLobes()) run.lobeEnergyTables = lobeEnergyTables_;
                PipelineControl control;
                control.symbolPrefix = samplerPrefix_;
                control.lowering = lowering;
                TableCache tables("");  // unused: the run starts specialized, with its tables
                DiagnosticEngine diags;
                if (!runKernelPipeline(run, control, PipelineTarget::forJit(*code.jit, samplerLevel_), tables, diags)) {
                    std::string text = diags.str();
                    while (!text.empty() && text.back() == '\n') text.pop_back();
                    fail(text.empty() ? "its pipeline stopped without a diagnostic" : text);
                    return;
                }
                cached = CachedKernel{std::move(run.object), lowering.variant.name(), -1.0};
                origin = "compiled";
                storeInCaches(*memoryCache_, *diskCache_, samplerKey_, samplerCachePath_, samplerCache_, *cached);
            }
            llvm::orc::JITDylib& dylib = code.addObject(cached->object, samplerPrefix_ + ".sampler");
            const std::string& p = samplerPrefix_;
            if (lowering.emitScalar) {
                code.install(code.sampleScalar, dylib, p + "_sample_scalar");
                code.install(code.pdfScalar, dylib, p + "_pdf_scalar");
            }
            if (lowering.emitBatch) {
                code.install(code.sampleBatch, dylib, p + "_sample_batch");
                code.install(code.pdfBatch, dylib, p + "_pdf_batch");
            }
            code.samplerOrigin = origin;  // read only after the call_once
        } catch (const std::exception& e) {
            fail(e.what());
        }
    });
}

const std::string& Kernel::samplerError() const {
    static const std::string& none = immortal<std::string>();
    ensureSampler();
    return code_ ? code_->samplerError : none;
}

std::string Kernel::samplerOrigin() const {
    ensureSampler();
    return code_ ? code_->samplerOrigin : "";
}

std::string Kernel::samplerTier() const {
    ensureSampler();
    bool jit = entryPoint(code_, &KernelCode::sampleScalar) || entryPoint(code_, &KernelCode::sampleBatch);
    return jit ? "jit" : "reference";
}

}  // namespace facet
