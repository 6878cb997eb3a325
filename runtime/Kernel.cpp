// Kernel: option parsing, the compile pipeline, kernel caches, evaluation.
#include "Kernel.h"
#include "Immortal.h"
#include "KernelCacheFile.h"

#include "CacheFiles.h"
#include "CodegenIdentity.h"
#include "Checker.h"
#include "Interpreter.h"
#include "Jit.h"
#include "KullaConty.h"
#include "Pipeline.h"
#include "ReferenceComparison.h"
#include "Sampling.h"
#include "TableCache.h"
#include "TierUp.h"

#include <llvm/Config/llvm-config.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/ADT/StringExtras.h>
#include <llvm/Support/SHA256.h>
#include <llvm/Support/raw_ostream.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <thread>
#include <random>
#include <set>
#include <unistd.h>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>

namespace facet {

const char* backendName(Backend b) {
    switch (b) {
        case Backend::Interp: return "interp";
        case Backend::Scalar: return "scalar";
        case Backend::Simd: return "simd";
    }
    return "?";
}

LoweringOptions loweringOptionsFor(const CompileOptions& options, const EnergyTable* energyTable, bool simd, int width) {
    LoweringOptions lowering;
    lowering.energyTable = energyTable;
    lowering.math = options.math;
    lowering.variant = options.math == MathMode::Fast ? MathVariant::fast() : MathVariant::exact();
    lowering.variant.floatFirst = options.floatFirst;
    lowering.trustInputs = options.assumeUnit;
    lowering.width = simd ? width : 4;
    lowering.emitScalar = !simd;
    lowering.emitBatch = simd;
    return lowering;
}

namespace {

std::optional<double> parseDouble(const std::string& s) {
    if (s.empty()) return std::nullopt;
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size()) return std::nullopt;
    return v;
}

double millisSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// Largest kernel cache file read; objects are tens of kilobytes.
constexpr uint64_t kMaxCacheFileBytes = uint64_t(256) << 20;

// Candidate variants for a tolerance, fastest first. The model
// substitutions only appear where they apply to the material.
std::vector<MathVariant> toleranceCandidates(const CheckedMaterial& m) {
    bool smithBeckmann = walterLambdaApplies(m);
    bool dielectric = schlickDielectricApplies(m);
    std::vector<MathVariant> out;
    for (bool walter : {true, false})
        for (bool schlick : {true, false}) {
            if ((walter && !smithBeckmann) || (schlick && !dielectric)) continue;
            MathVariant v = MathVariant::fast();
            v.walterLambda = walter;
            v.schlickDielectric = schlick;
            out.push_back(v);
        }
    out.push_back(MathVariant::exact());
    return out;
}

// The math variant a cached record names: the compile's own, or for a
// tolerance build one of the candidates the search tries (named as the
// search names them); nullopt for any other name (a record that is not
// this compile's: recompiled).
std::optional<MathVariant> cachedVariant(const CheckedMaterial& material, const MathVariant& variant, bool tolerance,
                                         const std::string& name) {
    if (!tolerance) return name == variant.name() ? std::optional<MathVariant>(variant) : std::nullopt;
    for (MathVariant v : toleranceCandidates(material))
        if (v.name() == name) {
            v.floatFirst = variant.floatFirst;
            return v;
        }
    return std::nullopt;
}

}  // namespace

// A Compiler's in-memory cache of compiled objects, eval kernels' and
// samplers'. Shared with the kernels it built: a kernel gets its sampler on
// first use, which may come after the Compiler is gone.
struct MemoryCache {
    std::mutex mutex;
    std::map<std::string, CachedKernel> objects;  // key -> record
};

namespace {

// The record cached under `key`: from memory (cache=on or memory), else
// from the disk file `cachePath` (cache=on; "" = no disk cache), which is
// then kept in memory too. `origin` says which ("memory cache", "disk
// cache"). A file that does not parse as this key's record (truncated,
// corrupted, another key) is a miss: the caller compiles and overwrites it.
std::optional<CachedKernel> lookUpCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key,
                                         const std::string& cachePath, CompileOptions::Cache cache,
                                         std::string& origin) {
    if (cache == CompileOptions::Cache::Off) return std::nullopt;
    {
        std::lock_guard<std::mutex> lock(memory.mutex);
        auto it = memory.objects.find(key);
        if (it != memory.objects.end()) {
            origin = "memory cache";
            return it->second;
        }
    }
    if (cache != CompileOptions::Cache::On || cachePath.empty()) return std::nullopt;
    std::optional<std::string> bytes = disk.read(cachePath, kMaxCacheFileBytes);
    std::optional<CachedKernel> record = bytes ? parseKernelCacheFile(*bytes, key) : std::nullopt;
    if (record) {
        origin = "disk cache";
        std::lock_guard<std::mutex> lock(memory.mutex);
        memory.objects.emplace(key, *record);
    }
    return record;
}

