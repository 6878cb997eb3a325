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

// An albedo by a sampler's mean weight, `weight(u)` for u0 (the mixture's
// choice) random and u1, u2 stratified on an n x n grid with a jitter.
template <typename Weight>
std::array<double, 3> stratifiedAlbedo(int64_t samples, uint64_t seed, const Weight& weight) {
    int n = std::max(1, int(std::sqrt(double(samples))));
    std::array<double, 3> sum{};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            WalkRandom random(seed, uint64_t(i) * uint64_t(n) + uint64_t(j));
            std::array<double, 3> u{random.next(), (i + random.next()) / n, (j + random.next()) / n};
            std::array<double, 3> w = weight(u);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += w[ch];
        }
    for (double& v : sum) v /= double(n) * double(n);
    return sum;
}

// A lobe's albedo at wo by its reference sampler.
std::array<double, 3> samplerAlbedo(const ResolvedMaterial<double>& model, const V& wo, int64_t samples, uint64_t seed) {
    return stratifiedAlbedo(samples, seed, [&](const std::array<double, 3>& u) { return sampleBrdf(model, wo, u).weight; });
}

// Two models' f and the walk's at one wi cell, per channel, with the walk's
// standard error: what the shape errors sum.
struct CellValues {
    std::array<double, 3> model{}, other{}, walk{}, walkError{};
};

// The shape errors of the two models over the grid of the options (the
// header's relative RMS with the walk's noise taken off), and that noise.
template <typename Cell>
void shapeErrors(const WalkComparisonOptions& options, const Cell& cell, double* error, double* otherError,
                 double* noise) {
    double walkSquares = 0, noiseSquares = 0, diffSquares = 0, otherSquares = 0;
    for (int i = 0; i < options.gridTheta; ++i)
        for (int j = 0; j < options.gridPhi; ++j) {
            // Cells of equal projected solid angle: mu^2 uniform in [0, 1], phi uniform.
            double mu = std::sqrt((i + 0.5) / options.gridTheta), s = std::sqrt(1 - mu * mu);
            double phi = 2 * std::numbers::pi * (j + 0.5) / options.gridPhi;
            V wi{s * std::cos(phi), s * std::sin(phi), mu};
            uint64_t cellSeed = options.seed + 2 + uint64_t(i * options.gridPhi + j) * 0x10001ull;
            CellValues v = cell(wi, cellSeed);
            for (int ch = 0; ch < 3; ++ch) {
                walkSquares += v.walk[ch] * v.walk[ch];
                noiseSquares += v.walkError[ch] * v.walkError[ch];
                diffSquares += (v.model[ch] - v.walk[ch]) * (v.model[ch] - v.walk[ch]);
                otherSquares += (v.other[ch] - v.walk[ch]) * (v.other[ch] - v.walk[ch]);
            }
        }
    auto relative = [&](double squares) {
        return walkSquares > 0 ? std::sqrt(std::max(0.0, squares - noiseSquares) / walkSquares) : 0.0;
    };
    *error = relative(diffSquares), *otherError = relative(otherSquares);
    *noise = walkSquares > 0 ? std::sqrt(noiseSquares / walkSquares) : 0.0;
}

V viewDirection(double theta) {
    double t = theta * std::numbers::pi / 180;
    return {std::sin(t), 0, std::cos(t)};
}

}  // namespace

std::vector<WalkComparisonRow> compareWithWalk(const ResolvedMaterial<double>& lobe, const WalkComparisonOptions& options) {
    ResolvedMaterial<double> model = lobe;
    model.diffuse = lobe.specularLobe().diffuse;  // the `none` base
    ResolvedMaterial<double> single = model.withoutEnergy();
    MicrosurfaceWalk walk(lobe);
    std::vector<WalkComparisonRow> rows;
    for (double theta : options.thetas) {
        V wo = viewDirection(theta);
        WalkComparisonRow row;
        row.thetaO = theta;
        WalkEstimate a = walk.albedo(wo, options.albedoPaths, options.seed);
        row.walkAlbedo = a.mean, row.walkAlbedoError = a.stdError, row.abandoned = a.abandoned;
        row.modelAlbedo = samplerAlbedo(model, wo, 4 * options.albedoPaths, options.seed + 1);
        row.singleAlbedo = samplerAlbedo(single, wo, 4 * options.albedoPaths, options.seed + 1);
        auto cell = [&](const V& wi, uint64_t seed) {
            WalkEstimate f = walk.brdf(wi, wo, options.brdfPaths, seed);
            row.abandoned += f.abandoned;
            return CellValues{model.brdf(wi, wo), single.brdf(wi, wo), f.mean, f.stdError};
        };
        shapeErrors(options, cell, &row.modelShapeError, &row.singleShapeError, &row.shapeNoise);
        rows.push_back(row);
    }
    return rows;
}

