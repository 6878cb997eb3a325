// BenchRunner: timing, compile timing and error measurement (see BenchRunner.h).
#include "BenchRunner.h"

#include "Checker.h"
#include "CompileStack.h"
#include "ReferenceComparison.h"
#include "Jit.h"
#include "Kernel.h"
#include "ReferenceModels.h"

#include "KullaConty.h"
#include "LambdaTable.h"
#include "TableCache.h"
#include "WalkComparison.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <thread>

namespace facet::bench {

BenchSettings BenchSettings::quickSettings() {
    BenchSettings s;
    s.lanes = 8192;
    s.interpLanes = 256;
    s.runs = 5;
    s.warmup = 1;
    s.compileRuns = 2;
    s.diskRuns = 1;
    s.quick = true;
    return s;
}

const BenchRow* MaterialBench::find(const std::string& backend, const std::string& mode) const {
    for (const BenchRow& r : rows)
        if (r.backend == backend && r.mode == mode) return &r;
    return nullptr;
}

std::string ErrorStats::Worst::str() const {
    if (!present) return "-";
    static const char* channels = "rgb";
    std::string in;
    for (const auto& [name, value] : inputs) in += fmt::format(" {}={:.9g}", name, value);
    return fmt::format("rel {:.3g} ch {} wi=({:.9g},{:.9g},{:.9g}) wo=({:.9g},{:.9g},{:.9g}){} got {:.9g} want {:.17g}",
                       rel, channels[channel], wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], in, got, want);
}

namespace {

// Every time here is the CPU time of this thread (CLOCK_THREAD_CPUTIME_ID),
// with the compile-stack threads it waits for counted as its own
// (callerCpuNanos, CompileStack.h: LLVM's stages run there): on a shared
// machine a wall clock also counts the time slices other processes take,
// which turns long runs into noise. On an idle machine the two agree.
struct Clock {
    using time_point = double;  // ns
    static double now() { return callerCpuNanos(); }
};

double millisSince(Clock::time_point start) { return (Clock::now() - start) * 1e-6; }
double nanosSince(Clock::time_point start) { return Clock::now() - start; }

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Output columns of one evaluation.
struct Output {
    std::vector<float> c[3];
    float* ptr[3] = {};
    int64_t invalid = 0;
    explicit Output(size_t n) {
        for (int k = 0; k < 3; ++k) {
            c[k].assign(n, -1.0f);  // -1: a lane the evaluator did not write shows up as an error
            ptr[k] = c[k].data();
        }
    }
};

// The error of one evaluation against the reference (ReferenceComparison.h),
// with the lane data of the worst value for the report.
ErrorStats compare(const CheckedMaterial& m, const LaneBatch& s, const ReferenceValues& ref, const Output& out) {
    const float* const rgb[3] = {out.c[0].data(), out.c[1].data(), out.c[2].data()};
    ReferenceComparison cmp = compareWithReference(ref, rgb);
    ErrorStats st;
    st.values = cmp.values;
    st.skipped = cmp.skipped;
    st.nonFinite = cmp.nonFinite;
    st.negative = cmp.negative;
    st.invalidLanes = out.invalid;
    st.referenceInvalid = int64_t(std::count(ref.valid.begin(), ref.valid.end(), 0));
    st.maxRel = cmp.maxRel;
    st.p999Rel = cmp.quantile(0.999);
    st.maxUlp = cmp.maxUlp;
    if (cmp.worst.present) {
        ErrorStats::Worst& w = st.worst;
        size_t i = cmp.worst.lane;
        w.present = true;
        w.lane = i;
        w.channel = cmp.worst.channel;
        for (int d = 0; d < 3; ++d) w.wi[d] = s.dir[d][i], w.wo[d] = s.dir[3 + d][i];
        for (int k = 0; k < m.slotCount; ++k) w.inputs.push_back({m.slotName(k), s.slots[k][i]});
        w.got = cmp.worst.got, w.want = cmp.worst.want, w.rel = cmp.worst.rel;
    }
    return st;
}

// Median and minimum ns per lane of `runs` calls of f (one whole batch of
// n lanes each) after `warmup` calls.
template <typename F>
std::pair<double, double> timeBatches(int warmup, int runs, size_t n, F&& f) {
    for (int i = 0; i < warmup; ++i) f();
    std::vector<double> t;
    for (int i = 0; i < runs; ++i) {
        auto start = Clock::now();
        f();
        t.push_back(nanosSince(start) / double(n));
    }
    return {median(t), *std::min_element(t.begin(), t.end())};
}

// The same for evaluators called lane by lane (scalar entry, interpreter):
// nothing is amortized over a batch, so each run is timed in chunks of
// `chunk` lanes (well under a scheduler time slice) and the median is over
// all chunks of all runs: a time slice lost to another process then spoils
// one chunk, not a whole run. f(begin, end) evaluates lanes [begin, end).
template <typename F>
std::pair<double, double> timeChunks(int warmup, int runs, size_t n, size_t chunk, F&& f) {
    for (int i = 0; i < warmup; ++i) f(size_t(0), n);
    std::vector<double> t;
    for (int i = 0; i < runs; ++i)
        for (size_t begin = 0; begin < n; begin += chunk) {
            size_t end = std::min(n, begin + chunk);
            auto start = Clock::now();
            f(begin, end);
            t.push_back(nanosSince(start) / double(end - begin));
        }
    return {median(t), *std::min_element(t.begin(), t.end())};
}

// The scalar entry point of the SPEC, called once per lane as a renderer
// would call it (inputs gathered per lane from the SoA columns).
void evalScalarLanes(const Kernel& k, const LaneBatch& s, size_t begin, size_t end, Output& out) {
    int slots = k.inputCount();
    float in[64];  // more slots than this take the vector below
    std::vector<float> many(slots > 64 ? slots : 0);
    float* inputs = slots > 64 ? many.data() : in;
    const float* const* wi = s.wi();
    const float* const* wo = s.wo();
    const float* const* columns = s.inputs();
    for (size_t i = begin; i < end; ++i) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, o[3];
        for (int j = 0; j < slots; ++j) inputs[j] = columns[j][i];
        k.eval(a, b, inputs, o);
        out.ptr[0][i] = o[0], out.ptr[1][i] = o[1], out.ptr[2][i] = o[2];
    }
}

