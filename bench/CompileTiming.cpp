// facet_compile_timing: cold JIT compile time and kernel speed, per material.
//
//   facet_compile_timing [--runs N] [--evals N] [--dump DIR] [--no-speed]
//                        [--grazing] [--extra OPTIONS] FILE.mat...
//
// For every material and each of simd exact, simd fast and scalar exact it
// prints the median (over --runs, default 11) cold compile time with
// cache=off, split into lowering, the middle-end (FacetJit::optimize) and
// object emission (FacetJit::emitObject) at the level the compile returns
// (quick when tiered, the default; --extra codegen=optimized for the
// optimized code alone), the median CPU time of the tier-up thread's
// optimized compile (0 when not tiered), and for the SIMD rows the median
// ns/eval of a batch of --evals (default 65536) lanes of `facet bench`'s
// regular sample (scalar rows: 8192 lanes one by one through Kernel::eval).
// With --dump DIR it writes the outputs of the regular and
// hard-case samples to DIR/<material>.<row>.bin, to compare two builds bit
// for bit (cmp). --grazing puts every lane's wi at n.wi = 1e-7 (azimuth
// kept), below the 1e-6 guard of the two-body kernels, so that every
// vector runs both bodies; --extra appends OPTIONS (e.g. float_first=off)
// to each row's option string. Times are CPU time of the thread doing the
// work (see BenchRunner.cpp); speed and dumps use the optimized code.
#include "BenchSamples.h"
#include "Checker.h"
#include "CompileStack.h"
#include "Jit.h"
#include "Kernel.h"
#include "Pipeline.h"

#include <llvm/IR/LLVMContext.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

using namespace facet;

namespace {

// This thread's CPU time, LLVM's stages on the compile stack included.
double nowNs() { return callerCpuNanos(); }

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n == 0 ? 0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Row {
    const char* name;
    const char* options;
};
const Row kRows[] = {{"simd-exact", "backend=simd;math=exact;cache=off"},
                     {"simd-fast", "backend=simd;math=fast;cache=off"},
                     {"scalar-exact", "backend=scalar;math=exact;cache=off"}};

void dump(const std::string& path, const Kernel& k, const LaneBatch& s) {
    std::vector<float> c[3];
    float* out[3];
    for (int i = 0; i < 3; ++i) c[i].assign(s.size(), -1.0f), out[i] = c[i].data();
    int64_t invalid = k.evalBatch(int64_t(s.size()), s.wi(), s.wo(), s.inputs(), out);
    std::ofstream f(path, std::ios::binary | std::ios::app);
    f.write(reinterpret_cast<const char*>(&invalid), sizeof invalid);
    for (auto& v : c) f.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(float)));
}

}  // namespace

