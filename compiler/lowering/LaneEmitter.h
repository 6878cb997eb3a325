// LaneEmitter: one lane body of a kernel -- the BRDF of one lane (float) or
// of a vector of lanes (<W x float>) as straight-line IR.
//
// It computes what every model shares (the checked, renormalized
// directions and the half vector, the material's inputs and lets, the
// validity of the lane) and assembles f = F D G / (4 ci co) + diffuse +
// f_ms from the models' term emitters (TermEmitters.h). The model terms
// are in the emitters; the decisions (precisions, guards, forms) are in the
// plan's BodyPlan, which this class only reads.
//
// Arithmetic goes through three MathEmitters, named by the type they
// compute in: floatMath() (the lane type), preciseMath() (double in an
// exact plain body, float otherwise) and doubleMath() (always double). In
// the emitters' code they are `fm`, `pm` and `dm`.
//
// Files: LaneEmitter.cpp (geometry, assembly), ExprLowering.cpp (the
// material's expressions and parameters), LaneTerms.cpp (helpers several
// model terms share, constant tables and their lookups), LaneDielectric.cpp
// and LaneDielectricSampling.cpp (a lobe over the whole sphere).
#pragma once

#include "Diagnostics.h"
#include "Lowering.h"
#include "TermEmitters.h"
#include "NewtonLoop.h"
#include "VectorMath.h"

#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/Module.h>

#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace facet {

constexpr double kPi = 3.141592653589793238462643383279502884;

// A lowered expression value: one channel for float, three for rgb. When the
// three channel Values are the same pointer the rgb is gray and every
// operation on it is emitted once ("computed once" specialization).
struct LVal {
    std::array<llvm::Value*, 3> c{};
    bool rgb = false;
    bool gray() const { return c[0] == c[1] && c[1] == c[2]; }
    static LVal scalar(llvm::Value* v) { return {{v, v, v}, false}; }
};

// Unit directions, half vector and wo.h of one lane.
struct LaneGeometry {
    std::array<llvm::Value*, 3> wi, wo, h;  // float
    std::array<llvm::Value*, 3> hD;  // h in the precise type (h and hD are null where the half angle is in float)
    // h up to scale for the exponent NDFs, precise type: wi + wo (with its
    // squared length slopeHLen2) in double, the unit h (slopeHLen2 null) in float.
    std::array<llvm::Value*, 3> slopeH;
    llvm::Value* slopeHLen2 = nullptr;
    std::array<llvm::Value*, 3> wiD, woD;  // the unit directions in the precise type
    // Where the precise body normalized the directions itself (not the
    // float body's corrected sums): the float inputs as given and 1/|w| in
    // the precise type, for terms homogeneous in w that can start from the
    // inputs and scale afterwards (null elsewhere).
    std::array<llvm::Value*, 3> wiIn{}, woIn{};
    llvm::Value *wiInvLen = nullptr, *woInvLen = nullptr;
    llvm::Value* cosD;          // wo.h = wi.h in [0, 1], precise type
    llvm::Value* oneMinusCosD;  // 1 - wo.h = |wo - h|^2 / 2, precise type, without cancellation at wi = wo
    llvm::Value* sin2D;         // 1 - (wo.h)^2 from the same, precise type
    llvm::Value* hNonZero;
};

class LaneEmitter {
public:
    LaneEmitter(const CheckedMaterial& material, const LoweringPlan& plan, const BodyPlan& body,
                const EnergyTable* energyTable, llvm::IRBuilder<>& builder, llvm::Type* laneType,
                llvm::Module& module, const EnergyTable* energyTableInside = nullptr);

    struct Result {
        std::array<llvm::Value*, 3> rgb;
        llvm::Value* invalid;
        llvm::Value* untrusted;  // guarded body: lanes to recompute in the other body (includes invalid ones)
    };
    Result emit(std::array<llvm::Value*, 3> wi, std::array<llvm::Value*, 3> wo,
                const std::vector<llvm::Value*>& slots);

