// LoweringPlan: the decisions of the lowering, made once from the material,
// the math variant and the models' lowering traits (see LoweringPlan.h).
#include "LoweringPlan.h"

#include "Diagnostics.h"

#include <algorithm>
#include "Specialize.h"
#include "reference/DielectricEnergy.h"

#include <fmt/format.h>
#include "TermEmitters.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace facet {

const char* mathModeName(MathMode m) { return m == MathMode::Exact ? "exact" : "fast"; }

std::string MathVariant::name() const {
    std::string s = precise && !estimates && !shortPolynomials ? (floatFirst ? "exact" : "exact-double")
                                                                : (!precise && estimates && shortPolynomials ? "fast" : "custom");
    if (walterLambda) s += "+walter";
    if (schlickDielectric) s += "+schlick";
    return s;
}

const char* precisionName(Precision p) { return p == Precision::Float ? "float" : "double"; }

const char* batchBodiesName(BatchBodies b) {
    switch (b) {
        case BatchBodies::Plain: return "plain";
        case BatchBodies::FloatFirst: return "float-first";
        case BatchBodies::GuardedFast: return "guarded-fast";
    }
    return "?";
}

const char* bodyRoleName(BodyRole r) {
    switch (r) {
        case BodyRole::Plain: return "plain";
        case BodyRole::FloatGuarded: return "float-guarded";
        case BodyRole::FastGuarded: return "fast-guarded";
    }
    return "?";
}

const char* halfVectorFormName(HalfVectorForm h) {
    switch (h) {
        case HalfVectorForm::Precise: return "precise";
        case HalfVectorForm::InFloat: return "in-float";
        case HalfVectorForm::Estimated: return "estimated";
        case HalfVectorForm::Direct: return "direct";
    }
    return "?";
}

const char* lambdaFormName(LambdaForm l) {
    switch (l) {
        case LambdaForm::None: return "none";
        case LambdaForm::RootSums: return "root-sums";
        case LambdaForm::ClosedForm: return "closed-form";
        case LambdaForm::WalterFit: return "walter-fit";
        case LambdaForm::Table: return "table";
    }
    return "?";
}

const char* specularSamplingName(SpecularSampling s) {
    switch (s) {
        case SpecularSampling::None: return "none";
        case SpecularSampling::NdfNormals: return "ndf-normals";
        case SpecularSampling::VisibleNormals: return "visible-normals";
    }
    return "?";
}