// Stores `record` in memory (cache=on or memory) and in the disk file
// `cachePath` (cache=on; "" = memory only). A cache that cannot be
// written is only slower.
void storeInCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key, const std::string& cachePath,
                   CompileOptions::Cache cache, const CachedKernel& record) {
    if (cache == CompileOptions::Cache::On && !cachePath.empty()) disk.write(cachePath, kernelCacheFileBytes(key, record));
    if (cache != CompileOptions::Cache::Off) {
        std::lock_guard<std::mutex> lock(memory.mutex);
        memory.objects.emplace(key, record);
    }
}

}  // namespace

double measureKernelError(const Kernel& kernel, const CheckedMaterial& material, size_t samples) {
    // Directions cosine-uniform over the hemisphere (where a renderer
    // evaluates), inputs uniform over their ranges; fixed seed so a
    // tolerance choice is reproducible.
    std::mt19937_64 rng(0x5eed);
    std::uniform_real_distribution<double> u(0, 1);
    LaneBatch batch;
    batch.slots.resize(size_t(material.slotCount));
    std::vector<double> laneSlots(size_t(material.slotCount));
    for (size_t i = 0; i < samples; ++i) {
        double w[2][3];
        for (auto& d : w) {
            double z = std::sqrt(u(rng)), phi = 2 * M_PI * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
            d[0] = r * std::cos(phi), d[1] = r * std::sin(phi), d[2] = z;
        }
        for (const CheckedInput& in : material.inputs)
            for (int c = 0; c < in.slotCount(); ++c) {
                double lo = in.hasRange ? in.lo : 0.0, hi = in.hasRange ? in.hi : 2 * in.defaultValue[c];
                laneSlots[size_t(in.firstSlot + c)] = lo + (hi - lo) * u(rng);
            }
        batch.push(w[0], w[1], laneSlots);
    }
    batch.finish();
    std::vector<float> out[3];
    for (auto& o : out) o.assign(samples, 0.0f);
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    kernel.evalBatch(int64_t(samples), batch.wi(), batch.wo(), batch.inputs(), rgb);
    const float* const written[3] = {rgb[0], rgb[1], rgb[2]};
    return compareWithReference(evaluateReference(material, batch, kernel.energyTable()), written).maxRel;
}

namespace {
}  // namespace

