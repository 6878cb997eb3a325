// Interpreter: the reference evaluator of a checked material.
//
// It walks the checked material in double precision (or any wider real type;
// the hard-case checks run it in __float128; in float it is the SPEC
// formula evaluated in float, fast mode's accuracy bar) and evaluates each model term
// from the formulas of SPEC section 3, written for obvious correctness rather
// than speed. Every compiled evaluator is tested against it, so it shares no
// code with the JIT lowering: only the checked material and the builtin
// function semantics (ExprEval.h) are common.
//
// Resolving a material against a set of input values gives one
// ResolvedMaterial per lobe (SPEC 10; a material without lobe blocks has
// one), whose term functions (D, Lambda, G, F) the physics tests call
// directly, and the combination's weights (ResolvedBsdf, LobeCombination.h).
#pragma once

#include "Builtins.h"
#include "ExprEval.h"
#include "GaussianNormalization.h"
#include "KullaConty.h"
#include "Material.h"

#include <array>
#include <memory>
#include <mutex>
#include <vector>

namespace facet {

// One lobe with its parameters evaluated for one set of input values: each
// slot's catalog entry and its clamped arguments. The term functions
// dispatch to the entries' reference formulas. ndf is null for a diffuse
// lobe (only `diffuse`): its specular term is zero.
template <typename Real>
struct ResolvedMaterial {
    bool valid = true;  // false when an input or parameter is not finite
    const NdfEntry* ndf = nullptr;
    const MaskingEntry* masking = nullptr;
    const FresnelEntry* fresnel = nullptr;
    const EnergyEntry* energy = nullptr;
    const DiffuseEntry* diffuse = nullptr;
    ModelArgs<Real> ndfArgs, maskingArgs, fresnelArgs, diffuseArgs;
    // energy = kulla_conty (KullaContyEval.h): the E table, the roughness it
    // is looked up with, 1 - E_avg there, and F_avg per channel.
    std::shared_ptr<const EnergyTable> energyTable;
    Real energyAlpha = 1, ecAvg = 0;
    std::array<Real, 3> favg{};
    // A whole-sphere lobe's compensation (DielectricEnergy.h): energyTable
    // is the table seen from outside, this one from inside (the same table
    // for a thin sheet), 1 - E_avg there, and the share of the compensated
    // energy that crosses the surface, per channel, from outside and from inside.
    std::shared_ptr<const EnergyTable> energyTableInside;
    Real ecAvgInside = 0;
    std::array<Real, 3> crossingOutside{}, crossingInside{};
    // SPEC 11: where the lobe scatters, whether it is a thin sheet, and the
    // transport of its transmission (DielectricLobe.h).
    Scatter scatter = Scatter::Reflect;
    bool thin = false;
    Transport transport = Transport::Radiance;

    // Scatters over the whole sphere (DielectricLobe.h) rather than as a BRDF.
    bool wholeSphere() const { return scatter != Scatter::Reflect || thin; }

    // The specular lobe alone: no Fresnel term, no energy compensation, no
    // diffuse base (the F = 1 albedo of the physics checks).
    ResolvedMaterial specularLobe() const;
    // Energy compensation switched off.
    ResolvedMaterial withoutEnergy() const;

    // Microfacet normal distribution D(m), m a unit vector (zero below the horizon).
    Real D(const Vec3<Real>& m) const;
    // Smith Lambda(v) of the NDF (NDFs with a closed-form Lambda only).
    Real lambda(const Vec3<Real>& v) const;
    // (n.v) Lambda(v): finite at grazing, where Lambda itself grows like 1/(n.v).
    Real cosLambda(const Vec3<Real>& v) const;
    // Smith G1(v, m) = chi+(v.m) / (1 + Lambda(v)).
    Real smithG1(const Vec3<Real>& v, const Vec3<Real>& m) const;
    // Shadowing-masking G(wi, wo, h) of the material's masking model, for
    // any microfacet normal h. brdf() passes cosHalf = wi.h = wo.h = |wi+wo|/2
    // for the half vector, one value for both so that f stays reciprocal.
    Real G(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real cosHalf = -1) const;
    // scale * G / ((n.wi)(n.wo)), formed without G or the product (the BRDF's
    // factor with scale = D; no 0/0 or 0 * Inf when they underflow at grazing).
    // oh = wi.h = wo.h.
    Real GOverCosines(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real oh,
                      Real scale = 1) const;
    // Fresnel reflectance of channel ch at cos = wi.h.
    Real F(Real cosTheta, int ch) const;
    // The same, given also sin^2 = 1 - cos^2 (accurate near cos = 1).
    Real fresnelAt(Real cosTheta, Real sin2Theta, int ch) const;
    // The BRDF (without the cosine factor), rgb; wi and wo must be unit
    // vectors. Zero for directions below the horizon, except for a
    // whole-sphere lobe (the BSDF of DielectricLobe.h).
    std::array<Real, 3> brdf(const Vec3<Real>& wi, const Vec3<Real>& wo) const;
    // The same with wi + wo given (eval() computes it more accurately than
    // the sum of the rounded unit vectors).
    std::array<Real, 3> brdf(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& sum) const;
};

// The isotropic specular lobe of `ndf` with roughness alpha (clamped to
// >= kMinAlpha) and masking `masking`, F = 1, as a reference material; the
// tables' and previews' lobes. `shape` holds the values of the NDF's
// tableShapeParams then the masking's.
ResolvedMaterial<double> lobeAtAlpha(const NdfEntry& ndf, const MaskingEntry& masking, double alpha,
                                     const std::vector<double>& shape = {});

// A whole material resolved for one set of input values: its lobes (in
// CheckedMaterial::lobes order) and, per node of CheckedMaterial::bsdf, the
// node's weight per channel, clamped (Scale >= 0; Mix and Layer to [0, 1];
// 1 where the node has none).
template <typename Real>
struct ResolvedBsdf {
    bool valid = true;  // false when an input, parameter or weight is not finite
    std::vector<ResolvedMaterial<Real>> lobes;
    std::vector<std::array<Real, 3>> weights;
};

template <typename Real>
struct EvalResult {
    std::array<Real, 3> rgb{};
    bool valid = true;
};

template <typename Real>
struct SampleResult;  // Sampling.h
template <typename Real>
struct PdfResult;

template <typename Real>
class Interpreter {
public:
    // A material with energy = kulla_conty uses `energyTable` (e.g. from a
    // TableCache, compiler/tables/TableCache.h); without one, the interpreter
    // builds its table in memory on first use (~0.5 s).
    // `energyTable` is the table of a material's single lobe (a material
    // that combines lobes builds one per compensating lobe).
    explicit Interpreter(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> energyTable = nullptr);
    // A combination with the tables of its lobes given (per lobe, in
    // CheckedMaterial::lobes order; null where a lobe has none or where the
    // interpreter is to build it).
    Interpreter(const CheckedMaterial& material, const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables);

