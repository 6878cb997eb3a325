// SamplingVariance: what the importance-sampling technique is worth, measured
// the way a renderer sees it (SPEC 8).
//
// For GGX, Beckmann and Blinn-Phong lobes (Smith height-correlated masking,
// Schlick F0 = 0.9, no diffuse) at alpha 0.05 and 0.3, the preview renderer
// (SphereRender.h) draws the sphere under the sky alone (the light's eval
// lane has no variance) with a few samples per pixel, once per technique of
// compiler/reference/Sampling.h: visible normals, NDF sampling and cosine sampling, all
// through the double reference sampler with exact pdfs (so every image is an
// unbiased estimate of the same one). Each is compared with a render of many
// samples per pixel by the kernel's own sampler: the RMSE of the radiance
// over the pixels the sphere covers. The same point set per pixel serves
// every technique, so the differences are the techniques'.
//
// Used by `facet_sampling_variance` (bench/, prints the table) and the test
// that asserts visible normals are the lowest (tests/preview).
#pragma once

#include "Kernel.h"
#include "Sampling.h"

#include <optional>
#include <string>
#include <vector>

namespace facet::preview {

struct VarianceSettings {
    int size = 128;               // image width = height
    int samples = 16;             // per pixel, per technique
    int referenceSamples = 4096;  // per pixel, the reference render
    int threads = 0;              // 0: every core
};

struct VarianceRow {
    std::string ndf;       // "ggx", "beckmann", "blinn_phong"
    double alpha = 0;
    std::string material;  // the material's source
    // RMSE per technique, in the order of kVarianceTechniques; none where
    // the technique does not apply (no visible-normal sampler).
    std::vector<std::optional<double>> rmse;
    double referenceMean = 0;  // mean radiance of the reference (for scale)
    double seconds = 0;        // wall time of the row's renders
};

// The techniques compared, in table order.
inline constexpr SamplingTechnique kVarianceTechniques[] = {SamplingTechnique::VisibleNormals,
                                                            SamplingTechnique::Normals, SamplingTechnique::Cosine};

// Runs the study over the six materials; `compiler` compiles the kernels
// (SIMD exact). Throws std::runtime_error if a material fails to compile.
std::vector<VarianceRow> measureSamplingVariance(Compiler& compiler, const VarianceSettings& settings);

// The table in Markdown, with the settings in a sentence above it.
std::string varianceTable(const std::vector<VarianceRow>& rows, const VarianceSettings& settings);

}  // namespace facet::preview