// Kernel::evalBatch on lanes [begin, end) of a sample. The input pointers
// live on the stack up to 64 slots: the batch-size table times this per
// call, and a heap allocation would cost more than a short batch.
int64_t evalBatchRange(const Kernel& k, const LaneBatch& s, size_t begin, size_t end, Output& out) {
    const float* wi[3] = {s.wi()[0] + begin, s.wi()[1] + begin, s.wi()[2] + begin};
    const float* wo[3] = {s.wo()[0] + begin, s.wo()[1] + begin, s.wo()[2] + begin};
    const size_t slots = s.slots.size();
    std::array<const float*, 64> few;
    std::vector<const float*> many(slots > few.size() ? slots : 0);
    const float** in = slots > few.size() ? many.data() : few.data();
    for (size_t j = 0; j < slots; ++j) in[j] = s.inputs()[j] + begin;
    float* rgb[3] = {out.ptr[0] + begin, out.ptr[1] + begin, out.ptr[2] + begin};
    return k.evalBatch(int64_t(end - begin), wi, wo, slots ? in : nullptr, rgb);
}

struct Mode {
    const char* name;     // row label
    const char* options;  // CompileOptions fragment
};
const Mode kModes[] = {{"exact", "math=exact"}, {"fast", "math=fast"}, {"tol 1e-3", "tolerance=1e-3"},
                       {"tol 1e-5", "tolerance=1e-5"}};
const char* const kBackends[] = {"interp", "scalar", "simd"};
// Chunk sizes of the lane-by-lane timings (about 0.2-0.5 ms each).
constexpr size_t kScalarChunk = 4096, kInterpChunk = 256;

// A private, empty kernel cache directory for the bench of one file (its
// compiles write there, and the disk-hit measurement reads it); removed when
// that bench ends.
struct TempDir {
    std::string path;
    TempDir() {
        std::random_device rd;
        for (int attempt = 0; attempt < 100 && path.empty(); ++attempt) {
            auto p = std::filesystem::temp_directory_path() / fmt::format("facet-bench-{:016x}", uint64_t(rd()) << 32 | rd());
            std::error_code ec;
            if (std::filesystem::create_directory(p, ec)) path = p.string();
        }
    }
    ~TempDir() {
        std::error_code ec;
        if (!path.empty()) std::filesystem::remove_all(path, ec);
    }
};

class MaterialRunner {
public:
    // `compiler` keeps its kernels in `kernelDir` (empty: memory only).
    MaterialRunner(const CheckedMaterial& m, const BenchSettings& settings, Compiler& compiler,
                   std::string kernelDir, std::FILE* progress)
        : m_(m), settings_(settings), compiler_(compiler), kernelDir_(std::move(kernelDir)), progress_(progress) {}

