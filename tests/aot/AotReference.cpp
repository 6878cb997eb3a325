// facet_aot_reference: the JIT side of the ahead-of-time tests.
//
//   facet_aot_reference inputs FILE.mat MATERIAL OPTIONS RANDOM INPUTS.bin
//       writes the lanes: the hard-case sample of the material (SPEC 7)
//       followed by RANDOM random direction pairs (uniform over the sphere,
//       so a quarter with both directions above the horizon) with inputs
//       uniform over their ranges, and three uniform numbers per lane for
//       the sampler (on the hard cases also 0, the float below 1, and
//       invalid ones: 1, negative, NaN).
//   facet_aot_reference same-as-jit FILE.mat MATERIAL OPTIONS RANDOM OUTPUTS.bin
//       compiles the JIT kernel of OPTIONS (facet_compile_file's option
//       string) and requires aot_run's outputs to be its outputs bit for bit:
//       the batch call, the one-lane eval entry, the invalid count; and the
//       sampler's (sample and pdf, batch and one-lane, invalid counts and
//       lanes), which the object must have exactly where the JIT kernel has
//       a compiled sampler.
//   facet_aot_reference against-interpreter FILE.mat MATERIAL OPTIONS RANDOM OUTPUTS.bin
//       checks aot_run's outputs (of an object for another target) against
//       the double interpreter as the hard-case tests check the host JIT
//       (apps/verify/Verify.h: bound, ill-conditioning allowance, no NaN, Inf
//       or negative output, invalid lanes 0 and counted), and checks the
//       host JIT kernel of the same options the same way, for comparison;
//       the object's sampler against the host JIT kernel's (the same invalid
//       lanes, wi within 1e-5, pdf and weight within 1e-4 relative, at most
//       one lane in 10^4 apart, where u0 falls within rounding of the lobe
//       probability).
// Exit 0 when the check passes, 1 when it fails, 2 on a usage or I/O error.
#include "Checker.h"
#include "HardCases.h"
#include "Kernel.h"
#include "Verify.h"

#include <array>
#include <limits>
#include <algorithm>
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

// Three uniform numbers per lane; `hard` lanes first (the hard cases).
std::vector<std::array<float, 3>> uniforms(size_t n, size_t hard) {
    std::mt19937_64 rng(0x5a3);
    std::uniform_real_distribution<double> u(0, 1);
    const float below1 = std::nextafter(1.0f, 0.0f), nan = std::numeric_limits<float>::quiet_NaN();
    const std::array<float, 3> edges[] = {
        {0, 0, 0}, {below1, below1, below1}, {1, 0.5f, 0.5f}, {0.5f, -1e-30f, 0.5f}, {0.5f, 0.5f, nan}};
    std::vector<std::array<float, 3>> out(n);
    for (size_t i = 0; i < n; ++i) {
        if (i < hard && i % 8 < 5) {
            out[i] = edges[i % 8];
            continue;
        }
        for (float& v : out[i]) v = std::min(float(u(rng)), below1);
    }
    return out;
}

// The sampler's outputs for n lanes: sample (wi, pdf, weight as 7 streams)
// through the batch call and lane by lane, and pdf through both.
struct SamplerRun {
    int64_t sampleCount = 0, pdfCount = 0;
    std::vector<float> sampleBatch, sampleScalar, pdf;  // 7 n, 7 n, 2 n (batch, one-lane)
    std::vector<char> sampleInvalid;                    // one-lane calls
};

struct AotRun {
    std::vector<float> batch[3], eval[3];
    int64_t batchCount = 0;
    std::vector<char> invalid;
    bool hasSampler = false;
    SamplerRun sampler;
};

template <typename T>
bool readVector(std::ifstream& in, std::vector<T>& v, size_t count) {
    v.resize(count);
    return bool(in.read(reinterpret_cast<char*>(v.data()), std::streamsize(count * sizeof(T))));
}

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
    int32_t hasSampler = 0;
    if (!in.read(reinterpret_cast<char*>(&run.batchCount), 8) || !readVector(in, run.invalid, n) ||
        !in.read(reinterpret_cast<char*>(&hasSampler), 4) || (hasSampler != 0 && hasSampler != 1))
        return false;
    run.hasSampler = hasSampler == 1;
    SamplerRun& s = run.sampler;
    if (run.hasSampler &&
        (!in.read(reinterpret_cast<char*>(&s.sampleCount), 8) || !readVector(in, s.sampleBatch, 7 * n) ||
         !readVector(in, s.sampleScalar, 7 * n) || !readVector(in, s.sampleInvalid, n) ||
         !in.read(reinterpret_cast<char*>(&s.pdfCount), 8) || !readVector(in, s.pdf, 2 * n)))
        return false;
    return in.peek() == std::char_traits<char>::eof();
}