std::string CompileOptions::parse(const std::string& spec, CompileOptions& out) {
    auto trim = [](std::string t) {
        t.erase(0, t.find_first_not_of(" \t"));
        t.erase(t.find_last_not_of(" \t") + 1);
        return t;
    };
    std::set<std::string> seen;
    size_t start = 0;
    while (start <= spec.size()) {
        size_t end = spec.find(';', start);
        std::string item = spec.substr(start, end == std::string::npos ? std::string::npos : end - start);
        start = end == std::string::npos ? spec.size() + 1 : end + 1;
        // Blanks around items, keys and values are allowed: "backend = simd ; math=fast".
        item = trim(item);
        if (item.empty()) continue;
        size_t eq = item.find('=');
        if (eq == std::string::npos) return fmt::format("option '{}' is not key=value", item);
        std::string key = trim(item.substr(0, eq)), value = trim(item.substr(eq + 1));
        // A repeated option is a mistake either way it would be resolved.
        if (!seen.insert(key).second) return fmt::format("option '{}' is given twice", key);
        if (key == "backend") {
            if (value == "scalar") out.backend = Backend::Scalar;
            else if (value == "simd") out.backend = Backend::Simd;
            else if (value == "interp") out.backend = Backend::Interp;
            else return fmt::format("backend '{}' is not scalar, simd or interp", value);
        } else if (key == "math") {
            if (value == "exact") out.math = MathMode::Exact;
            else if (value == "fast") out.math = MathMode::Fast;
            else return fmt::format("math '{}' is not exact or fast", value);
        } else if (key == "tolerance") {
            auto v = parseDouble(value);
            if (!v || !(*v > 0) || !std::isfinite(*v)) return fmt::format("tolerance '{}' is not a positive number", value);
            out.tolerance = *v;
        } else if (key == "width") {
            if (value == "4" || value == "8" || value == "16") out.width = std::stoi(value);
            else return fmt::format("width '{}' is not 4, 8 or 16", value);
        } else if (key == "float_first") {
            if (value == "on") out.floatFirst = true;
            else if (value == "off") out.floatFirst = false;
            else return fmt::format("float_first '{}' is not on or off", value);
        } else if (key == "assume") {
            if (value == "unit") out.assumeUnit = true;
            else if (value == "none") out.assumeUnit = false;
            else return fmt::format("assume '{}' is not unit or none", value);
        } else if (key == "codegen") {
            if (value == "tiered") out.codegen = Codegen::Tiered;
            else if (value == "quick") out.codegen = Codegen::Quick;
            else if (value == "optimized") out.codegen = Codegen::Optimized;
            else return fmt::format("codegen '{}' is not tiered, quick or optimized", value);
        } else if (key == "cache") {
            if (value == "on") out.cache = Cache::On;
            else if (value == "off") out.cache = Cache::Off;
            else if (value == "memory") out.cache = Cache::Memory;
            else return fmt::format("cache '{}' is not on, off or memory", value);
        } else if (key.rfind("set.", 0) == 0 && key.size() > 4) {
            std::vector<double> values;
            size_t p = 0;
            while (p <= value.size()) {
                size_t comma = value.find(',', p);
                std::string field = value.substr(p, comma == std::string::npos ? std::string::npos : comma - p);
                auto v = parseDouble(field);
                if (!v || !std::isfinite(*v)) return fmt::format("{}: '{}' is not a finite number", key, field);
                values.push_back(*v);
                p = comma == std::string::npos ? value.size() + 1 : comma + 1;
            }
            if (values.size() != 1 && values.size() != 3)
                return fmt::format("{}: expected one value or three (r,g,b)", key);
            out.bindings[key.substr(4)] = values;
        } else {
            return fmt::format("unknown option '{}' (known: backend, math, tolerance, width, cache, float_first, codegen, assume, set.NAME)", key);
        }
    }
    return "";
}

std::string CompileOptions::canonical() const {
    std::string s = fmt::format("backend={};math={};width={}", backendName(backend), mathModeName(math), width);
    if (tolerance) s += fmt::format(";tolerance={}", *tolerance);
    if (!floatFirst) s += ";float_first=off";
    if (assumeUnit) s += ";assume=unit";
    if (codegen == Codegen::Quick) s += ";codegen=quick";
    for (const auto& [name, values] : bindings) {
        s += ";set." + name + "=";
        for (size_t i = 0; i < values.size(); ++i) s += fmt::format("{}{}", i ? "," : "", values[i]);
    }
    return s;
}

// A compiled kernel's entry points and the dylibs that hold their code. The
// entry points are atomics because a tier-up replaces them while other
// threads may be evaluating; every dylib stays loaded until the last owner
// (the Kernel, or a tier-up still running) lets go.
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

    ~KernelCode() {
        for (llvm::orc::JITDylib* d : dylibs) jit->release(*d);
    }
    // Ends a pending tier-up: optimized unless `error` says why not.
    void settle(std::string error, double millis) {
        std::lock_guard<std::mutex> lock(mutex);
        optimized = error.empty();
        tierUpError = std::move(error);
        tierUpMillis = millis;
        tierUpPending = false;
        settled.notify_all();
    }
};

Kernel::~Kernel() = default;

std::string Kernel::codeTier() const {
    if (!code_) return "interpreter";
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->optimized ? "optimized" : "quick";
}

void Kernel::waitOptimized() const {
    if (!code_) return;
    std::unique_lock<std::mutex> lock(code_->mutex);
    code_->settled.wait(lock, [this] { return !code_->tierUpPending; });
}

std::string Kernel::tierUpError() const {
    if (!code_) return "";
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->tierUpError;
}

double Kernel::tierUpMillis() const {
    if (!code_) return 0;
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->tierUpMillis;
}