    // ---- importance sampling (LaneSampling.cpp; SPEC 8, the plan's
    // SamplingPlan): the body of the sample and pdf entry points ----
    struct SampleResult {
        std::array<llvm::Value*, 3> wi;      // float; 0 without a sample
        llvm::Value* pdf;                    // float, the mixture's density at wi
        std::array<llvm::Value*, 3> weight;  // float, f (n.wi) / pdf; 0 below the horizon
        llvm::Value* invalid;
        llvm::Value* untrusted;  // guarded body: lanes to recompute in the other body (includes invalid ones)
    };
    // One sample for the direction wo and the uniform numbers u (float lanes).
    SampleResult emitSample(const std::array<llvm::Value*, 3>& wo, const std::array<llvm::Value*, 3>& u,
                            const std::vector<llvm::Value*>& slots);
    struct PdfResult {
        llvm::Value* pdf;  // float
        llvm::Value* invalid;
    };
    PdfResult emitPdf(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                      const std::vector<llvm::Value*>& slots);

    // ---- what the combination of lobes uses (CombinationEmitter.cpp) ----
    // The material's inputs and lets the plan reads (for a weight emitter:
    // a plan whose reads are the combination's), then an expression of
    // them clamped to [lo, hi], in double; a NaN value marks the lane invalid.
    void lowerExpressions(const std::vector<llvm::Value*>& slots) { lowerInputsAndLets(slots); }
    LVal clampedExpression(const Expr& e, double lo, double hi);
    llvm::Value* invalidLanes() const { return invalid_; }

    // ---- what the term emitters use ----
    const CheckedMaterial& material;
    const LoweringPlan& plan;
    const BodyPlan& body;
    llvm::IRBuilder<>& builder;

    MathEmitter& floatMath() { return floatMath_; }
    MathEmitter& preciseMath() { return preciseMath_; }
    MathEmitter& doubleMath() { return doubleMath_; }
    // The emitter of the material's expressions (BodyPlan::expressions).
    MathEmitter& expressionMath() {
        return body.expressions == Precision::Double && !preciseMath_.isDouble() ? doubleMath_ : preciseMath_;
    }
    llvm::Module& module() { return module_; }
    const EnergyTable* energyTable() const { return energyTable_; }
    // A whole-sphere lobe's compensation table from inside (its outside's
    // is energyTable(); a thin sheet's are the same table).
    const EnergyTable* energyTableInside() const { return energyTableInside_; }

    // Lane validity: `cond` lanes are invalid (value 0, counted).
    void markInvalid(llvm::Value* cond);
    // The lanes `cond()` emits break the host's promise of valid inputs (a
    // direction not finite or not unit, a non-finite input, u outside [0,
    // 1)): invalid lanes; where the plan trusts the inputs the test is not
    // emitted at all.
    template <typename Cond>
    void rejectInput(Cond&& cond) {
        if (!plan.trustInputs) markInvalid(cond());
    }
    // Guarded body only: `cond` lanes are recomputed in the kernel's other body.
    void distrust(llvm::Value* cond);

    // Model parameter p of `use`, clamped to the catalog domain (and to
    // `capHi`); NaN, or infinite in float after clamping, marks the lane
    // invalid. The result is float (floatResult) or the precise type.
    llvm::Value* scalarParam(const ModelUse& use, int p, bool floatResult = true, double capHi = INFINITY);
    LVal rgbParam(const ModelUse& use, int p, bool floatResult = true, double capHi = INFINITY);

    // Applies `op` channel-wise, once for gray values.
    template <typename Op>
    LVal map(const std::vector<LVal>& args, bool rgb, Op op) {
        LVal out;
        out.rgb = rgb;
        bool gray = true;
        for (const LVal& a : args) gray &= a.gray();
        for (int ch = 0; ch < 3; ++ch) {
            if (gray && ch > 0) {
                out.c[ch] = out.c[0];
                continue;
            }
            std::vector<llvm::Value*> xs;
            for (const LVal& a : args) xs.push_back(a.c[ch]);
            out.c[ch] = op(xs);
        }
        return out;
    }

