// TermEmitters: the lowering hooks of the model catalog.
//
// Every catalog entry has, next to its reference formulas (the entry file
// compiler/models/<slot>/<Stem>.cpp), an emitter in
// compiler/models/<slot>/<Stem>Emitter.cpp: its terms written as IR for
// float lanes (scalar or SIMD), plus the lowering traits the plan reads.
// The two are written independently on purpose: the differential tests
// compare them. The build lists the emitter files in a generated registry
// (as it does the entries), and termEmitters() finds an entry's emitter by
// the entry's name; a catalog test fails when an entry has none.
//
// The trait methods are pure (no IR); the emit methods append IR through
// the LaneEmitter they are given, which holds the body's plan, its
// arithmetic emitters, the lane's geometry and the material's parameters.
#pragma once

#include "CodegenIdentity.h"
#include "LoweringPlan.h"

#include <array>
#include <string_view>
#include <vector>

namespace llvm {
class Value;
}

namespace facet {

class LaneEmitter;
struct LaneGeometry;
struct LVal;

// The NDF's parameters for one lane: alphas (float, and in the precise
// type), and up to three values of the model's own (documented by each
// emitter: the Blinn-Phong exponent, GTR's gamma, ...).
struct NdfParams {
    llvm::Value *ax = nullptr, *ay = nullptr;    // float
    llvm::Value *axD = nullptr, *ayD = nullptr;  // precise type
    bool isotropic = false;
    std::array<llvm::Value*, 3> own{};
};

struct NdfLoweringTraits {
    // D needs h only up to scale (an exponent of slope ratios, or GGX's
    // ratio of powers): a double body may keep the half angle in float and
    // give D wi + wo, and so may a float-first body (floatFirstBody).
    bool dFromUnnormalizedHalf = false;
    // The whole lobe is one formula (no D, no masking): wholeLobe().
    bool wholeLobe = false;
    // D and the Smith forms have a guarded float body (float-first exact
    // kernels), and, isotropic, a guarded fast body (D as one fraction).
    bool floatFirstBody = false;
    bool guardedFastBody = false;
    // Smith terms from R(v) = sqrt((n.v)^2 + proj(v)) (smithRootSquared).
    bool smithRootSums = false;
    // Its Smith Lambda has the Beckmann profile: Walter's fit can replace it.
    bool beckmannProfileLambda = false;
    // Always isotropic (one alpha parameter).
    bool isotropicOnly = false;
    // Has the samplers in IR (sampleNormal / sampleVisibleNormal); the plan
    // picks which one the catalog asks for, and emits no sampler when the
    // emitter lacks it.
    bool samplesNormals = false;
    bool samplesVisibleNormals = false;
    // Its samplers keep float's accuracy in a guarded float body (closed
    // forms, no CDF inversion), distrusting the lanes where they would not
    // (LaneEmitter::distrust): float-first exact sample batches.
    bool floatFirstSampler = false;
};

class NdfEmitter {
public:
    virtual ~NdfEmitter() = default;
    NdfLoweringTraits traits;

    // Clamped parameters of the lane (in the lane's expression order).
    virtual NdfParams params(LaneEmitter& lane) const = 0;
    // D(h) in the precise type.
    virtual llvm::Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const;
    // f without Fresnel for a whole-lobe NDF, precise type.
    virtual llvm::Value* wholeLobe(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const;
    // The alphas of the Smith projection (vx ax)^2 + (vy ay)^2, float; iso
    // set when they are one value.
    virtual void smithAlphas(LaneEmitter& lane, const NdfParams& n, llvm::Value*& ax, llvm::Value*& ay,
                             bool& isotropic) const;
    // (n.v) Lambda(v), float.
    virtual llvm::Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<llvm::Value*, 3>& v) const;
    // R(v)^2 = (n.v)^2 + proj(v), float (smithRootSums), where R(v) = (n.v)(1
    // + 2 Lambda(v)). R is a norm of v (homogeneous of degree 1): the Smith
    // forms may take it of an unnormalized v and scale, and take the roots
    // of both directions together. `unit`: v is a unit vector to float
    // rounding, so the NDF may take |v| = 1 for granted.
    virtual llvm::Value* smithRootSquared(LaneEmitter& lane, const NdfParams& n, const std::array<llvm::Value*, 3>& v,
                                          bool unit) const;
    // The roughness the Kulla-Conty table is looked up with, precise type
    // (default: alpha, or sqrt(ax ay) for an anisotropic lobe).
    virtual llvm::Value* energyAlpha(LaneEmitter& lane, const NdfParams& n) const;