void Kernel::eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]) const {
    if (ScalarStatusFn scalar = code_ ? code_->scalarStatus.load(std::memory_order_acquire) : nullptr) {
        scalar(wi, wo, inputs, rgb);
        return;
    }
    // A SIMD kernel evaluates one lane through its batch entry. The column
    // pointers of the lane's inputs live on the stack for the usual slot
    // counts: a heap allocation would cost a sizeable part of the call.
    const float* const wiP[3] = {&wi[0], &wi[1], &wi[2]};
    const float* const woP[3] = {&wo[0], &wo[1], &wo[2]};
    constexpr int kStackSlots = 32;
    const int slots = inputCount();
    const float* few[kStackSlots];
    std::vector<const float*> many(inputs && slots > kStackSlots ? size_t(slots) : 0);
    const float** in = slots > kStackSlots ? many.data() : few;
    if (inputs)
        for (int s = 0; s < slots; ++s) in[s] = &inputs[s];
    float* const out[3] = {&rgb[0], &rgb[1], &rgb[2]};
    evalBatch(1, wiP, woP, inputs ? in : nullptr, out);
}

int64_t Kernel::evalBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                          float* const rgb[3], uint8_t* status) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    if (BatchKernelFn batch = code_ ? code_->batch.load(std::memory_order_acquire) : nullptr)
        return batch(n, wi, wo, inputs, rgb, status);
    ScalarStatusFn scalarStatus = code_ ? code_->scalarStatus.load(std::memory_order_acquire) : nullptr;
    // Scalar and interpreter kernels: one lane at a time, same conventions.
    int64_t invalid = 0;
    int slots = inputCount();
    std::vector<double> defaults = material_.defaultSlots();
    std::vector<float> laneInputs(std::max(1, slots));
    std::vector<double> laneSlots(std::max(1, slots));
    std::optional<Interpreter<double>> interp;
    if (!scalarStatus) interp.emplace(material_, energyTable_);
    for (int64_t i = 0; i < n; ++i) {
        for (int s = 0; s < slots; ++s) {
            laneSlots[s] = inputs && inputs[s] ? double(inputs[s][i]) : defaults[s];
            laneInputs[s] = float(laneSlots[s]);
        }
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, out[3];
        bool bad;
        if (scalarStatus) {
            bad = scalarStatus(a, b, laneInputs.data(), out) != 0;
        } else {
            double da[3] = {a[0], a[1], a[2]}, db[3] = {b[0], b[1], b[2]};
            EvalResult<double> r = interp->eval(da, db, laneSlots.data());
            bad = !r.valid;
            // As the compiled kernels: a result float cannot hold is an
            // invalid lane, never Inf.
            for (int c = 0; c < 3; ++c) {
                out[c] = float(r.rgb[c]);
                bad |= !std::isfinite(out[c]);
            }
            if (bad) out[0] = out[1] = out[2] = 0.0f;
        }
        invalid += bad;
        if (status) status[i] = uint8_t(bad);
        for (int c = 0; c < 3; ++c) rgb[c][i] = out[c];
    }
    return invalid;
}

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
            if (plannedSpecularSampling(material_) == SpecularSampling::None) return;
            std::optional<CachedKernel> cached =
                lookUpCaches(*memoryCache_, *diskCache_, samplerKey_, samplerCachePath_, samplerCache_, origin);
            if (!cached) {
                PipelineRun run = PipelineRun::fromSpecialized(material_, energyTable_);
                PipelineControl control;
                control.symbolPrefix = samplerPrefix_;
                control.lowering = lowering;
                PipelineTarget target;
                target.jit = code.jit.get();
                target.level = samplerLevel_;
                target.naturalWidth = code.jit->hostVectorWidth();
                TableCache tables("");  // unused: the run starts specialized, with its table
                DiagnosticEngine diags;
                if (!runKernelPipeline(run, control, target, tables, diags)) {
                    std::string text = diags.str();
                    while (!text.empty() && text.back() == '\n') text.pop_back();
                    fail(text.empty() ? "its pipeline stopped without a diagnostic" : text);
                    return;
                }
                cached = CachedKernel{std::move(run.object), lowering.variant.name(), -1.0};
                origin = "compiled";
                storeInCaches(*memoryCache_, *diskCache_, samplerKey_, samplerCachePath_, samplerCache_, *cached);
            }
            llvm::orc::JITDylib& dylib =
                code.jit->addObject(llvm::MemoryBuffer::getMemBufferCopy(cached->object, samplerPrefix_ + ".sampler"));
            {
                std::lock_guard<std::mutex> lock(code.mutex);
                code.dylibs.push_back(&dylib);
            }
            const std::string& p = samplerPrefix_;
            if (lowering.emitScalar) {
                code.sampleScalar.store(reinterpret_cast<SampleScalarFn>(code.jit->lookup(dylib, p + "_sample_scalar")),
                                        std::memory_order_release);
                code.pdfScalar.store(reinterpret_cast<PdfScalarFn>(code.jit->lookup(dylib, p + "_pdf_scalar")),
                                     std::memory_order_release);
            }
            if (lowering.emitBatch) {
                code.sampleBatch.store(reinterpret_cast<SampleBatchFn>(code.jit->lookup(dylib, p + "_sample_batch")),
                                       std::memory_order_release);
                code.pdfBatch.store(reinterpret_cast<PdfBatchFn>(code.jit->lookup(dylib, p + "_pdf_batch")),
                                    std::memory_order_release);
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
    bool jit = code_ && (code_->sampleScalar.load(std::memory_order_acquire) ||
                         code_->sampleBatch.load(std::memory_order_acquire));
    return jit ? "jit" : "reference";
}