    void run(MaterialBench& mb) {
        regular_ = regularSample(m_, settings_.lanes, settings_.seed);
        hard_ = hardCaseSample(m_);
        mb.regularLanes = regular_.size();
        mb.hardLanes = hard_.size();
        // The reference with the energy tables the kernels are built with
        // (the compiler's table cache), not a build of its own per sample.
        CompileOptions interp;
        interp.backend = Backend::Interp;
        std::unique_ptr<Kernel> tables = compileNoWait(compiler_, interp);
        refRegular_ = evaluateReference(m_, regular_, tables->lobeEnergyTables());
        refHard_ = evaluateReference(m_, hard_, tables->lobeEnergyTables());

        std::optional<ErrorStats> interpRegular, interpHard;
        for (const char* backend : kBackends)
            for (const Mode& mode : kModes) {
                BenchRow row;
                row.backend = backend;
                row.mode = mode.name;
                row.options = fmt::format("backend={};{}", backend, mode.options);
                if (!jitRow(row, interpRegular, interpHard)) continue;
                report(row);
                mb.rows.push_back(std::move(row));
            }
        const aot::ReferenceModel* model = aot::findReferenceModel(mb.aotModel);
        if (model) {
            BenchRow row = aotRow(*model, model->batch, "hand-written");
            report(row);
            mb.rows.push_back(std::move(row));
            double aotNs = mb.rows.back().nsPerEval;
            for (BenchRow& r : mb.rows)
                if (r.backend != "aot" && r.backend != "interp" && aotNs > 0) r.aotRatio = r.nsPerEval / aotNs;
        }
        if (model && model->bare) {
            BenchRow row = aotRow(*model, model->bare, "bare");
            report(row);
            double bareNs = row.nsPerEval;
            mb.rows.push_back(std::move(row));
            for (BenchRow& r : mb.rows)
                if (r.backend != "interp" && r.mode != "bare" && bareNs > 0) r.bareRatio = r.nsPerEval / bareNs;
        }
        batchSizeRows(mb, model);
        if (settings_.sampling) samplerRows(mb, model);
    }

private:
    void report(const BenchRow& row) {
        if (!progress_) return;
        std::fprintf(progress_, "  %-7s %-9s %10.2f ns/eval  max rel %.2g (hard %.2g)\n", row.backend.c_str(),
                     row.mode.c_str(), row.nsPerEval, row.regular.maxRel, row.hard.maxRel);
        std::fflush(progress_);
    }

    // Compiles and waits for a tiered kernel's optimized code (and with it
    // the cache entries its tier-up writes).
    std::unique_ptr<Kernel> compile(Compiler& compiler, const CompileOptions& options) {
        std::unique_ptr<Kernel> k = compileNoWait(compiler, options);
        k->waitOptimized();
        return k;
    }
    std::unique_ptr<Kernel> compileNoWait(Compiler& compiler, const CompileOptions& options) {
        DiagnosticEngine diags;
        std::unique_ptr<Kernel> k = compiler.compileMaterial(m_, options, diags);
        if (!k) throw std::runtime_error(fmt::format("bench: cannot compile {}: {}", m_.name, diags.str()));
        return k;
    }

    // Milliseconds until one compile returns its kernel; the kernel is kept
    // (its destruction, which unlinks it, is not part of the compile). The
    // next compile starts after its tier-up, whose CPU time goes to tierUp.
    double timedCompile(Compiler& compiler, const CompileOptions& options, std::vector<std::unique_ptr<Kernel>>& keep,
                        const char* expectOrigin, std::vector<double>* tierUp = nullptr) {
        auto start = Clock::now();
        std::unique_ptr<Kernel> k = compileNoWait(compiler, options);
        double ms = millisSince(start);
        k->waitOptimized();
        if (tierUp) tierUp->push_back(k->tierUpMillis());
        if (expectOrigin && k->origin() != expectOrigin)
            throw std::runtime_error(fmt::format("bench: expected a {} hit for {} ({}), got '{}'", expectOrigin,
                                                 m_.name, options.canonical(), k->origin()));
        keep.push_back(std::move(k));
        return ms;
    }