    // ---- importance sampling (SPEC 8), written independently of the
    // catalog entry's reference samplers; u1, u2 in [0, 1), everything in
    // the precise type ----
    // NDF sampling (traits.samplesNormals): a unit microfacet normal m with
    // m.z >= 0 and density normalPdf per solid angle of m.
    virtual std::array<llvm::Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, llvm::Value* u1,
                                                     llvm::Value* u2) const;
    // The density of sampleNormal at the unit normal `atM.h` (m.z > 0; a
    // geometry whose h, hD and slopeH are m): D(m) (n.m) by default.
    virtual llvm::Value* normalPdf(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& atM) const;
    // Visible-normal sampling (traits.samplesVisibleNormals) for the unit
    // wo, n.wo > 0: m with density G1(wo) (wo.m)+ D(m) / (n.wo), G1 from
    // visibleCosLambda.
    virtual std::array<llvm::Value*, 3> sampleVisibleNormal(LaneEmitter& lane, const NdfParams& n,
                                                            const std::array<llvm::Value*, 3>& wo, llvm::Value* u1,
                                                            llvm::Value* u2) const;
    // (n.v) Lambda(v) with the Lambda that normalizes the visible normals
    // (the exact Smith Lambda of D, the catalog's visibleCosLambda), for the
    // unit v (n.v > 0), both in the precise type. By default cosLambda (in
    // float, widened).
    virtual llvm::Value* visibleCosLambda(LaneEmitter& lane, const NdfParams& n,
                                          const std::array<llvm::Value*, 3>& v) const;
    // (n.v)(1 + Lambda(v)) with visibleCosLambda's Lambda, for the unit v
    // (n.v > 0), precise type: the visible-normal density's denominator
    // over 4. By default n.v + visibleCosLambda.
    virtual llvm::Value* visibleSmithSum(LaneEmitter& lane, const NdfParams& n,
                                         const std::array<llvm::Value*, 3>& v) const;
};

struct MaskingLoweringTraits {
    // Reads the unit h or divides by wo.h: the half angle stays precise.
    bool needsPreciseHalfAngle = false;
    // Needs Lambda(wi) and Lambda(wo) apart (not only their root sums).
    bool needsSeparateLambdas = false;
};

class MaskingEmitter {
public:
    virtual ~MaskingEmitter() = default;
    MaskingLoweringTraits traits;
    // D G / ((n.wi)(n.wo)) from `D` (D/4 in practice), precise type, formed
    // without G and without dividing two underflowed values.
    virtual llvm::Value* overCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                     const LaneGeometry& geo, llvm::Value* D) const = 0;
    // The same for a transmitted pair (SPEC 11), with wi mirrored above the
    // surface in `geo` (both cosines positive) and h the refracting facet:
    // scale G_T / ((n.wi)(n.wo)), G_T the masking's transmission form
    // (MaskingFormulas::transmittedGOverCosines). Only Smith forms have one.
    virtual llvm::Value* transmittedOverCosines(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                                const LaneGeometry& geo, llvm::Value* scale) const;
};

// A Fresnel model's per-lane F_avg inputs (Kulla-Conty): what average()
// needs, prepared once for the three channels.
struct FresnelAverageArgs {
    std::array<llvm::Value*, 3> a{}, b{};  // per channel, the model's own (f0; eta; eta and k)
    bool constant = false;                 // every parameter a constant: folded per channel
};