namespace {

// Calls laneFn(i, slots, floatSlots) for each of n lanes, with the lane's
// inputs as evalBatch reads them (the caller's value, or the slot's default
// where inputs or inputs[s] is NULL) in double and in float; returns how
// many lanes it reported invalid.
template <typename LaneFn>
int64_t forEachLane(const CheckedMaterial& material, int64_t n, const float* const* inputs, LaneFn laneFn) {
    const int slots = material.slotCount;
    std::vector<double> defaults = material.defaultSlots(), lane(std::max(1, slots));
    std::vector<float> laneF(std::max(1, slots));
    int64_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        for (int s = 0; s < slots; ++s) {
            lane[s] = inputs && inputs[s] ? double(inputs[s][i]) : defaults[s];
            laneF[s] = float(lane[s]);
        }
        invalid += laneFn(i, lane.data(), laneF.data()) ? 0 : 1;
    }
    return invalid;
}

}  // namespace

bool Kernel::sample(const float wo[3], const float u[3], const float* inputs, float wi[3], float* pdf,
                    float weight[3]) const {
    ensureSampler();
    if (SampleScalarFn fn = code_ ? code_->sampleScalar.load(std::memory_order_acquire) : nullptr)
        return fn(wo, u, inputs, wi, pdf, weight) == 0;
    // One lane through the batch entry (or the reference).
    const float* const woP[3] = {&wo[0], &wo[1], &wo[2]};
    const float* const uP[3] = {&u[0], &u[1], &u[2]};
    std::vector<const float*> in;
    if (inputs)
        for (int s = 0; s < inputCount(); ++s) in.push_back(&inputs[s]);
    float* const wiP[3] = {&wi[0], &wi[1], &wi[2]};
    float* const weightP[3] = {&weight[0], &weight[1], &weight[2]};
    return sampleBatch(1, woP, uP, inputs ? in.data() : nullptr, wiP, pdf, weightP) == 0;
}

float Kernel::pdf(const float wi[3], const float wo[3], const float* inputs) const {
    ensureSampler();
    float out = 0;
    if (PdfScalarFn fn = code_ ? code_->pdfScalar.load(std::memory_order_acquire) : nullptr) {
        fn(wi, wo, inputs, &out);
        return out;
    }
    const float* const wiP[3] = {&wi[0], &wi[1], &wi[2]};
    const float* const woP[3] = {&wo[0], &wo[1], &wo[2]};
    std::vector<const float*> in;
    if (inputs)
        for (int s = 0; s < inputCount(); ++s) in.push_back(&inputs[s]);
    pdfBatch(1, wiP, woP, inputs ? in.data() : nullptr, &out);
    return out;
}

