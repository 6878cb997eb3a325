// SphereRender: the lit-sphere preview of `facet render`.
//
// A unit sphere seen by an orthographic camera, shaded by a compiled kernel
// (any backend: the SIMD kernel for speed, the interpreter as reference)
// under one directional light plus a sky (constant, or an analytic
// horizon-to-zenith gradient over a darker ground) integrated with a fixed
// number of samples per pixel. The sky directions are drawn by the kernel's
// own importance sampler (Kernel::sampleBatch: the material's NDF, visible
// normals where it has them, and its cosine lobe, mixed by their albedos),
// and each contributes the sky's radiance times the sampler's weight
// f cos / pdf: the estimator a path tracer using Facet would run.
//
// Every pixel uses the same deterministic uniform numbers (one 3D point set,
// shifted per pixel by a hash), so two renders of the same material with
// different backends differ only by the kernels' own differences: that is
// how the tests compare the SIMD kernel with the interpreter.
//
// Conventions: world +Y is up (the sky's zenith and the sphere's pole, so an
// anisotropic material's tangent runs along the latitude lines); directions
// are given as (theta, phi) in degrees, theta from +Z (the default view
// axis), phi from +X towards +Y. The BRDF is evaluated with wi = light or
// sky direction and wo = view direction, both in the local frame
// (tangent, bitangent, normal).
#pragma once

#include "Color.h"
#include "Kernel.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace facet::preview {

enum class SkyModel { None, Constant, Gradient };

struct SphereScene {
    int size = 512;                                 // image width = height, pixels
    double lightThetaDeg = 45, lightPhiDeg = 135;   // towards the light (default: upper left, front)
    double lightIrradiance = 3;                     // at normal incidence
    double viewThetaDeg = 0, viewPhiDeg = 0;        // towards the camera
    SkyModel sky = SkyModel::Gradient;
    double skyRadiance = 1;                         // scale of the sky's radiance
    int skySamples = 64;                            // per pixel
    double exposureEv = 0;                          // PNG tone mapping: radiance * 2^EV
    int threads = 0;                                // 0: every core
    // The material scatters below its surface (SPEC 11): the sphere is that
    // one surface, and light from behind it reaches the camera through it
    // (the light's weight is irradiance |cos|, not max(0, cos)). A preview of
    // what comes through, not a solid ball (no second refraction).
    bool lightThrough = false;
};

struct RenderStats {
    double seconds = 0;       // wall time of the shading (lane set-up + kernel + accumulation)
    double kernelSeconds = 0; // time inside the kernel's eval and sample batch calls, summed over the threads
    int threads = 1;
    int64_t pixels = 0;       // pixels covered by the sphere
    int64_t evaluations = 0;  // kernel lanes evaluated (the light's)
    int64_t samples = 0;      // sky directions drawn by the kernel's sampler
    int64_t invalidLanes = 0; // eval and sample lanes the kernel reported invalid (0 for a valid material)
};

struct SphereImage {
    int size = 0;
    std::vector<float> radiance;  // size*size*3, linear outgoing radiance (0 off the sphere)
    std::vector<float> coverage;  // size*size, fraction of the pixel the sphere covers
    RenderStats stats;
    float& at(int x, int y, int c) { return radiance[(size_t(y) * size + x) * 3 + c]; }
    float at(int x, int y, int c) const { return radiance[(size_t(y) * size + x) * 3 + c]; }
};

// Checks the scene's numbers; returns "" or a message naming the bad field.
std::string validateScene(const SphereScene& scene);

// Draws n sky directions as Kernel::sampleBatch does (the material's
// default inputs); returns the number of invalid lanes.
using SkySampler = std::function<int64_t(int64_t n, const float* const wo[3], const float* const u[3],
                                         float* const wi[3], float* pdf, float* const weight[3])>;

// Renders the sphere with `kernel` at its default inputs. The scene must be
// valid (validateScene). The sky is sampled by `sampler` when given (e.g.
// another technique, SamplingVariance.h), else by the kernel's own sampler.
SphereImage renderSphere(const Kernel& kernel, const SphereScene& scene, const SkySampler& sampler = nullptr);

// Writes the image. .exr/.hdr: linear RGBA, colour premultiplied by
// coverage. Other formats (PNG, ...): 8-bit sRGB, radiance * 2^EV through
// the ACES filmic curve (Narkowicz 2015 fit), over a grey background.
// Returns "" or an error message.
std::string writeSphereImage(const SphereImage& image, const SphereScene& scene, const std::string& path);

// The pixel (x, y) (fractional, pixel centres at integers) where the mirror
// highlight of the light lies: where the normal is the half vector of the
// light and view directions. None when that point faces away from the camera.
std::optional<std::array<double, 2>> highlightPixel(const SphereScene& scene);

// The tone curve applied to PNG output (linear in, display-referred out,
// before sRGB encoding); exposed for the tests.
double acesFilmic(double x);

}  // namespace facet::preview
