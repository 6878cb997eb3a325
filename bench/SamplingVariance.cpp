// facet_sampling_variance: the importance-sampling technique table (SPEC 8).
//
//   facet_sampling_variance [--size N] [--samples N] [--reference-samples N] [--threads N]
//
// Renders the preview sphere under the sky for GGX, Beckmann and
// Blinn-Phong at alpha 0.05 and 0.3 once per technique (visible normals,
// NDF sampling, cosine sampling) at --samples per pixel (default 16) and
// prints the RMSE against a --reference-samples (default 4096) render as a
// Markdown table (apps/preview/SamplingVariance.h). Exit status 1 when
// visible normals are not the lowest RMSE in a row where they apply.
#include "SamplingVariance.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

using namespace facet;

namespace {

int usage(const char* why) {
    std::fprintf(stderr,
                 "facet_sampling_variance: %s\nusage: facet_sampling_variance [--size N] [--samples N] "
                 "[--reference-samples N] [--threads N]\n",
                 why);
    return 2;
}

bool parseCount(const char* text, int lo, int hi, int& out) {
    char* end = nullptr;
    long v = std::strtol(text, &end, 10);
    if (!end || *end || end == text || v < lo || v > hi) return false;
    out = int(v);
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    preview::VarianceSettings settings;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        int* target = a == "--size"                ? &settings.size
                      : a == "--samples"           ? &settings.samples
                      : a == "--reference-samples" ? &settings.referenceSamples
                      : a == "--threads"           ? &settings.threads
                                                   : nullptr;
        if (!target) return usage(("unknown argument '" + a + "'").c_str());
        if (i + 1 >= argc) return usage((a + " needs a value").c_str());
        int lo = a == "--threads" ? 0 : (a == "--size" ? 8 : 1);
        if (!parseCount(argv[++i], lo, a == "--size" ? 4096 : 1 << 20, *target))
            return usage((a + ": '" + argv[i] + "' is not a count in range").c_str());
    }
    try {
        Compiler compiler;
        std::vector<preview::VarianceRow> rows = preview::measureSamplingVariance(compiler, settings);
        std::printf("%s", preview::varianceTable(rows, settings).c_str());
        int failures = 0;
        for (const preview::VarianceRow& r : rows) {
            if (!r.rmse[0]) continue;
            for (size_t t = 1; t < r.rmse.size(); ++t)
                if (r.rmse[t] && *r.rmse[t] < *r.rmse[0]) ++failures;
        }
        if (failures) std::printf("\nvisible normals are not the lowest in %d comparisons\n", failures);
        return failures ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "facet_sampling_variance: %s\n", e.what());
        return 1;
    }
}