int64_t Kernel::sampleBatch(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                            float* const wi[3], float* pdf, float* const weight[3]) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    ensureSampler();
    if (SampleBatchFn fn = code_ ? code_->sampleBatch.load(std::memory_order_acquire) : nullptr)
        return fn(n, wo, u, inputs, wi, pdf, weight);
    SampleScalarFn scalar = code_ ? code_->sampleScalar.load(std::memory_order_acquire) : nullptr;
    std::optional<Interpreter<double>> interp;
    if (!scalar) interp.emplace(material_, energyTable_);
    return forEachLane(material_, n, inputs, [&](int64_t i, const double* lane, const float* laneF) {
        float o[3] = {wo[0][i], wo[1][i], wo[2][i]}, uu[3] = {u[0][i], u[1][i], u[2][i]};
        float w[3] = {0, 0, 0}, p = 0, wt[3] = {0, 0, 0};
        bool bad;
        if (scalar) {
            bad = scalar(o, uu, laneF, w, &p, wt) != 0;
        } else {
            double od[3] = {o[0], o[1], o[2]}, ud[3] = {uu[0], uu[1], uu[2]};
            SampleResult<double> r = interp->sample(od, ud, lane);
            w[0] = float(r.wi.x), w[1] = float(r.wi.y), w[2] = float(r.wi.z);
            p = float(r.pdf);
            // As the compiled samplers: a density that underflows float is
            // no density a renderer can divide by, so pdf 0 means weight 0.
            for (int c = 0; c < 3; ++c) wt[c] = p > 0 ? float(r.weight[c]) : 0.0f;
            // As the compiled kernels: a result float cannot hold is an invalid lane.
            bad = !r.valid || !std::isfinite(p) || !std::isfinite(wt[0]) || !std::isfinite(wt[1]) ||
                  !std::isfinite(wt[2]);
            if (bad) w[0] = w[1] = w[2] = p = wt[0] = wt[1] = wt[2] = 0.0f;
        }
        for (int c = 0; c < 3; ++c) wi[c][i] = w[c], weight[c][i] = wt[c];
        pdf[i] = p;
        return !bad;
    });
}

int64_t Kernel::pdfBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                         float* pdf) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    ensureSampler();
    if (PdfBatchFn fn = code_ ? code_->pdfBatch.load(std::memory_order_acquire) : nullptr)
        return fn(n, wi, wo, inputs, pdf);
    PdfScalarFn scalar = code_ ? code_->pdfScalar.load(std::memory_order_acquire) : nullptr;
    std::optional<Interpreter<double>> interp;
    if (!scalar) interp.emplace(material_, energyTable_);
    return forEachLane(material_, n, inputs, [&](int64_t i, const double* lane, const float* laneF) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, p = 0;
        bool bad;
        if (scalar) {
            bad = scalar(a, b, laneF, &p) != 0;
        } else {
            double ad[3] = {a[0], a[1], a[2]}, bd[3] = {b[0], b[1], b[2]};
            PdfResult<double> r = interp->pdf(ad, bd, lane);
            p = float(r.pdf);
            bad = !r.valid || !std::isfinite(p);
            if (bad) p = 0;
        }
        pdf[i] = p;
        return !bad;
    });
}

Compiler::Compiler()
    : jit_(FacetJit::Create()),
      cache_(std::make_shared<CacheDirectory>(defaultCacheRoot())),
      tables_(std::make_unique<TableCache>(cache_, "tables")),
      memoryCache_(std::make_shared<MemoryCache>()),
      tierUpWorker_(std::make_unique<TierUpWorker>()) {}
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

PipelineTarget Compiler::jitTarget(FacetJit::Level level) const {
    PipelineTarget target;
    target.jit = jit_.get();
    target.level = level;
    target.naturalWidth = jit_->hostVectorWidth();
    return target;
}

