// Sampling: the reference importance sampler of a resolved material (SPEC
// section 8), in the interpreter's real types.
//
// A material is a one-sample mixture of two lobes:
//   - the specular lobe: a microfacet normal m from the NDF's catalog entry
//     (visible normals under a Smith masking where the NDF has an exact
//     visible-normal sampler, else NDF sampling), wi the reflection of wo
//     about m, density pdf_m(m) / (4 |wo.m|);
//   - the cosine lobe, (n.wi) / pi, for the Lambert base and the
//     Kulla-Conty compensation (both flat or nearly so in wi), present only
//     when the material has one of them.
// u0 < p picks the specular lobe, p = specularProbability(wo); u1, u2 place
// the direction. The reported pdf is the whole mixture's, p pdf_spec +
// (1 - p) pdf_cos, at the sampled wi (what multiple importance sampling in a
// renderer needs), and weight = f(wi, wo) (n.wi) / pdf per channel.
//
// Conventions (those of eval): n = +z, wo and wi point away from the
// surface. With n.wo <= 0 the BRDF is zero for every wi: no sample (wi = 0,
// pdf = 0, weight = 0; a valid lane). A specular sample below the horizon
// (n.wi <= 0) is a valid sample of weight 0 whose pdf is reported, so that
// the density over the whole sphere integrates to 1.
//
// The JIT samplers are written independently of this file (like eval) and
// tested against it.
#pragma once

#include "Interpreter.h"

#include <array>
#include <vector>

namespace facet {

// Which technique draws the specular lobe. `Material` is the sampler every
// evaluator uses (visible normals where the catalog has them under a Smith
// masking, NDF sampling otherwise, and the cosine lobe where the material
// has one). The others exist to measure what the choice is worth (`facet
// bench`'s variance table, SamplingVariance.h): VisibleNormals forces
// visible normals (only for NDFs with a visible-normal sampler:
// hasVisibleNormalSampler), Normals forces NDF sampling, Cosine draws every
// direction from the cosine lobe. Each keeps its pdf exact, so all are
// unbiased estimators of the same integral.
enum class SamplingTechnique { Material, VisibleNormals, Normals, Cosine };
const char* samplingTechniqueName(SamplingTechnique t);

template <typename Real>
struct SampleResult {
    Vec3<Real> wi{};              // (0, 0, 0) when there is no sample
    Real pdf = 0;                 // solid-angle density of the mixture at wi
    std::array<Real, 3> weight{}; // f (n.wi) / pdf, rgb; 0 below the horizon
    bool valid = true;            // false: invalid input (everything else 0)
};

template <typename Real>
struct PdfResult {
    Real pdf = 0;
    bool valid = true;
};

// The probability of picking the specular lobe for this wo (n.wo > 0).
// From an albedo estimate of each lobe, averaged over the channels:
//   specular  F(n.wo) E(n.wo): the Fresnel term of a facet seen at wo's
//             angle times the F = 1 directional albedo E from the
//             Kulla-Conty table where the material has one (else 1);
//   cosine    the Lambert albedo plus, with Kulla-Conty, the compensation
//             lobe's albedo (1 - E(n.wo)) F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),
// p = specular / (specular + cosine), clamped to [0.05, 0.95] so that a
// poor estimate (F = 0 at n.wo but not at other angles) cannot starve a
// lobe whose f is not zero; p = 1 when the material has no cosine lobe.
// With SamplingTechnique::Cosine: 0 (every direction from the cosine lobe).
template <typename Real>
Real specularProbability(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo,
                         SamplingTechnique technique = SamplingTechnique::Material);

// True when the material's specular lobe is sampled through visible normals.
template <typename Real>
bool visibleNormalSampling(const ResolvedMaterial<Real>& r, SamplingTechnique technique = SamplingTechnique::Material) {
    if (technique == SamplingTechnique::VisibleNormals) return true;
    if (technique == SamplingTechnique::Normals) return false;
    return samplesVisibleNormals(*r.ndf, *r.masking);
}

// True when the material's NDF has an exact visible-normal sampler (what
// SamplingTechnique::VisibleNormals needs).
template <typename Real>
bool hasVisibleNormalSampler(const ResolvedMaterial<Real>& r) {
    return r.ndf->visibleNormals;
}

// The specular lobe's density of wi (solid angle; wi anywhere on the
// sphere), through the half vector h = (wi + wo) / |wi + wo|.
template <typename Real>
Real specularPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                SamplingTechnique technique = SamplingTechnique::Material);

// The density of the microfacet normal m that the specular lobe draws.
template <typename Real>
Real specularNormalPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const Vec3<Real>& m,
                SamplingTechnique technique = SamplingTechnique::Material);

// The mixture density of wi given wo (unit vectors, n.wo > 0; else 0).
template <typename Real>
Real brdfPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                SamplingTechnique technique = SamplingTechnique::Material);

// One sample for the unit direction wo and u0, u1, u2 in [0, 1) (not
// checked here: Interpreter::sample validates its inputs).
template <typename Real>
SampleResult<Real> sampleBrdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u,
                              SamplingTechnique technique = SamplingTechnique::Material);

// ---- combinations of lobes (LobeSampling.cpp) ----------------------------

// A leaf lobe of the combination and the probability of picking it.
struct LeafChoice {
    int lobe = -1;  // index into ResolvedBsdf::lobes
    double p = 0;
};
// The leaves of m's combination in tree order with their probabilities at
// n.wo = muO (summing to 1): each proportional to its estimated share of
// the albedo, at least 1 % of the largest share. The weights are r's, the
// albedos those of `estimates` (the sampler passes the material at its
// default inputs).
std::vector<LeafChoice> leafProbabilities(const CheckedMaterial& m, const ResolvedBsdf<double>& r,
                                          const ResolvedBsdf<double>& estimates, double muO);
// The mixture density sum_k p_k pdf_k(wi) of those leaves.
template <typename Real>
Real combinationPdf(const CheckedMaterial& m, const ResolvedBsdf<Real>& r, const std::vector<LeafChoice>& leaves,
                    const Vec3<Real>& wi, const Vec3<Real>& wo);
// One sample of the combination (unit wo, u in [0, 1)).
template <typename Real>
SampleResult<Real> sampleCombination(const Interpreter<Real>& in, const ResolvedBsdf<Real>& r, const Vec3<Real>& wo,
                                     const std::array<Real, 3>& u);

}  // namespace facet
