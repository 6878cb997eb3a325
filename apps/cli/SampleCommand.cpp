// facet sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S] [--material NAME]
//                   [--backend interp|scalar|simd] [--math exact|fast]
//
// Draws N samples of wi for the view direction wo at the material's default
// inputs and writes one CSV row per sample:
// wi_x,wi_y,wi_z,pdf,weight_r,weight_g,weight_b. The backend is eval's:
// simd (the default) and scalar run the kernel's compiled sampler (float,
// %.9g; a material whose NDF has no compiled sampler samples through the
// reference, and a note says so), interp the reference sampler
// (compiler/reference/Sampling.h, the interpreter in double, %.17g). The uniform
// numbers come from a 64-bit Mersenne Twister seeded with S (default 1),
// 53 bits each (rounded down to float below 1 for the kernels), so a seed
// gives the same samples on every platform. With
// --out, a summary goes to standard output: the mean weight per channel
// (an estimate of the directional albedo) and how many samples fell below
// the horizon (a refracting lobe's transmitted ones; wo may be below it too).
#include "Commands.h"

#include "Checker.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"
#include "Sampling.h"
#include "SamplingSetup.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <optional>

namespace facet {

namespace {

constexpr const char* kSampleUsage =
    "usage: facet sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S] [--material NAME]\n"
    "                     [--backend interp|scalar|simd] [--math exact|fast]\n"
    "  wo: the unit view direction, pointing away from the surface (n = +z); on either side of it\n"
    "      for a lobe that scatters below the surface (scatter = transmit | both, thin = true)\n";
constexpr long kMaxSamples = 100000000;
constexpr long kSampleChunk = 65536;

struct SampleUsageError {
    std::string message;
};

long parseCount(const std::string& text) {
    char* end = nullptr;
    long n = std::strtol(text.c_str(), &end, 10);
    if (end == text.c_str() || *end || n < 1 || n > kMaxSamples)
        throw SampleUsageError{fmt::format("-n expects a whole number from 1 to {}, got '{}'", kMaxSamples, text)};
    return n;
}

int runSample(const std::vector<std::string>& args) {
    std::string file, material, out, wo, backend = "simd", math = "exact";
    long count = 1000;
    uint64_t seed = 1;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--wo" || a == "-n" || a == "--out" || a == "-o" || a == "--seed" || a == "--material" ||
            a == "--backend" || a == "--math") {
            if (i + 1 >= args.size()) throw SampleUsageError{a + " needs a value"};
            const std::string& v = args[++i];
            if (a == "--wo") wo = v;
            else if (a == "--backend") backend = v;
            else if (a == "--math") math = v;
            else if (a == "-n") count = parseCount(v);
            else if (a == "--seed") {
                if (std::string why = parseSeed(a, v, seed); !why.empty()) throw SampleUsageError{why};
            }
            else if (a == "--material") material = v;
            else out = v;
        } else if (!a.empty() && a[0] == '-') {
            throw SampleUsageError{fmt::format("unknown option '{}'", a)};
        } else if (file.empty()) {
            file = a;
        } else {
            throw SampleUsageError{fmt::format("more than one material file ('{}' and '{}')", file, a)};
        }
    }
    if (file.empty()) throw SampleUsageError{"no material file given"};
    if (wo.empty()) throw SampleUsageError{"--wo X,Y,Z is required"};
    if (backend != "interp" && backend != "scalar" && backend != "simd")
        throw SampleUsageError{fmt::format("--backend '{}' is not interp, scalar or simd", backend)};
    if (math != "exact" && math != "fast") throw SampleUsageError{fmt::format("--math '{}' is not exact or fast", math)};
    std::array<double, 3> view;
    if (std::string why = parseViewDirection("--wo", wo, view); !why.empty()) throw SampleUsageError{why};
    if (!out.empty() && out != "-")
        if (std::string why = sameFileProblem("facet sample", out, {{file, "the material file"}}); !why.empty())
            throw SampleUsageError{why};

