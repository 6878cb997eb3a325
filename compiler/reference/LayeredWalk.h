// LayeredWalk: the stochastic reference of `layer(TOP, BASE)` (SPEC 10, 13):
// a position-free random walk between a rough dielectric interface and the
// base lobe below it (Guo, Hasan & Zhao 2018; pbrt-v4's LayeredBxDF estimates
// coated materials the same way), against which the albedo-scaled layer
// (LayerAlbedo.h) is measured.
//
// The physical model. TOP is read as a rough dielectric boundary: the
// microsurface of its NDF and roughness with the relative index eta of its
// `dielectric` Fresnel (per channel; a dispersive eta walks each distinct
// value separately), walked as Heitz et al. 2016's dielectric microsurface
// (MicrosurfaceWalk::cross): light reflects and refracts from facet to
// facet until it leaves above or below, so the boundary loses no energy
// (a single-scattering boundary, Walter et al. 2007's BSDF, loses what its
// masking loses on every crossing: 2-3% of a white base's energy under a coat
// of alpha 0.05, a quarter or more at 0.3). Light inside meets the boundary
// from below with eta inverted, and total internal reflection comes out of
// the walk. The path from wo carries the radiance form (leaving into a
// medium of relative index eta scales radiance by 1/eta^2), and the next
// event toward wi crosses from wi's side in the adjoint form, as pbrt-v4
// does; over a Lambertian base and a smooth top this is the classic coating
// (1 - F_i)(1 - F_o) rho / (pi eta^2 (1 - rho F_dr,inside)), which the tests
// check. An index-matched boundary (eta = 1) is not there: light passes
// straight through. BASE is the base lobe as the interpreter evaluates and
// samples it (Interpreter.h, Sampling.h). The layer between them has no
// thickness for geometry (position-free) and an optional absorption: a
// straight traversal at n.w attenuates by exp(-sigma_a / |n.w|) per channel
// (sigma_a: the absorption coefficient times the thickness).
//
// The estimator of f(wi, wo) for wi, wo above the layer (pbrt-v4's, without
// its multiple importance sampling): the boundary's own reflection (the
// dielectric walk's next-event estimate), plus a walk from wo: cross into
// the layer (a walk that reflects instead contributes nothing here), then at
// each meeting with the base a next-event estimate through the boundary
// toward wi (one crossing from wi drawn per walk, evaluated with the base's
// BRDF), and a new direction from the base's sampler; back at the boundary
// the walk is reflected into the layer or leaves (leaving ends it: its
// light was counted by the next events). Russian roulette after three
// bounces keeps it unbiased. sample() follows the same physics forward.
#pragma once

#include "MicrosurfaceWalk.h"

#include <array>
#include <string>

namespace facet {

struct LayerAbsorption {
    std::array<double, 3> sigma{};  // absorption coefficient x thickness, per channel (>= 0)
};

class LayeredWalk {
public:
    // Why TOP over BASE cannot be walked ("" when it can): TOP needs an NDF
    // the microsurface walk supports and a dielectric Fresnel; BASE a lobe.
    static std::string unsupported(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base);

    LayeredWalk(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base, LayerAbsorption absorption = {});

    // One walk's estimate of f(wi, wo) per channel (unit directions above
    // the layer; 0 otherwise).
    std::array<double, 3> pathBrdf(const Vec3<double>& wi, const Vec3<double>& wo, WalkRandom& random) const;
    // One walk forward from wo: the direction it leaves in and its weight
    // f (n.wi) / pdf per channel (weight 0 when it is absorbed or stopped).
    WalkSample sample(const Vec3<double>& wo, WalkRandom& random) const;

    WalkEstimate brdf(const Vec3<double>& wi, const Vec3<double>& wo, int64_t paths, uint64_t seed) const;
    WalkEstimate albedo(const Vec3<double>& wo, int64_t paths, uint64_t seed) const;

private:
    double transmittance(const Vec3<double>& w, int ch) const;
    std::array<double, 3> walkChannels(const Vec3<double>& wi, const Vec3<double>& wo, double eta,
                                       const std::array<bool, 3>& channels, WalkRandom& random) const;
    WalkSample sampleChannels(const Vec3<double>& wo, double eta, const std::array<bool, 3>& channels,
                              WalkRandom& random) const;

    const ResolvedMaterial<double>& top_;
    const ResolvedMaterial<double>& base_;
    LayerAbsorption absorption_;
    MicrosurfaceWalk boundary_;  // the top's microsurface, walked as a dielectric
    std::array<double, 3> eta_{};
};

}  // namespace facet