// The JIT kernel's sampler on the lanes, as aot_run calls the object's.
SamplerRun runSampler(const Kernel& kernel, const std::vector<HardCase>& cases,
                      const std::vector<std::array<float, 3>>& u) {
    const size_t n = cases.size();
    const int slots = kernel.inputCount();
    std::vector<float> dir[9], in(std::max(1, slots) * n);
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 9; ++k) dir[k].push_back(k < 3 ? float(cases[i].wi[k]) : k < 6 ? float(cases[i].wo[k - 3]) : u[i][k - 6]);
    std::vector<const float*> inPtr;
    for (int s = 0; s < slots; ++s) {
        for (size_t i = 0; i < n; ++i) in[s * n + i] = float(cases[i].slots[s]);
        inPtr.push_back(&in[s * n]);
    }
    SamplerRun r;
    r.sampleBatch.assign(7 * n, -1.0f), r.sampleScalar.assign(7 * n, -1.0f), r.pdf.assign(2 * n, -1.0f);
    r.sampleInvalid.assign(n, 0);
    const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
    const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
    const float* uu[3] = {dir[6].data(), dir[7].data(), dir[8].data()};
    float* swi[3] = {&r.sampleBatch[0], &r.sampleBatch[n], &r.sampleBatch[2 * n]};
    float* sweight[3] = {&r.sampleBatch[4 * n], &r.sampleBatch[5 * n], &r.sampleBatch[6 * n]};
    const float* const* inputs = slots ? inPtr.data() : nullptr;
    r.sampleCount = kernel.sampleBatch(int64_t(n), wo, uu, inputs, swi, &r.sampleBatch[3 * n], sweight);
    r.pdfCount = kernel.pdfBatch(int64_t(n), wi, wo, inputs, r.pdf.data());
    std::vector<float> lane(std::max(1, slots));
    for (size_t i = 0; i < n; ++i) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]};
        float c[3] = {uu[0][i], uu[1][i], uu[2][i]}, w[3], p, weight[3];
        for (int s = 0; s < slots; ++s) lane[s] = in[s * n + i];
        r.sampleInvalid[i] = !kernel.sample(b, c, slots ? lane.data() : nullptr, w, &p, weight);
        for (int k = 0; k < 3; ++k) r.sampleScalar[k * n + i] = w[k], r.sampleScalar[(4 + k) * n + i] = weight[k];
        r.sampleScalar[3 * n + i] = p;
        r.pdf[n + i] = kernel.pdf(a, b, slots ? lane.data() : nullptr);
    }
    return r;
}


bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Lanes whose `streams` consecutive streams of n floats (from stream
// `first`) differ in any bit between a and b.
size_t differingLanes(const std::vector<float>& a, const std::vector<float>& b, size_t n, size_t first, size_t streams) {
    size_t lanes = 0;
    for (size_t i = 0; i < n; ++i) {
        bool same = true;
        for (size_t k = first; k < first + streams; ++k) same &= sameBits(a[k * n + i], b[k * n + i]);
        lanes += !same;
    }
    return lanes;
}

// The object's sampler (another target's) against the host JIT kernel's:
// lanes whose invalid status differs, or whose wi differs by more than
// 1e-5 or pdf, weight or the pdf call by more than 1e-4 relative, or whose
// output is not finite or negative where a probability or weight is.
struct SamplerDeviation {
    size_t lanes = 0, status = 0;
    double wi = 0, rel = 0;  // largest deviations among the lanes within bounds
};
SamplerDeviation compareSamplers(const SamplerRun& object, const SamplerRun& jit, size_t n) {
    SamplerDeviation d;
    auto rel = [](float x, float y) { return x == y ? 0.0 : std::fabs(double(x) - y) / std::max(std::fabs(double(y)), 1e-30); };
    for (size_t i = 0; i < n; ++i) {
        if (object.sampleInvalid[i] != jit.sampleInvalid[i]) {
            ++d.status, ++d.lanes;
            continue;
        }
        double wi = 0, worst = 0;
        bool finite = true;
        for (size_t k = 0; k < 7; ++k) {
            float x = object.sampleBatch[k * n + i], y = jit.sampleBatch[k * n + i];
            finite &= std::isfinite(x) && (k < 3 || x >= 0);
            if (k < 3) wi = std::max(wi, std::fabs(double(x) - y));
            else worst = std::max(worst, rel(x, y));
        }
        for (size_t k = 0; k < 2; ++k) {
            float x = object.pdf[k * n + i], y = jit.pdf[k * n + i];
            finite &= std::isfinite(x) && x >= 0;
            worst = std::max(worst, rel(x, y));
        }
        if (!finite || wi > 1e-5 || worst > 1e-4) {
            ++d.lanes;
            continue;
        }
        d.wi = std::max(d.wi, wi), d.rel = std::max(d.rel, worst);
    }
    return d;
}

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
    const std::vector<std::array<float, 3>> u = uniforms(n, n - random);

    if (mode == "inputs") {
        std::ofstream out(path, std::ios::binary);
        int32_t s32 = slots;
        int64_t n64 = int64_t(n);
        out.write("FACETAOT", 8);
        out.write(reinterpret_cast<const char*>(&s32), 4);
        out.write(reinterpret_cast<const char*>(&n64), 8);
        std::vector<float> stream(n);
        for (int k = 0; k < 9 + slots; ++k) {
            for (size_t i = 0; i < n; ++i)
                stream[i] = k < 3           ? float(cases[i].wi[k])
                            : k < 6         ? float(cases[i].wo[k - 3])
                            : k < 6 + slots ? float(cases[i].slots[k - 6])
                                            : u[i][k - 6 - slots];
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
        const bool jitSampler = kernel->samplerTier() == "jit";
        bool samplerFailed = aot.hasSampler != jitSampler;
        if (samplerFailed) {
            std::printf("  FAIL: the object %s sampler functions, the JIT kernel samples through %s\n",
                        aot.hasSampler ? "has" : "has no", jitSampler ? "its compiled sampler" : "the reference");
        } else if (!jitSampler) {
            std::printf("  no compiled sampler: the object has none, as the JIT kernel (reference sampling)\n");
        } else {
            SamplerRun j = runSampler(*kernel, cases, u);
            const SamplerRun& a = aot.sampler;
            size_t sampleBatch = differingLanes(a.sampleBatch, j.sampleBatch, n, 0, 7);
            size_t sample = differingLanes(a.sampleScalar, j.sampleScalar, n, 0, 7);
            size_t pdfBatch = differingLanes(a.pdf, j.pdf, n, 0, 1), pdf = differingLanes(a.pdf, j.pdf, n, 1, 1);
            size_t status = 0, invalid = 0;
            for (size_t i = 0; i < n; ++i) status += a.sampleInvalid[i] != j.sampleInvalid[i], invalid += a.sampleInvalid[i];
            std::printf("  sampler: differing from the JIT kernel: sample batch %zu, sample %zu, pdf batch %zu, pdf "
                        "%zu, lane status %zu; invalid samples AOT %lld, JIT %lld; invalid pdf lanes AOT %lld, "
                        "JIT %lld\n",
                        sampleBatch, sample, pdfBatch, pdf, status, (long long)a.sampleCount,
                        (long long)j.sampleCount, (long long)a.pdfCount, (long long)j.pdfCount);
            samplerFailed = sampleBatch || sample || pdfBatch || pdf || status || a.sampleCount != j.sampleCount ||
                            a.pdfCount != j.pdfCount || size_t(a.sampleCount) != invalid || invalid == 0 ||
                            size_t(a.sampleCount) == n;
        }
        return batchDiff || evalDiff || statusDiff || aot.batchCount != count || samplerFailed ? 1 : 0;
    }

    if (mode == "against-interpreter") {
        Interpreter<double> interp(*material, kernel->energyTable());
        HardCaseReference ref = evaluateHardCaseReference(interp, cases);
        QuadReference quad(*material, kernel->energyTable());
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
        bool samplerOk = aot.hasSampler == (kernel->samplerTier() == "jit");
        if (!samplerOk) {
            std::printf("  FAIL: the object %s sampler functions, the host JIT kernel %s\n",
                        aot.hasSampler ? "has" : "has no", aot.hasSampler ? "has none" : "has");
        } else if (aot.hasSampler) {
            SamplerDeviation d = compareSamplers(aot.sampler, runSampler(*kernel, cases, u), n);
            samplerOk = d.lanes <= std::max<size_t>(1, n / 10000);
            std::printf("  sampler against the host JIT kernel's: %zu lanes apart (%zu by invalid status), the "
                        "others within %.3g (wi) and %.3g relative (pdf, weight)\n",
                        d.lanes, d.status, d.wi, d.rel);
        }
        return aotStats.ok() && jitStats.ok() && aotStats.nan + aotStats.inf + aotStats.negative == 0 && samplerOk
                   ? 0
                   : 1;
    }
    return usage();
}