    NamedMaterial named = loadNamedMaterial(file, material);
    if (named.fileErrors) return kExitMaterialError;
    if (!named.material) throw SampleUsageError{named.missing};
    const CheckedMaterial* m = named.material;
    if (std::string why = viewSideProblem("--wo", wo, view, *m); !why.empty()) throw SampleUsageError{why};
    SampleUniforms uniforms(seed);
    auto uniform = [&] { return uniforms.next(); };
    std::array<double, 3> sum{};
    long below = 0, invalid = 0;
    // The kernel first: a material that does not compile leaves the output
    // untouched.
    std::optional<Compiler> compiler;  // (a JIT: only for the compiled backends)
    std::unique_ptr<Kernel> kernel;
    if (backend != "interp") {
        compiler.emplace();
        CompileOptions options;
        std::string problem = CompileOptions::parse(fmt::format("backend={};math={}", backend, math), options);
        internal_assert(problem.empty()) << problem;
        DiagnosticEngine diags;
        kernel = compiler->compileMaterial(*m, options, diags);
        if (!kernel) {
            std::fputs(diags.str().c_str(), stderr);
            return kExitMaterialError;
        }
        if (!kernel->samplerError().empty())
            std::fprintf(stderr, "facet: warning: material %s: %s; sampling through the reference\n",
                         m->name.c_str(), kernel->samplerError().c_str());
        else if (kernel->samplerTier() != "jit")
            std::fprintf(stderr, "facet: note: material %s has no compiled sampler (%s); sampling through the "
                                 "reference\n", m->name.c_str(), samplerlessWhat(*m).c_str());
    }
    OutputStream output(out);
    if (!output.write("wi_x,wi_y,wi_z,pdf,weight_r,weight_g,weight_b\n")) return kExitFailed;
    // Samples are drawn and written kSampleChunk at a time, so that memory
    // stays the same whatever N is.
    std::string csv;
    if (backend == "interp") {
        std::unique_ptr<Interpreter<double>> interp = referenceInterpreter(*m);
        for (long i = 0; i < count; ++i) {
            double u[3] = {uniform(), uniform(), uniform()};
            SampleResult<double> s = interp->sample(view.data(), u, nullptr);
            invalid += !s.valid;
            below += s.valid && s.pdf > 0 && s.wi.z <= 0;
            for (int ch = 0; ch < 3; ++ch) sum[ch] += s.weight[ch];
            csv += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", s.wi.x, s.wi.y, s.wi.z,
                               s.pdf, s.weight[0], s.weight[1], s.weight[2]);
            if ((i + 1) % kSampleChunk == 0 || i + 1 == count) {
                if (!output.write(csv)) return kExitFailed;
                csv.clear();
            }
        }
    } else {
        const float wo3[3] = {float(view[0]), float(view[1]), float(view[2])};
        const size_t chunk = size_t(std::min<long>(count, kSampleChunk));
        std::array<std::vector<float>, 3> wos, us, wis, weights;
        std::vector<float> pdfs(chunk);
        for (int c = 0; c < 3; ++c) {
            wos[c].assign(chunk, wo3[c]);
            wis[c].resize(chunk), weights[c].resize(chunk), us[c].resize(chunk);
        }
        const float* woP[3] = {wos[0].data(), wos[1].data(), wos[2].data()};
        const float* uP[3] = {us[0].data(), us[1].data(), us[2].data()};
        float* wiP[3] = {wis[0].data(), wis[1].data(), wis[2].data()};
        float* weightP[3] = {weights[0].data(), weights[1].data(), weights[2].data()};
        for (long done = 0; done < count;) {
            const size_t n = size_t(std::min<long>(count - done, long(chunk)));
            // Floats below 1: a double u rounds down, never up to 1.
            for (size_t i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) {
                    float f = float(uniform());
                    us[c][i] = f < 1 ? f : std::nextafter(1.0f, 0.0f);
                }
            invalid += long(kernel->sampleBatch(int64_t(n), woP, uP, nullptr, wiP, pdfs.data(), weightP));
            csv.clear();
            for (size_t i = 0; i < n; ++i) {
                below += pdfs[i] > 0 && wis[2][i] <= 0;
                for (int ch = 0; ch < 3; ++ch) sum[ch] += weights[ch][i];
                csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", wis[0][i], wis[1][i],
                                   wis[2][i], pdfs[i], weights[0][i], weights[1][i], weights[2][i]);
            }
            if (!output.write(csv)) return kExitFailed;
            done += long(n);
        }
    }
    if (!output.finish()) return kExitFailed;
    if (invalid > 0) {
        std::fprintf(stderr, "facet: sample: %ld of %ld samples are invalid (the material's default inputs are not "
                             "finite, or a result overflowed); their rows are zero\n", invalid, count);
        return kExitFailed;
    }
    if (!out.empty() && out != "-")
        std::printf("%ld samples of material %s at wo = (%s): mean weight (%.6f, %.6f, %.6f), %ld below the "
                    "horizon; wrote %s\n",
                    count, m->name.c_str(), wo.c_str(), sum[0] / count, sum[1] / count, sum[2] / count, below,
                    out.c_str());
    return kExitOk;
}

}  // namespace

int cmdSample(const std::vector<std::string>& args) {
    try {
        return runSample(args);
    } catch (const SampleUsageError& e) {
        std::fprintf(stderr, "facet: sample: %s\n%s", e.message.c_str(), kSampleUsage);
        return kExitUsage;
    }
}

}  // namespace facet
