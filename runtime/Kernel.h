// Kernel: the C++ library API — compile a material with options, evaluate it.
//
// A Compiler owns one JIT and the compiled-kernel caches (in memory, and on
// disk under FACET_CACHE_DIR, $XDG_CACHE_HOME/facet or ~/.cache/facet, used
// only when trusted: CacheFiles.h), which hold the kernels' eval objects
// and, under keys of their own, their samplers'. Several Compilers may live
// in one process. A Kernel is immutable once built and safe to evaluate from
// many threads at once.
//
// Options (SPEC section 4) are "key=value" pairs separated by ';':
//   backend=scalar|simd|interp   math=exact|fast   tolerance=X
//   width=4|8|16                 set.NAME=VALUE (rgb: set.NAME=r,g,b)
//   cache=on|off|memory          float_first=on|off
//   codegen=tiered|quick|optimized   assume=unit|none
//
// Tiered compilation (the default): a compile returns a kernel whose code was
// emitted quickly (FacetJit::Level::Quick, about half the emission time, the
// same bits, 10-40% slower), and queues the optimized emission of the same
// IR on the Compiler's tier-up thread, which switches the kernel's entry
// points to the optimized code when it is linked. Evaluations running at the
// switch finish on the quick code, which stays loaded as long as the kernel.
// The caches keep only optimized objects, so a tiered compile fills them
// when its tier-up is done: with caching on it runs even if the kernel was
// released first. A Compiler's destructor waits for the tier-up running and
// of those queued runs only the ones that fill the disk cache; the others'
// kernels keep the quick code.
#pragma once

#include "Aot.h"
#include "Jit.h"
#include "KernelCacheFile.h"
#include "Lowering.h"
#include "Material.h"
#include "Specialize.h"
#include "TierUp.h"

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace llvm::orc { class JITDylib; }

namespace facet {

class Kernel;
struct KernelCode;
struct PipelineRun;
struct PipelineControl;
class EnergyTable;
class TableCache;
class CacheDirectory;
struct MemoryCache;

// Max relative error of `kernel` against the double interpreter of
// `material` on a fixed sample (cosine-distributed directions, inputs
// uniform in their ranges), by the conventions of ReferenceComparison.h.
double measureKernelError(const Kernel& kernel, const CheckedMaterial& material, size_t samples = 4096);

enum class Backend { Interp, Scalar, Simd };
const char* backendName(Backend b);

struct CompileOptions {
    Backend backend = Backend::Simd;
    MathMode math = MathMode::Exact;
    std::optional<double> tolerance;
    int width = 0;  // 0: the host's natural width
    InputBindings bindings;
    enum class Cache { On, Off, Memory } cache = Cache::On;
    // SIMD kernels with two bodies (MathVariant::floatFirst). math=exact:
    // evaluate in float where the lane is well-conditioned and in double
    // elsewhere; off: double wherever float rounding could be amplified, as
    // the scalar kernel (then scalar and SIMD agree within 4 ulp).
    // math=fast, isotropic GGX: the unscaled Smith forms where range guards
    // allow them, the scaled forms elsewhere; off: the scaled forms, as the
    // scalar kernel.
    bool floatFirst = true;
    // How the object code is emitted (FacetJit::Level): quick, optimized, or
    // tiered: a quick kernel first and the optimized one in the background.
    enum class Codegen { Tiered, Quick, Optimized } codegen = Codegen::Tiered;
    // assume=unit: the host promises finite directions with |w| within 1e-3
    // of 1 and finite inputs (and u in [0, 1) for the sampler). Compiled kernels then skip the work that only detects
    // invalid lanes (LoweringPlan::trustInputs): on such inputs the outputs
    // are bit-identical to the default's; batch calls return 0 and the
    // status array is all 0; other inputs give undefined values, but never
    // a crash or an out-of-bounds read. The interpreter always validates.
    bool assumeUnit = false;
    // transport=radiance|importance (SPEC 11): the transport of a refracting
    // lobe's f; radiance includes the 1/eta^2 of transmitted radiance.
    Transport transport = Transport::Radiance;

