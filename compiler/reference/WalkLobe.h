// WalkLobe: the reference of a lobe with `energy = random_walk` (SPEC 13,
// docs/sampling.md): the multiple-scattering microfacet BSDF of Heitz et
// al. 2016 as a path tracer uses it, with the random numbers the kernels
// draw, so that a compiled lane and the reference walk the same path.
//
// - eval: f = the lobe's single scattering (exact, height-correlated
//   Smith) + one walk's next-event estimate of the orders >= 2
//   (MicrosurfaceWalk::pathBrdfCos with WalkOrders::minOrder = 2). The walk
//   is seeded by the directions, quantized to a 2^-16 grid (offset so that
//   the round values hard cases use are not on a cell's edge): a
//   deterministic f whose noise changes from one grid cell to the next. Its
//   expectation over seeds is Heitz's BSDF; one value of it is not
//   reciprocal (the walk starts from wo).
// - sample: the whole walk from wo, seeded by the bits of the three
//   uniforms; wi is the direction it leaves in and the weight the product
//   of the Fresnel terms met, f (n.wi) / p exactly for the walk's own
//   density p, which has no closed form.
// - pdf: a density for multiple importance sampling only (the weight does
//   not divide by it): (1 - q) p_ss(wi) + q (n.wi)/pi, p_ss the single
//   reflection of a visible normal of wo, and q = Lambda(wo) / (1 +
//   Lambda(wo)) clamped to [0.05, 0.95] (the share of wo's rays that the
//   surface masks, a stand-in for the multiply scattered share).
// Walks longer than kLaneWalkMaxOrder reflections are cut (weight 0; fewer
// than one walk in 1e30 at alpha = 1).
#pragma once

#include "Interpreter.h"
#include "MicrosurfaceWalk.h"
#include "Sampling.h"

#include <array>
#include <cstdint>

namespace facet {

inline constexpr int kLaneWalkMaxOrder = 256;

// The seed of eval's walk from the unit directions (SPEC 13).
uint32_t evalWalkSeed(const Vec3<double>& wi, const Vec3<double>& wo);
// The seed of the sampler's walk from the bits of the uniforms as floats.
uint32_t sampleWalkSeed(const std::array<float, 3>& u);

// Eval's multiple-scattering term f_ms(wi, wo) (unit directions above the
// horizon), per channel; computed in double whatever Real is (it is a
// Monte Carlo estimate: its accuracy is its variance).
template <typename Real>
std::array<Real, 3> walkMultipleScattering(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo);

// The sampler and its MIS density (n.wo > 0).
template <typename Real>
SampleResult<Real> sampleWalkLobe(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u);
template <typename Real>
Real walkLobePdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo);

}  // namespace facet
