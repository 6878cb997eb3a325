// facet sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S] [--material NAME]
//
// Draws N samples of wi for the view direction wo with the reference
// sampler (compiler/Sampling.h, the interpreter in double) at the
// material's default inputs, and writes one CSV row per sample:
// wi_x,wi_y,wi_z,pdf,weight_r,weight_g,weight_b (%.17g). The uniform
// numbers come from a 64-bit Mersenne Twister seeded with S (default 1),
// 53 bits each, so a seed gives the same samples on every platform. With
// --out, a summary goes to standard output: the mean weight per channel
// (an estimate of the directional albedo) and how many samples fell below
// the horizon.
#include "Commands.h"

#include "Checker.h"
#include "OutputFile.h"
#include "Sampling.h"
#include "SamplingSetup.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <random>

namespace facet {

namespace {

constexpr const char* kSampleUsage =
    "usage: facet sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S] [--material NAME]\n"
    "  wo: the unit view direction, pointing away from the surface (n = +z)\n";
constexpr long kMaxSamples = 100000000;

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

uint64_t parseSeed(const std::string& text) {
    char* end = nullptr;
    unsigned long long s = std::strtoull(text.c_str(), &end, 10);
    if (end == text.c_str() || *end || text[0] == '-')
        throw SampleUsageError{fmt::format("--seed expects a whole number from 0 to 2^64 - 1, got '{}'", text)};
    return s;
}

int runSample(const std::vector<std::string>& args) {
    std::string file, material, out, wo;
    long count = 1000;
    uint64_t seed = 1;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--wo" || a == "-n" || a == "--out" || a == "-o" || a == "--seed" || a == "--material") {
            if (i + 1 >= args.size()) throw SampleUsageError{a + " needs a value"};
            const std::string& v = args[++i];
            if (a == "--wo") wo = v;
            else if (a == "-n") count = parseCount(v);
            else if (a == "--seed") seed = parseSeed(v);
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
    std::array<double, 3> view;
    if (std::string why = parseViewDirection("--wo", wo, view); !why.empty()) throw SampleUsageError{why};

    DiagnosticEngine diags;
    CheckedProgram program = loadProgramFile(file, diags);
    if (diags.hasErrors()) {
        std::fputs(diags.str().c_str(), stderr);
        return 65;
    }
    const CheckedMaterial* m = program.find(material);
    if (!m) throw SampleUsageError{fmt::format("no material named '{}' in {}", material, file)};
    std::unique_ptr<Interpreter<double>> interp = referenceSampler(*m);

    std::mt19937_64 rng(seed);
    auto uniform = [&] { return double(rng() >> 11) * 0x1p-53; };  // [0, 1), the same on every platform
    std::string csv = "wi_x,wi_y,wi_z,pdf,weight_r,weight_g,weight_b\n";
    std::array<double, 3> sum{};
    long below = 0, invalid = 0;
    for (long i = 0; i < count; ++i) {
        double u[3] = {uniform(), uniform(), uniform()};
        SampleResult<double> s = interp->sample(view.data(), u, nullptr);
        invalid += !s.valid;
        below += s.valid && s.pdf > 0 && s.wi.z <= 0;
        for (int ch = 0; ch < 3; ++ch) sum[ch] += s.weight[ch];
        csv += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", s.wi.x, s.wi.y, s.wi.z, s.pdf,
                           s.weight[0], s.weight[1], s.weight[2]);
    }
    if (!writeOutput(out, csv)) return 1;
    if (invalid > 0) {
        std::fprintf(stderr, "facet: sample: %ld of %ld samples are invalid (the material's default inputs are not "
                             "finite, or a result overflowed); their rows are zero\n", invalid, count);
        return 1;
    }
    if (!out.empty() && out != "-")
        std::printf("%ld samples of material %s at wo = (%s): mean weight (%.6f, %.6f, %.6f), %ld below the "
                    "horizon; wrote %s\n",
                    count, m->name.c_str(), wo.c_str(), sum[0] / count, sum[1] / count, sum[2] / count, below,
                    out.c_str());
    return 0;
}

}  // namespace

int cmdSample(const std::vector<std::string>& args) {
    try {
        return runSample(args);
    } catch (const SampleUsageError& e) {
        std::fprintf(stderr, "facet: sample: %s\n%s", e.message.c_str(), kSampleUsage);
        return 2;
    }
}

}  // namespace facet
