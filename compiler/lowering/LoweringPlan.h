// LoweringPlan: every decision the LLVM lowering makes about a material,
// made once, before any IR exists.
//
// planLowering() is a pure function of the checked (specialized) material
// and the math variant: which bodies the batch kernel has (plain, or a
// guarded first body with a fallback), in which precision each body
// computes geometry, expressions and the Fresnel term, which Smith form the
// masking uses, which guards a guarded body needs. The per-model facts it
// needs come from the models' lowering traits (TermEmitters.h), never from
// a switch on model kinds. The emitters read the plan and re-derive
// nothing; `facet ir --plan FILE` prints it (printPlan).
#pragma once

#include "LambdaTable.h"
#include "Material.h"
#include "ValueRange.h"

#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace facet {

enum class MathMode { Exact, Fast };
const char* mathModeName(MathMode m);

// Which approximations a kernel uses. `exact` keeps every term at full float
// accuracy (double where float rounding would be amplified); `fast` computes
// everything in float with shorter polynomials and lets the backend use
// estimates refined by one Newton step where it can (see `estimates`). The
// two model substitutions change the model the user named, so only a
// tolerance may enable them.
struct MathVariant {
    bool precise = true;            // geometry, exponents, exact Fresnel, parameters in double
    bool estimates = false;         // x/sqrt(y) by an rsqrt estimate + 1 Newton step
    bool shortPolynomials = false;  // exp/log/atan2 polynomials for ~1e-6 instead of 1 ulp
    bool walterLambda = false;      // Beckmann-profile Smith Lambda: Walter et al. 2007 rational fit
    bool schlickDielectric = false; // dielectric(eta) evaluated as Schlick with f0 from eta
    // With `precise`: evaluate each lane first in float (IEEE division and
    // sqrt, the exact polynomials) and keep that value only where the lane is
    // well-conditioned (the guards); every other lane is recomputed in the
    // precise body. Without `precise` (fast): evaluate each lane first with
    // the unscaled Smith forms and D G / (4 ci co) as one fraction, keep that
    // value where the range guards show that no intermediate left float's
    // normal range, and recompute the other lanes in the plain fast body.
    // The plan decides per material whether either applies.
    bool floatFirst = true;

    static MathVariant exact() { return {}; }
    static MathVariant fast() { return {false, true, true, false, false}; }
    std::string name() const;  // e.g. "exact", "fast", "fast+walter"
    bool operator==(const MathVariant&) const = default;
};

enum class Precision { Float, Double };
const char* precisionName(Precision p);

// The bodies of a batch kernel.
enum class BatchBodies {
    Plain,        // one body
    FloatFirst,   // exact: a guarded float body, the precise body for untrusted lanes
    GuardedFast,  // fast: a guarded body with unscaled Smith forms, the plain fast body for the rest
};
const char* batchBodiesName(BatchBodies b);

// What one lane body is.
enum class BodyRole {
    Plain,         // every lane's value is final
    FloatGuarded,  // the float body of a float-first exact kernel
    FastGuarded,   // the guarded body of a fast kernel
};
const char* bodyRoleName(BodyRole r);

// How |wi + wo|, wo.h, 1 - wo.h and sin^2 are computed.
enum class HalfVectorForm {
    Precise,    // in the body's precise type, cancellation-free 1 - cos
    InFloat,    // in float, no unit h: a double body's consumers are well-conditioned in float,
                // or the float-first body's D takes wi + wo
    Estimated,  // 1/|h| from an rsqrt estimate, 1 - cos = 1 - |h|/2 (fast bodies)
    Direct,     // |h| in the precise type, 1 - cos = 1 - |h|/2, no unit h (double bodies)
};
const char* halfVectorFormName(HalfVectorForm h);

// How the Smith masking gets its (n.v)(1 + Lambda(v)) terms.
enum class LambdaForm {
    None,       // the masking is not a Smith form
    RootSums,   // from R(v) = sqrt((n.v)^2 + proj(v)) (the NDF's root form)
    ClosedForm, // the NDF's closed-form (n.v) Lambda(v)
    WalterFit,  // Walter et al. 2007's rational fit of the Beckmann-profile Lambda
    Table,      // the NDF's tabulated Lambda (LambdaTable.h), embedded in the kernel
};
const char* lambdaFormName(LambdaForm l);

