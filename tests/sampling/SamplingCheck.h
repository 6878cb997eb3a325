// SamplingCheck: one goodness-of-fit run of a sampler against a pdf for one
// view direction (ChiSquare.h): histogram of the samples, the pdf integrated
// over the same cells, the normalization and Pearson's test.
#pragma once

#include "ChiSquare.h"
#include "Sampling.h"

#include <array>
#include <cstdint>
#include <functional>
#include <string>

namespace sampling_test {

using namespace facet;
using V3 = Vec3<double>;

using Sampler = std::function<facet::SampleResult<double>(const std::array<double, 3>& u)>;

struct CheckSettings {
    int samples = 100000;
    double minExpected = 5;
    double level = 0.01;       // per test (already Sidak-corrected)
    uint64_t seed = 1;
    bool renormalize = false;  // scale the expected counts to the samples drawn (shape only)
    // The normalization the caller asserts (|integral - 1| <= it). The
    // cells are integrated to a tenth of it in all, which also keeps each
    // expected count within a fraction of a sample of its exact value.
    double normalizationTolerance = 1e-4;
};

struct CheckOutcome {
    double integral = 0;       // the pdf over the whole sphere
    double belowHorizon = 0;   // ... over n.wi < 0
    int noSample = 0;          // draws that returned pdf = 0
    Chi2Outcome chi2;
    std::string describe() const;
};

CheckOutcome checkSampler(const Sampler& sampler, const PdfFunction& pdf, const SphereGrid& grid,
                          const CheckSettings& settings);

// The same for a resolved material and a view direction: sampleBrdf
// against brdfPdf (or `pdf` when given), on a grid graded toward the mirror
// direction of wo from half the lobe's smallest roughness.
// The grid of checkMaterial: graded toward the mirror direction of wo from
// half the lobe's smallest roughness.
SphereGrid lobeGrid(const facet::ResolvedMaterial<double>& r, const V3& wo);

CheckOutcome checkMaterial(const facet::ResolvedMaterial<double>& r, const V3& wo, const CheckSettings& settings,
                           const PdfFunction& pdf = nullptr);

}  // namespace sampling_test