    // ---- shared pieces of model terms (LaneTerms.cpp) ----
    // alpha_x = parameter px of `use` and alpha_y = py (or alpha_x), in the
    // precise type; then roundAlphas() gives their float values.
    NdfParams alphaParams(const ModelUse& use, int px, int py, bool isotropic);
    void roundAlphas(NdfParams& n);
    // Both, for an NDF with alpha_x = px and alpha_y = py (px == py: one
    // alpha; also one where the plan says the NDF is isotropic) and, in
    // NdfParams::own in this order, the model's own parameters `own` in the
    // precise type.
    NdfParams roundedAlphaParams(const ModelUse& use, int px, int py, std::initializer_list<int> own = {}) {
        NdfParams n = alphaParams(use, px, py, px == py || plan.ndfIsotropic);
        int k = 0;
        for (int p : own) n.own.at(k++) = scalarParam(use, p, false);
        roundAlphas(n);
        return n;
    }
    llvm::Value* intrinsic(llvm::Intrinsic::ID id, llvm::Value* a);
    // exp(-e) for the NDF tails (e >= 0), 0 where it would leave the precise
    // type's normal range.
    llvm::Value* expTail(llvm::Value* e);
    double expTailLimit() const { return preciseMath_.isDouble() ? 700.0 : 85.0; }
    // expm1(y)/y, continuous at 0.
    llvm::Value* expm1OverX(llvm::Value* y);
    // mx^2/ax^2 + my^2/ay^2 (float; one division when isotropic).
    llvm::Value* slope2(const NdfParams& n, const std::array<llvm::Value*, 3>& h);
    // (mx^2/ax^2 + my^2/ay^2)/mz^2 in the precise type, of h or of any multiple of it.
    llvm::Value* slopeExponent(const NdfParams& n, const std::array<llvm::Value*, 3>& h);
    // alpha(v)^2 sin^2(theta_v) = (vx ax)^2 + (vy ay)^2, float.
    llvm::Value* smithProjection(const NdfEmitter& ndf, const NdfParams& n, const std::array<llvm::Value*, 3>& v);
    // The direction-correlation weight of Ashikhmin et al.: 4.41 phi / (4.41 phi + 1), precise type.
    llvm::Value* azimuthWeight(const LaneGeometry& geo);
    // x / y; when x is D/4 known as a fraction num/den (setQuarterD), num /
    // (den y): one IEEE division instead of two in a guarded body.
    llvm::Value* quarterDOver(llvm::Value* x, llvm::Value* y);
    // x / (y z), in steps where the plan scales the masking sums.
    llvm::Value* overProduct(llvm::Value* x, llvm::Value* y, llvm::Value* z);
    void setQuarterDFraction(llvm::Value* num, llvm::Value* den) { quarterD_ = {nullptr, num, den}; }
    // cos(theta_d) for the exact Fresnel terms in `math` (>= 1e-18 in float).
    llvm::Value* fresnelCos(MathEmitter& math, const LaneGeometry& geo);
    // Sampling helpers for the NDF emitters, precise type: the unit normal
    // with slopes (sx, sy); the one at sin^2(theta) = sin2 (and cos^2(theta)
    // = cos2 where the caller has it more accurately than 1 - sin2) and
    // azimuth 2 pi u; the normal of a shape-invariant NDF whose standard (alpha = 1)
    // slopes have squared radius r2 and azimuth 2 pi u, stretched by the
    // lane's alphas.
    std::array<llvm::Value*, 3> normalFromSlopes(llvm::Value* sx, llvm::Value* sy);
    std::array<llvm::Value*, 3> normalFromPolar(llvm::Value* sin2, llvm::Value* u, llvm::Value* cos2 = nullptr);
    std::array<llvm::Value*, 3> stretchedSlopeNormal(const NdfParams& n, llvm::Value* r2, llvm::Value* u);
    // expm1(y), precise type.
    llvm::Value* expm1(llvm::Value* y);
    // x in [lo, hi] with cdf(x) = target, for a cdf increasing on [lo, hi]:
    // bracketedNewton on cdf(x) - target from (lo + hi)/2. `cdfAndPdf(x)`
    // emits cdf(x) and its derivative.
    using CdfAndPdf = std::function<std::pair<llvm::Value*, llvm::Value*>(llvm::Value* x)>;
    llvm::Value* invertIncreasing(MathEmitter& math, const CdfAndPdf& cdfAndPdf, llvm::Value* target, llvm::Value* lo,
                                  llvm::Value* hi, int steps);
    // For the samplers that invert a CDF: emitBracketedNewton (NewtonLoop.h)
    // with this lane's builder.
    using NewtonTerms = facet::NewtonTerms;
    llvm::Value* bracketedNewton(MathEmitter& math, const std::function<NewtonTerms(llvm::Value*)>& eval,
                                 llvm::Value* v0, llvm::Value* lo, llvm::Value* hi, int steps,
                                 double settledStep = 0, double settledFloor = 0);
    // A thin sheet's reflectance R' = 2F / (1 + F) and transmittance T' =
    // T / (2 - T) = (1 - F) / (1 + F), summed over the bounces inside it
    // (LaneDielectric.cpp; precise type).
    llvm::Value* sheetReflectance(llvm::Value* F);
    llvm::Value* sheetTransmittance(llvm::Value* T);
    // Upper clamp of eta and k for the exact Fresnel terms (float: |N|^4 must stay finite).
    double maxFresnelIndex() const { return body.precise == Precision::Double ? INFINITY : 1e9; }