struct BodyPlan {
    BodyRole role = BodyRole::Plain;
    // The type of the quantities that need more than float in exact mode
    // (D, the Smith sums, F and the lobe): double in an exact plain body,
    // float otherwise.
    Precision precise = Precision::Double;
    bool estimates = false;         // reciprocal/rsqrt estimates allowed
    bool shortPolynomials = false;  // the fast elementary functions
    HalfVectorForm halfVector = HalfVectorForm::Precise;
    // wi + wo and wi - wo from the float inputs as they are, plus the
    // normalization as a small correction w (1/|w| - 1) with |w|^2 - 1 in
    // double: each sum is then accurate relative to itself. Float bodies
    // need it (the float-first body, the plain fast bodies): summing the
    // unit directions rounded to float instead decides h by those roundings
    // where wi + wo cancels (near-opposite directions), which amplifies
    // them by 1/|wi + wo| and D by another ~2/alpha. Double bodies
    // normalize in double. The guarded fast body sums the rounded unit
    // directions (the double |w|^2 of the correction would cost it ~60%)
    // and its NDF distrusts the lanes where that rounding would move D
    // beyond fast mode's accuracy, which its fallback recomputes.
    bool correctedSums = false;
    // With correctedSums, in a body with a fallback (the float-first body)
    // of an isotropic NDF: the pair's corrections from float arithmetic
    // alone, the common part from |w|^2 - 1 in float and the difference
    // from (wi - wo).(wi + wo) (LaneEmitter::floatPairCorrections). That
    // difference is off by up to ~1e-8, which moves the corrected wi + wo
    // by ~1 ulp of its length along wi - wo: harmless where D sees only the
    // angle between h and n, but not where an anisotropic D resolves a
    // tangential component of h that nearly cancels, with an alpha as
    // small as that component (docs/numerics.md). It is accurate only for
    // nearly unit inputs; the body distrusts the others, and its fallback
    // decides their validity, as a body without a fallback could not.
    bool floatPairCorrections = false;
    // The masking forms in float are scaled by max(ci, co) and divide in
    // steps, so that no sum of products falls into the subnormal range and
    // an intermediate overflows only if the result does. Unneeded in double,
    // and in a guarded body (its guards keep the sums in range).
    bool scaleMaskingSums = false;
    // The material's own expressions (inputs, lets, model arguments).
    Precision expressions = Precision::Double;
    // Whether the output needs the NaN/Inf/negative check: a guarded body
    // without a diffuse term has its value bounded by its guards.
    bool checkOutput = true;
    // A float-subnormal n.wi or n.wo is read as 0, what DAZ would make of
    // it: the plain fast bodies' float forms (the masking sums scaled by
    // max(ci, co), the cosine products) are written for cosines that are 0
    // or normal (anisotropic student_t's gives 2.8e5 times f on subnormal ones).
    // Reading them as 0 costs a compare and a select per direction; setting
    // FTZ/DAZ for the call would cost two MXCSR writes, which serialize
    // the FP pipeline (docs/perf-log.md). Every entry reads its directions
    // this way (LaneEmitter::readDirection). Guarded bodies distrust small
    // cosines anyway, and double bodies represent them.
    bool subnormalCosinesAsZero = false;

    bool guarded() const { return role != BodyRole::Plain; }
};

struct FresnelPlan {
    bool substituteSchlick = false;  // the tolerance's Schlick substitution for a dielectric
    bool exactInFloat = false;       // the exact term in float (well-conditioned constant parameters)
    bool rangeGuard = true;          // guarded body: check 1e-8 <= F (and F <= 2 unless atMostOne)
    bool atMostOne = false;          // F <= 1 by construction
    // F can be 0: every term but none, unless constant arguments keep F >= 1e-12.
    bool canVanish = true;
};

// How the sample and pdf entry points draw and weigh directions (SPEC 8):
// the specular lobe through visible normals or NDF sampling (the catalog's
// samplesVisibleNormals), a cosine lobe where the material has a diffuse
// base or energy compensation, and the lobe probability's albedo estimate.
enum class SpecularSampling {
    None,           // the NDF has no JIT sampler: no sample/pdf entry points
    NdfNormals,     // m with density normalPdf(m), the NDF entry's own
    VisibleNormals, // m with density G1(wo) (wo.m)+ D(m) / (n.wo)
};
const char* specularSamplingName(SpecularSampling s);

