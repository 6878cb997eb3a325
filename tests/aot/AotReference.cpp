// facet_aot_reference: the JIT side of the ahead-of-time tests.
//
//   facet_aot_reference inputs FILE.mat MATERIAL OPTIONS RANDOM INPUTS.bin
//       writes the lanes: the hard-case sample of the material (SPEC 7)
//       followed by RANDOM random direction pairs (uniform over the sphere,
//       so a quarter with both directions above the horizon) with inputs
//       uniform over their ranges.
//   facet_aot_reference same-as-jit FILE.mat MATERIAL OPTIONS RANDOM OUTPUTS.bin
//       compiles the JIT kernel of OPTIONS (facet_compile_file's option
//       string) and requires aot_run's outputs to be its outputs bit for bit:
//       the batch call, the one-lane eval entry, the invalid count.
//   facet_aot_reference against-interpreter FILE.mat MATERIAL OPTIONS RANDOM OUTPUTS.bin
//       checks aot_run's outputs (of an object for another target) against
//       the double interpreter as the hard-case tests check the host JIT
//       (apps/verify/Verify.h: bound, ill-conditioning allowance, no NaN, Inf
//       or negative output, invalid lanes 0 and counted), and checks the
//       host JIT kernel of the same options the same way, for comparison.
// Exit 0 when the check passes, 1 when it fails, 2 on a usage or I/O error.
#include "Checker.h"
#include "HardCases.h"
#include "Kernel.h"
#include "Verify.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace facet;

