// DielectricLobe: the reference of a lobe that scatters over the whole
// sphere (SPEC 11): a rough dielectric interface (Walter et al. 2007) with
// `scatter = transmit | both`, or a thin-walled sheet (`thin = true`).
//
// Rough interface. eta = n_inside / n_outside, the inside is -z, and wi, wo
// lie on either side. Everything is computed in wo's frame: the pair is
// mirrored (z -> -z) when wo is inside, so that wo is above a surface whose
// far side has the relative index eta' = eta (wo outside) or 1/eta (wo
// inside); the NDF, Lambda and the masking are the same seen from either
// side (Heitz et al. 2016's symmetry of the microsurface). Then
//   reflection (n.wi > 0): h = (wi + wo)/|wi + wo|,
//     f = F(wo.h, eta') D(h) G / (4 |n.wi| |n.wo|);
//   transmission (n.wi < 0): v = eta' wi + wo, m = v/|v| turned to m.z > 0,
//     f = (1 - F(wo.m, eta')) D(m) G |wi.m| |wo.m| / (|n.wi| |n.wo| |v|^2)
//     in radiance transport (the eta_o^2 / (eta_i wi.m + eta_o wo.m)^2 of
//     Walter's f_t with relative indices: (eta' wi.m + wo.m)^2 = |v|^2), times
//     eta'^2 in importance transport (Veach 1997, 5.14);
// zero where a facet faces away from either direction (wi.m (n.wi) <= 0 or
// wo.m (n.wo) <= 0). F is the exact dielectric term, which is 1 beyond the
// critical angle (total internal reflection sends everything to
// reflection). G is the masking's reflection form for a reflected pair and
// its transmission form (MaskingFormulas::transmittedGOverCosines) for a
// transmitted one, both on the directions mirrored above the surface. An
// eta within kEtaClampFromOne of 1 is moved to 1 +- kEtaClampFromOne: the
// transmitted lobe of an index-matched interface is a delta (|v| -> 0 at
// wi = -wo), which no finite f can hold. `scatter = transmit` keeps only the
// transmitted pairs.
//
// Thin sheet (MDL's thin_walled, OpenPBR's thin-walled mode): the same
// interface on both sides of a sheet of negligible thickness, so nothing
// bends: transmission leaves on the far side along the mirror image of a
// reflection. With the pair mirrored above the surface (both z -> |z|) and
// h their half vector, f = w(wo.h) D(h) G / (4 |n.wi| |n.wo|), G the
// reflection form, w = R' = 2F / (1 + F) for a reflected pair and T' = (1 -
// F) / (1 + F) for a transmitted one: the sheet's reflectance and
// transmittance summed over the bounces between its two faces (F + (1-F)^2
// F / (1 - F^2) = 2F / (1 + F)), which add to 1. eta may be rgb here (no
// direction depends on it). The sheet is symmetric, so f(wi, wo) = f(wo, wi).
//
// Sampling (wo's frame): a visible normal m of wo (NDF sampling where the
// NDF has no visible-normal sampler), reflection with probability P_R = F(wo.m)
// (the rough interface; 0 for scatter = transmit) or R' (the sheet;
// transmission with T'), wi the reflection or refraction of wo about m;
// pdf = P_R p_m(m) / (4 wo.m) for reflection, P_T p_m(m) eta'^2 |wi.m| /
// |v|^2 for refraction; weight = f |n.wi| / pdf. The density integrates to
// the share of draws that give a direction (a reflection past the horizon
// gives none, as in pbrt-v4). With energy = kulla_conty the lobe also holds
// the compensation of DielectricEnergy.h: f adds it, and the sampler draws
// from it with its own probability (a mixture; the pdf is the mixture's).
#pragma once

#include "Interpreter.h"
#include "Sampling.h"

#include <array>

namespace facet {

inline constexpr double kEtaClampFromOne = 1e-3;

// eta moved out of (1 - kEtaClampFromOne, 1 + kEtaClampFromOne), away from 1.
template <typename Real>
Real clampedFromOne(Real eta) {
    const Real clamp = Real(kEtaClampFromOne);
    if (eta >= 1 && eta < 1 + clamp) return 1 + clamp;
    if (eta < 1 && eta > 1 - clamp) return 1 - clamp;
    return eta;
}

// The BSDF of a whole-sphere lobe (r.wholeSphere()); `sum` = wi + wo,
// computed accurately by the caller.
template <typename Real>
std::array<Real, 3> dielectricBsdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                                   const Vec3<Real>& sum);

template <typename Real>
SampleResult<Real> sampleDielectricLobe(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo,
                                        const std::array<Real, 3>& u);

template <typename Real>
Real dielectricLobePdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo);

// R + T of the interface lobe r (scatter = both, importance transport, so
// that f |n.wi| integrates to the power scattered) seen from mu = n.wo > 0
// above, whose relative index is r's eta: over the facets the sampler draws
// for wo from a grid x grid midpoint grid of (u1, u2), both branches of each
// facet (DielectricEnergy.h's tables).
double interfaceAlbedo(const ResolvedMaterial<double>& r, double mu, int grid);

// Whether `scatter` keeps a pair on one side of the surface (reflected) or
// across it: scatter = transmit drops the first, reflect the second.
template <typename Real>
bool keepsPair(const ResolvedMaterial<Real>& r, bool reflected) {
    return reflected ? r.scatter != Scatter::Transmit : r.scatter != Scatter::Reflect;
}

// The lobe's index of refraction of channel ch, clamped away from 1.
template <typename Real>
Real clampedEta(const ResolvedMaterial<Real>& r, int ch);

}  // namespace facet
