// Compiler: the facade of the C++ API (Kernel.h) for JIT kernels: a
// Compiler's lifetime, compileFile/Text/Material, and the compile itself
// (cache lookup, the quick or optimized object, linking), with the tier-up
// that later swaps a tiered kernel's quick code for optimized code.
// Ahead-of-time objects and IR text are in CompilerOutputs.cpp, the
// tolerance search in ToleranceSearch.cpp, the lazily compiled sampler in
// LazySampler.cpp.
#include "Kernel.h"

#include "CacheFiles.h"
#include "CompileStack.h"
#include "Checker.h"
#include "KernelCache.h"
#include "KernelCode.h"
#include "Pipeline.h"
#include "TableCache.h"
#include "ToleranceSearch.h"

#include <chrono>
#include <mutex>

namespace facet {

namespace {

double millisSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// This thread's CPU time with LLVM's work on the compile stack counted.
double threadCpuMillis() { return callerCpuNanos() * 1e-6; }

// LLVM creates some of its state lazily, in function-local statics of its
// passes and code generator, and destroys it at exit(). State created after
// a static Compiler (the first kernel a renderer's plugin compiles) is
// destroyed before that Compiler, whose destructor still runs the queued
// tier-ups (Kernel.h): they then used freed memory (valgrind: an invalid
// read in a MachineFunctionPass; a crash in InstCombine's library-call
// lookup). So the first Compiler of the process compiles one kernel, eval
// and sampler, scalar and SIMD, optimized, before its constructor returns:
// that state then outlives every Compiler (tests/jit/StaticCompilerExit.cpp).
void warmUpLlvm(Compiler& compiler) {
    static std::once_flag once;
    std::call_once(once, [&compiler] {
        static const char* const kMaterial =
            "material warm_up { input roughness = 0.5 in 0 .. 1; ndf = ggx(roughness * roughness); "
            "masking = smith_height_correlated; fresnel = schlick(rgb(0.9, 0.6, 0.5)); }\n";
        for (const char* spec : {"backend=simd;codegen=optimized;cache=off", "backend=scalar;codegen=optimized;cache=off"}) {
            CompileOptions options;
            std::string error = CompileOptions::parse(spec, options);
            internal_assert(error.empty()) << error;
            DiagnosticEngine diags;
            std::unique_ptr<Kernel> k = compiler.compileText(kMaterial, "<warm-up>", "", options, diags);
            internal_assert(k) << diags.str();
            float wo[3] = {0, 0, 1}, u[3] = {0.5f, 0.5f, 0.5f}, wi[3], pdf, weight[3], roughness = 0.5f;
            k->sample(wo, u, &roughness, wi, &pdf, weight);
        }
    });
}

}  // namespace

// What the tier-up thread does for one kernel (see the top of Kernel.h).
struct Compiler::TierUpJob {
    std::weak_ptr<KernelCode> code;
    CheckedMaterial material;
    std::shared_ptr<const EnergyTable> energyTable;  // keeps lowering.energyTable alive
    std::shared_ptr<const EnergyTable> energyTableInside;  // and lowering.energyTableInside
    LoweringOptions lowering;
    std::string prefix, key, cachePath;
    CompileOptions::Cache cache;
    CachedKernel record;  // variant name and measured error, for the caches
};

Compiler::Compiler()
    : jit_(FacetJit::Create()),
      cache_(std::make_shared<CacheDirectory>(defaultCacheRoot())),
      tables_(std::make_unique<TableCache>(cache_, "tables")),
      memoryCache_(std::make_shared<MemoryCache>()),
      tierUpWorker_(std::make_unique<TierUpWorker>()) {
    warmUpLlvm(*this);
}


Compiler::~Compiler() {
    tierUpWorker_.reset();  // first: its running job uses the JIT and the caches
}

void Compiler::finishTierUps() { tierUpWorker_->drain(); }

void Compiler::setCacheDir(std::string dir) { cache_ = std::make_shared<CacheDirectory>(std::move(dir)); }
const std::string& Compiler::cacheDir() const { return cache_->root(); }
std::string Compiler::cacheWarning() const { return cache_->warning(); }

int Compiler::resolveWidth(const CompileOptions& options) const {
    return options.width ? options.width : jit_->hostVectorWidth();
}

std::unique_ptr<Kernel> Compiler::compileFile(const std::string& path, const std::string& name,
                                              const CompileOptions& options, DiagnosticEngine& diags) {
    std::string error;
    std::optional<std::string> text = readSourceFile(path, error);
    if (!text) {
        diags.error({std::make_shared<const std::string>(path), 0, 0}, error);
        return nullptr;
    }
    return compileText(*text, path, name, options, diags);
}

std::unique_ptr<Kernel> Compiler::compileText(const std::string& text, const std::string& path,
                                              const std::string& name, const CompileOptions& options,
                                              DiagnosticEngine& diags) {
    PipelineRun run = PipelineRun::fromText(text, path, name, options);
    return compile(run, diags);
}

std::unique_ptr<Kernel> Compiler::compileMaterial(const CheckedMaterial& material, const CompileOptions& options,
                                                  DiagnosticEngine& diags) {
    PipelineRun run = PipelineRun::fromChecked(material, options);
    return compile(run, diags);
}

bool Compiler::runPipeline(PipelineRun& run, const PipelineControl& control, FacetJit::Level level,
                           DiagnosticEngine& diags) {
    return runKernelPipeline(run, control, PipelineTarget::forJit(*jit_, level), *tables_, diags);
}

std::unique_ptr<Kernel> Compiler::compile(PipelineRun& run, DiagnosticEngine& diags) {
    auto start = std::chrono::steady_clock::now();
    const CompileOptions& options = run.options;
    // Up to the plan's inputs: what the cache key needs.
    PipelineControl keyed;
    keyed.stopAfter = options.backend == Backend::Interp ? PipelineStage::Specialized : PipelineStage::Planned;
    if (!runPipeline(run, keyed, FacetJit::Level::Optimized, diags)) return nullptr;

    std::unique_ptr<Kernel> kernel(new Kernel());
    kernel->material_ = run.specialized;
    kernel->backend_ = options.backend;
    kernel->transport_ = options.transport;
    kernel->energyTable_ = run.energyTable;
    kernel->energyTableInside_ = run.energyTableInside;
    kernel->lobeEnergyTables_ = run.specialized.combinesLobes()
                                    ? run.lobeEnergyTables
                                    : std::vector<std::shared_ptr<const EnergyTable>>{run.energyTable};
    for (int s = 0; s < kernel->material_.slotCount; ++s) kernel->slotNames_.push_back(kernel->material_.slotName(s));
    if (options.backend == Backend::Interp) {
        kernel->origin_ = "interpreter";
        kernel->compileMillis_ = millisSince(start);
        return kernel;
    }
    kernel->width_ = run.simd ? run.lowering.width : 1;
    LoweringOptions lowering = run.lowering;

    // Cached under what the kernel computes, how and with what (KernelCache.h).
    const KernelCacheKey keys(kernel->material_, options, lowering.width, *jit_, kernel->lobeEnergyTables_);
    const std::string& key = keys.eval();
    std::string prefix = "facet_" + key.substr(0, 16);
    std::shared_ptr<CacheDirectory> disk = cache_;
    std::string cachePath = disk->usable() ? kernelCacheFileName(key) : "";  // relative to the cache root

    std::string origin;
    std::optional<CachedKernel> cached = lookUpCaches(*memoryCache_, *disk, key, cachePath, options.cache, origin);
    if (cached) {
        // The variant the object was compiled with (a tolerance search's
        // choice): the sampler is compiled with it too.
        std::optional<MathVariant> variant =
            cachedVariant(kernel->material_, lowering.variant, options.tolerance.has_value(), cached->variant);
        if (variant) lowering.variant = *variant, kernel->origin_ = origin;
        else cached.reset();
    }
    // Cached objects are optimized, except under codegen=quick's own key.
    const bool tiered = !cached && options.codegen == CompileOptions::Codegen::Tiered;
    const FacetJit::Level level = tiered || options.codegen == CompileOptions::Codegen::Quick
                                      ? FacetJit::Level::Quick
                                      : FacetJit::Level::Optimized;
    if (!cached) {
        MathVariant chosen = lowering.variant;
        cached = options.tolerance
                     ? searchVariants(kernel->material_, lowering, *options.tolerance, prefix, level, chosen)
                     : CachedKernel{compileObject(kernel->material_, lowering, prefix, level), lowering.variant.name(),
                                    -1.0};
        lowering.variant = chosen;
        kernel->origin_ = "compiled";
        // A tiered kernel's caches are filled by its tier-up, with optimized code.
        if (!tiered) storeInCaches(*memoryCache_, *disk, key, cachePath, options.cache, *cached);
    }
    kernel->code_ = std::make_shared<KernelCode>();
    kernel->code_->jit = jit_;
    kernel->code_->optimized = level == FacetJit::Level::Optimized;
    link(*kernel->code_, cached->object, prefix, lowering);
    kernel->samplerLowering_ = lowering;
    kernel->samplerLevel_ = options.codegen == CompileOptions::Codegen::Quick ? FacetJit::Level::Quick
                                                                              : FacetJit::Level::Optimized;
    kernel->samplerPrefix_ = prefix;
    // The sampler is compiled with the variant the eval code was compiled
    // with, and cached where eval's object is.
    kernel->samplerKey_ = keys.sampler(lowering.variant.name());
    kernel->samplerCachePath_ = cachePath.empty() ? "" : kernelCacheFileName(kernel->samplerKey_);
    kernel->samplerCache_ = options.cache;
    kernel->memoryCache_ = memoryCache_;
    kernel->diskCache_ = disk;
    kernel->variant_ = cached->variant;
    kernel->measuredError_ = cached->measuredError;
    if (tiered) {
        kernel->code_->tierUpPending = true;
        // The record without the quick object: the tier-up stores its own.
        auto job = std::make_shared<TierUpJob>(TierUpJob{kernel->code_, kernel->material_, kernel->energyTable_,
                                                         kernel->energyTableInside_, lowering, prefix, key, cachePath, options.cache,
                                                         CachedKernel{"", cached->variant, cached->measuredError}});
        tierUpWorker_->post([this, job](TierUpWorker::Run run) { tierUp(*job, run); });
    }
    kernel->compileMillis_ = millisSince(start);
    return kernel;
}

void Compiler::tierUp(const TierUpJob& job, TierUpWorker::Run run) {
    std::shared_ptr<KernelCode> code = job.code.lock();
    if (run == TierUpWorker::Run::Abandoned) {
        if (code) code->settle("not optimized: the process forked before its tier-up ran", 0);
        return;
    }
    // A released kernel's optimized code is still worth having in a cache;
    // once the Compiler is closing, only in the disk cache, which outlives it.
    const bool closing = run == TierUpWorker::Run::Closing;
    const bool forDisk = job.cache == CompileOptions::Cache::On && !job.cachePath.empty();
    const bool wanted = closing ? forDisk : code || job.cache != CompileOptions::Cache::Off;
    if (!wanted) {
        if (code) code->settle("not optimized: the compiler was destroyed first", 0);
        return;
    }
    double start = threadCpuMillis();
    std::string error;
    try {
        CachedKernel record = job.record;
        record.object = compileObject(job.material, job.lowering, job.prefix, FacetJit::Level::Optimized);
        storeInCaches(*memoryCache_, *cache_, job.key, job.cachePath, job.cache, record);
        if (code) link(*code, record.object, job.prefix, job.lowering);
    } catch (const std::exception& e) {
        // Internal (LLVM) failure; the quick code computes the same values.
        error = e.what();
    }
    if (code) code->settle(error, threadCpuMillis() - start);
}

std::string Compiler::compileObject(const CheckedMaterial& material, const LoweringOptions& lowering,
                                    const std::string& prefix, FacetJit::Level level) {
    PipelineRun run = PipelineRun::fromSpecialized(material, nullptr);
    PipelineControl control;
    control.symbolPrefix = prefix;
    control.lowering = lowering;
    DiagnosticEngine diags;  // a specialized material has no user errors left
    internal_assert(runPipeline(run, control, level, diags)) << diags.str();
    return std::move(run.object);
}

void Compiler::link(KernelCode& code, const std::string& object, const std::string& prefix,
                    const LoweringOptions& lowering) {
    llvm::orc::JITDylib& dylib = code.addObject(object, prefix);
    if (lowering.emitScalar) code.install(code.scalarStatus, dylib, prefix + "_scalar_status");
    if (lowering.emitBatch) code.install(code.batch, dylib, prefix + "_batch");
}

}  // namespace facet