namespace {

std::vector<HardCase> sample(const CheckedMaterial& material, size_t random) {
    std::vector<HardCase> cases = hardCases(material);
    std::mt19937_64 rng(0xa07);
    std::uniform_real_distribution<double> u(0, 1);
    auto direction = [&](std::array<double, 3>& w) {
        double z = 2 * u(rng) - 1, phi = 2 * M_PI * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
        w = {double(float(r * std::cos(phi))), double(float(r * std::sin(phi))), double(float(z))};
    };
    for (size_t i = 0; i < random; ++i) {
        HardCase c;
        direction(c.wi);
        direction(c.wo);
        c.slots.assign(material.slotCount, 0.0);
        for (const CheckedInput& in : material.inputs)
            for (int k = 0; k < in.slotCount(); ++k) {
                double lo = in.hasRange ? in.lo : 0.0, hi = in.hasRange ? in.hi : 2 * in.defaultValue[k];
                c.slots[in.firstSlot + k] = double(float(lo + (hi - lo) * u(rng)));
            }
        c.label = "random";
        cases.push_back(std::move(c));
    }
    return cases;
}

struct AotRun {
    std::vector<float> batch[3], eval[3];
    int64_t batchCount = 0;
    std::vector<char> invalid;
};

bool readRun(const std::string& path, size_t n, AotRun& run) {
    std::ifstream in(path, std::ios::binary);
    char magic[8];
    int64_t lanes = 0;
    if (!in.read(magic, 8) || std::memcmp(magic, "FACETRUN", 8) != 0 || !in.read(reinterpret_cast<char*>(&lanes), 8) ||
        lanes != int64_t(n))
        return false;
    for (auto* streams : {run.batch, run.eval})
        for (int c = 0; c < 3; ++c) {
            streams[c].resize(n);
            if (!in.read(reinterpret_cast<char*>(streams[c].data()), std::streamsize(n * sizeof(float)))) return false;
        }
    run.invalid.resize(n);
    return bool(in.read(reinterpret_cast<char*>(&run.batchCount), 8)) &&
           bool(in.read(run.invalid.data(), std::streamsize(n))) && in.peek() == std::char_traits<char>::eof();
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

int usage() {
    std::fprintf(stderr,
                 "usage: facet_aot_reference inputs|same-as-jit|against-interpreter FILE.mat MATERIAL OPTIONS "
                 "RANDOM FILE.bin\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 7) return usage();
    std::string mode = argv[1], file = argv[2], name = argv[3], spec = argv[4], path = argv[6];
    size_t random = std::strtoull(argv[5], nullptr, 10);
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramFile(file, diags);
    const CheckedMaterial* material = diags.hasErrors() ? nullptr : program.find(name);
    if (!material) {
        std::fprintf(stderr, "%s%s: no material '%s'\n", diags.str().c_str(), file.c_str(), name.c_str());
        return 2;
    }
    std::vector<HardCase> cases = sample(*material, random);
    const size_t n = cases.size();
    const int slots = material->slotCount;

    if (mode == "inputs") {
        std::ofstream out(path, std::ios::binary);
        int32_t s32 = slots;
        int64_t n64 = int64_t(n);
        out.write("FACETAOT", 8);
        out.write(reinterpret_cast<const char*>(&s32), 4);
        out.write(reinterpret_cast<const char*>(&n64), 8);
        std::vector<float> stream(n);
        for (int k = 0; k < 6 + slots; ++k) {
            for (size_t i = 0; i < n; ++i)
                stream[i] = float(k < 3 ? cases[i].wi[k] : k < 6 ? cases[i].wo[k - 3] : cases[i].slots[k - 6]);
            out.write(reinterpret_cast<const char*>(stream.data()), std::streamsize(n * sizeof(float)));
        }
        out.close();
        if (!out) {
            std::fprintf(stderr, "%s: cannot write\n", path.c_str());
            return 2;
        }
        std::printf("%s: %zu lanes (%zu hard cases), %d slots\n", path.c_str(), n, n - random, slots);
        return 0;
    }

    AotRun aot;
    if (!readRun(path, n, aot)) {
        std::fprintf(stderr, "%s: not aot_run's output for %zu lanes\n", path.c_str(), n);
        return 2;
    }
    CompileOptions options;
    if (std::string problem = CompileOptions::parse(spec + ";codegen=optimized;cache=off", options); !problem.empty()) {
        std::fprintf(stderr, "options: %s\n", problem.c_str());
        return 2;
    }
    Compiler compiler;
    std::unique_ptr<Kernel> kernel = compiler.compileMaterial(*material, options, diags);
    if (!kernel) {
        std::fputs(diags.str().c_str(), stderr);
        return 2;
    }
    KernelRun jit = runKernel(*kernel, cases);

    if (mode == "same-as-jit") {
        // runKernel's rgb is the eval entry's for scalar kernels and the
        // batch call's for SIMD ones; get both explicitly.
        std::vector<float> dir[6], in(std::max(1, slots) * n), batch[3];
        for (int k = 0; k < 6; ++k)
            for (size_t i = 0; i < n; ++i) dir[k].push_back(float(k < 3 ? cases[i].wi[k] : cases[i].wo[k - 3]));
        std::vector<const float*> inPtr;
        for (int s = 0; s < slots; ++s) {
            for (size_t i = 0; i < n; ++i) in[s * n + i] = float(cases[i].slots[s]);
            inPtr.push_back(&in[s * n]);
        }
        for (auto& b : batch) b.assign(n, -1.0f);
        const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
        const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
        float* rgb[3] = {batch[0].data(), batch[1].data(), batch[2].data()};
        int64_t count = kernel->evalBatch(int64_t(n), wi, wo, slots ? inPtr.data() : nullptr, rgb);
        size_t batchDiff = 0, evalDiff = 0, statusDiff = 0;
        size_t firstDiff = SIZE_MAX;
        for (size_t i = 0; i < n; ++i) {
            float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, o[3];
            std::vector<float> lane(std::max(1, slots));
            for (int s = 0; s < slots; ++s) lane[s] = in[s * n + i];
            kernel->eval(a, b, lane.data(), o);
            bool lb = true, le = true;
            for (int c = 0; c < 3; ++c) {
                lb &= sameBits(aot.batch[c][i], batch[c][i]);
                le &= sameBits(aot.eval[c][i], o[c]);
            }
            batchDiff += !lb;
            evalDiff += !le;
            statusDiff += aot.invalid[i] != jit.invalid[i];
            if ((!lb || !le) && firstDiff == SIZE_MAX) firstDiff = i;
        }
        std::printf("%s %s [%s]: %zu lanes; differing from the JIT kernel: batch %zu, eval %zu, lane status %zu; "
                    "invalid count AOT %lld, JIT %lld\n",
                    file.c_str(), name.c_str(), spec.c_str(), n, batchDiff, evalDiff, statusDiff,
                    (long long)aot.batchCount, (long long)count);
        if (firstDiff != SIZE_MAX)
            std::printf("  first difference: lane %zu (%s): AOT batch %.9g, JIT %.9g\n", firstDiff,
                        cases[firstDiff].label.c_str(), aot.batch[0][firstDiff], batch[0][firstDiff]);
        return batchDiff || evalDiff || statusDiff || aot.batchCount != count ? 1 : 0;
    }

    if (mode == "against-interpreter") {
        Interpreter<double> interp(*material, kernel->energyTable());
        HardCaseReference ref = evaluateHardCaseReference(interp, cases);
        QuadReference quad(*material);
        std::vector<double> kappa(n, -1);
        auto condition = [&](size_t i) { return kappa[i] >= 0 ? kappa[i] : kappa[i] = quad.condition(cases[i]); };
        KernelRun target;
        target.rgb.resize(n);
        for (size_t i = 0; i < n; ++i) target.rgb[i] = {aot.batch[0][i], aot.batch[1][i], aot.batch[2][i]};
        target.invalid = aot.invalid;
        target.batchCount = aot.batchCount;
        for (char v : aot.invalid) target.laneCount += v != 0;
        MathMode math = options.math;
        SampleStats aotStats = checkKernel("aot", target, cases, ref, hardCaseBound(math), condition, hardCaseRoundoff(math));
        SampleStats jitStats = checkKernel("jit", jit, cases, ref, hardCaseBound(math), condition, hardCaseRoundoff(math));
        std::printf("%s %s [%s], %zu lanes against the double interpreter:\n  AOT object: %s\n  host JIT:   %s\n",
                    file.c_str(), name.c_str(), spec.c_str(), n, aotStats.summary().c_str(), jitStats.summary().c_str());
        for (const auto& [i, why] : aotStats.failures)
            std::printf("  AOT failure, lane %zu (%s): %s\n", i, cases[i].label.c_str(), why.c_str());
        return aotStats.ok() && jitStats.ok() && aotStats.nan + aotStats.inf + aotStats.negative == 0 ? 0 : 1;
    }
    return usage();
}