struct SamplingPlan {
    // Whether the kernel has compiled sample and pdf entry points (one lobe:
    // the NDF has a sampler in IR; a combination: every lobe that has an NDF).
    bool compiled = false;
    SpecularSampling specular = SpecularSampling::None;
    bool cosineLobe = false;          // diffuse base or Kulla-Conty compensation
    bool compensationAlbedo = false;  // the lobe probability reads the Kulla-Conty table
    // energy = random_walk: sample by walking the microsurface, and the
    // walk's MIS density as pdf (LaneWalk.cpp, compiler/reference/WalkLobe.h).
    bool walk = false;
    // The plain body: the scalar sample and pdf entries, the batch pdf
    // entry, and the lanes a float-first sample batch body distrusts.
    BodyPlan body;
    // The sample batch entry's bodies: Plain (`body` alone) or FloatFirst
    // (an exact kernel whose NDF samples well in float: `batchBody`, the
    // guarded float body, first, and `body` for the lanes it distrusts).
    // Fast kernels sample in `body`, which is float already.
    BatchBodies batchBodies = BatchBodies::Plain;
    BodyPlan batchBody;
};

// A model parameter as the material's expressions can give it (ValueRange.h):
// the lowering tests a lane's parameter only for what its range leaves
// possible, and emitters may pick forms that hold within the range.
struct ParamPlan {
    ValueRange range;            // after the clamp to the catalog domain
    bool testNaN = true;         // the argument can be NaN (the lane is then invalid)
    bool testFloatRange = true;  // the clamped value can overflow float (invalid too)
};

struct LobeLowering;
struct MuTable;  // LayerAlbedo.h
class EnergyTable;

struct LoweringPlan {
    MathVariant variant;
    BatchBodies batchBodies = BatchBodies::Plain;
    BodyPlan scalarBody;                 // the scalar kernel: always plain
    BodyPlan batchBody;                  // the batch kernel's (first) body
    std::optional<BodyPlan> fallbackBody;  // for the lanes a guarded batch body distrusts
    // A batch call of one lane runs the batch's lane body at one lane
    // (where LoweringOptions::oneLaneBodies has it emitted) instead of a
    // vector of `width` lanes: on every bench material a one-lane vector
    // call cost 1.0-3.5x a scalar call (docs/perf-log.md), while at two
    // lanes the vector wins on about half of them.
    bool oneLaneBody = true;
    bool ndfIsotropic = false;           // one alpha, or equal constant alphas
    LambdaForm lambda = LambdaForm::None;
    std::shared_ptr<const LambdaTable> lambdaTable;  // LambdaForm::Table: the material's table
    FresnelPlan fresnel;
    bool compensatesEnergy = false;
    // energy = random_walk: eval adds a walk's estimate of the orders >= 2
    // (LaneWalk.cpp); every body is the exact plain body (fast mode too: a
    // walk in float would branch away from the reference's path).
    bool walksMicrosurface = false;
    // SPEC 11: the lobe scatters over the whole sphere (LaneDielectric.cpp;
    // the reference is compiler/reference/DielectricLobe.h): a refracting
    // interface or a thin sheet (thinSheet), the pairs it keeps (on one
    // side, across), and the transport its refracted pairs are for. One
    // plain body (double in exact mode, float in fast mode), its sampler
    // in LaneDielectricSampling.cpp.
    bool wholeSphere = false;
    bool thinSheet = false;
    bool keepsReflection = true, keepsTransmission = false;
    Transport transport = Transport::Radiance;
    // Its energy = kulla_conty (compensatesEnergy; WholeSphereEnergy.cpp):
    // the crossing shares' constants, from the lobe's constant index
    // (compiler/reference/DielectricEnergy.h, crossingConstants): the smooth
    // interface's share 1 - F_avg and eta^2, which each lane limits by its
    // tables' averages, or the thin sheet's share per channel.
    double smoothCrossing = 0, interfaceEta2 = 1;
    std::array<double, 3> sheetCrossing{};
    // The host's promise (assume=unit): finite directions with |w| within
    // 1e-3 of 1, finite inputs, u in [0, 1). The kernel then drops the work
    // whose only purpose is to find lanes that break it: the direction,
    // input and u tests, the invalid count and the status (0). It keeps
    // everything that can change a value on such inputs: the normalization,
    // the input range clamps, the clamps of model parameters to their
    // domains and their NaN/overflow tests (those the parameters' ranges
    // leave possible, as in the default), the output check, the guards of
    // two-body kernels; so its outputs are bit-identical to the default's
    // there.
    bool trustInputs = false;
    // What the model arguments read (CheckedMaterial::readByModels): only
    // those inputs are loaded and tested, only those lets lowered.
    CheckedMaterial::Reads reads;
    // Whether slot s (CheckedMaterial's flat slot index) is read.
    bool slotRead(int slot) const;
    SamplingPlan sampling;
    // By ModelSlot, then the catalog's canonical parameter index.
    std::array<std::vector<ParamPlan>, kModelSlotCount> params;
    const ParamPlan& param(ModelSlot slot, int p) const { return params.at(int(slot)).at(p); }