bool Compiler::runPipeline(PipelineRun& run, const PipelineControl& control, FacetJit::Level level,
                           DiagnosticEngine& diags) {
    return runKernelPipeline(run, control, jitTarget(level), *tables_, diags);
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
    kernel->energyTable_ = run.energyTable;
    for (int s = 0; s < kernel->material_.slotCount; ++s) kernel->slotNames_.push_back(kernel->material_.slotName(s));
    if (options.backend == Backend::Interp) {
        kernel->origin_ = "interpreter";
        kernel->compileMillis_ = millisSince(start);
        return kernel;
    }
    kernel->width_ = run.simd ? run.lowering.width : 1;
    LoweringOptions lowering = run.lowering;

    // The cache key: what the kernel computes (the specialized material,
    // printed), how (options incl. tolerance, width), and with what (LLVM,
    // CPU, code generator (CodegenIdentity.h) and optimization pipeline).
    std::string tableId = kernel->energyTable_ ? fmt::format("{}/v{}/{}", kernel->energyTable_->key.name(),
                                                             kEnergyTableVersion, kernel->energyTable_->quadrature.describe())
                                               : "";
    std::string keyText = fmt::format("{}|{}|w{}|{}|{}|{}|{}|{}|{}", printMaterial(kernel->material_),
                                      options.canonical(), lowering.width, LLVM_VERSION_STRING, jit_->cpuName(),
                                      jit_->cpuFeatures(), codegenIdentity(kernel->material_), FacetJit::kPipelineId, tableId);
    auto digest = llvm::SHA256::hash(llvm::arrayRefFromStringRef(keyText));
    std::string key = llvm::toHex(digest, true);
    std::string prefix = "facet_" + key.substr(0, 16);
    std::shared_ptr<CacheDirectory> disk = cache_;
    std::string cachePath = disk->usable() ? key + ".fko" : "";  // relative to the cache root

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
    // The sampler's key: the kernel's, the sampler, and the variant its
    // eval code was compiled with.
    kernel->samplerKey_ = llvm::toHex(
        llvm::SHA256::hash(llvm::arrayRefFromStringRef(keyText + "|sampler|" + lowering.variant.name())), true);
    kernel->samplerCachePath_ = cachePath.empty() ? "" : kernel->samplerKey_ + ".fko";
    kernel->samplerCache_ = options.cache;
    kernel->memoryCache_ = memoryCache_;
    kernel->diskCache_ = disk;
    kernel->variant_ = cached->variant;
    kernel->measuredError_ = cached->measuredError;
    if (tiered) {
        kernel->code_->tierUpPending = true;
        // The record without the quick object: the tier-up stores its own.
        auto job = std::make_shared<TierUpJob>(TierUpJob{kernel->code_, kernel->material_, kernel->energyTable_,
                                                         lowering, prefix, key, cachePath, options.cache,
                                                         CachedKernel{"", cached->variant, cached->measuredError}});
        tierUpWorker_->post([this, job](TierUpWorker::Run run) { tierUp(*job, run); });
    }
    kernel->compileMillis_ = millisSince(start);
    return kernel;
}

namespace {
double threadCpuMillis() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}
}  // namespace

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
    llvm::orc::JITDylib& dylib = jit_->addObject(llvm::MemoryBuffer::getMemBufferCopy(object, prefix));
    {
        std::lock_guard<std::mutex> lock(code.mutex);
        code.dylibs.push_back(&dylib);
    }
    if (lowering.emitScalar)
        code.scalarStatus.store(reinterpret_cast<ScalarStatusFn>(jit_->lookup(dylib, prefix + "_scalar_status")),
                                std::memory_order_release);
    if (lowering.emitBatch)
        code.batch.store(reinterpret_cast<BatchKernelFn>(jit_->lookup(dylib, prefix + "_batch")),
                         std::memory_order_release);

}

CachedKernel Compiler::searchVariants(const CheckedMaterial& material, LoweringOptions lowering, double tolerance,
                                      const std::string& prefix, FacetJit::Level level, MathVariant& chosen) {
    const bool floatFirst = lowering.variant.floatFirst;
    // Fastest first; the first whose measured error meets the tolerance wins.
    // Exact is always last: if even it does not meet the tolerance, it is
    // returned with its (larger) measured error for the caller to report.
    CachedKernel best;
    for (const MathVariant& v : toleranceCandidates(material)) {
        lowering.variant = v;
        lowering.variant.floatFirst = floatFirst;
        // Both codegen levels compute the same bits, so a quick candidate
        // measures the error of its optimized code too.
        CachedKernel candidate{compileObject(material, lowering, prefix, level), v.name(), 0.0};
        Kernel probe;
        probe.material_ = material;
        if (lowering.energyTable) probe.energyTable_ = tables_->getFor(material);
        probe.backend_ = lowering.emitBatch ? Backend::Simd : Backend::Scalar;
        probe.code_ = std::make_shared<KernelCode>();
        probe.code_->jit = jit_;
        link(*probe.code_, candidate.object, prefix, lowering);
        candidate.measuredError = measureKernelError(probe, material);
        best = std::move(candidate);
        chosen = lowering.variant;
        if (best.measuredError <= tolerance) break;
    }
    return best;
}