namespace {

// Whether the NDF's two alphas are one: one alpha (the checker's flag;
// specialization may have copied the shared expression), or equal
// constants. The isotropic forms save divisions.
bool ndfIsIsotropic(const ModelUse& use) {
    if (use.isotropic || !use.model) return true;
    const int ax = paramIndex(*use.model, "alpha_x"), ay = paramIndex(*use.model, "alpha_y");
    if (ax < 0 || ay < 0 || !use.has(ax) || !use.has(ay)) return false;
    const Expr &x = *use.args[ax], &y = *use.args[ay];
    return &x == &y ||
           (isConstantExpr(x) && isConstantExpr(y) && constantValue(x)[0] == constantValue(y)[0]);
}

// A float body may evaluate the material's own expressions in float when
// they only multiply (and take square roots, min/max, small integer
// powers): each operation adds at most half an ulp of relative error, and
// up to 8 of them bound it to 8 * 2^-24 = 4.8e-7. A sum can cancel and a
// long chain drifts (a 20000-step let chain drifted 3e-5 in float), so
// anything else stays in double.
constexpr int kMaxFloatExpressionOperations = 8;

bool onlyMultiplicativeExpressions(const CheckedMaterial& material) {
    struct Scan : ExprVisitor {
        bool additive = false;
        int operations = 0;
        void visitBinary(const BinaryExpr& e) override {
            ++operations;
            if (e.op == BinaryOp::Add || e.op == BinaryOp::Sub) additive = true;
            if (e.op == BinaryOp::Pow && !smallPower(*e.rhs)) additive = true;
            ExprVisitor::visitBinary(e);
        }
        void visitCall(const CallExpr& e) override {
            ++operations;
            switch (e.function->id) {
                case BuiltinFn::Sqrt:
                case BuiltinFn::Abs:
                case BuiltinFn::Min:
                case BuiltinFn::Max:
                case BuiltinFn::Clamp:
                case BuiltinFn::Rgb: break;
                case BuiltinFn::Pow:
                    if (!smallPower(*e.args[1].value)) additive = true;
                    break;
                default: additive = true;  // exp, log, mix, phong conversions (a subtraction)
            }
            ExprVisitor::visitCall(e);
        }
        // powInt squares repeatedly, doubling the relative error each
        // time: up to |k| = 4 it stays within a few ulp.
        static bool smallPower(const Expr& x) {
            std::optional<long> k = smallIntegerConstant(x);
            return k && std::labs(*k) <= 4;
        }
    } scan;
    for (const CheckedLet& let : material.lets) scan.visit(*let.value);
    for (const ModelUse* use : {&material.singleLobe().ndf, &material.singleLobe().masking, &material.singleLobe().fresnel, &material.singleLobe().diffuse, &material.singleLobe().energy})
        for (const ExprPtr& arg : use->args)
            if (arg) scan.visit(*arg);
    return !scan.additive && scan.operations <= kMaxFloatExpressionOperations;
}

// The exact kernel's batch body is float-first when the NDF has a guarded
// float body, the Fresnel term can be evaluated there (see each emitter's
// floatFirstCapable), and no energy table is looked up.
bool floatFirstApplies(const CheckedMaterial& material, const MaterialEmitters& em, const MathVariant& variant) {
    if (!variant.precise || !variant.floatFirst || variant.estimates || variant.shortPolynomials) return false;
    return em.ndf.traits.floatFirstBody && !material.singleLobe().compensatesEnergy() &&
           em.fresnel.floatFirstCapable(material.singleLobe().fresnel);
}

// Otherwise (a Fresnel term or expressions the float-first body cannot
// take) the fast kernel's batch body is guarded when the NDF has a guarded
// fast body and is isotropic: an anisotropic D is not one fraction, so the
// guarded body would save only the Smith divisions (measured 3% faster for
// 5 ms more compile time: docs/perf-log.md).
bool guardedFastApplies(const CheckedMaterial& material, const MaterialEmitters& em, const MathVariant& variant,
                        bool ndfIsotropic) {
    if (variant.precise || !variant.floatFirst || !variant.estimates || !variant.shortPolynomials) return false;
    return em.ndf.traits.guardedFastBody && ndfIsotropic && !material.singleLobe().compensatesEnergy();
}

// Where the exact kernel has a guarded float body, a fast kernel takes it,
// with the plain fast body for the lanes it distrusts: that body skips the
// scaled masking sums and output checks of the plain fast body, and since
// it forms no unit h and no x, y Smith terms it is also faster than the
// guarded fast body (docs/perf-log.md); fast mode is then never slower
// than exact, and no less accurate. A variant that substitutes a model (a
// tolerance's choice) or turns float-first off keeps its own bodies.
bool fastTakesFloatFirst(const CheckedMaterial& material, const MaterialEmitters& em, const MathVariant& variant) {
    if (variant.precise || !variant.floatFirst || variant.walterLambda || variant.schlickDielectric) return false;
    return floatFirstApplies(material, em, MathVariant::exact());
}

// One body of the kernel. `role` and `bodyVariant` (the variant the body
// computes with: a float-first body is the exact variant without
// `precise`) settle its types; the model traits settle its forms.
BodyPlan planBody(const CheckedMaterial& material, const MaterialEmitters& em, const LoweringPlan& plan,
                  BodyRole role, const MathVariant& bodyVariant) {
    BodyPlan body;
    body.role = role;
    body.precise = bodyVariant.precise && role == BodyRole::Plain ? Precision::Double : Precision::Float;
    body.estimates = bodyVariant.estimates;
    body.shortPolynomials = bodyVariant.shortPolynomials;
    const bool inDouble = body.precise == Precision::Double;

    // A fast body takes 1 - wo.h as 1 - |wi + wo|/2 with |wi + wo| from an
    // rsqrt estimate: the cancellation leaves an absolute error of ~2e-7 in
    // q = 1 - cos, which moves Schlick's F relative to itself by at most
    // 4 dq/q where q^5 = 4 f0: 1e-5 for f0 = 1e-6. So only for no Fresnel
    // term or one that stays >= 1e-6; the exact terms need 1 - cos to
    // relative precision near their critical angle and near eta = 1.
    // A double body may leave out the unit h when every consumer is
    // well-conditioned without it: D from wi + wo (the exponent NDFs) and a
    // masking that neither divides by wo.h nor reads the unit h. Its 1 - cos
    // is then 1 - |wi + wo|/2 in double (dq ~ 2e-16, which moves F by at
    // most 2e-13 where F >= 1e-12) or, for a Fresnel term fine with a float
    // cos, the cancellation-free form in float (docs/perf-log.md has the
    // speed-ups).
    const bool unitHalfUnused = inDouble && role == BodyRole::Plain && em.ndf.traits.dFromUnnormalizedHalf &&
                                !em.masking.traits.needsPreciseHalfAngle;
    if (!inDouble && body.estimates && em.fresnel.atLeast(material.singleLobe().fresnel, 1e-6))
        body.halfVector = HalfVectorForm::Estimated;
    else if (unitHalfUnused && em.fresnel.atLeast(material.singleLobe().fresnel, 1e-12))
        body.halfVector = HalfVectorForm::Direct;
    else if (unitHalfUnused && em.fresnel.halfAngleInFloatOk(material.singleLobe().fresnel, plan.fresnel))
        body.halfVector = HalfVectorForm::InFloat;

    // The float-first body leaves the unit h out where the NDF's float D
    // takes wi + wo and the masking reads no unit h: D then waits neither
    // for |wi + wo|'s square root nor for the normalizing division, which
    // shortens the loop's longest chain.
    if (role == BodyRole::FloatGuarded && em.ndf.traits.dFromUnnormalizedHalf &&
        !em.masking.traits.needsPreciseHalfAngle)
        body.halfVector = HalfVectorForm::InFloat;

    body.correctedSums = !inDouble && role != BodyRole::FastGuarded;
    body.floatPairCorrections = body.correctedSums && role == BodyRole::FloatGuarded && plan.ndfIsotropic;

    // In float, the masking sums are scaled; in double and in a guarded
    // body (whose guards keep the sums in range) they need not be.
    body.scaleMaskingSums = !(inDouble || body.guarded());

    if (role == BodyRole::FloatGuarded)
        body.expressions = onlyMultiplicativeExpressions(material) ? Precision::Float : Precision::Double;
    else
        body.expressions = body.precise;

    // The guards bound a guarded body's value (F times the lobe) unless a
    // diffuse term (the user's unbounded albedo) is added.
    body.checkOutput = !(body.guarded() && !em.diffuse.present());
    body.subnormalCosinesAsZero = !inDouble && !body.guarded();
    return body;
}

}  // namespace