    // Parses the ';'-separated option string; returns an error message or "".
    static std::string parse(const std::string& spec, CompileOptions& out);
    std::string canonical() const;  // stable text, part of the cache key
};

// The lowering options of a kernel compiled with `options`: one entry point
// (scalar, or a batch of `width` lanes) and the math mode's variant. The one
// mapping from compile options to lowering options (compiles, `facet ir`,
// ahead-of-time builds and facet_compile_timing use it).
LoweringOptions loweringOptionsFor(const CompileOptions& options, const EnergyTable* energyTable, bool simd, int width);

// The scalar kernel; it returns 1 where the lane was invalid.
using ScalarStatusFn = int32_t (*)(const float*, const float*, const float*, float*);
// The batch kernel; the last argument is the optional per-lane status array.
using BatchKernelFn = int64_t (*)(int64_t, const float* const*, const float* const*, const float* const*,
                                  float* const*, uint8_t*);
// The sampler's entry points (Lowering.h, LoweredModule): scalar ones
// return 1 for an invalid lane, batch ones the number of invalid lanes.
using SampleScalarFn = int32_t (*)(const float*, const float*, const float*, float*, float*, float*);
using PdfScalarFn = int32_t (*)(const float*, const float*, const float*, float*);
using SampleBatchFn = int64_t (*)(int64_t, const float* const*, const float* const*, const float* const*,
                                  float* const*, float*, float* const*);
using PdfBatchFn = int64_t (*)(int64_t, const float* const*, const float* const*, const float* const*, float*);

class Kernel {
public:
    ~Kernel();
    const CheckedMaterial& material() const { return material_; }  // specialized
    Backend backend() const { return backend_; }
    int width() const { return width_; }
    int inputCount() const { return material_.slotCount; }
    const std::string& inputName(int slot) const { return slotNames_.at(slot); }
    // How this kernel was obtained: "compiled", "memory cache", "disk cache".
    const std::string& origin() const { return origin_; }
    // The math variant compiled ("exact", "fast", "fast+walter", ...), and for
    // tolerance builds the error measured when it was chosen (else < 0).
    const std::string& variant() const { return variant_; }
    // energy = kulla_conty: the E table the kernel was built with (null
    // otherwise); a reference Interpreter of material() should use it too.
    const std::shared_ptr<const EnergyTable>& energyTable() const { return energyTable_; }
    // The same per lobe (CheckedMaterial::lobes order; null for a lobe without
    // energy compensation): what a reference of a combination should use.
    const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables() const { return lobeEnergyTables_; }
    double measuredError() const { return measuredError_; }
    double compileMillis() const { return compileMillis_; }
    // The transport option (SPEC 11) the reference fallbacks evaluate with.
    Transport transport() const { return transport_; }
    // The code the entry points run now: "quick" or "optimized" (tiered
    // kernels change from the first to the second once), "interpreter".
    std::string codeTier() const;
    // Blocks until a tiered kernel runs its optimized code, or its tier-up
    // failed (then it keeps the quick code, which computes the same values,
    // and tierUpError() says why). Returns at once for other kernels.
    void waitOptimized() const;
    std::string tierUpError() const;
    // CPU time the tier-up thread spent on this kernel's optimized code
    // (lowering, optimization, emission, linking); 0 until it is done.
    double tierUpMillis() const;