    // ---- a combination of lobes (CheckedMaterial::combinesLobes; SPEC 10) ----
    // Per lobe (CheckedMaterial::lobes order): the lobe alone (lobeView) and
    // its own plan, with one plain body (no float-first or guarded body: a
    // lane's value needs every lobe, so a guarded body's fallback would be
    // the whole combination). The fields above describe the combination's
    // entries: its reads (every lobe's and the weights'), the bodies' common
    // attributes (lobe 0's body), no parameters and no compiled sampler.
    std::vector<std::shared_ptr<const LobeLowering>> lobes;
    // Per node of CheckedMaterial::bsdf: a layer's g table (LayerAlbedo.h),
    // baked from the constant parameters it depends on; null elsewhere.
    std::vector<std::shared_ptr<const MuTable>> layerG;
    // The mixture sampler's estimates: per node of CheckedMaterial::bsdf, a
    // lobe's directional albedo (at the default inputs: the probabilities
    // are estimates, the pdf is the mixture's whatever they are) and a
    // layer's top albedo E_top; null elsewhere, and all null in a plan made
    // without the sampler's tables (planLowering's samplerTables).
    std::vector<std::shared_ptr<const MuTable>> nodeAlbedo;
    bool combines() const { return !lobes.empty(); }
};

struct LobeLowering {
    CheckedMaterial material;  // lobeView(combination, lobe)
    LoweringPlan plan;
};

// `material` checked (and usually specialized). `trustInputs`: the host's
// promise of valid inputs (LoweringPlan::trustInputs).
// A combination of lobes is planned lobe by lobe (CombinationPlan.cpp);
// `lobeEnergyTables` (per lobe, null for none) spare the layers' bake
// building the lobes' Kulla-Conty tables again.
// `samplerTables` false leaves out the mixture sampler's albedo tables
// (LoweringPlan::nodeAlbedo), which only sample and pdf entry points read:
// an eval-only compile of a combination does not integrate them.
LoweringPlan planLowering(const CheckedMaterial& material, const MathVariant& variant, bool trustInputs = false,
                          const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables = {},
                          bool samplerTables = true, Transport transport = Transport::Radiance);
// CombinationPlan.cpp: planLowering() and printPlan() of a combination.
LoweringPlan planCombination(const CheckedMaterial& material, const MathVariant& variant, bool trustInputs,
                             const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables,
                             bool samplerTables);
void printCombinationPlan(std::ostringstream& os, const CheckedMaterial& material, const LoweringPlan& plan);

// How the specular lobe of `material` is sampled in IR (None: the kernel
// has no compiled sampler), as planLowering() plans it for every variant.
SpecularSampling plannedSpecularSampling(const CheckedMaterial& material);
// Whether planLowering() plans compiled sample and pdf entry points
// (SamplingPlan::compiled).
bool hasCompiledSampler(const CheckedMaterial& material);

// The plan as text, one decision per line (`facet ir --plan`).
std::string printPlan(const CheckedMaterial& material, const LoweringPlan& plan);

// Whether the model substitutions of MathVariant can change this material:
// a Smith masking on a Beckmann-profile Lambda for walterLambda, a
// dielectric Fresnel term for schlickDielectric.
bool walterLambdaApplies(const CheckedMaterial& material);
bool schlickDielectricApplies(const CheckedMaterial& material);

}  // namespace facet