// The technique is the catalog's (visible normals only where the entry has
// an exact sampler and the masking is a Smith form); the NDF's emitter says
// whether it has that sampler in IR.
SpecularSampling plannedSpecularSampling(const CheckedMaterial& material) {
    // A combination is sampled by the reference's mixture (runtime), a
    // diffuse lobe alone too.
    if (material.combinesLobes() || !material.singleLobe().hasNdf()) return SpecularSampling::None;
    const NdfEmitter& ndf = termEmitters(material).ndf;
    const bool visible = samplesVisibleNormals(ndfEntry(*material.singleLobe().ndf.model), maskingEntry(*material.singleLobe().masking.model));
    if (!(visible ? ndf.traits.samplesVisibleNormals : ndf.traits.samplesNormals)) return SpecularSampling::None;
    return visible ? SpecularSampling::VisibleNormals : SpecularSampling::NdfNormals;
}

bool hasCompiledSampler(const CheckedMaterial& material) {
    if (!material.combinesLobes()) return plannedSpecularSampling(material) != SpecularSampling::None;
    for (size_t l = 0; l < material.lobes.size(); ++l)
        if (material.lobes[l].hasNdf() && plannedSpecularSampling(lobeView(material, int(l))) == SpecularSampling::None)
            return false;
    return true;
}

bool LoweringPlan::slotRead(int slot) const { return reads.slots.at(size_t(slot)); }