    // ---- constant tables (LaneTerms.cpp): made once per module and name ----
    llvm::GlobalVariable* floatTable(const std::vector<float>& data, const std::string& name);
    llvm::GlobalVariable* doubleTable(const std::vector<double>& data, const std::string& name);
    llvm::GlobalVariable* uint64Table(const std::vector<uint64_t>& data, const std::string& name);
    // table[index] of a float table for an integer-valued index in the
    // precise type (a gather across lanes), or in the type of `math` where
    // given (so are lerpFetch's and bilerpFetch's arguments and results).
    llvm::Value* fetch(llvm::GlobalVariable* table, llvm::Value* index, MathEmitter* math = nullptr);
    // 4-point Lagrange interpolation in a double table of `size` nodes at the
    // node coordinate u in [0, size - 1], all in double.
    llvm::Value* lagrangeFetch(llvm::GlobalVariable* table, int size, llvm::Value* u);
    // n-point Lagrange interpolation (n even) in a double table, all in
    // double: the stencil at node coordinate u in [0, size - 1] (its first
    // node, integer-valued, and the n weights), and the sum of weight k times
    // table[base + first + k] for an integer-valued base.
    struct LagrangeStencil {
        llvm::Value* first;
        std::vector<llvm::Value*> w;
    };
    LagrangeStencil lagrangeStencil(int size, int n, llvm::Value* u);
    llvm::Value* stencilFetch(llvm::GlobalVariable* table, const LagrangeStencil& st, llvm::Value* base);
    // table[index] + t (table[index + 1] - table[index]).
    llvm::Value* lerpFetch(llvm::GlobalVariable* table, llvm::Value* index, llvm::Value* t, MathEmitter* math = nullptr);
    // Bilinear interpolation in a row-major table with `stride` entries per row.
    llvm::Value* bilerpFetch(llvm::GlobalVariable* table, int stride, llvm::Value* row, llvm::Value* col,
                             llvm::Value* tRow, llvm::Value* tCol, MathEmitter* math = nullptr);

private:
    llvm::Type* boolType();
    // A direction as the body reads it: a float-subnormal z is 0 where the
    // plan says so (BodyPlan::subnormalCosinesAsZero). Every entry reads its
    // input directions through it once, before anything else uses them.
    std::array<llvm::Value*, 3> readDirection(const std::array<llvm::Value*, 3>& w);
    // `wiSampled`: wi is a float body's own sample (unit to float rounding).
    LaneGeometry geometry(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                          bool wiSampled = false);
    std::array<llvm::Value*, 3> brdf(const LaneGeometry& geo);
    // LaneDielectric.cpp: a lobe over the whole sphere (plan.wholeSphere).
    // f from the input directions, in float: its own geometry and the
    // lane's inputs and lets.
    std::array<llvm::Value*, 3> wholeSphereBsdf(const std::array<llvm::Value*, 3>& wi,
                                                const std::array<llvm::Value*, 3>& wo,
                                                const std::vector<llvm::Value*>& slots);
    // The lane's NDF parameters and index of refraction (per channel; the
    // interface's moved away from 1, SPEC 11), after lowerInputsAndLets.
    struct WholeSphereTerms {
        NdfParams n;
        LVal eta;
        llvm::Value* interfaceEta = nullptr;  // null for a thin sheet
    };
    WholeSphereTerms wholeSphereTerms();
    // eta' = the far side's index relative to wo's side (eta where wo is
    // above, woUp; else 1/eta), and eta' - 1 without cancellation near 1.
    std::pair<llvm::Value*, llvm::Value*> relativeEta(const WholeSphereTerms& t, llvm::Value* woUp);
    // f per channel in the precise type for unit wi, wo in the precise type
    // (0 where the selected facet faces away; either direction in the
    // surface is the caller's).
    LVal wholeSphereValue(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                          const WholeSphereTerms& t);
    // The facets eval and pdf select from unit wi, wo (LaneDielectric.cpp
    // says why these): the mirrored pair i = (wi.x, wi.y, |wi.z|), o =
    // (wo.x, wo.y, |wo.z|), their sum s, |s|, the unit h and wo.h = |s|/2
    // (at most 1); and, from it, the refracted facet of eta' - 1, with wi
    // in wo's frame (below), v = s' + (eta' - 1) wi', m = v/|v| turned up,
    // wi.m, wo.m, and whether m faces both directions.
    struct MirroredPair {
        std::array<llvm::Value*, 3> i, o, s, h;
        llvm::Value *len, *cos;
    };
    MirroredPair mirroredPair(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo);
    struct RefractedFacet {
        std::array<llvm::Value*, 3> wiFrame, m;
        llvm::Value *lenSq, *im, *om, *faces;
    };
    RefractedFacet refractedFacet(const MirroredPair& p, llvm::Value* etaMinusOne);
    // LaneDielectricSampling.cpp: its sample and pdf bodies.
    SampleResult emitWholeSphereSample(const std::array<llvm::Value*, 3>& wo, const std::array<llvm::Value*, 3>& u,
                                       const std::vector<llvm::Value*>& slots);
    PdfResult emitWholeSpherePdf(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                                 const std::vector<llvm::Value*>& slots);
    // The single-scattering sampler's density at unit wi for unit wo, both
    // off the surface (the mixture's part besides the compensation's).
    llvm::Value* singleScatteringPdf(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo,
                                     const WholeSphereTerms& t);
    // 0 for an invalid lane, in a one-lane body (LaneEmitter.cpp says why
    // not by a select).
    void zeroInvalidLaneByBranch(std::array<llvm::Value*, 3>& values);
    // f per channel in the precise type and the lanes where it applies (both
    // directions above the horizon, wi + wo not 0; elsewhere f = 0).
    std::array<llvm::Value*, 3> brdfPrecise(const LaneGeometry& geo, llvm::Value*& valid);
    // The unit direction of w in the precise type (SPEC 2: a non-finite or
    // non-unit w marks the lane invalid); with a double precise type, the
    // unit w in float too (unitF; else untouched), and 1/|w| (invLen).
    llvm::Value* checkedLength2(MathEmitter& math, const std::array<llvm::Value*, 3>& w,
                                std::array<llvm::Value*, 3>& widened);
    llvm::Value* length2(MathEmitter& math, const std::array<llvm::Value*, 3>& w, std::array<llvm::Value*, 3>& widened);
    std::array<llvm::Value*, 3> unitDirection(const std::array<llvm::Value*, 3>& w, std::array<llvm::Value*, 3>& unitF,
                                              llvm::Value** invLen = nullptr);
    // Float body: 1/|w| - 1 in float (the unit w is w + w times it), the
    // length checked as the precise body checks it (undecided lanes go to it).
    llvm::Value* unitCorrection(const std::array<llvm::Value*, 3>& w);
    // The corrected wi, wo, wi + wo and wi - wo of a float body with a
    // fallback, from float arithmetic only (BodyPlan::floatPairCorrections).
    struct CorrectedPair {
        std::array<llvm::Value*, 3> wi, wo, sum, diff;
    };
    CorrectedPair floatPairCorrections(const std::array<llvm::Value*, 3>& wi, const std::array<llvm::Value*, 3>& wo);