class FresnelEmitter {
public:
    virtual ~FresnelEmitter() = default;
    // Pure traits for the plan.
    virtual bool atMostOne() const { return false; }
    virtual bool canVanish() const { return true; }
    // The exact formula is well-conditioned in float for these arguments.
    virtual bool evaluableInFloat(const ModelUse&) const { return false; }
    // A float-first body can evaluate it for these arguments.
    virtual bool floatFirstCapable(const ModelUse& use) const { return evaluableInFloat(use); }
    // The half angle may be in float for it (with this plan's choices).
    virtual bool halfAngleInFloatOk(const ModelUse&, const FresnelPlan& plan) const {
        return !plan.substituteSchlick && plan.exactInFloat;
    }
    // F >= bound at every angle, settled by constant arguments.
    virtual bool atLeast(const ModelUse&, double) const { return false; }
    // The Schlick substitution (MathVariant::schlickDielectric) applies.
    virtual bool substitutableBySchlick() const { return false; }

    // F per channel, precise type.
    virtual LVal F(LaneEmitter& lane, const LaneGeometry& geo) const = 0;
    virtual FresnelAverageArgs averageArgs(LaneEmitter& lane) const;
    // F_avg of channel ch, precise type.
    virtual llvm::Value* average(LaneEmitter& lane, const FresnelAverageArgs& args, int ch) const = 0;

    // ---- the interface of a lobe that refracts or is a thin sheet (SPEC
    // 11; the checker allows only the dielectric term there) ----
    // The refractive index per channel, clamped to the catalog domain, precise type.
    virtual LVal refractiveIndex(LaneEmitter& lane) const;
    // F and the transmittance 1 - F at cos c on the near side of an
    // interface whose far side has the relative index eta (eta < 1: total
    // internal reflection past the critical angle); and the transmittance
    // of a refracted pair from its cosines with the facet on the near side
    // (c) and on the far side (ct > 0). Precise type; c in [0, 1].
    virtual llvm::Value* reflectanceAcross(LaneEmitter& lane, llvm::Value* eta, llvm::Value* c) const;
    virtual llvm::Value* transmittanceAcross(LaneEmitter& lane, llvm::Value* eta, llvm::Value* c) const;
    virtual llvm::Value* pairTransmittance(LaneEmitter& lane, llvm::Value* eta, llvm::Value* c, llvm::Value* ct) const;
};

class DiffuseEmitter {
public:
    virtual ~DiffuseEmitter() = default;
    virtual bool present() const { return false; }
    // f_diffuse per channel, precise type (present() only).
    virtual LVal diffuse(LaneEmitter& lane) const;
};

// What the sampler's lobe probability needs from an energy compensation at
// n.wo: 1 - E(n.wo) and the compensation lobe's albedo (channel mean).
struct CompensationAlbedo {
    llvm::Value* oneMinusE = nullptr;
    llvm::Value* albedo = nullptr;
};

class EnergyEmitter {
public:
    virtual ~EnergyEmitter() = default;
    // f_ms per channel, precise type (only for an entry that compensates).
    virtual std::array<llvm::Value*, 3> compensation(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                                     const FresnelEmitter& fresnel, llvm::Value* ci,
                                                     llvm::Value* co) const;
    // The same entry's albedos at n.wo = co for the lobe probability,
    // precise type (only for an entry that compensates).
    virtual CompensationAlbedo samplingAlbedo(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                                              const FresnelEmitter& fresnel, llvm::Value* co) const;
};

// One emitter of a registry file: the catalog entry's name and its emitter.
struct TermEmitterEntry {
    ModelSlot slot;
    const char* modelName;
    const void* emitter;  // the slot's emitter class
    // The constant tables the emitter embeds in the kernel of `material`
    // (the cache key hashes them). Per material, because building a table
    // can cost more than a compile: only kernels that embed it pay.
    std::vector<EmbeddedTable> (*tables)(const CheckedMaterial& material) = nullptr;
};

// The emitters of one material's models (internal error when a model has none).
struct MaterialEmitters {
    const NdfEmitter& ndf;
    const MaskingEmitter& masking;
    const FresnelEmitter& fresnel;
    const DiffuseEmitter& diffuse;
    const EnergyEmitter& energy;
};
MaterialEmitters termEmitters(const CheckedMaterial& material);

// Every registered emitter (catalog tests); nullptr where a model has none.
const TermEmitterEntry* findTermEmitterEntry(const ModelInfo& model);
const void* findTermEmitter(const ModelInfo& model);
const std::vector<TermEmitterEntry>& termEmitterRegistry();

}  // namespace facet