    bool jitRow(BenchRow& row, std::optional<ErrorStats>& interpRegular, std::optional<ErrorStats>& interpHard) {
        CompileOptions options;
        std::string error = CompileOptions::parse(row.options, options);
        if (!error.empty()) throw std::runtime_error("bench: " + error);
        bool interp = options.backend == Backend::Interp;

        // One untimed compile first (one-time LLVM set-up is not the
        // material's compile time); it fills the memory cache and the kernel
        // directory for the hits below, and its kernel is the one timed and
        // measured.
        CompileOptions mem = options, disk = options;
        mem.cache = CompileOptions::Cache::Memory;
        disk.cache = CompileOptions::Cache::On;
        std::unique_ptr<Kernel> kernel = compile(compiler_, kernelDir_.empty() ? mem : disk);
        // Cold compiles: cache=off.
        options.cache = CompileOptions::Cache::Off;
        std::vector<std::unique_ptr<Kernel>> keep;
        std::vector<double> cold, tierUp;
        for (int i = 0; i < settings_.compileRuns; ++i)
            cold.push_back(timedCompile(compiler_, options, keep, nullptr, &tierUp));
        row.coldMs = median(cold);
        keep.clear();
        if (!interp) {
            row.tierUpMs = median(tierUp);
            CompileOptions optimized = options;
            optimized.codegen = CompileOptions::Codegen::Optimized;
            std::vector<double> coldOptimized;
            for (int i = 0; i < settings_.compileRuns; ++i)
                coldOptimized.push_back(timedCompile(compiler_, optimized, keep, nullptr));
            row.coldOptimizedMs = median(coldOptimized);
            keep.clear();
        }
        row.variant = kernel->variant();
        row.measuredError = kernel->measuredError();
        row.width = kernel->width();

        if (!interp) {
            // Memory-cache hits of the entry the first compile made.
            std::vector<double> hits;
            for (int i = 0; i < settings_.compileRuns; ++i)
                hits.push_back(timedCompile(compiler_, mem, keep, "memory cache"));
            row.memoryHitMs = median(hits);
            keep.clear();
            // Disk-cache hits: a fresh Compiler (empty memory cache) on the
            // directory the first compile filled.
            if (!kernelDir_.empty()) {
                std::vector<double> diskHits;
                for (int i = 0; i < settings_.diskRuns; ++i) {
                    Compiler reader;
                    reader.setCacheDir(kernelDir_);
                    std::vector<std::unique_ptr<Kernel>> k;
                    diskHits.push_back(timedCompile(reader, disk, k, "disk cache"));
                }
                row.diskHitMs = median(diskHits);
            }
        }

        // Speed.
        size_t n = interp ? std::min(settings_.interpLanes, regular_.size()) : regular_.size();
        Output out(regular_.size());
        std::pair<double, double> t;
        int runs = interp ? std::max(3, settings_.runs / 3) : settings_.runs;
        int warmup = interp ? 1 : settings_.warmup;
        if (options.backend == Backend::Scalar) {
            t = timeChunks(warmup, runs, n, kScalarChunk,
                           [&](size_t b, size_t e) { evalScalarLanes(*kernel, regular_, b, e, out); });
        } else if (interp) {
            t = timeChunks(warmup, runs, n, kInterpChunk,
                           [&](size_t b, size_t e) { evalBatchRange(*kernel, regular_, b, e, out); });
        } else {
            t = timeBatches(warmup, runs, n, [&] {
                kernel->evalBatch(int64_t(n), regular_.wi(), regular_.wo(), regular_.inputs(), out.ptr);
            });
        }
        row.lanes = n;
        row.runs = runs;
        row.nsPerEval = t.first;
        row.nsPerEvalMin = t.second;
        row.evalsPerSecond = 1e9 / row.nsPerEval;

        // Error. Kernel::evalBatch of a scalar kernel calls its status entry
        // per lane, so invalid lanes are counted for every backend. The
        // interpreter has no math modes: its rows share one measurement.
        if (interp && interpRegular) {
            row.regular = *interpRegular;
            row.hard = *interpHard;
            return true;
        }
        row.regular = errorOn(*kernel, regular_, refRegular_);
        row.hard = errorOn(*kernel, hard_, refHard_);
        if (interp) interpRegular = row.regular, interpHard = row.hard;
        return true;
    }

    // The sampler rows (SamplerRow): sample and pdf on the regular sample's
    // directions, u uniform in [0, 1).
    void samplerRows(MaterialBench& mb, const aot::ReferenceModel* model) {
        const size_t n = regular_.size();
        std::mt19937_64 rng(settings_.seed + 1);
        std::uniform_real_distribution<float> uniform(0, 1);
        std::array<std::vector<float>, 3> u, wi, weight;
        for (int c = 0; c < 3; ++c) {
            u[c].resize(n);
            for (float& x : u[c]) x = std::min(uniform(rng), 1 - 0x1p-24f);
            wi[c].assign(n, 0), weight[c].assign(n, 0);
        }
        std::vector<float> pdf(n);
        const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
        float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
        float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};

