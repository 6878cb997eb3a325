// FresnelAverage: the hemispherical Fresnel averages F_avg = 2 Int_0^1 F(mu) mu dmu
// of the exact dielectric and conductor terms, and their tables.
//
// A neutral numerical library: the interpreter's energy compensation
// (KullaConty) and the LLVM lowering's (FresnelEmitter) both take F_avg from
// here, and neither's Fresnel formula is used to make it: the integrand is
// this file's own unpolarized Fresnel reflectance of a complex index. What
// verifies it is independent of both (tests/energy/FresnelAverageTests: a
// Simpson rule over the catalog's reference Fresnel).
#pragma once

#include <vector>

namespace facet {

// Schlick: (20 f0 + 1) / 21 (exact).
inline double fresnelAverageSchlick(double f0) { return (20 * f0 + 1) / 21; }
// Exact dielectric / conductor averages by graded Gauss-Legendre quadrature
// (relative error < 1e-12); eta is clamped to >= kFresnelAverageMinEta, k to >= 0,
// an infinite eta or k gives 1.
constexpr double kFresnelAverageMinEta = 1e-4;
double fresnelAverageDielectric(double eta);
double fresnelAverageConductor(double eta, double k);

// The panels of the F_avg quadratures on [0, 1]: graded toward grazing
// incidence (features of width ~1/|eta + ik|); for eta < 1 toward the
// critical angle of total internal reflection (a square-root kink); for eta
// >= 1 near N = eta + ik = 1 toward the peak of F(mu) mu at mu = sqrt|N^2 -
// 1| (F ~ |N^2 - 1|^2 / mu^4 above it, which makes F_avg ~ (2/3)(eta -
// 1)/(eta + 1) for a dielectric); none wider than 1/16. The
// interpreter's own quadrature (KullaContyEval.h) uses them too.
std::vector<double> fresnelAverageBreaks(double eta, double k);

// Schlick's average at the conductor's normal reflectance,
// F0 = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2): the base the conductor table corrects.
double conductorSchlickAverage(double eta, double k);

// Tables for evaluators that cannot integrate per evaluation (the JIT, when
// eta or k are per-lane inputs; constant ones fold to the exact quadrature).
// Immutable process-wide constants (a pure function of nothing), built on
// first use (~0.35 s).
//   dielectric: F_avg / s over s = (eta - 1)/(eta + 1) for eta >= 1, s in
//     [0, 1] (2/3 at s = 0, where F_avg ~ (2/3) s), kDielectricCount nodes
//     uniform in sqrt(s), linear interpolation, times s: accurate relative
//     to F_avg near eta = 1 too. For eta < 1: F_avg(eta) = 1 - eta^2 (1 -
//     F_avg(1/eta)) (exact reciprocity of the hemispherical transmittance).
//   conductor: the residual F_avg - conductorSchlickAverage(eta, k) over
//     (a, b) = (eta/(eta+1), sqrt(k)/(sqrt(k)+1)) in [0, 1]^2, kConductorCount^2
//     nodes uniform in a and b (eta = 1 is node 64), bilinear; the last row and
//     column hold 0 (eta or k infinite: F = 1). Max error 6e-5 for metals
//     (eta in [0.01, 10], k in [0.5, 10]), 8e-4 for k < 0.5 (near the
//     dielectric kink of total internal reflection at eta = 1, k = 0), 3e-3
//     over [1e-3, 1e3]^2.
// Measured accuracy is asserted by tests/energy (FresnelAverageTests).
struct FresnelAverageTables {
    static constexpr int kDielectricCount = 2048;
    static constexpr int kConductorCount = 129;
    std::vector<float> dielectric;  // kDielectricCount
    std::vector<float> conductor;   // [ib * kConductorCount + ia], ia along eta, ib along sqrt(k): the residual

    double dielectricAt(double eta) const;
    double conductorAt(double eta, double k) const;
};
const FresnelAverageTables& fresnelAverageTables();

}  // namespace facet