int main(int argc, char** argv) {
    int runs = 11;
    size_t evals = 65536;
    bool speed = true, grazing = false;
    std::string extra;
    std::string dumpDir;
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
        else if (a == "--evals" && i + 1 < argc) evals = size_t(std::atoll(argv[++i]));
        else if (a == "--dump" && i + 1 < argc) dumpDir = argv[++i];
        else if (a == "--no-speed") speed = false;
        else if (a == "--grazing") grazing = true;
        else if (a == "--extra" && i + 1 < argc) extra = std::string(";") + argv[++i];
        else files.push_back(a);
    }
    Compiler compiler;
    compiler.setCacheDir("");
    std::vector<double> allCold;
    std::printf("%-26s %-12s %8s %8s %8s %8s %8s %9s\n", "material", "row", "cold ms", "lower", "opt", "emit",
                "tier-up", "ns/eval");
    for (const std::string& file : files) {
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramFile(file, diags);
        if (diags.hasErrors()) {
            std::fprintf(stderr, "%s", diags.str().c_str());
            return 1;
        }
        for (const CheckedMaterial& m : program.materials) {
            LaneBatch regular = bench::regularSample(m, evals, 1234);
            if (grazing) {
                for (size_t i = 0; i < regular.size(); ++i) {
                    double x = regular.dir[0][i], y = regular.dir[1][i], r = std::hypot(x, y), z = 1e-7;
                    double s = r > 0 ? std::sqrt(1 - z * z) / r : 0;
                    regular.dir[0][i] = r > 0 ? float(x * s) : 1.0f;
                    regular.dir[1][i] = float(y * s);
                    regular.dir[2][i] = float(z);
                }
            }
            LaneBatch hard = bench::hardCaseSample(m);
            for (const Row& row : kRows) {
                CompileOptions options;
                std::string err = CompileOptions::parse(row.options + extra, options);
                if (!err.empty()) return std::fprintf(stderr, "%s\n", err.c_str()), 2;
                std::unique_ptr<Kernel> kernel = compiler.compileMaterial(m, options, diags);  // untimed warm-up
                if (!kernel) return std::fprintf(stderr, "%s", diags.str().c_str()), 1;
                kernel->waitOptimized();
                std::vector<std::unique_ptr<Kernel>> keep;
                std::vector<double> cold, tierUp;
                for (int r = 0; r < runs; ++r) {
                    double t0 = nowNs();
                    keep.push_back(compiler.compileMaterial(m, options, diags));
                    cold.push_back((nowNs() - t0) * 1e-6);
                    // The next compile starts when this one's tier-up is done.
                    keep.back()->waitOptimized();
                    tierUp.push_back(keep.back()->tierUpMillis());
                }
                keep.clear();
                const FacetJit::Level level = options.codegen == CompileOptions::Codegen::Optimized
                                                  ? FacetJit::Level::Optimized
                                                  : FacetJit::Level::Quick;
                // The same compile in phases: the pipeline's stages, timed as they end.
                std::vector<double> tl, to, te;
                for (int r = 0; r < runs; ++r) {
                    PipelineRun run = PipelineRun::fromChecked(m, options);
                    PipelineControl control;
                    control.symbolPrefix = "facet_timing";
                    double planned = 0, lowered = 0, optimized = 0, emitted = 0;
                    control.afterStage = [&](PipelineStage stage, const PipelineRun&) {
                        double now = nowNs();
                        if (stage == PipelineStage::Planned) planned = now;
                        if (stage == PipelineStage::Lowered) lowered = now;
                        if (stage == PipelineStage::Optimized) optimized = now;
                        if (stage == PipelineStage::Emitted) emitted = now;
                    };
                    if (!compiler.runPipeline(run, control, level, diags))
                        return std::fprintf(stderr, "%s", diags.str().c_str()), 1;
                    tl.push_back((lowered - planned) * 1e-6), to.push_back((optimized - lowered) * 1e-6);
                    te.push_back((emitted - optimized) * 1e-6);
                }
                double ns = 0;
                if (speed && options.backend == Backend::Scalar) {
                    // Lane by lane through Kernel::eval, as a renderer calls the scalar entry.
                    size_t n = std::min<size_t>(regular.size(), 8192);
                    std::vector<float> in(std::max<size_t>(1, regular.slots.size()));
                    std::vector<double> t;
                    for (int r = 0; r < 21; ++r) {
                        float sink = 0;
                        double t0 = nowNs();
                        for (size_t i = 0; i < n; ++i) {
                            float a[3] = {regular.dir[0][i], regular.dir[1][i], regular.dir[2][i]};
                            float b[3] = {regular.dir[3][i], regular.dir[4][i], regular.dir[5][i]}, o[3];
                            for (size_t j = 0; j < regular.slots.size(); ++j) in[j] = regular.slots[j][i];
                            kernel->eval(a, b, in.data(), o);
                            sink += o[0];
                        }
                        t.push_back((nowNs() - t0) / double(n));
                        if (sink == -1.0f) std::printf(" ");  // keeps the loop
                    }
                    ns = median(t);
                }
                if (speed && options.backend == Backend::Simd) {
                    std::vector<float> c[3];
                    float* out[3];
                    for (int i = 0; i < 3; ++i) c[i].assign(regular.size(), 0.0f), out[i] = c[i].data();
                    std::vector<double> t;
                    for (int r = 0; r < 3; ++r) kernel->evalBatch(int64_t(regular.size()), regular.wi(), regular.wo(), regular.inputs(), out);
                    for (int r = 0; r < 41; ++r) {
                        double t0 = nowNs();
                        kernel->evalBatch(int64_t(regular.size()), regular.wi(), regular.wo(), regular.inputs(), out);
                        t.push_back((nowNs() - t0) / double(regular.size()));
                    }
                    ns = median(t);
                }
                if (!dumpDir.empty()) {
                    std::string path = dumpDir + "/" + m.name + "." + row.name + ".bin";
                    std::remove(path.c_str());
                    dump(path, *kernel, regular);
                    dump(path, *kernel, hard);
                }
                double c = median(cold);
                allCold.push_back(c);
                std::printf("%-26s %-12s %8.2f %8.2f %8.2f %8.2f %8.2f %9.3f\n", m.name.c_str(), row.name, c, median(tl),
                            median(to), median(te), median(tierUp), ns);
                std::fflush(stdout);
            }
        }
    }
    std::printf("median cold ms over all rows: %.2f (max %.2f)\n", median(allCold),
                allCold.empty() ? 0.0 : *std::max_element(allCold.begin(), allCold.end()));
    return 0;
}