std::optional<AotKernel> Compiler::compileAot(const CheckedMaterial& material, const CompileOptions& options,
                                              llvm::TargetMachine& target, int width, const std::string& prefix,
                                              AotOutput output, DiagnosticEngine& diags) {
    internal_assert(options.backend != Backend::Interp) << "an ahead-of-time build needs a compiled backend";
    PipelineTarget aotTarget;
    aotTarget.machine = &target;
    aotTarget.aotOutput = output;
    aotTarget.naturalWidth = width;
    PipelineRun run = PipelineRun::fromChecked(material, options);
    PipelineControl control;
    control.symbolPrefix = prefix;
    control.aotEntryPoints = true;
    control.stopAfter = PipelineStage::Planned;
    if (!runKernelPipeline(run, control, aotTarget, *tables_, diags)) return std::nullopt;
    AotKernel aot;
    aot.material = run.specialized;
    aot.width = run.simd ? run.lowering.width : 1;
    aot.variant = run.lowering.variant.name();
    // The eval kernel's lowering with the sampler's entry points in the same
    // module: lowering and the middle end work function by function, so
    // they are the code the JIT kernel compiles in a module of its own.
    LoweringOptions lowering = run.lowering;
    lowering.emitSampling = true;
    if (options.tolerance) {
        // The variant compileMaterial chooses for the host: the same search,
        // measuring JIT kernels of the host's width against the interpreter.
        LoweringOptions host = loweringOptionsFor(options, run.energyTable.get(), run.simd, resolveWidth(options));
        MathVariant chosen = host.variant;
        CachedKernel probe = searchVariants(run.specialized, host, *options.tolerance, "facet_aot_probe",
                                            FacetJit::Level::Quick, chosen);
        lowering.variant = chosen;
        aot.variant = probe.variant;
        aot.measuredError = probe.measuredError;
    }
    run.rewindTo(PipelineStage::Specialized);
    control.lowering = lowering;
    control.stopAfter = PipelineStage::Emitted;
    if (!runKernelPipeline(run, control, aotTarget, *tables_, diags)) return std::nullopt;
    aot.output = std::move(run.object);
    aot.hasSampler = !run.lowered.sampleScalarSymbol.empty() || !run.lowered.sampleBatchSymbol.empty();
    return aot;
}

std::string Compiler::irText(const std::string& path, const std::string& name, const CompileOptions& options,
                             bool simd, IrOutput output, DiagnosticEngine& diags) {
    PipelineRun run = PipelineRun::fromFile(path, name, options);
    run.simd = simd;
    PipelineControl control;
    control.stopAfter = output == IrOutput::Plan ? PipelineStage::Planned : PipelineStage::Optimized;
    std::string out;
    if (output == IrOutput::Stages) {
        control.afterStage = [&](PipelineStage stage, const PipelineRun& r) {
            std::string text = pipelineStageText(stage, r);
            switch (stage) {
                case PipelineStage::Checked: out += "; ==== stage 1: checked material\n"; break;
                case PipelineStage::Specialized:
                    out += fmt::format("; ==== stage 2: specialized material ({} inputs bound)\n",
                                       r.options.bindings.size());
                    break;
                case PipelineStage::Planned:
                    out += "; ==== stage 3: lowering plan\n";
                    // As IR comments, so that the whole dump stays one IR-like text.
                    for (size_t start = 0; start < text.size();) {
                        size_t end = text.find('\n', start);
                        out += "; " + text.substr(start, end - start) + "\n";
                        start = end == std::string::npos ? text.size() : end + 1;
                    }
                    return;
                case PipelineStage::Lowered: out += "; ==== stage 4: lowered IR (verified, unoptimized)\n"; break;
                case PipelineStage::Optimized: out += "; ==== stage 5: optimized IR\n"; break;
                default: return;
            }
            out += text;
        };
    }
    if (!runPipeline(run, control, FacetJit::Level::Optimized, diags)) return "";
    if (output == IrOutput::Plan) return pipelineStageText(PipelineStage::Planned, run);
    if (output == IrOutput::Optimized) return pipelineStageText(PipelineStage::Optimized, run);
    return out;
}

}  // namespace facet
