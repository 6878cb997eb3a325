// WalkComparison: how far a lobe's closed-form model is from its stochastic
// reference (SPEC 13): the single-scattering lobe, and the lobe with its
// energy compensation (Kulla-Conty), against the multiple-scattering BSDF of
// the random walk on the same microsurface (MicrosurfaceWalk.h), with the
// lobe's own Fresnel term at every reflection.
//
// The same for a material whose combination is layer(TOP, BASE) of two
// lobes: the albedo-scaled layer (SPEC 10, LayerAlbedo.h) against the
// layered walk of TOP read as a dielectric interface over BASE
// (LayeredWalk.h); a layer weight W < 1 mixes in the base alone, W walk +
// (1 - W) base, on both sides.
//
// Two measures per view angle theta_o:
//   - the directional albedo Int f (n.wi) dwi of each: the model's by its
//     reference sampler (Sampling.h) with stratified numbers, the walk's as
//     the mean weight of its exits; with its standard error;
//   - a BRDF-shaped error: the relative RMS difference of f over a grid of
//     wi cells of equal projected solid angle (so that the norm is that of
//     f over the measure (n.wi) dwi), sqrt(sum (f_model - f_walk)^2 / sum
//     f_walk^2), with the walk's f at each cell by next-event estimation.
//     The walk's noise adds its variance to each squared difference, so the
//     error reported is sqrt(max(0, sum ((f_model - f_walk)^2 - se^2)) / sum
//     f_walk^2), se the walk's standard error at the cell; `shapeNoise`,
//     sqrt(sum se^2 / sum f_walk^2), is what was taken off: an error well
//     above the noise is the model's.
// Both sum the three channels. The material's masking enters the model
// (a separable Smith lobe is compared as written), the walk is always the
// height-correlated microsurface; its diffuse base is left out of both.
#pragma once

#include "LayeredWalk.h"
#include "MicrosurfaceWalk.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace facet {

struct WalkComparisonOptions {
    std::vector<double> thetas = {0, 45, 70, 85};  // theta_o, degrees (phi_o = 0)
    int64_t albedoPaths = 20000;   // walks per albedo; the model's sampler takes 4x as many
    int64_t brdfPaths = 256;       // walks per wi cell
    int gridTheta = 12, gridPhi = 24;
    uint64_t seed = 1;
};

struct WalkComparisonRow {
    double thetaO = 0;
    std::array<double, 3> singleAlbedo{}, modelAlbedo{}, walkAlbedo{}, walkAlbedoError{};
    double singleShapeError = 0, modelShapeError = 0, shapeNoise = 0;
    int64_t abandoned = 0;  // walks given up (MicrosurfaceWalk: kMaxWalkSteps)
};

// `lobe` must be supported by the walk (MicrosurfaceWalk::unsupported);
// the model is `lobe` without its diffuse base, "single" the same without
// energy compensation. One row per theta of the options.
std::vector<WalkComparisonRow> compareWithWalk(const ResolvedMaterial<double>& lobe,
                                               const WalkComparisonOptions& options = {});

// Why the material's combination has no layered walk ("" when it has one).
std::string layerWalkUnsupported(const CheckedMaterial& material, const ResolvedBsdf<double>& r);

// One row per theta of the options (the single-scattering fields unused:
// modelAlbedo and modelShapeError are the layer's). `interp` resolved `r`
// at the default inputs; layerWalkUnsupported must be "".
std::vector<WalkComparisonRow> compareLayerWithWalk(const Interpreter<double>& interp, const ResolvedBsdf<double>& r,
                                                    const WalkComparisonOptions& options = {});

}  // namespace facet