        auto timeRow = [&](SamplerRow& row, bool interp, auto&& sample, auto&& density) {
            size_t lanes = interp ? std::min(settings_.interpLanes, n) : n;
            int runs = interp ? std::max(3, settings_.runs / 3) : settings_.runs;
            int warmup = interp ? 1 : settings_.warmup;
            row.lanes = lanes;
            row.nsPerSample = timeBatches(warmup, runs, lanes, [&] { sample(lanes); }).first;
            row.nsPerPdf = timeBatches(warmup, runs, lanes, [&] { density(lanes); }).first;
        };
        for (const char* backend : kBackends)
            for (const char* math : {"exact", "fast"}) {
                bool interp = std::string(backend) == "interp";
                if (interp && std::string(math) == "fast") continue;  // the interpreter has one math
                CompileOptions options;
                std::string error = CompileOptions::parse(fmt::format("backend={};math={};cache=off", backend, math),
                                                          options);
                if (!error.empty()) throw std::runtime_error("bench: " + error);
                std::unique_ptr<Kernel> kernel = compile(compiler_, options);
                SamplerRow row;
                row.backend = backend;
                row.mode = math;
                row.width = kernel->width();
                // The first sampling call compiles a JIT sampler.
                auto start = Clock::now();
                kernel->sampleBatch(1, regular_.wo(), uP, regular_.inputs(), wiP, pdf.data(), weightP);
                row.firstUseMs = millisSince(start);
                row.tier = kernel->samplerTier();
                timeRow(
                    row, interp,
                    [&](size_t lanes) {
                        kernel->sampleBatch(int64_t(lanes), regular_.wo(), uP, regular_.inputs(), wiP, pdf.data(),
                                            weightP);
                    },
                    [&](size_t lanes) {
                        kernel->pdfBatch(int64_t(lanes), regular_.wi(), regular_.wo(), regular_.inputs(), pdf.data());
                    });
                reportSampler(row);
                mb.samplerRows.push_back(std::move(row));
            }
        if (model && model->sample && model->pdf) {
            SamplerRow row;
            row.backend = "aot";
            row.mode = "hand-written";
            row.tier = "aot";
            timeRow(
                row, false,
                [&](size_t lanes) {
                    model->sample(int64_t(lanes), regular_.wo(), uP, regular_.inputs(), wiP, pdf.data(), weightP);
                },
                [&](size_t lanes) {
                    model->pdf(int64_t(lanes), regular_.wi(), regular_.wo(), regular_.inputs(), pdf.data());
                });
            reportSampler(row);
            for (SamplerRow& r : mb.samplerRows)
                if (r.backend != "interp" && row.nsPerSample > 0) r.aotRatio = r.nsPerSample / row.nsPerSample;
            mb.samplerRows.push_back(std::move(row));
        }
    }

    void reportSampler(const SamplerRow& row) {
        if (!progress_) return;
        std::fprintf(progress_, "  %-7s %-9s %10.2f ns/sample %8.2f ns/pdf  (%s sampler)\n", row.backend.c_str(),
                     row.mode.c_str(), row.nsPerSample, row.nsPerPdf, row.tier.c_str());
        std::fflush(progress_);
    }

    ErrorStats errorOn(const Kernel& kernel, const LaneBatch& s, const ReferenceValues& ref) {
        Output out(s.size());
        out.invalid = kernel.evalBatch(int64_t(s.size()), s.wi(), s.wo(), s.inputs(), out.ptr);
        return compare(m_, s, ref, out);
    }

    // The row of one AOT function (`batch`: the model's hand-written or bare
    // one). The bare function's host promises valid input, which the
    // hard-case sample is not: its error is measured on the regular sample only.
    BenchRow aotRow(const aot::ReferenceModel& model, aot::BatchFn batch, const char* mode) {
        BenchRow row;
        row.backend = "aot";
        row.mode = mode;
        row.variant = "-";
        row.width = 1;
        size_t n = regular_.size();
        Output out(n);
        auto t = timeBatches(settings_.warmup, settings_.runs, n,
                             [&] { batch(int64_t(n), regular_.wi(), regular_.wo(), regular_.inputs(), out.ptr); });
        row.lanes = n;
        row.runs = settings_.runs;
        row.nsPerEval = t.first;
        row.nsPerEvalMin = t.second;
        row.evalsPerSecond = 1e9 / row.nsPerEval;
        bool bare = batch == model.bare;
        for (const auto* s : {&regular_, &hard_}) {
            if (bare && s == &hard_) continue;
            Output o(s->size());
            o.invalid = batch(int64_t(s->size()), s->wi(), s->wo(), s->inputs(), o.ptr);
            (s == &regular_ ? row.regular : row.hard) = compare(m_, *s, s == &regular_ ? refRegular_ : refHard_, o);
        }
        return row;
    }

    // ns/eval of `evalRange(begin, end)` over the regular sample in
    // consecutive batches of n lanes (the last one shorter), median of runs.
    template <typename F>
    double batchedNs(size_t n, F&& evalRange) {
        const size_t lanes = regular_.size();
        return timeBatches(settings_.warmup, settings_.runs, lanes, [&] {
                   for (size_t b = 0; b < lanes; b += n) evalRange(b, std::min(lanes, b + n));
               }).first;
    }

    // The BatchSizeRow table (BenchRunner.h).
    void batchSizeRows(MaterialBench& mb, const aot::ReferenceModel* model) {
        Output out(regular_.size());
        auto row = [&](std::string label, auto&& evalRange) {
            BatchSizeRow r{std::move(label), {}};
            for (size_t n : kBatchSizes) r.nsPerEval.push_back(batchedNs(n, evalRange));
            mb.batchSizes.push_back(std::move(r));
        };
        auto oneLane = [&](std::string label, auto&& evalRange) {
            BatchSizeRow r{std::move(label), std::vector<double>(std::size(kBatchSizes), NAN)};
            r.nsPerEval[0] = batchedNs(1, evalRange);
            mb.batchSizes.push_back(std::move(r));
        };
        // The regular sample keeps the host's promise of assume=unit (unit
        // directions, inputs in range), on which its kernels give the same
        // bits (tests/jit/AssumeUnitTests.cpp): the rows show what it saves.
        for (bool unit : {false, true})
            for (const char* math : {"exact", "fast"}) {
                CompileOptions options;
                std::string error = CompileOptions::parse(
                    fmt::format("backend=simd;math={};assume={}", math, unit ? "unit" : "none"), options);
                if (!error.empty()) throw std::runtime_error("bench: " + error);
                std::unique_ptr<Kernel> kernel = compile(compiler_, options);
                row(fmt::format("simd {}{}", math, unit ? ", assume=unit" : ""),
                    [&](size_t b, size_t e) { evalBatchRange(*kernel, regular_, b, e, out); });
            }
        // The AOT twins' inputs are the material's (mb.aotModel is set only
        // then), a handful: their pointers live on the stack.
        constexpr size_t kMaxAotInputs = 8;
        if (model && regular_.slots.size() > kMaxAotInputs)
            throw std::logic_error(fmt::format("bench: aot model '{}' has more than {} inputs", mb.aotModel, kMaxAotInputs));
        auto aotRange = [&](aot::BatchFn fn) {
            return [this, fn, &out](size_t b, size_t e) {
                const float* wi[3] = {regular_.wi()[0] + b, regular_.wi()[1] + b, regular_.wi()[2] + b};
                const float* wo[3] = {regular_.wo()[0] + b, regular_.wo()[1] + b, regular_.wo()[2] + b};
                const float* in[kMaxAotInputs] = {};
                const size_t slots = regular_.slots.size();
                for (size_t j = 0; j < slots; ++j) in[j] = regular_.inputs()[j] + b;
                float* rgb[3] = {out.ptr[0] + b, out.ptr[1] + b, out.ptr[2] + b};
                fn(int64_t(e - b), wi, wo, slots ? in : nullptr, rgb);
            };
        };
        if (model) row("aot hand-written", aotRange(model->batch));
        if (model && model->bare) row("aot bare", aotRange(model->bare));
        CompileOptions scalarOptions;
        std::string error = CompileOptions::parse("backend=scalar;math=exact", scalarOptions);
        if (!error.empty()) throw std::runtime_error("bench: " + error);
        std::unique_ptr<Kernel> scalar = compile(compiler_, scalarOptions);
        oneLane("scalar exact, one call per lane",
                [&](size_t b, size_t e) { evalScalarLanes(*scalar, regular_, b, e, out); });
    }

    const CheckedMaterial& m_;
    const BenchSettings& settings_;
    Compiler& compiler_;
    const std::string kernelDir_;
    std::FILE* progress_;
    LaneBatch regular_, hard_;
    ReferenceValues refRegular_, refHard_;
};