    void eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]) const;
    // n lanes, SoA (facet.h). Returns the number of invalid lanes (their rgb
    // is 0), 0 for n = 0 and -1 for n < 0. `status`, when not null, receives
    // one byte per lane: 0 valid, 1 invalid (a non-finite or non-unit
    // direction, a non-finite input it reads, a model parameter not finite in float,
    // or a result float cannot hold) -- on every backend alike; compiled
    // kernels under assume=unit return 0 and a status of 0s.
    int64_t evalBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* const rgb[3], uint8_t* status = nullptr) const;

    // Importance sampling (SPEC 8; facet.h has the conventions). sample()
    // draws wi for wo from the uniform numbers u (u[0] picks the lobe, u[1]
    // and u[2] place the direction) and gives the mixture's pdf at wi and
    // weight = f (n.wi) / pdf; pdf() is that density for any wi. sample()
    // returns false and pdf() 0 for an invalid lane: a non-finite or
    // non-unit direction, u outside [0, 1), a non-finite input it reads, or a result
    // float cannot hold; its outputs are 0. With n.wo <= 0 there is no
    // sample (wi = 0, pdf = 0, weight = 0, a valid lane); a sample below
    // the horizon is valid with weight 0 and its pdf reported. A lobe that
    // scatters below the surface (SPEC 11) takes wo and wi on either side.
    bool sample(const float wo[3], const float u[3], const float* inputs, float wi[3], float* pdf,
                float weight[3]) const;
    float pdf(const float wi[3], const float wo[3], const float* inputs) const;
    // n lanes, SoA, as evalBatch: the number of invalid lanes, 0 for n = 0,
    // -1 for n < 0.
    int64_t sampleBatch(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                        float* const wi[3], float* pdf, float* const weight[3]) const;
    int64_t pdfBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                     float* pdf) const;
    // Which code samples: "jit" (the kernel's own sample/pdf entry points,
    // scalar or SIMD as eval), or "reference" (the interpreter's sampler in
    // double, lane by lane: interp kernels, materials whose NDF has no
    // sampler in IR, which `facet ir --plan` shows as sampling:
    // specular=none, and JIT kernels whose sampler failed, see
    // samplerError). A JIT kernel gets its sampler (optimized, with the
    // lowering options of its eval code: math variant, a tolerance search's
    // choice included, and width) on the first call of any sampling
    // function, this one included, so that eval-only hosts never pay for
    // it: from the caches of the Compiler that built the kernel, as eval's
    // object (same key plus a sampler component, same cache= option), or
    // compiled and stored there.
    std::string samplerTier() const;
    // How the sampler's code was obtained: "compiled", "memory cache" or
    // "disk cache"; "" where the reference samples. Gets the sampler first.
    std::string samplerOrigin() const;
    // Why a JIT kernel samples through the reference: its sampler did not
    // compile, link or resolve (an internal error, or a cached object that
    // is not what its key says); "" otherwise. Gets the sampler first; the
    // text lives as long as the kernel.
    const std::string& samplerError() const;

private:
    friend class Compiler;
    Kernel() = default;
    // Gets and links the sampler's entry points once (see samplerTier).
    void ensureSampler() const;
    // What ensureSampler() needs: the eval kernel's lowering options and
    // symbol prefix, the codegen level (quick only under codegen=quick: the
    // sampler is compiled once, so a tiered kernel's is optimized), the
    // sampler's cache entry, and the caches (shared with the Compiler, which
    // the kernel may outlive).
    LoweringOptions samplerLowering_;
    FacetJit::Level samplerLevel_ = FacetJit::Level::Optimized;
    std::string samplerPrefix_, samplerKey_, samplerCachePath_;
    CompileOptions::Cache samplerCache_ = CompileOptions::Cache::Off;
    std::shared_ptr<MemoryCache> memoryCache_;
    std::shared_ptr<CacheDirectory> diskCache_;
    CheckedMaterial material_;  // holds its expression trees by shared pointer
    Backend backend_ = Backend::Simd;
    int width_ = 1;
    std::vector<std::string> slotNames_;
    // Entry points and the dylibs behind them; shared with a pending tier-up
    // (null for interpreter kernels).
    std::shared_ptr<KernelCode> code_;
    std::string origin_;
    std::string variant_ = "reference";
    std::shared_ptr<const EnergyTable> energyTable_;
    // Per lobe (CheckedMaterial::lobes order; {energyTable_} for one lobe):
    // the tables the reference fallbacks evaluate the lobes with.
    std::vector<std::shared_ptr<const EnergyTable>> lobeEnergyTables_;
    // A compensated lobe over the whole sphere: its table from inside (the
    // sampler's lowering and the tier-up point to it).
    std::shared_ptr<const EnergyTable> energyTableInside_;
    double measuredError_ = -1;
    double compileMillis_ = 0;
    Transport transport_ = Transport::Radiance;  // of the reference fallbacks (SPEC 11)
};

// An ahead-of-time build of a material (`facet build`, Compiler::compileAot).
struct AotKernel {
    std::string output;        // object file, assembly, IR text or bitcode (AotOutput)
    CheckedMaterial material;  // specialized: its slots are the entry points' inputs
    std::string variant;       // the math variant compiled ("exact", "fast", ...)
    double measuredError = -1; // tolerance builds: the chosen variant's error on the host
    int width = 1;             // SIMD lanes (1: scalar kernel)
    // Whether the object has PREFIX_sample, _sample_batch, _pdf and
    // _pdf_batch: false where the plan has no compiled sampler for the NDF
    // (sampling: specular=none), which the JIT samples through the
    // interpreter and an object cannot.
    bool hasSampler = false;
};