std::string layerWalkUnsupported(const CheckedMaterial& material, const ResolvedBsdf<double>& r) {
    const BsdfNode& root = material.bsdfRoot();
    if (root.kind != BsdfKind::Layer) return "the combination is not a layer";
    const BsdfNode& top = material.bsdf.at(size_t(root.a));
    const BsdfNode& base = material.bsdf.at(size_t(root.b));
    if (top.kind != BsdfKind::Lobe || base.kind != BsdfKind::Lobe)
        return "the layer's top and base must each be one lobe";
    return LayeredWalk::unsupported(r.lobes.at(size_t(top.lobe)), r.lobes.at(size_t(base.lobe)));
}

std::vector<WalkComparisonRow> compareLayerWithWalk(const Interpreter<double>& interp, const ResolvedBsdf<double>& r,
                                                    const WalkComparisonOptions& options) {
    const CheckedMaterial& m = interp.material();
    const BsdfNode& root = m.bsdfRoot();
    const ResolvedMaterial<double>& base = r.lobes.at(size_t(m.bsdf.at(size_t(root.b)).lobe));
    LayeredWalk walk(r.lobes.at(size_t(m.bsdf.at(size_t(root.a)).lobe)), base);
    const std::array<double, 3>& weight = r.weights.back();
    std::vector<WalkComparisonRow> rows;
    for (double theta : options.thetas) {
        V wo = viewDirection(theta);
        WalkComparisonRow row;
        row.thetaO = theta;
        // The model's albedo by the interpreter's sampler of the whole material.
        row.modelAlbedo = stratifiedAlbedo(4 * options.albedoPaths, options.seed + 1, [&](const std::array<double, 3>& u) {
            double o[3] = {wo.x, wo.y, wo.z};
            return interp.sample(o, u.data(), nullptr).weight;
        });
        WalkEstimate a = walk.albedo(wo, options.albedoPaths, options.seed);
        std::array<double, 3> baseAlbedo = base.ndf ? samplerAlbedo(base, wo, 4 * options.albedoPaths, options.seed + 1)
                                                    : std::array<double, 3>{};
        if (!base.ndf)  // a diffuse lobe: its albedo is pi times its constant f
            for (int ch = 0; ch < 3; ++ch) baseAlbedo[ch] = base.brdf(V{0, 0, 1}, wo)[ch] * std::numbers::pi;
        for (int ch = 0; ch < 3; ++ch) {
            row.walkAlbedo[ch] = weight[ch] * a.mean[ch] + (1 - weight[ch]) * baseAlbedo[ch];
            row.walkAlbedoError[ch] = weight[ch] * a.stdError[ch];
        }
        row.abandoned = a.abandoned;
        auto cell = [&](const V& wi, uint64_t seed) {
            WalkEstimate f = walk.brdf(wi, wo, options.brdfPaths, seed);
            V sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
            CellValues v{interp.combinedBrdf(r, wi, wo, sum, nullptr), {}, {}, {}};
            std::array<double, 3> fb = base.brdf(wi, wo);
            for (int ch = 0; ch < 3; ++ch) {
                v.walk[ch] = weight[ch] * f.mean[ch] + (1 - weight[ch]) * fb[ch];
                v.walkError[ch] = weight[ch] * f.stdError[ch];
            }
            return v;
        };
        double unused = 0;
        shapeErrors(options, cell, &row.modelShapeError, &unused, &row.shapeNoise);
        rows.push_back(row);
    }
    return rows;
}

}  // namespace facet