std::string readText(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

std::string aotTagFor(const std::string& source, const std::string& path, const CheckedMaterial& material,
                      const std::vector<CheckedMaterial>& all) {
    // Tags by line; a tag belongs to the first material declared below it.
    std::map<int, std::string> tags;
    std::istringstream lines(source);
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
        size_t p = line.find("//");
        if (p == std::string::npos) continue;
        std::string rest = line.substr(p + 2);
        rest.erase(0, rest.find_first_not_of(" \t"));
        if (rest.rfind("aot:", 0) != 0) continue;
        rest = rest.substr(4);
        rest.erase(0, rest.find_first_not_of(" \t"));
        rest.erase(rest.find_last_not_of(" \t\r") + 1);
        tags[number] = rest;
    }
    for (const auto& [tagLine, name] : tags) {
        const CheckedMaterial* owner = nullptr;
        for (const CheckedMaterial& m : all)
            if (m.loc.line > tagLine && (!owner || m.loc.line < owner->loc.line)) owner = &m;
        if (owner && owner->name == material.name) return name;
    }
    // Fallback: bench/models/<model>.mat holds its model as first material.
    std::string stem = std::filesystem::path(path).stem().string();
    if (!all.empty() && &all.front() == &material && aot::findReferenceModel(stem)) return stem;
    return "";
}

namespace {

// The median CPU time of `runs` (at least one) reads of a table file by
// `load`, which returns "" or why the file did not load: then `note` says so
// and there is no time.
template <typename Load>
std::optional<double> timeLoads(int runs, const std::string& file, int& done, std::string& note, Load&& load) {
    std::vector<double> ms;
    for (int r = 0; r < std::max(1, runs); ++r) {
        auto start = Clock::now();
        std::string why = load();
        double t = millisSince(start);
        if (!why.empty()) {
            note = fmt::format("cannot read {} back: {}", file, why);
            return std::nullopt;
        }
        ms.push_back(t);
    }
    done = int(ms.size());
    return median(ms);
}

}  // namespace