class Compiler {
public:
    Compiler();
    ~Compiler();
    // Compiles material `name` (empty: the first) of the file. On a user
    // error returns null and fills diags.
    std::unique_ptr<Kernel> compileFile(const std::string& path, const std::string& name,
                                        const CompileOptions& options, DiagnosticEngine& diags);
    std::unique_ptr<Kernel> compileText(const std::string& text, const std::string& path, const std::string& name,
                                        const CompileOptions& options, DiagnosticEngine& diags);
    // Compiles an already checked material (bindings in options are applied).
    std::unique_ptr<Kernel> compileMaterial(const CheckedMaterial& material, const CompileOptions& options,
                                            DiagnosticEngine& diags);

    // The kernel `compileMaterial` would build with `options`, with its
    // sampler, lowered with `prefix` for `target` (Aot.h) and given the C
    // entry points PREFIX_eval / PREFIX_eval_batch and (where the material
    // has a compiled sampler) PREFIX_sample / _sample_batch / _pdf /
    // _pdf_batch: the same specialization, lowering,
    // middle end and codegen, so that on the host the object computes what
    // the JIT kernel computes. A tolerance is resolved on the host (the
    // variant search measures JIT kernels). `width`: the target's natural
    // SIMD width, used unless options.width is set. On a user error returns
    // nullopt and fills diags.
    std::optional<AotKernel> compileAot(const CheckedMaterial& material, const CompileOptions& options,
                                        llvm::TargetMachine& target, int width, const std::string& prefix,
                                        AotOutput output, DiagnosticEngine& diags);

    // What `facet ir` prints: the optimized IR; every stage (the checked and
    // specialized material, the lowering plan, the IR before and after
    // optimization); or only the lowering plan.
    enum class IrOutput { Optimized, Stages, Plan };
    std::string irText(const std::string& path, const std::string& name, const CompileOptions& options,
                       bool simd, IrOutput output, DiagnosticEngine& diags);

    // Blocks until every tier-up queued so far is done (its kernel switched,
    // the caches filled).
    void finishTierUps();

    FacetJit& jit() { return *jit_; }
    int resolveWidth(const CompileOptions& options) const;
    // The kernel objects' disk cache ("" = none); the tables stay in the
    // default root's tables/ directory. Call before compiling.
    void setCacheDir(std::string dir);
    const std::string& cacheDir() const;
    // The warning given when the disk cache was refused (CacheFiles.h), or "".
    std::string cacheWarning() const;
    // The Kulla-Conty and Lambda tables (memory + the default root's
    // tables/ on disk) and its events: what was loaded, built or rebuilt.
    const TableCache& tables() const { return *tables_; }

    // Runs the kernel pipeline (Pipeline.h) on this Compiler's JIT and
    // tables; for the timing tool and tests that look at its stages.
    bool runPipeline(PipelineRun& run, const PipelineControl& control, FacetJit::Level level, DiagnosticEngine& diags);

private:
    std::unique_ptr<Kernel> compile(PipelineRun& run, DiagnosticEngine& diags);
    std::string compileObject(const CheckedMaterial& material, const LoweringOptions& lowering,
                              const std::string& prefix, FacetJit::Level level);
    // Links `object` into a fresh dylib and installs its entry points in
    // `code` (replacing the ones there; the old dylib stays loaded).
    void link(KernelCode& code, const std::string& object, const std::string& prefix, const LoweringOptions& lowering);
    // The fastest variant meeting `tolerance`; its MathVariant in `chosen`.
    CachedKernel searchVariants(const CheckedMaterial& material, LoweringOptions lowering, double tolerance,
                                const std::string& prefix, FacetJit::Level level, MathVariant& chosen);
    // What the tier-up thread does for one kernel (see the top of this
    // file); defined in Compiler.cpp.
    struct TierUpJob;
    void tierUp(const TierUpJob& job, TierUpWorker::Run run);

    std::shared_ptr<FacetJit> jit_;
    std::shared_ptr<CacheDirectory> cache_;  // kernel objects; tables/ below it
    std::unique_ptr<TableCache> tables_;     // Kulla-Conty E and Lambda tables (memory + disk)
    std::shared_ptr<MemoryCache> memoryCache_;  // key -> compiled object (eval and sampler)
    // Its thread starts with the first tiered compile; the destructor stops
    // it first, because its running job uses everything above.
    std::unique_ptr<TierUpWorker> tierUpWorker_;
};

}  // namespace facet
