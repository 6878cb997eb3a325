// WalkComparison: the closed-form lobe against the random walk; see the
// header for the two measures.
#include "WalkComparison.h"

#include "Sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace facet {
namespace {

using V = Vec3<double>;

// The model's albedo at wo by its reference sampler: u1, u2 stratified on
// an n x n grid with a jitter, u0 (the mixture's choice) random.
std::array<double, 3> samplerAlbedo(const ResolvedMaterial<double>& model, const V& wo, int64_t samples, uint64_t seed) {
    int n = std::max(1, int(std::sqrt(double(samples))));
    std::array<double, 3> sum{};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            WalkRandom random(seed, uint64_t(i) * uint64_t(n) + uint64_t(j));
            std::array<double, 3> u{random.next(), (i + random.next()) / n, (j + random.next()) / n};
            SampleResult<double> s = sampleBrdf(model, wo, u);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += s.weight[ch];
        }
    for (double& v : sum) v /= double(n) * double(n);
    return sum;
}

}  // namespace

std::vector<WalkComparisonRow> compareWithWalk(const ResolvedMaterial<double>& lobe, const WalkComparisonOptions& options) {
    ResolvedMaterial<double> model = lobe;
    model.diffuse = lobe.specularLobe().diffuse;  // the `none` base
    ResolvedMaterial<double> single = model.withoutEnergy();
    MicrosurfaceWalk walk(lobe);
    std::vector<WalkComparisonRow> rows;
    for (double theta : options.thetas) {
        double t = theta * std::numbers::pi / 180;
        V wo{std::sin(t), 0, std::cos(t)};
        WalkComparisonRow row;
        row.thetaO = theta;
        WalkEstimate a = walk.albedo(wo, options.albedoPaths, options.seed);
        row.walkAlbedo = a.mean, row.walkAlbedoError = a.stdError, row.abandoned = a.abandoned;
        row.modelAlbedo = samplerAlbedo(model, wo, 4 * options.albedoPaths, options.seed + 1);
        row.singleAlbedo = samplerAlbedo(single, wo, 4 * options.albedoPaths, options.seed + 1);
        // Cells of equal projected solid angle: mu^2 uniform in [0, 1], phi uniform.
        double walkSquares = 0, noiseSquares = 0, modelSquares = 0, singleSquares = 0;
        for (int i = 0; i < options.gridTheta; ++i)
            for (int j = 0; j < options.gridPhi; ++j) {
                double mu = std::sqrt((i + 0.5) / options.gridTheta), s = std::sqrt(1 - mu * mu);
                double phi = 2 * std::numbers::pi * (j + 0.5) / options.gridPhi;
                V wi{s * std::cos(phi), s * std::sin(phi), mu};
                uint64_t cellSeed = options.seed + 2 + uint64_t(i * options.gridPhi + j) * 0x10001ull;
                WalkEstimate f = walk.brdf(wi, wo, options.brdfPaths, cellSeed);
                row.abandoned += f.abandoned;
                std::array<double, 3> fm = model.brdf(wi, wo), fs = single.brdf(wi, wo);
                for (int ch = 0; ch < 3; ++ch) {
                    walkSquares += f.mean[ch] * f.mean[ch];
                    noiseSquares += f.stdError[ch] * f.stdError[ch];
                    modelSquares += (fm[ch] - f.mean[ch]) * (fm[ch] - f.mean[ch]);
                    singleSquares += (fs[ch] - f.mean[ch]) * (fs[ch] - f.mean[ch]);
                }
            }
        if (walkSquares > 0) {
            row.modelShapeError = std::sqrt(std::max(0.0, modelSquares - noiseSquares) / walkSquares);
            row.singleShapeError = std::sqrt(std::max(0.0, singleSquares - noiseSquares) / walkSquares);
            row.shapeNoise = std::sqrt(noiseSquares / walkSquares);
        }
        rows.push_back(row);
    }
    return rows;
}

}  // namespace facet