std::optional<EnergyTableBench> benchEnergyTable(const CheckedMaterial& m, int loadRuns,
                                                 const std::optional<std::string>& cacheDir) {
    // (a combination's lobes: their tables are benched with the lobes' own materials)
    if (m.combinesLobes() || !m.singleLobe().compensatesEnergy() || kullaContyUnsupported(m, m.singleLobe()))
        return std::nullopt;
    EnergyTableKey key = energyTableKey(m);
    EnergyTableBench e;
    e.ndf = key.ndf->name;
    e.masking = key.masking->name;
    e.key = key.name();
    // Cold: the quadrature itself, on the threads a cache miss uses.
    std::shared_ptr<EnergyTable> table = buildEnergyTable(key);
    e.buildMs = table->buildMillis;
    e.muCount = table->muCount;
    e.alphaCount = table->alphaCount;
    e.threads = std::min(int(std::max(1u, std::thread::hardware_concurrency())), table->alphaCount);
    // Cached: the EXR in the table cache directory, written first if it is
    // missing or not a valid table of this key (as a cache miss would).
    TableCache cache(cacheDir ? *cacheDir : defaultTableCacheDir());
    e.cacheFile = cache.pathFor(key);
    if (e.cacheFile.empty()) {
        e.note = "no table cache directory (FACET_CACHE_DIR, XDG_CACHE_HOME and HOME unset)";
        return e;
    }
    if (readEnergyTableExr(e.cacheFile, &key).status != TableFileStatus::Ok) {
        std::string err = replaceEnergyTableExr(*table, e.cacheFile);
        if (!err.empty()) {
            e.note = "cannot write the table cache: " + err;
            return e;
        }
    }
    e.cachedLoadMs = timeLoads(loadRuns, e.cacheFile, e.loadRuns, e.note, [&] {
        TableFileResult loaded = readEnergyTableExr(e.cacheFile, &key);
        return loaded.status == TableFileStatus::Ok ? std::string() : loaded.message;
    });
    return e;
}

std::optional<WalkBench> benchWalk(const CheckedMaterial& m) {
    if (m.combinesLobes() || !m.singleLobe().compensatesEnergy() || kullaContyUnsupported(m, m.singleLobe()))
        return std::nullopt;
    Interpreter<double> interp(m);
    ResolvedMaterial<double> lobe = interp.resolve(nullptr);
    if (!lobe.valid || !MicrosurfaceWalk::unsupported(lobe).empty()) return std::nullopt;
    WalkBench w;
    WalkComparisonOptions options;
    options.thetas = {w.thetaO};
    WalkComparisonRow row = compareWithWalk(lobe, options).at(0);
    auto mean = [](const std::array<double, 3>& v) { return (v[0] + v[1] + v[2]) / 3; };
    w.single = mean(row.singleAlbedo), w.compensated = mean(row.modelAlbedo);
    w.walk = mean(row.walkAlbedo), w.walkError = mean(row.walkAlbedoError);
    w.singleShape = row.singleShapeError, w.compensatedShape = row.modelShapeError, w.noise = row.shapeNoise;
    return w;
}

std::optional<LambdaTableBench> benchLambdaTable(const CheckedMaterial& m, int loadRuns,
                                                 const std::optional<std::string>& cacheDir) {
    if (m.combinesLobes() || !usesTabulatedLambda(m)) return std::nullopt;
    const NdfEntry& ndf = ndfEntry(*m.singleLobe().ndf.model);
    std::vector<double> shape = tabulatedLambdaShape(m);
    LambdaTableBench e;
    e.key = lambdaTableName(ndf, shape);
    // Cold: the quadrature itself, not the process's shared table.
    std::shared_ptr<LambdaTable> table = tabulateCosLambda(ndf, shape, quadratureCosLambda);
    e.buildMs = table->buildMillis;
    e.nodes = int(table->z.size());
    e.threads = table->buildThreads;
    // The reference interpreter (the error columns) asks the memory layer for
    // this very table: give it the one just built rather than a second
    // quadrature of ~10 s.
    adoptLambdaTable(table);
    // Cached: the file in the table cache directory, written first if it is
    // missing or not a valid table of this key (as a cache miss would).
    std::string dir = cacheDir ? *cacheDir : defaultTableCacheDir();
    if (dir.empty()) {
        e.note = "no table cache directory (FACET_CACHE_DIR, XDG_CACHE_HOME and HOME unset)";
        return e;
    }
    e.cacheFile = dir + "/" + lambdaTableFileName(ndf, shape);
    if (readLambdaTableFile(e.cacheFile, ndf, shape).status != TableFileStatus::Ok) {
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        std::string err = writeFileAtomically(e.cacheFile, encodeLambdaTable(*table));
        if (!err.empty()) {
            e.note = "cannot write the table cache: " + err;
            return e;
        }
    }
    e.cachedLoadMs = timeLoads(loadRuns, e.cacheFile, e.loadRuns, e.note, [&] {
        LambdaTableFileResult loaded = readLambdaTableFile(e.cacheFile, ndf, shape);
        return loaded.status == TableFileStatus::Ok ? std::string() : loaded.message;
    });
    return e;
}

