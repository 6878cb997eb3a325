// DielectricEnergy: `energy = kulla_conty` on a lobe that scatters over the
// whole sphere (SPEC 11): the energy a rough dielectric interface or a thin
// sheet loses to its single-scattering model (light the microsurface masks
// and would scatter again), given back as a diffuse-like lobe on both
// sides, reciprocal in the generalized sense.
//
// Rough interface, eta = n_inside / n_outside. E_o(mu) and E_i(mu) are the
// single-scattering R + T of the non-absorbing interface seen from outside
// (far side eta) and from inside (far side 1/eta), in power (importance
// transport), tabulated over (mu, alpha) for the material's constant eta
// (EnergyTableKey::interfaceEta; two tables). With Ec = 1 - E and
// A = 1 - E_avg = 2 Int Ec(mu) mu dmu on each side, the compensation in
// importance transport is, for wo on side s and wi on side s',
//   s' = s:  (1 - x_s) Ec_s(mu_o) Ec_s(mu_i) / (pi A_s)
//   s' != s:      x_s  Ec_s(mu_o) Ec_s'(mu_i) / (pi A_s')
// so that from either side it scatters exactly Ec_s(mu_o) (R + T = 1 up to
// the tables' interpolation), x_s of it across the surface. Generalized
// reciprocity (f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2 in radiance; the
// importance form is its adjoint) ties the two shares:
//   x_i = x_o A_o / (eta^2 A_i).
// x_o is the smooth interface's share, 1 - F_avg(eta), lowered where x_i
// would pass 1: x_o = min(1 - F_avg, eta^2 A_i / A_o). Radiance transport
// divides the crossing lobe by eta^2 going in (wo outside) and multiplies
// by eta^2 going out, as the single-scattering lobe does. (Kulla & Conty
// 2017 split a dielectric's multiple scattering between the sides by the
// same reciprocity argument; this is that construction with tables of R + T
// instead of separate reflection and transmission fits.)
//
// Thin sheet: nothing bends, so its single-scattering R' + T' = 1 summed over
// the mirrored pairs leaves exactly the reflection lobe's loss: the tables
// are the F = 1 reflection table of the NDF and masking (on both sides), and
// the crossing share is the sheet's average transmittance 2 Int T'(mu) mu dmu
// per channel (eta may be rgb), the same from both sides; no eta^2 factors.
//
// `scatter = reflect | transmit` keeps the same part of the compensation as
// of the single-scattering lobe.
//
// Sampling: with probability p = the compensation's albedo from wo's side
// (less what scatter drops; at most 0.9), a side chosen by the shares, then
// the cosine lobe there; otherwise the single-scattering sampler. The pdf is
// the mixture's.
#pragma once

#include "Interpreter.h"

#include <array>
#include <memory>

namespace facet {

// The table of the inside for the table key of a lobe's outside (the same
// key for a thin sheet's reflection table).
EnergyTableKey insideTableKey(const EnergyTableKey& outside);

// Fills r's compensation fields from the two tables (r resolved otherwise).
template <typename Real>
void resolveWholeSphereCompensation(ResolvedMaterial<Real>& r, std::shared_ptr<const EnergyTable> outside,
                                    std::shared_ptr<const EnergyTable> inside);

// The sheet's average transmittance 2 Int T'(mu) mu dmu of channel ch,
// T' = (1 - F) / (1 + F): its crossing share from either side.
template <typename Real>
Real sheetTransmittanceAverage(const ResolvedMaterial<Real>& r, int ch);

// What the crossing shares take from the lobe's index alone, for the
// compiled kernels (compiler/lowering/WholeSphereEnergy.cpp), which have
// the tables' averages per lane: the smooth interface's share 1 - F_avg and
// the clamped eta^2, or the sheet's crossing share per channel. `material`
// is a single whole-sphere lobe with a constant index; resolved at its
// inputs' defaults without building its tables.
struct CrossingConstants {
    double smoothCrossing = 0, eta2 = 1;
    std::array<double, 3> sheetCrossing{};
};
CrossingConstants crossingConstants(const CheckedMaterial& material);

// The compensation lobe f_ms(wi, wo), rgb; 0 where r has none.
template <typename Real>
std::array<Real, 3> wholeSphereCompensation(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi,
                                            const Vec3<Real>& wo);

// The sampler's probability of drawing wi from the compensation lobe at wo.
template <typename Real>
Real compensationProbability(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo);
// That draw's density at wi and the draw itself from u in [0, 1)^3.
template <typename Real>
Real compensationPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo);
template <typename Real>
Vec3<Real> sampleCompensation(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u);

}  // namespace facet