namespace {

// The parameters' plans (the clamp LaneEmitter::clampParam applies; a NaN
// argument or a clamped value beyond float makes the lane invalid, so the
// lowering tests for what the range leaves possible).
void planParams(const CheckedMaterial& material, LoweringPlan& plan) {
    const ValueRanges ranges(material);
    for (int s = 0; s < kModelSlotCount; ++s) {
        const ModelUse& use = material.singleLobe().use(ModelSlot(s));
        for (int p = 0; use.model && p < int(use.model->canonical.size()); ++p) {
            const ModelParam& domain = use.model->canonical[p];
            ValueRange arg = ranges.argument(use, p);
            ParamPlan param;
            param.range = arg.clampedTo(domain.lo, domain.hi);
            param.testNaN = arg.maybeNaN;
            param.testFloatRange = !param.range.withinFloat();
            plan.params[s].push_back(param);
        }
    }
}

}  // namespace

// energy = random_walk: the exact variant's plain double body everywhere
// (the walk branches on its random numbers: in float a lane would leave
// the reference's path), closed-form Smith sums (GGX, the checker's
// condition) and the walk's sampler.
static LoweringPlan planWalk(const CheckedMaterial& material, const MaterialEmitters& em, LoweringPlan plan,
                      const MathVariant& requested, bool trustInputs) {
    (void)requested;  // a fast kernel computes what the exact one does
    plan.variant = MathVariant::exact();
    plan.trustInputs = trustInputs;
    plan.ndfIsotropic = ndfIsIsotropic(material.singleLobe().ndf);
    plan.reads = material.readByModels();
    internal_assert(em.ndf.traits.smithRootSums && em.ndf.traits.samplesVisibleNormals)
        << "random_walk lowered for an NDF without closed-form Smith sums and a visible-normal sampler";
    plan.lambda = LambdaForm::RootSums;
    const FresnelEmitter& fresnel = em.fresnel;
    plan.fresnel.exactInFloat = fresnel.evaluableInFloat(material.singleLobe().fresnel);
    plan.fresnel.rangeGuard = !fresnel.atLeast(material.singleLobe().fresnel, 1e-6);
    plan.fresnel.atMostOne = fresnel.atMostOne();
    plan.fresnel.canVanish = fresnel.canVanish() && !fresnel.atLeast(material.singleLobe().fresnel, 1e-12);
    plan.scalarBody = planBody(material, em, plan, BodyRole::Plain, plan.variant);
    plan.batchBodies = BatchBodies::Plain;
    plan.batchBody = plan.scalarBody;
    planParams(material, plan);
    plan.sampling.specular = plannedSpecularSampling(material);
    internal_assert(plan.sampling.specular == SpecularSampling::VisibleNormals) << "random_walk without visible normals";
    plan.sampling.compiled = true;
    plan.sampling.walk = true;
    plan.sampling.body = plan.scalarBody;
    plan.sampling.batchBody = plan.scalarBody;
    return plan;
}

// A lobe over the whole sphere (SPEC 11): one plain body, which computes
// its own geometry (LaneDielectric.cpp) from directions it normalizes in
// the precise type. The float-first and guarded bodies' guards are written
// for the reflection geometry (h = wi + wo), so neither applies. Its sampler
// (LaneDielectricSampling.cpp) draws the NDF's normals as a reflecting
// lobe's does, in the same body.
static LoweringPlan planWholeSphere(const CheckedMaterial& material, const MaterialEmitters& em, LoweringPlan plan,
                                    Transport transport) {
    const CheckedLobe& lobe = material.singleLobe();
    internal_assert(lobe.hasNdf() && !em.ndf.traits.wholeLobe && plan.lambda != LambdaForm::None)
        << "a whole-sphere lobe without a microfacet NDF and a Smith masking";
    plan.thinSheet = lobe.thin;
    plan.keepsReflection = lobe.scatter != Scatter::Transmit;
    plan.keepsTransmission = lobe.scatter != Scatter::Reflect;
    plan.transport = transport;
    if (plan.compensatesEnergy) {
        CrossingConstants constants = crossingConstants(material);
        plan.smoothCrossing = constants.smoothCrossing;
        plan.interfaceEta2 = constants.eta2;
        plan.sheetCrossing = constants.sheetCrossing;
    }
    plan.scalarBody = planBody(material, em, plan, BodyRole::Plain, plan.variant);
    plan.scalarBody.halfVector = HalfVectorForm::Precise;
    plan.scalarBody.correctedSums = false;
    plan.batchBodies = BatchBodies::Plain;
    plan.batchBody = plan.scalarBody;
    planParams(material, plan);
    plan.sampling.specular = plannedSpecularSampling(material);
    plan.sampling.compiled = plan.sampling.specular != SpecularSampling::None;
    plan.sampling.body = plan.sampling.batchBody = plan.scalarBody;
    return plan;
}