static LobesAlone benchLobesAlone(const CheckedMaterial& m, const BenchSettings& settings, Compiler& compiler) {
    const LaneBatch sample = regularSample(m, settings.lanes, settings.seed);
    auto compile = [&](const CheckedMaterial& material) {
        CompileOptions o;
        std::string error = CompileOptions::parse("backend=simd;math=exact;cache=memory", o);
        internal_assert(error.empty()) << error;
        DiagnosticEngine diags;
        std::unique_ptr<Kernel> k = compiler.compileMaterial(material, o, diags);
        if (!k) throw std::runtime_error(diags.str());
        k->waitOptimized();
        return k;
    };
    std::vector<std::unique_ptr<Kernel>> kernels;
    kernels.push_back(compile(m));
    for (size_t l = 0; l < m.lobes.size(); ++l) kernels.push_back(compile(lobeView(m, int(l))));
    // Interleaved: one run of each kernel in turn, so that a busy moment of
    // the machine falls on all of them alike.
    Output out(sample.size());
    std::vector<std::vector<double>> t(kernels.size());
    for (int run = 0; run < settings.warmup + settings.runs; ++run)
        for (size_t k = 0; k < kernels.size(); ++k) {
            auto start = Clock::now();
            evalBatchRange(*kernels[k], sample, 0, sample.size(), out);
            if (run >= settings.warmup) t[k].push_back(nanosSince(start) / double(sample.size()));
        }
    LobesAlone r;
    r.combination = median(t[0]);
    for (size_t l = 0; l < m.lobes.size(); ++l) r.lobes.push_back({m.lobes[l].name, median(t[l + 1])});
    return r;
}

void describeHost(BenchReport& report) {
    Compiler compiler;
    report.cpu = compiler.jit().cpuName();
    report.cpuFeatures = compiler.jit().cpuFeatures();
    report.hostWidth = compiler.jit().hostVectorWidth();
    report.hardSample = hardCaseSampleDescription();
}

bool benchFile(const std::string& path, const BenchSettings& settings, BenchReport& report, DiagnosticEngine& diags,
               std::FILE* progress) {
    auto start = Clock::now();
    CheckedProgram program = loadProgramFile(path, diags);
    if (diags.hasErrors()) return false;
    double parseCheckMs = millisSince(start);
    std::string source = readText(path);
    TempDir kernelDir;
    Compiler compiler;
    if (!kernelDir.path.empty()) compiler.setCacheDir(kernelDir.path);
    for (const CheckedMaterial& m : program.materials) {
        if (std::string why = compiledBackendsRefuse(m); !why.empty()) {
            DiagnosticEngine refused;
            refused.error(m.loc, why);
            throw std::runtime_error(refused.str());
        }
        MaterialBench mb;
        mb.file = path;
        mb.material = m.name;
        mb.parseCheckMs = parseCheckMs;
        std::string tag = aotTagFor(source, path, m, program.materials);
        if (!tag.empty()) {
            const aot::ReferenceModel* model = aot::findReferenceModel(tag);
            std::vector<std::string> slots;
            for (int s = 0; s < m.slotCount; ++s) slots.push_back(m.slotName(s));
            std::vector<std::string> expected;
            if (model)
                for (const char* in : model->inputs) expected.push_back(in);
            if (!model) mb.aotNote = fmt::format("unknown aot model '{}'", tag);
            else if (slots != expected) mb.aotNote = fmt::format("aot model '{}' has other inputs than '{}'", tag, m.name);
            else mb.aotModel = tag;
        }
        mb.energyTable = benchEnergyTable(m, std::max(3, settings.diskRuns));
        mb.lambdaTable = benchLambdaTable(m, std::max(3, settings.diskRuns));
        mb.walk = benchWalk(m);
        if (progress) std::fprintf(progress, "bench %s (%s)\n", m.name.c_str(), path.c_str());
        MaterialRunner(m, settings, compiler, kernelDir.path, progress).run(mb);
        if (m.combinesLobes()) mb.lobesAlone = benchLobesAlone(m, settings, compiler);
        report.materials.push_back(std::move(mb));
    }
    return true;
}

}  // namespace facet::bench
