// BenchRunner: the measurements of `facet bench` (SPEC section 6).
//
// For every material: one row per backend (interp, scalar, simd) x math
// mode (exact, fast, tolerance 1e-3, tolerance 1e-5), plus the hand-written
// ahead-of-time model (bench/aot) when the material file is tagged
// `// aot: NAME`, and the sampler rows (SamplerRow). Each eval row has
// - speed: median ns/eval over repeated warm runs: the SIMD batch entry and
//   the AOT batch function on the whole batch per run; the scalar entry
//   (called lane by lane) and the interpreter (Kernel::evalBatch, on fewer
//   lanes) timed in chunks of a few thousand / hundred lanes;
// - compile time: cold (cache=off), memory-cache hit, disk-cache hit (a
//   fresh Compiler on a private cache directory), medians.
// All times are CPU time of the benchmarking thread, with the compile-stack
// threads it waits for counted as its own (callerCpuNanos, CompileStack.h),
// so that other processes on a shared machine do not inflate them (on an
// idle machine CPU and wall time agree);
// - error against the double interpreter on the regular and on the
//   hard-case sample: max and p99.9 relative error, max ULP, and the input
//   with the largest error.
// The report (BenchReport.h) and plot (BenchPlot.h) only format these.
#pragma once

#include "BenchSamples.h"
#include "Diagnostics.h"
#include "Material.h"

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace facet::bench {

struct BenchSettings {
    size_t lanes = 65536;       // timed batch (scalar, simd, aot) and regular-sample size
    size_t interpLanes = 2048;  // the interpreter is timed on fewer lanes
    int runs = 15;              // timed runs per row (median)
    int warmup = 3;             // untimed runs first
    int compileRuns = 7;        // cold compiles and memory-cache hits (median)
    int diskRuns = 3;           // disk-cache hits (a fresh Compiler each)
    bool quick = false;
    bool sampling = true;  // the sampler rows
    uint64_t seed = 20240607;

    static BenchSettings quickSettings();
};

// Error of one row against the reference on one sample, by the conventions of
// ReferenceComparison.h (relative error with an absolute floor of
// kAbsoluteErrorFloor, FLT_MIN as the smallest divisor).
struct ErrorStats {
    size_t values = 0;      // channel values compared
    size_t skipped = 0;     // reference beyond float range (not representable)
    size_t nonFinite = 0;   // outputs NaN or Inf (SPEC 2 forbids them)
    size_t negative = 0;    // outputs < 0
    int64_t invalidLanes = 0;      // lanes the evaluator reported invalid
    int64_t referenceInvalid = 0;  // lanes the reference found invalid
    double maxRel = 0, p999Rel = 0, maxUlp = 0;
    struct Worst {
        bool present = false;
        size_t lane = 0;
        int channel = 0;
        float wi[3] = {}, wo[3] = {};
        std::vector<std::pair<std::string, float>> inputs;
        double got = 0, want = 0, rel = 0;
        std::string str() const;  // printable
    } worst;
};

struct BenchRow {
    std::string backend;  // interp | scalar | simd | aot
    std::string mode;     // exact | fast | tol 1e-3 | tol 1e-5 | hand-written
    std::string options;  // the CompileOptions string ("" for aot)
    std::string variant;  // the math variant the compiler picked (Kernel::variant), or "-"
    double measuredError = -1;  // the compiler's own measurement for tolerance builds (< 0: none)
    int width = 1;
    size_t lanes = 0;
    int runs = 0;
    double nsPerEval = 0, nsPerEvalMin = 0, evalsPerSecond = 0;
    // coldMs: a cold compile (cache=off) with the row's options, i.e. tiered
    // unless they say otherwise: the time until compile returns a kernel.
    // tierUpMs: the tier-up thread's CPU time for the optimized code of
    // that compile (0 if not tiered). coldOptimizedMs: a cold compile with
    // codegen=optimized, which returns only once the optimized code is linked.
    std::optional<double> coldMs, tierUpMs, coldOptimizedMs, memoryHitMs, diskHitMs;
    std::optional<double> aotRatio;   // this row's ns/eval over the AOT row's
    std::optional<double> bareRatio;  // and over the bare AOT row's
    ErrorStats regular, hard;  // hard: none (values = 0) for the bare row, whose host promises valid input
    std::string label() const { return backend + " " + mode; }
};

// The importance sampler of a material (SPEC 8): one row per backend x
// math mode (interp; scalar and simd, exact and fast) and the hand-written
// sampler of its AOT model where there is one. Speed of Kernel::sampleBatch
// and Kernel::pdfBatch on the regular sample's wo (and wi for pdf) with
// uniform u, medians like eval's rows (the interpreter on fewer lanes);
// `tier` says whether the kernel's own compiled sampler ran ("jit") or the
// interpreter's reference sampler ("reference"); firstUseMs is the first
// sampling call of a fresh kernel, which compiles a JIT sampler (the
// kernel's eval entry points were compiled already).
struct SamplerRow {
    std::string backend;  // interp | scalar | simd | aot
    std::string mode;     // exact | fast | hand-written
    std::string tier;     // jit | reference | aot
    int width = 1;
    size_t lanes = 0;
    double nsPerSample = 0, nsPerPdf = 0;
    std::optional<double> firstUseMs;
    std::optional<double> aotRatio;  // ns/sample over the AOT sampler's
    std::string label() const { return backend + " " + mode; }
};

// What the bench measures of a table cache file: the cold build time and
// the time to load the file back.
struct TableTiming {
    double buildMs = 0;
    std::optional<double> cachedLoadMs;  // none when the cache could not be written or read (see note)
    int loadRuns = 0;
    std::string cacheFile;  // the file read back
    std::string note;       // why cachedLoadMs is missing, else ""
};

// The Kulla-Conty E table of a material with energy = kulla_conty: its
// (NDF, masking) pair, the time to build it by quadrature (cold: directly,
// not through any cache; wall time, on `threads` threads) and the time to
// load it back from the EXR file in the table cache directory (median of
// `loadRuns` reads, CPU time of the benchmarking thread like the other times).
struct EnergyTableBench : TableTiming {
    std::string ndf, masking;  // "ggx", "smith_height_correlated"
    std::string key;           // the table key, e.g. "ggx_smith_height_correlated"
    int muCount = 0, alphaCount = 0;
    int threads = 0;
    std::string pair() const { return ndf + " x " + masking; }
};

// The Smith Lambda table of a material whose masking needs its NDF's table
// (LambdaTable.h, e.g. student_t): the time to build it by quadrature (cold:
// directly, not through any cache; one thread) and the time to load it back
// from its file in the table cache directory (median of `loadRuns` reads and
// checks, spot-check quadrature included; CPU time like the other times).
struct LambdaTableBench : TableTiming {
    std::string key;  // the table's name, e.g. "student_t_g3"
    int nodes = 0;
    int threads = 1;  // the cold build's
};

// ns/eval by batch size (kBatchSizes): the regular sample evaluated in
// consecutive batches of n lanes, one call each, as a wavefront renderer
// evaluates its per-material queues; per call the caller's pointer
// arithmetic included. One row per evaluator: simd exact and fast
// (Kernel::evalBatch, what facet_eval_batch calls after its argument
// checks), the same under the host's promise assume=unit, the AOT
// hand-written and bare functions (through a function pointer: at n = 1,
// one call of the bare function per lane); plus the
// scalar entry called once per lane (Kernel::eval, what facet_eval calls),
// in the n = 1 column only.
inline constexpr size_t kBatchSizes[] = {1, 4, 16, 64, 256, 65536};
struct BatchSizeRow {
    std::string label;                // "simd exact", "aot bare", "scalar entry" ...
    std::vector<double> nsPerEval;    // per kBatchSizes entry; NaN where not measured
};

// A combination of lobes (SPEC 10): its SIMD exact ns/eval against each
// lobe's alone (the lobe as a material of its own, lobeView), timed on the
// same sample in interleaved runs.
struct LobesAlone {
    std::vector<std::pair<std::string, double>> lobes;  // name, ns/eval
    double combination = 0;                              // ns/eval
    double sum() const {
        double s = 0;
        for (const auto& l : lobes) s += l.second;
        return s;
    }
};

// energy = kulla_conty against its stochastic reference, the random walk on
// the lobe's microsurface (WalkComparison.h), at the default inputs and one
// view angle: albedos (rgb mean) and BRDF-shaped errors.
struct WalkBench {
    double thetaO = 60;
    double single = 0, compensated = 0, walk = 0, walkError = 0;
    double singleShape = 0, compensatedShape = 0, noise = 0;
};

struct MaterialBench {
    std::string file, material;
    std::string aotModel;  // "" when the file has no AOT twin
    std::string aotNote;   // why the AOT row is missing, if the tag did not fit
    double parseCheckMs = 0;
    std::optional<EnergyTableBench> energyTable;  // energy = kulla_conty only
    std::optional<LambdaTableBench> lambdaTable;  // a tabulated Smith Lambda only
    std::optional<WalkBench> walk;                // energy = kulla_conty with a walkable lobe only
    std::optional<LobesAlone> lobesAlone;         // a combination of lobes only
    size_t regularLanes = 0, hardLanes = 0;
    std::vector<BenchRow> rows;
    std::vector<SamplerRow> samplerRows;  // empty with BenchSettings::sampling off
    std::vector<BatchSizeRow> batchSizes;
    const BenchRow* find(const std::string& backend, const std::string& mode) const;
};

struct BenchReport {
    BenchSettings settings;
    std::string cpu, cpuFeatures;
    int hostWidth = 0;
    std::string hardSample;  // description
    std::vector<MaterialBench> materials;
};

// Benchmarks every material of `path`. On a material file error returns
// false with diagnostics in `diags`. `progress` (may be null) gets one line
// per row as it is measured.
bool benchFile(const std::string& path, const BenchSettings& settings, BenchReport& report,
               DiagnosticEngine& diags, std::FILE* progress);

// Builds the Kulla-Conty table of `material` (energy = kulla_conty, else
// nullopt) cold, stores it in the table cache directory (`cacheDir`, default
// defaultTableCacheDir(); "" or unwritable: no cached load) unless a valid
// file is there already, and times reading that file back `loadRuns` times.
std::optional<EnergyTableBench> benchEnergyTable(const CheckedMaterial& material, int loadRuns,
                                                 const std::optional<std::string>& cacheDir = std::nullopt);

// The same for the Lambda table of `material` (usesTabulatedLambda, else
// nullopt): built cold, stored as lambda_<key>.bin in `cacheDir` (default
// defaultTableCacheDir()) unless a valid file is there, read back `loadRuns` times.
std::optional<LambdaTableBench> benchLambdaTable(const CheckedMaterial& material, int loadRuns,
                                                 const std::optional<std::string>& cacheDir = std::nullopt);

// Kulla-Conty against the random walk for a one-lobe material with energy =
// kulla_conty whose NDF the walk supports (else nullopt); about a second.
std::optional<WalkBench> benchWalk(const CheckedMaterial& material);

// Fills the host fields of a report (CPU, features, vector width).
void describeHost(BenchReport& report);

// The `// aot: NAME` tag that applies to material `name` in `source` (the
// nearest tag above the material), else "" — and the bench/models file
// name as a fallback (ggx_schlick.mat -> "ggx_schlick").
std::string aotTagFor(const std::string& source, const std::string& path, const CheckedMaterial& material,
                      const std::vector<CheckedMaterial>& all);

}  // namespace facet::bench