LoweringPlan planLowering(const CheckedMaterial& material, const MathVariant& variant, bool trustInputs,
                          const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables, bool samplerTables,
                          Transport transport) {
    if (material.combinesLobes())
        return planCombination(material, variant, trustInputs, lobeEnergyTables, samplerTables);
    const MaterialEmitters em = termEmitters(material);
    LoweringPlan plan;
    plan.walksMicrosurface = material.singleLobe().walksMicrosurface();
    if (plan.walksMicrosurface) return planWalk(material, em, plan, variant, trustInputs);
    plan.variant = variant;
    plan.trustInputs = trustInputs;
    plan.ndfIsotropic = ndfIsIsotropic(material.singleLobe().ndf);
    plan.compensatesEnergy = material.singleLobe().compensatesEnergy();
    plan.reads = material.readByModels();

    if (!material.singleLobe().masking.model->smith || !material.singleLobe().hasNdf())
        plan.lambda = LambdaForm::None;
    else if (em.ndf.traits.smithRootSums && !em.masking.traits.needsSeparateLambdas)
        plan.lambda = LambdaForm::RootSums;
    else if (variant.walterLambda && em.ndf.traits.beckmannProfileLambda)
        plan.lambda = LambdaForm::WalterFit;
    else if (ndfEntry(*material.singleLobe().ndf.model).tabulatedLambda) {
        plan.lambda = LambdaForm::Table;
        plan.lambdaTable = lambdaTable(ndfEntry(*material.singleLobe().ndf.model), tabulatedLambdaShape(material));
    } else
        plan.lambda = LambdaForm::ClosedForm;

    // The refracting lobe needs the exact term's transmittance: no Schlick substitution.
    plan.wholeSphere = material.singleLobe().wholeSphere();
    if (plan.wholeSphere) plan.variant.schlickDielectric = plan.variant.floatFirst = false;
    const FresnelEmitter& fresnel = em.fresnel;
    plan.fresnel.substituteSchlick = plan.variant.schlickDielectric && fresnel.substitutableBySchlick();
    plan.fresnel.exactInFloat = !plan.fresnel.substituteSchlick && fresnel.evaluableInFloat(material.singleLobe().fresnel);
    plan.fresnel.rangeGuard = !fresnel.atLeast(material.singleLobe().fresnel, 1e-6);
    plan.fresnel.atMostOne = fresnel.atMostOne();
    // F >= 1e-12 at every angle (a constant f0 or eta that keeps it there)
    // stays positive in either type, rounded or flushed, so the lobe needs
    // no F = 0 select. (A smaller bound would admit a Schlick eta within
    // 1e-14 of 1, which a float body rounds to 1: f0 = 0.)
    plan.fresnel.canVanish = fresnel.canVanish() && !fresnel.atLeast(material.singleLobe().fresnel, 1e-12);
    if (plan.wholeSphere) return planWholeSphere(material, em, plan, transport);

    // The scalar kernel computes the plain body: per lane, float is no
    // faster than double except for division and square root, and the
    // guards would cost more than they save (docs/perf-log.md).
    plan.scalarBody = planBody(material, em, plan, BodyRole::Plain, variant);
    if (floatFirstApplies(material, em, variant) || fastTakesFloatFirst(material, em, variant)) {
        plan.batchBodies = BatchBodies::FloatFirst;
        // The exact variant's float body, in float (a fast kernel's
        // estimates and short polynomials are not for it).
        MathVariant floatVariant = variant.precise ? variant : MathVariant::exact();
        floatVariant.precise = false;
        plan.batchBody = planBody(material, em, plan, BodyRole::FloatGuarded, floatVariant);
        plan.fallbackBody = plan.scalarBody;
    } else if (guardedFastApplies(material, em, variant, plan.ndfIsotropic)) {
        plan.batchBodies = BatchBodies::GuardedFast;
        plan.batchBody = planBody(material, em, plan, BodyRole::FastGuarded, variant);
        plan.fallbackBody = plan.scalarBody;
    } else {
        plan.batchBodies = BatchBodies::Plain;
        plan.batchBody = plan.scalarBody;
    }

    // (A caller's tighter cap only narrows the clamp.)
    planParams(material, plan);

    plan.sampling.specular = plannedSpecularSampling(material);
    plan.sampling.compiled = plan.sampling.specular != SpecularSampling::None;
    plan.sampling.cosineLobe = em.diffuse.present() || material.singleLobe().compensatesEnergy();
    plan.sampling.compensationAlbedo = material.singleLobe().compensatesEnergy();
    plan.sampling.body = plan.scalarBody;
    plan.sampling.batchBody = plan.scalarBody;
    // Only exact kernels: a fast kernel samples in its plain body, which is
    // float already and has no guards to pay for.
    if (variant.precise && plan.batchBodies == BatchBodies::FloatFirst && em.ndf.traits.floatFirstSampler) {
        plan.sampling.batchBodies = BatchBodies::FloatFirst;
        plan.sampling.batchBody = plan.batchBody;
    }
    return plan;
}