    // LaneWalk.cpp: energy = random_walk
    struct WalkState;
    using WalkStep = std::function<std::vector<llvm::Value*>(const WalkState&, llvm::Value* order, llvm::Value* met,
                                                             llvm::Value* left, const std::vector<llvm::Value*>& carried)>;
    std::vector<llvm::Value*> emitWalk(const std::array<llvm::Value*, 3>& wo, llvm::Value* seed, llvm::Value* walking,
                                       const std::vector<llvm::Value*>& carriedInit, const WalkStep& step);
    LVal walkFresnel(llvm::Value* cosine);
    std::array<llvm::Value*, 3> walkScattering(const LaneGeometry& geo, llvm::Value* above);
    struct WalkExit {
        std::array<llvm::Value*, 3> wi, weight;
    };
    WalkExit walkFromView(const std::array<llvm::Value*, 3>& wo, llvm::Value* walking,
                          const std::array<llvm::Value*, 3>& u);

    // LaneSampling.cpp
    struct SamplingTerms;
    SampleResult emitWalkSample(const std::array<llvm::Value*, 3>& wo, const std::array<llvm::Value*, 3>& u,
                                const std::vector<llvm::Value*>& slots);
    llvm::Value* walkPdf(SamplingTerms& t, const std::array<llvm::Value*, 3>& wi);
    void finishSample(SampleResult& r, llvm::Value* noSample);
    PdfResult finishPdf(llvm::Value* pdf);
    SamplingTerms samplingTerms(const std::array<llvm::Value*, 3>& wo);
    llvm::Value* specularProbability(SamplingTerms& t);
    llvm::Value* specularPdf(SamplingTerms& t, const std::array<llvm::Value*, 3>& m, llvm::Value* om);
    llvm::Value* mixturePdf(SamplingTerms& t, llvm::Value* spec, const std::array<llvm::Value*, 3>& wi);

    // ExprLowering.cpp
    void lowerInputsAndLets(const std::vector<llvm::Value*>& slots);
    LVal lower(const Expr& e);
    llvm::Value* applyBuiltin(BuiltinFn fn, const std::vector<llvm::Value*>& a);
    llvm::Value* powInt(llvm::Value* x, long k);
    llvm::Value* clampParam(llvm::Value* x, const ParamPlan& param, double lo, double hi, bool floatResult);

    const EnergyTable* energyTable_;
    const EnergyTable* energyTableInside_;
    llvm::Module& module_;
    MaterialEmitters emitters_;
    MathEmitter floatMath_;
    MathEmitter preciseMath_;
    MathEmitter doubleMath_;
    struct {
        llvm::Value *value, *num, *den;
    } quarterD_{nullptr, nullptr, nullptr};  // value = num / den
    llvm::Value* invalid_ = nullptr;
    llvm::Value* untrusted_ = nullptr;
    std::vector<LVal> inputs_, lets_;
};

}  // namespace facet
