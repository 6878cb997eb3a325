// ReferenceModels: hand-written ahead-of-time C++ of four reference BSDFs.
//
// These are the baseline `facet bench` times the JIT against (SPEC section 6):
// what a good engineer writes by hand for speed in plain C++ — float, std::
// math, branch-free loops over SoA arrays that the compiler vectorizes — built
// with -O3 -march=native (see bench/CMakeLists.txt). Each function has the
// calling convention of the JIT batch kernel (runtime/Kernel.h BatchKernelFn)
// and its conventions (SPEC section 2): a lane whose directions are not finite
// or not unit within 1e-3, or whose inputs are not finite, yields 0 and is
// counted; valid directions are renormalized; below the horizon f = 0.
//
// The matching material files live in bench/models/ (same constants, same
// inputs and defaults, and a `// aot: NAME` line that ties them to a model
// here). tests/bench/AotReferenceTests.cpp checks both against the
// interpreter.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace facet::aot {

// n lanes, SoA: wi[0..2], wo[0..2], rgb[0..2] each point to n floats; inputs
// is null (all defaults) or inputs[s] points to n floats (or is null: that
// slot's default). Returns the number of invalid lanes.
using BatchFn = int64_t (*)(int64_t n, const float* const wi[3], const float* const wo[3],
                            const float* const* inputs, float* const rgb[3]);

// The sampler's batch functions, SoA as facet_sample_batch and
// facet_pdf_batch (facet.h): wo[0..2], u[0..2], wi[0..2], weight[0..2]
// each point to n floats, pdf to n floats; inputs as for BatchFn. Return
// the number of invalid lanes.
using SampleBatchFn = int64_t (*)(int64_t n, const float* const wo[3], const float* const u[3],
                                  const float* const* inputs, float* const wi[3], float* pdf, float* const weight[3]);
using PdfBatchFn = int64_t (*)(int64_t n, const float* const wi[3], const float* const wo[3],
                               const float* const* inputs, float* pdf);

struct ReferenceModel {
    const char* name;         // the `// aot: NAME` tag
    const char* modelFile;    // bench/models/<modelFile>, relative to the source tree
    const char* description;  // one line: ndf + masking + fresnel
    std::vector<const char*> inputs;  // slot names, in slot order (as Kernel::inputName)
    BatchFn batch;
    SampleBatchFn sample = nullptr;  // a hand-written sampler, where there is one
    PdfBatchFn pdf = nullptr;
    BatchFn bare = nullptr;  // the bare loop of the same BRDF (below)
    bool wholeSphere = false;  // f over the whole sphere (SPEC 11), not 0 below the horizon
};

// (a) isotropic GGX + Smith height-correlated + Schlick with an rgb f0.
// Input: roughness (alpha = roughness^2).
int64_t ggxSchlick(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]);
// The importance sampler of (a), the baseline of the JIT samplers (SPEC
// section 8): visible-normal sampling of GGX by spherical caps (Dupuy &
// Benyoub 2023), pdf = D(m) / (4 (n.wo) (1 + Lambda(wo))), weight =
// F(wo.m) G2 / G1(wo), written like the BRDFs here (float, one branch-free
// vectorized loop) with the conventions of facet_sample_batch: a lane with
// a non-finite or non-unit wo (within 1e-3), u outside [0, 1) or a
// non-finite input gives wi = 0, pdf = 0, weight = 0 and is counted; n.wo
// <= 0 gives no sample (zeros, valid); a sample below the horizon is valid
// with weight 0 and its pdf. The material has no diffuse lobe: u[0] (the
// lobe choice) is checked, not used; u[1] is the azimuth and u[2] the
// height on the cap, as in Facet's GGX sampler.
int64_t ggxSchlickSample(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                         float* const wi[3], float* pdf, float* const weight[3]);
// The density of wi given wo for (a), as facet_pdf_batch.
int64_t ggxSchlickPdf(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* pdf);

// (b) isotropic Beckmann + Smith separable + conductor (complex eta + ik, rgb).
// Input: roughness (alpha = roughness^2).
int64_t beckmannConductor(int64_t n, const float* const wi[3], const float* const wo[3],
                          const float* const* inputs, float* const rgb[3]);
// (c) anisotropic GGX + Smith height-correlated + exact dielectric (rgb eta).
// Inputs: roughness_x, roughness_y (alpha_x,y = roughness_x,y^2).
int64_t anisoGgxDielectric(int64_t n, const float* const wi[3], const float* const wo[3],
                           const float* const* inputs, float* const rgb[3]);

// The bare twins of (a), (b), (c) (BareModels.cpp): the same BRDFs in
// float as a renderer's own loop, for hosts that promise finite unit
// directions and in-range inputs: no validation, renormalization, input
// range clamp or output check; alpha >= 1e-4 and f = 0 below the horizon
// as the SPEC's formulas. They return 0.
int64_t bareGgxSchlick(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                       float* const rgb[3]);
int64_t bareBeckmannConductor(int64_t n, const float* const wi[3], const float* const wo[3],
                              const float* const* inputs, float* const rgb[3]);
int64_t bareAnisoGgxDielectric(int64_t n, const float* const wi[3], const float* const wo[3],
                               const float* const* inputs, float* const rgb[3]);

// (d) a rough glass over the whole sphere (RoughGlassModel.cpp): isotropic
// GGX + Smith separable + exact dielectric (eta 1.5), scatter = both. Input:
// roughness. f is defined for wi and wo on either side (no 0 below the
// horizon); its bare twin follows.
int64_t roughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]);
int64_t bareRoughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                       float* const rgb[3]);
// The importance sampler of (d), the baseline of Facet's whole-sphere
// samplers: in wo's frame (z flipped where n.wo < 0, the far side's
// relative index eta' = 1.5 or 1/1.5), a visible normal m of GGX by
// spherical caps (Dupuy & Benyoub 2023; u[1] the azimuth, u[2] the height
// on the cap, as in Facet's GGX sampler), reflection about m where u[0] < F
// (wo.m, eta') (exactly: u[0] (F + T) < F), else refraction by Snell's law
// (Walter et al. 2007); pdf = D_wo(m) times F / (4 |wo.m|) or (1 - F)
// eta'^2 |wi.m| / (eta' wi.m + wo.m)^2; weight = f |n.wi| / pdf = G1(wi),
// over eta'^2 for a refraction (radiance transport). Written like
// ggxSchlickSample, with the conventions of facet_sample_batch for a lobe
// over the whole sphere: wo on either side is valid; a non-finite or
// non-unit wo (within 1e-3), u outside [0, 1) or a non-finite input gives
// wi = 0, pdf = 0, weight = 0 and is counted; n.wo = 0, a reflection below
// the horizon, a refraction above it and the refraction past the critical
// angle (which u[0] never chooses: T = 0 there) are no sample (zeros,
// valid). It draws what Facet's reference sampler draws for the same u.
int64_t roughGlassSample(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                         float* const wi[3], float* pdf, float* const weight[3]);
// The density of wi given wo for (d), as facet_pdf_batch (0 where n.wi or n.wo is 0).
int64_t roughGlassPdf(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* pdf);

// All four, in the order above.
const std::vector<ReferenceModel>& referenceModels();
// The model tagged `name`, or null.
const ReferenceModel* findReferenceModel(std::string_view name);

}  // namespace facet::aot
