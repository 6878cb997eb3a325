// LayeredWalk: the stochastic reference of `layer(TOP, BASE)` (SPEC 10, 13):
// a position-free random walk between a rough dielectric interface and the
// base lobe below it (Guo, Hasan & Zhao 2018; pbrt-v4's LayeredBxDF estimates
// coated materials the same way), against which the albedo-scaled layer
// (LayerAlbedo.h) is measured.
//
// The physical model. TOP is read as a rough dielectric interface: its NDF
// and roughness, height-correlated Smith masking, and the relative index
// eta of its `dielectric` Fresnel (per channel; a dispersive eta walks each
// distinct value separately). It reflects and refracts (Walter et al. 2007):
//   reflection   D(h) F G2 / (4 |n.wi| |n.wo|)
//   refraction   |wi.m| |wo.m| D(m) (1 - F) G2 / (|n.wi| |n.wo| (eta_i wi.m + eta_o wo.m)^2),
// with m the generalized half vector and back-facing microfacets rejected;
// light inside meets the interface from below with eta inverted, and is
// totally reflected past the critical angle. The path from wo carries the
// radiance form (a refraction into a medium of relative index eta scales
// radiance by 1/eta^2 as seen from the far side), and the next event toward
// wi draws its refraction from wi's side in the adjoint form, as pbrt-v4 does;
// over a Lambertian base and a smooth top this gives the classic coating
// (1 - F_i)(1 - F_o) rho / (pi eta^2 (1 - rho F_dr,inside)), which the tests
// check. An index-matched interface (eta = 1) is invisible: light passes
// straight through (the microfacet refraction degenerates there, SPEC 11).
// BASE is the base lobe as the interpreter evaluates and samples it
// (Interpreter.h, Sampling.h). The layer between them has no thickness for
// geometry (position-free) and an optional absorption: a straight traversal
// at n.w attenuates by exp(-sigma_a / |n.w|) per channel (sigma_a: the
// absorption coefficient times the thickness).
//
// The estimator of f(wi, wo) for wi, wo above the layer (pbrt-v4's, without
// its multiple importance sampling): the interface's reflection, exact, plus
// a walk from wo: refract into the layer (transmission alone sampled, its
// probability in the weight), then at each meeting with the base a
// next-event estimate through the interface toward wi (a refraction from wi
// drawn once per walk, evaluated with the base's BRDF), and a new direction
// from the base's sampler; back at the interface the walk reflects or
// leaves, chosen by the Fresnel term (leaving ends it: its light was
// counted by the next events). Russian roulette after three bounces keeps it
// unbiased. sample() follows the same physics forward for albedos.
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

    // The interface's own reflection f_r(wi, wo) for wi, wo above it, channel ch.
    double interfaceReflection(const Vec3<double>& wi, const Vec3<double>& wo, int ch) const;

private:
    struct Crossing;
    // A direction from the interface given w (pointing away from it, on
    // the side it is seen from), eta the far side's index over w's side:
    // reflected or refracted with probability F, or refracted only
    // (`transmitOnly`, the probability in the weight). `radiance`: the
    // weight of the path's own direction (1/eta^2 on refraction), else of
    // the adjoint (the next event's light side).
    Crossing scatter(const Vec3<double>& w, double eta, bool transmitOnly, bool radiance, WalkRandom& random) const;
    double lambda(const Vec3<double>& w) const;  // Smith Lambda of |n.w|'s side
    double transmittance(const Vec3<double>& w, int ch) const;
    std::array<double, 3> walkChannels(const Vec3<double>& wi, const Vec3<double>& wo, double eta,
                                       const std::array<bool, 3>& channels, WalkRandom& random) const;
    WalkSample sampleChannels(const Vec3<double>& wo, double eta, const std::array<bool, 3>& channels,
                              WalkRandom& random) const;

    const ResolvedMaterial<double>& top_;
    const ResolvedMaterial<double>& base_;
    LayerAbsorption absorption_;
    std::array<double, 3> eta_{};
};

}  // namespace facet