namespace {

void printBody(std::ostringstream& os, const char* what, const BodyPlan& body) {
    os << what << ": role=" << bodyRoleName(body.role) << " precise=" << precisionName(body.precise)
       << " expressions=" << precisionName(body.expressions) << " half-vector=" << halfVectorFormName(body.halfVector)
       << " corrected-sums=" << (body.correctedSums ? (body.floatPairCorrections ? "float-pair" : "yes") : "no")
       << " estimates=" << (body.estimates ? "yes" : "no")
       << " short-polynomials=" << (body.shortPolynomials ? "yes" : "no")
       << " scale-masking-sums=" << (body.scaleMaskingSums ? "yes" : "no")
       << " check-output=" << (body.checkOutput ? "yes" : "no")
       << " subnormal-cosines-as-zero=" << (body.subnormalCosinesAsZero ? "yes" : "no") << "\n";
}

}  // namespace

std::string printPlan(const CheckedMaterial& material, const LoweringPlan& plan) {
    std::ostringstream os;
    if (plan.combines()) {
        printCombinationPlan(os, material, plan);
        return os.str();
    }
    auto yesNo = [](bool b) { return b ? "yes" : "no"; };
    os << "material " << material.name << "\n";
    os << "models: ndf=" << (material.singleLobe().hasNdf() ? material.singleLobe().ndf.model->name : "none") << " masking=" << material.singleLobe().masking.model->name
       << " fresnel=" << material.singleLobe().fresnel.model->name << " energy=" << material.singleLobe().energy.model->name
       << " diffuse=" << material.singleLobe().diffuse.model->name << "\n";
    os << "variant: " << plan.variant.name() << "\n";
    os << "batch-bodies: " << batchBodiesName(plan.batchBodies) << "\n";
    printBody(os, "scalar-body", plan.scalarBody);
    printBody(os, "batch-body", plan.batchBody);
    os << "one-lane-batch: " << (plan.oneLaneBody ? "one-lane-body" : "vector") << "\n";
    if (plan.fallbackBody) printBody(os, "fallback-body", *plan.fallbackBody);
    os << "ndf-isotropic: " << yesNo(plan.ndfIsotropic) << "\n";
    os << "smith-lambda: " << lambdaFormName(plan.lambda);
    if (plan.lambdaTable) os << " (" << plan.lambdaTable->name() << ", " << plan.lambdaTable->z.size() << " nodes)";
    os << "\n";
    os << "fresnel: substitute-schlick=" << yesNo(plan.fresnel.substituteSchlick)
       << " exact-in-float=" << yesNo(plan.fresnel.exactInFloat) << " range-guard=" << yesNo(plan.fresnel.rangeGuard)
       << " at-most-one=" << yesNo(plan.fresnel.atMostOne) << " can-vanish=" << yesNo(plan.fresnel.canVanish) << "\n";
    os << "energy-compensation: " << yesNo(plan.compensatesEnergy) << "\n";
    if (plan.walksMicrosurface) os << "random-walk: yes (exact double body; sampler walks, pdf for MIS)\n";
    if (plan.wholeSphere)
        os << "whole-sphere: " << (plan.thinSheet ? "thin sheet" : "refracting interface")
           << " keeps=" << (plan.keepsReflection ? "reflection" : "") << (plan.keepsReflection && plan.keepsTransmission ? "+" : "")
           << (plan.keepsTransmission ? "transmission" : "")
           << " transport=" << (plan.transport == Transport::Importance ? "importance" : "radiance")
           << " (one plain body)\n";
    if (plan.wholeSphere && plan.compensatesEnergy) {
        if (plan.thinSheet)
            os << fmt::format("whole-sphere-compensation: tables of both sides, crossing share {:.6g} {:.6g} {:.6g}\n",
                              plan.sheetCrossing[0], plan.sheetCrossing[1], plan.sheetCrossing[2]);
        else
            os << fmt::format("whole-sphere-compensation: tables outside and inside, smooth crossing share {:.6g}, "
                              "eta^2 {:.6g} (each lane limits the share by its tables' averages)\n",
                              plan.smoothCrossing, plan.interfaceEta2);
    }
    os << "trust-inputs: " << yesNo(plan.trustInputs) << "\n";
    auto count = [](const std::vector<bool>& v) { return std::count(v.begin(), v.end(), true); };
    os << "reads: inputs " << count(plan.reads.inputs) << " of " << plan.reads.inputs.size() << ", lets "
       << count(plan.reads.lets) << " of " << plan.reads.lets.size() << "\n";
    for (int s = 0; s < kModelSlotCount; ++s) {
        const ModelUse& use = material.singleLobe().use(ModelSlot(s));
        for (int p = 0; p < int(plan.params[s].size()); ++p) {
            if (!use.has(p)) continue;
            const ParamPlan& param = plan.params[s][p];
            os << "param " << modelSlotName(ModelSlot(s)) << "." << use.model->canonical[p].name << ": "
               << param.range.str() << " tests=";
            if (param.testNaN) os << "nan";
            if (param.testNaN && param.testFloatRange) os << ",";
            if (param.testFloatRange) os << "float-range";
            if (!param.testNaN && !param.testFloatRange) os << "none";
            os << "\n";
        }
    }
    os << "sampling: specular=" << specularSamplingName(plan.sampling.specular)
       << " cosine-lobe=" << yesNo(plan.sampling.cosineLobe)
       << " compensation-albedo=" << yesNo(plan.sampling.compensationAlbedo) << "\n";
    if (plan.sampling.specular != SpecularSampling::None) {
        os << "sampling-batch-bodies: " << batchBodiesName(plan.sampling.batchBodies) << "\n";
        printBody(os, "sampling-body", plan.sampling.body);
        if (plan.sampling.batchBodies != BatchBodies::Plain)
            printBody(os, "sampling-batch-body", plan.sampling.batchBody);
    }
    return os.str();
}

bool walterLambdaApplies(const CheckedMaterial& material) {
    if (material.combinesLobes() || !material.singleLobe().hasNdf()) {  // any of its lobes
        for (size_t l = 0; material.combinesLobes() && l < material.lobes.size(); ++l)
            if (material.lobes[l].hasNdf() && walterLambdaApplies(lobeView(material, int(l)))) return true;
        return false;
    }
    return termEmitters(material).ndf.traits.beckmannProfileLambda && material.singleLobe().masking.model->smith;
}

bool schlickDielectricApplies(const CheckedMaterial& material) {
    if (material.combinesLobes()) {  // any of its lobes
        for (size_t l = 0; l < material.lobes.size(); ++l)
            if (schlickDielectricApplies(lobeView(material, int(l)))) return true;
        return false;
    }
    return termEmitters(material).fresnel.substitutableBySchlick();
}

}  // namespace facet