    // Evaluates every let, model argument and weight for the given slot
    // values (material().slotCount of them; null means all defaults).
    // Inputs are clamped to their declared ranges; a non-finite input that
    // the material reads, or a non-finite parameter or weight, makes the
    // result invalid.
    ResolvedBsdf<Real> resolveAll(const Real* slots) const;
    // The same for a material that does not combine lobes: its one lobe.
    ResolvedMaterial<Real> resolve(const Real* slots) const;
    // The BRDF of the whole combination (LobeCombination.cpp); for one lobe
    // exactly that lobe's brdf().
    std::array<Real, 3> combinedBrdf(const ResolvedBsdf<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo,
                                     const Vec3<Real>& sum, const Real* slots) const;

    // Full evaluation with the SPEC section 2 conventions: directions that
    // are not finite or not unit length within 1e-3 give an invalid lane
    // (f = 0); valid directions are renormalized.
    EvalResult<Real> eval(const Real wi[3], const Real wo[3], const Real* slots) const;

    // Importance sampling (SPEC 8, Sampling.h), with eval()'s checks of the
    // directions; u holds three numbers in [0, 1). An invalid lane
    // (an invalid direction, input or u, or a non-finite result) has wi =
    // 0, pdf = 0, weight = 0 and valid = false. Defined in Sampling.cpp.
    SampleResult<Real> sample(const Real wo[3], const Real u[3], const Real* slots) const;
    PdfResult<Real> pdf(const Real wi[3], const Real wo[3], const Real* slots) const;

    const CheckedMaterial& material() const { return material_; }
    // The transport of refracting lobes (SPEC 11; radiance unless set).
    void setTransport(Transport transport) { transport_ = transport; }
    Transport transport() const { return transport_; }

    // The material resolved at its inputs' defaults, in double: what the
    // sampler estimates a combination's leaf probabilities from (LobeSampling.h).
    // Resolved on first use, once per interpreter and its copies, not once
    // per sample or pdf call. Defined in Sampling.cpp.
    const ResolvedBsdf<double>& resolvedDefaults() const;

private:
    void addInsideTables();
    const CheckedMaterial& material_;
    CheckedMaterial::Reads read_;  // what the models read: nothing else is evaluated
    Transport transport_ = Transport::Radiance;
    std::vector<std::shared_ptr<EnergyTableSlot>> energy_;  // per lobe; kulla_conty lobes only
    // Per lobe: the inside's table of a whole-sphere lobe with kulla_conty
    // (DielectricEnergy.h), built in memory on first use; null elsewhere.
    std::vector<std::shared_ptr<EnergyTableSlot>> energyInside_;
    struct ResolvedDefaults {
        std::once_flag once;
        ResolvedBsdf<double> value;
    };
    std::shared_ptr<ResolvedDefaults> defaults_ = std::make_shared<ResolvedDefaults>();
};

extern template class Interpreter<float>;
extern template class Interpreter<double>;
extern template class Interpreter<long double>;
extern template struct ResolvedMaterial<float>;
extern template struct ResolvedMaterial<double>;
extern template struct ResolvedMaterial<long double>;
// __float128 (libquadmath): include QuadMath.h before this header to compute with it.
extern template class Interpreter<__float128>;
extern template struct ResolvedMaterial<__float128>;

}  // namespace facet
