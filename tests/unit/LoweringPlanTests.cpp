// The lowering's decisions, without LLVM code: planLowering() on small
// materials (which bodies, which precisions, which forms), every catalog
// entry having an emitter, and the codegen part of the cache key.
#include "CodegenIdentity.h"
#include "LoweringPlan.h"
#include "TermEmitters.h"

#include "Checker.h"
#include "models/ModelCatalog.h"

#include <doctest/doctest.h>
#include <llvm/Support/SHA256.h>
#include <llvm/ADT/StringExtras.h>

#include <fstream>
#include <sstream>
#include <string>

using namespace facet;

namespace {

// The checked material of `body` (its statements), one per call.
CheckedMaterial material(const std::string& body) {
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramText("material m {\n" + body + "\n}\n", "plan.mat", diags);
    INFO(diags.str());
    REQUIRE(!diags.hasErrors());
    REQUIRE(program.materials.size() == 1);
    return program.materials[0];
}

LoweringPlan exactPlan(const std::string& body) { return planLowering(material(body), MathVariant::exact()); }
LoweringPlan fastPlan(const std::string& body) { return planLowering(material(body), MathVariant::fast()); }

}  // namespace

TEST_SUITE("plan") {

TEST_CASE("exact GGX with Schlick f0: a guarded float body and the double body for the rest") {
    CheckedMaterial m = material("input r = 0.5; ndf = ggx(r * r); masking = smith_height_correlated; fresnel = schlick(f0 = 0.04);");
    LoweringPlan p = planLowering(m, MathVariant::exact());
    CHECK(p.batchBodies == BatchBodies::FloatFirst);
    CHECK(p.batchBody.role == BodyRole::FloatGuarded);
    CHECK(p.batchBody.precise == Precision::Float);
    CHECK(p.batchBody.expressions == Precision::Float);  // r * r: one multiplication
    CHECK_FALSE(p.batchBody.checkOutput);                 // no diffuse: the guards bound the value
    REQUIRE(p.fallbackBody);
    CHECK(p.fallbackBody->role == BodyRole::Plain);
    CHECK(p.fallbackBody->precise == Precision::Double);
    CHECK(p.scalarBody.precise == Precision::Double);
    CHECK(p.lambda == LambdaForm::RootSums);
    CHECK_FALSE(p.fresnel.rangeGuard);  // f0 = 0.04 >= 1e-6 at every angle
    CHECK(p.fresnel.atMostOne);
    // Double bodies represent a float-subnormal cosine, the guarded body distrusts it.
    CHECK_FALSE(p.batchBody.subnormalCosinesAsZero);
    CHECK_FALSE(p.fallbackBody->subnormalCosinesAsZero);
    CHECK_FALSE(p.scalarBody.subnormalCosinesAsZero);
    CHECK(printPlan(m, p).find("batch-bodies: float-first") != std::string::npos);
}

TEST_CASE("F = 0 needs its own select only where constant arguments do not keep F positive") {
    const std::string lobe = "ndf = ggx(0.3); masking = smith_height_correlated; ";
    CHECK_FALSE(exactPlan(lobe + "fresnel = schlick(f0 = 0.04);").fresnel.canVanish);
    CHECK_FALSE(fastPlan(lobe + "fresnel = schlick(f0 = rgb(0.9, 0.5, 1e-10));").fresnel.canVanish);
    CHECK_FALSE(fastPlan(lobe + "fresnel = schlick(eta = 1.5);").fresnel.canVanish);
    CHECK(exactPlan(lobe + "fresnel = schlick(f0 = rgb(0.9, 0.5, 0));").fresnel.canVanish);
    CHECK(exactPlan(lobe + "fresnel = schlick(f0 = 1e-40);").fresnel.canVanish);  // 0 in float
    CHECK(exactPlan(lobe + "fresnel = schlick(eta = 1);").fresnel.canVanish);
    // f0 = 2.5e-29 in double, but 1 in float, f0 = 0, in a fast body.
    CHECK(fastPlan(lobe + "fresnel = schlick(eta = 1.00000000000001);").fresnel.canVanish);
    CHECK(exactPlan("input f = 0.5; " + lobe + "fresnel = schlick(f0 = f);").fresnel.canVanish);
    CHECK(exactPlan(lobe + "fresnel = dielectric(1.5);").fresnel.canVanish);
    CHECK_FALSE(exactPlan(lobe + "fresnel = none;").fresnel.canVanish);
}

TEST_CASE("the float body keeps sums, long chains and exp in double") {
    CHECK(exactPlan("input r = 0.5; ndf = ggx(r + 0.01); fresnel = schlick(f0 = 0.04);").batchBody.expressions ==
          Precision::Double);
    CHECK(exactPlan("input r = 0.5; ndf = ggx(exp(r)); fresnel = schlick(f0 = 0.04);").batchBody.expressions ==
          Precision::Double);
    CHECK(exactPlan("input r = 0.5; let a = r*r*r*r*r*r*r*r*r*r; ndf = ggx(a); fresnel = schlick(f0 = 0.04);")
              .batchBody.expressions == Precision::Double);
    CHECK(exactPlan("input r = 0.5; ndf = ggx(pow(r, 4)); fresnel = schlick(f0 = 0.04);").batchBody.expressions ==
          Precision::Float);
}

TEST_CASE("no float-first body where float would lose accuracy or a table is read") {
    // Schlick from eta: (eta - 1)/(eta + 1) cancels near 1 in float.
    CHECK(exactPlan("ndf = ggx(0.3); fresnel = schlick(eta = 1.5);").batchBodies == BatchBodies::Plain);
    // A per-lane dielectric eta may cross the critical angle.
    CHECK(exactPlan("input eta = 1.5; ndf = ggx(0.3); fresnel = dielectric(eta);").batchBodies == BatchBodies::Plain);
    CHECK(exactPlan("ndf = ggx(0.3); fresnel = dielectric(1.5);").batchBodies == BatchBodies::FloatFirst);
    CHECK(exactPlan("ndf = ggx(0.3); masking = smith_height_correlated; energy = kulla_conty;").batchBodies ==
          BatchBodies::Plain);
    CHECK(exactPlan("ndf = beckmann(0.3); masking = smith_separable;").batchBodies == BatchBodies::Plain);
    MathVariant doubleOnly = MathVariant::exact();
    doubleOnly.floatFirst = false;
    CHECK(planLowering(material("ndf = ggx(0.3);"), doubleOnly).batchBodies == BatchBodies::Plain);
}

TEST_CASE("a diffuse term keeps the output check of a guarded body") {
    LoweringPlan p = exactPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04); diffuse = lambert(0.5);");
    REQUIRE(p.batchBodies == BatchBodies::FloatFirst);
    CHECK(p.batchBody.checkOutput);
}

TEST_CASE("fast GGX: the exact float-first body where it applies, else a guarded fast body when isotropic") {
    // Schlick with f0 (or no Fresnel term): the exact kernel's float body.
    for (const char* body : {"ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);", "ndf = ggx(0.3);"}) {
        LoweringPlan p = fastPlan(body);
        CHECK(p.batchBodies == BatchBodies::FloatFirst);
        CHECK(p.batchBody.role == BodyRole::FloatGuarded);
        REQUIRE(p.fallbackBody);
        CHECK(p.fallbackBody->estimates);
    }
    // Schlick from eta is not the float-first body's: the guarded fast body.
    LoweringPlan iso = fastPlan("ndf = ggx(0.3); fresnel = schlick(eta = 1.5);");
    CHECK(iso.batchBodies == BatchBodies::GuardedFast);
    CHECK(iso.batchBody.role == BodyRole::FastGuarded);
    CHECK(iso.batchBody.halfVector == HalfVectorForm::Estimated);  // f0 >= 1e-6
    CHECK_FALSE(iso.batchBody.scaleMaskingSums);
    CHECK(iso.scalarBody.scaleMaskingSums);
    // Fast mode reads a float-subnormal cosine as 0 in its plain float
    // bodies; its guarded body distrusts the lane.
    CHECK(iso.scalarBody.subnormalCosinesAsZero);
    CHECK_FALSE(iso.batchBody.subnormalCosinesAsZero);
    REQUIRE(iso.fallbackBody);
    CHECK(iso.fallbackBody->subnormalCosinesAsZero);
    // Equal constant alphas are one alpha.
    CHECK(fastPlan("ndf = ggx(alpha_x = 0.3, alpha_y = 0.3);").ndfIsotropic);
    CHECK(fastPlan("ndf = ggx(alpha_x = 0.3, alpha_y = 0.3); fresnel = schlick(eta = 1.5);").batchBodies ==
          BatchBodies::GuardedFast);
    CHECK_FALSE(fastPlan("ndf = ggx(alpha_x = 0.3, alpha_y = 0.5);").ndfIsotropic);
    // Anisotropic: the exact kernel's guarded float body (estimates and
    // short polynomials off), the plain fast body for its distrusted lanes.
    LoweringPlan aniso = fastPlan("ndf = ggx(alpha_x = 0.3, alpha_y = 0.5);");
    CHECK(aniso.batchBodies == BatchBodies::FloatFirst);
    CHECK(aniso.batchBody.role == BodyRole::FloatGuarded);
    CHECK_FALSE(aniso.batchBody.estimates);
    CHECK_FALSE(aniso.batchBody.shortPolynomials);
    CHECK_FALSE(aniso.batchBody.scaleMaskingSums);
    REQUIRE(aniso.fallbackBody);
    CHECK(aniso.fallbackBody->estimates);
    CHECK(aniso.fallbackBody->precise == Precision::Float);
    CHECK(aniso.fallbackBody->subnormalCosinesAsZero);
    CHECK_FALSE(aniso.batchBody.subnormalCosinesAsZero);
    // ... but not with float_first=off, nor for a tolerance's model substitution,
    // nor where the exact kernel has no float-first body (Beckmann).
    MathVariant noFloatFirst = MathVariant::fast();
    noFloatFirst.floatFirst = false;
    CHECK(planLowering(material("ndf = ggx(alpha_x = 0.3, alpha_y = 0.5);"), noFloatFirst).batchBodies ==
          BatchBodies::Plain);
    MathVariant schlick = MathVariant::fast();
    schlick.schlickDielectric = true;
    CHECK(planLowering(material("ndf = ggx(alpha_x = 0.3, alpha_y = 0.5); fresnel = dielectric(1.5);"), schlick)
              .batchBodies == BatchBodies::Plain);
    CHECK(fastPlan("ndf = beckmann(alpha_x = 0.3, alpha_y = 0.5);").batchBodies == BatchBodies::Plain);
    // An f0 that can reach 0 keeps the cancellation-free 1 - cos and the F guard.
    LoweringPlan lanes = fastPlan("input eta = 1.5; ndf = ggx(0.3); fresnel = schlick(eta = eta);");
    REQUIRE(lanes.batchBodies == BatchBodies::GuardedFast);
    CHECK(lanes.batchBody.halfVector == HalfVectorForm::Precise);
    CHECK(lanes.fresnel.rangeGuard);
}

TEST_CASE("float bodies sum the float directions with a normalization correction; double bodies normalize") {
    LoweringPlan guarded = fastPlan("ndf = ggx(0.3); fresnel = schlick(eta = 1.5);");
    REQUIRE(guarded.batchBodies == BatchBodies::GuardedFast);
    REQUIRE(guarded.fallbackBody);
    CHECK_FALSE(guarded.batchBody.correctedSums);
    CHECK(guarded.fallbackBody->correctedSums);
    CHECK(guarded.scalarBody.correctedSums);
    for (const char* body : {"ndf = beckmann(0.3); fresnel = conductor(eta = 0.2, k = 3.7);",
                             "ndf = ggx(alpha_x = 0.3, alpha_y = 0.5); fresnel = dielectric(1.5);"}) {
        LoweringPlan fast = fastPlan(body);
        CHECK(fast.scalarBody.correctedSums);
        CHECK(fast.batchBody.correctedSums);
        CHECK(fast.sampling.body.correctedSums);
        LoweringPlan exact = exactPlan(body);
        CHECK_FALSE(exact.scalarBody.correctedSums);
        CHECK(exact.batchBody.correctedSums == (exact.batchBodies == BatchBodies::FloatFirst));
    }
    LoweringPlan floatFirst = exactPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);");
    REQUIRE(floatFirst.batchBodies == BatchBodies::FloatFirst);
    CHECK(floatFirst.batchBody.correctedSums);
    CHECK_FALSE(floatFirst.fallbackBody->correctedSums);
    CHECK(printPlan(material("ndf = ggx(0.3);"), guarded).find("corrected-sums=yes") != std::string::npos);
}

TEST_CASE("float pair corrections: only the isotropic float-first body, which has a fallback") {
    LoweringPlan floatFirst = exactPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);");
    REQUIRE(floatFirst.batchBodies == BatchBodies::FloatFirst);
    CHECK(floatFirst.batchBody.floatPairCorrections);
    CHECK_FALSE(floatFirst.fallbackBody->floatPairCorrections);
    CHECK_FALSE(floatFirst.scalarBody.floatPairCorrections);
    CHECK(printPlan(material("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);"), floatFirst).find("corrected-sums=float-pair") !=
          std::string::npos);
    // An anisotropic D resolves a tangential component of h that may nearly
    // cancel, which the float difference of the corrections moves by ~1 ulp
    // of |h|: the double corrections there.
    LoweringPlan aniso = exactPlan("ndf = ggx(alpha_x = 0.3, alpha_y = 0.5); fresnel = dielectric(1.5);");
    REQUIRE(aniso.batchBodies == BatchBodies::FloatFirst);
    CHECK(aniso.batchBody.correctedSums);
    CHECK_FALSE(aniso.batchBody.floatPairCorrections);
    // Bodies without a fallback (fast mode's plain float bodies) decide a
    // direction's validity themselves, on |w|^2 - 1 in double.
    LoweringPlan fast = fastPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);");
    CHECK(fast.scalarBody.correctedSums);
    CHECK_FALSE(fast.scalarBody.floatPairCorrections);
    CHECK_FALSE(fast.fallbackBody->floatPairCorrections);
}

TEST_CASE("the half angle without the unit h: NDFs whose D takes wi + wo, with well-conditioned consumers") {
    // Schlick with a constant f0 >= 1e-12 (or no Fresnel term): 1 - cos
    // directly from |wi + wo| in double.
    CHECK(exactPlan("ndf = beckmann(0.3); masking = smith_separable; fresnel = schlick(f0 = 0.04);")
              .scalarBody.halfVector == HalfVectorForm::Direct);
    CHECK(exactPlan("ndf = ggx(0.3); masking = smith_separable;").scalarBody.halfVector == HalfVectorForm::Direct);
    CHECK(exactPlan("ndf = ggx(0.3); fresnel = schlick(f0 = rgb(1e-12, 0.5, 1));").scalarBody.halfVector ==
          HalfVectorForm::Direct);
    // f0 below the bound, per lane, or from an eta within 1e-6 of 1: the
    // cancellation-free form, with the half angle in float.
    CHECK(exactPlan("ndf = ggx(0.3); fresnel = schlick(f0 = rgb(0.5, 5e-13, 0.5));").scalarBody.halfVector ==
          HalfVectorForm::InFloat);
    CHECK(exactPlan("input f0 = 0.5; ndf = ggx(0.3); fresnel = schlick(f0 = f0);").scalarBody.halfVector ==
          HalfVectorForm::InFloat);
    CHECK(exactPlan("ndf = ggx(0.3); fresnel = schlick(eta = 1.000001);").scalarBody.halfVector ==
          HalfVectorForm::InFloat);
    CHECK(exactPlan("ndf = beckmann(0.3); masking = cook_torrance;").scalarBody.halfVector == HalfVectorForm::Precise);
    CHECK(exactPlan("ndf = ggx(0.3); masking = kelemen;").scalarBody.halfVector == HalfVectorForm::Precise);
    // An NDF whose D needs the unit h.
    CHECK(exactPlan("ndf = gtr(alpha = 0.3, gamma = 1.5); masking = smith_separable;").scalarBody.halfVector ==
          HalfVectorForm::Precise);
    LoweringPlan constant = exactPlan("ndf = beckmann(0.3); fresnel = dielectric(1.5);");
    CHECK(constant.fresnel.exactInFloat);
    CHECK(constant.scalarBody.halfVector == HalfVectorForm::InFloat);
    LoweringPlan perLane = exactPlan("input eta = 1.5; ndf = beckmann(0.3); fresnel = dielectric(eta);");
    CHECK_FALSE(perLane.fresnel.exactInFloat);
    CHECK(perLane.scalarBody.halfVector == HalfVectorForm::Precise);
    // Fast bodies compute in float already: an estimated |h| where F stays
    // >= 1e-6, the cancellation-free form otherwise.
    CHECK(fastPlan("ndf = beckmann(0.3);").scalarBody.halfVector == HalfVectorForm::Estimated);
    CHECK(fastPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);").scalarBody.halfVector == HalfVectorForm::Estimated);
    CHECK(fastPlan("ndf = ggx(0.3); fresnel = schlick(f0 = 1e-7);").scalarBody.halfVector == HalfVectorForm::Precise);
    CHECK(fastPlan("ndf = beckmann(0.3); fresnel = dielectric(1.5);").scalarBody.halfVector == HalfVectorForm::Precise);
    // The float-first body: GGX's float D from wi + wo, without the unit h,
    // unless the masking reads the unit h; the guarded fast body's D guard
    // takes the unit h.
    for (const char* body : {"ndf = ggx(0.3); fresnel = schlick(f0 = 0.04);",
                             "ndf = ggx(alpha_x = 0.3, alpha_y = 0.5); fresnel = dielectric(1.5);"}) {
        LoweringPlan floatFirst = exactPlan(body);
        REQUIRE(floatFirst.batchBodies == BatchBodies::FloatFirst);
        CHECK(floatFirst.batchBody.halfVector == HalfVectorForm::InFloat);
    }
    LoweringPlan kelemen = exactPlan("ndf = ggx(0.3); masking = kelemen; fresnel = schlick(f0 = 0.04);");
    REQUIRE(kelemen.batchBodies == BatchBodies::FloatFirst);
    CHECK(kelemen.batchBody.halfVector == HalfVectorForm::Precise);
    LoweringPlan guardedFast = fastPlan("ndf = ggx(0.3); fresnel = schlick(eta = 1.5);");
    REQUIRE(guardedFast.batchBodies == BatchBodies::GuardedFast);
    CHECK(guardedFast.batchBody.halfVector == HalfVectorForm::Estimated);
}

TEST_CASE("the Smith Lambda form and the model substitutions") {
    CHECK(exactPlan("ndf = ggx(0.3); masking = smith_separable;").lambda == LambdaForm::RootSums);
    CHECK(exactPlan("ndf = ggx(0.3); masking = smith_height_direction_correlated;").lambda == LambdaForm::ClosedForm);
    CHECK(exactPlan("ndf = beckmann(0.3); masking = smith_separable;").lambda == LambdaForm::ClosedForm);
    CHECK(exactPlan("ndf = ggx(0.3); masking = neumann;").lambda == LambdaForm::None);
    // student_t: its tabulated Lambda, the table of the material's gamma carried by the plan.
    LoweringPlan st = exactPlan("let g = 0.9 * 2; ndf = student_t(0.3, g); masking = smith_separable;");
    CHECK(st.lambda == LambdaForm::Table);
    REQUIRE(st.lambdaTable);
    CHECK(st.lambdaTable->name() == "student_t_g1.8");
    MathVariant walter = MathVariant::exact();
    walter.walterLambda = true;
    CHECK(planLowering(material("ndf = beckmann(0.3); masking = smith_separable;"), walter).lambda ==
          LambdaForm::WalterFit);
    CHECK(planLowering(material("ndf = ggx(0.3); masking = smith_separable;"), walter).lambda ==
          LambdaForm::RootSums);
    CHECK(walterLambdaApplies(material("ndf = blinn_phong(20); masking = smith_separable;")));
    CHECK_FALSE(walterLambdaApplies(material("ndf = ggx(0.3); masking = smith_separable;")));
    CHECK_FALSE(walterLambdaApplies(material("ndf = beckmann(0.3); masking = kelemen;")));
    MathVariant schlick = MathVariant::exact();
    schlick.schlickDielectric = true;
    LoweringPlan p = planLowering(material("ndf = ggx(0.3); fresnel = dielectric(1.5);"), schlick);
    CHECK(p.fresnel.substituteSchlick);
    CHECK_FALSE(p.fresnel.exactInFloat);
    CHECK(schlickDielectricApplies(material("ndf = ggx(0.3); fresnel = dielectric(1.5);")));
    CHECK_FALSE(schlickDielectricApplies(material("ndf = ggx(0.3); fresnel = conductor(eta = 0.2, k = 3);")));
}

TEST_CASE("every NDF has a compiled sampler of the catalog's technique") {
    // Visible normals under a Smith masking where the entry has them (GGX,
    // Beckmann), NDF sampling elsewhere (gaussian: a numerically inverted CDF).
    CHECK(exactPlan("ndf = beckmann(0.3); masking = smith_separable;").sampling.specular ==
          SpecularSampling::VisibleNormals);
    CHECK(fastPlan("ndf = beckmann(0.3, 0.01); masking = smith_height_correlated;").sampling.specular ==
          SpecularSampling::VisibleNormals);
    CHECK(exactPlan("ndf = beckmann(0.3); masking = kelemen;").sampling.specular == SpecularSampling::NdfNormals);
    CHECK(exactPlan("input a = 0.2; ndf = gaussian(a); masking = cook_torrance;").sampling.specular ==
          SpecularSampling::NdfNormals);
    for (const ModelInfo* m : catalog())
        if (m->slot == ModelSlot::Ndf) {
            CAPTURE(m->name);
            const NdfEmitter* e = static_cast<const NdfEmitter*>(findTermEmitter(*m));
            REQUIRE(e);
            CHECK(e->traits.samplesNormals);
            CHECK(e->traits.samplesVisibleNormals == ndfEntry(*m).visibleNormals);
        }
}

TEST_CASE("every catalog entry has an emitter") {
    for (const ModelInfo* m : catalog()) {
        CAPTURE(modelSlotName(m->slot));
        CAPTURE(m->name);
        CHECK(findTermEmitter(*m) != nullptr);
    }
    // ... and every emitter names a catalog entry of its slot.
    for (const TermEmitterEntry& e : termEmitterRegistry()) {
        CAPTURE(e.modelName);
        CHECK(findModel(e.slot, e.modelName) != nullptr);
    }
}

TEST_CASE("model parameters: NaN and float-range tests only where the expressions leave them possible") {
    auto alpha = [](const std::string& body) { return exactPlan(body).param(ModelSlot::Ndf, 0); };
    // roughness in 0 .. 1 squared: never NaN, never beyond float.
    const std::string bench = "input roughness = 0.4 in 0 .. 1; let alpha = roughness * roughness; ndf = ggx(alpha);";
    ParamPlan squared = alpha(bench);
    CHECK_FALSE(squared.testNaN);
    CHECK_FALSE(squared.testFloatRange);
    CHECK(squared.range.lo == 1e-4);  // ggx's domain
    CHECK(squared.range.hi < 1.00001);
    CHECK(printPlan(material(bench), exactPlan(bench)).find("param ndf.alpha_x: [0.0001, 1.0000") != std::string::npos);
    // sqrt of a negative, division by a range holding 0: NaN possible.
    CHECK(alpha("input x = 0.25 in -1 .. 1; ndf = ggx(sqrt(x));").testNaN);
    CHECK(alpha("input x = 0.25 in 0 .. 1; ndf = ggx(1 / x);").testNaN);
    // A finite float input is within float; its square is not.
    CHECK_FALSE(alpha("input x = 0.5; ndf = ggx(x);").testFloatRange);
    CHECK_FALSE(alpha("input x = 0.5; ndf = ggx(x);").testNaN);
    CHECK(alpha("input x = 0.5; ndf = ggx(x * x);").testFloatRange);
    CHECK_FALSE(alpha("input x = 0.5; ndf = ggx(x * x);").testNaN);
    CHECK(printPlan(material("input x = 0.5; ndf = ggx(x * x);"), exactPlan("input x = 0.5; ndf = ggx(x * x);"))
              .find("tests=float-range") != std::string::npos);
}

}  // TEST_SUITE

TEST_SUITE("codegen_key") {

TEST_CASE("the codegen identity changes with any embedded table value") {
    // One material per table: a per-lane Gaussian alpha, per-lane dielectric
    // and conductor parameters under energy compensation.
    CheckedMaterial m = material(
        "input a = 0.3; input eta = 1.5; ndf = gaussian(a); masking = cook_torrance; fresnel = dielectric(eta); "
        "energy = kulla_conty;");
    std::vector<EmbeddedTable> tables = embeddedTables(m);
    REQUIRE(tables.size() == 2);
    CHECK(tables[0].name == "facet_gaussian_norm_table");
    CHECK(tables[1].name == "facet_favg_dielectric");
    std::vector<EmbeddedTable> conductor = embeddedTables(material(
        "input k = 3; ndf = ggx(0.3); masking = smith_separable; fresnel = conductor(eta = 0.2, k = k); "
        "energy = kulla_conty;"));
    REQUIRE(conductor.size() == 1);
    CHECK(conductor[0].name == "facet_favg_conductor");
    tables.push_back(conductor[0]);
    const std::string base = codegenIdentity(codegenSourceDigest(), tables);
    for (size_t t = 0; t < tables.size(); ++t) {
        CAPTURE(tables[t].name);
        REQUIRE(tables[t].bytes > 0);
        std::vector<unsigned char> copy(static_cast<const unsigned char*>(tables[t].data),
                                        static_cast<const unsigned char*>(tables[t].data) + tables[t].bytes);
        copy[copy.size() / 2] ^= 1;  // one bit of one entry
        std::vector<EmbeddedTable> changed = tables;
        changed[t].data = copy.data();
        CHECK(codegenIdentity(codegenSourceDigest(), changed) != base);
    }
    CHECK(codegenIdentity("0000", tables) != base);
    CHECK(base.find("llvm 19") != std::string::npos);
}

TEST_CASE("a kernel's key hashes only the tables it embeds") {
    // Building the F_avg tables takes about half a second: a material that
    // folds its constants (or needs no F_avg) must not pay for them.
    CHECK(embeddedTables(material("ndf = ggx(0.3); fresnel = dielectric(1.5); energy = kulla_conty;")).empty());
    CHECK(embeddedTables(material("input eta = 1.5; ndf = ggx(0.3); fresnel = dielectric(eta);")).empty());
    CHECK(embeddedTables(material("ndf = gaussian(0.3);")).empty());
    CHECK(embeddedTables(material("ndf = student_t(0.3, 2.5); masking = cook_torrance;")).empty());
    std::vector<EmbeddedTable> lambda = embeddedTables(material("ndf = student_t(0.3, 2.5); masking = smith_separable;"));
    REQUIRE(lambda.size() == 1);
    CHECK(lambda[0].name == "facet_lambda_student_t_g2.5");
    CHECK(lambda[0].bytes == (LambdaTable::kSize + 1) * sizeof(double));  // the nodes and the grazing node
    CheckedMaterial plain = material("ndf = ggx(0.3); fresnel = schlick(0.04);");
    CHECK(codegenIdentity(plain) == codegenIdentity(codegenSourceDigest(), {}));
}

TEST_CASE("the source digest is the contents of the listed sources, recomputed here") {
    // What cmake/HashSources.cmake does at build time, redone independently:
    // two builds of the same sources give this digest wherever they are built.
    std::istringstream list(codegenSourceList());
    std::string rel, manifest;
    int files = 0;
    while (list >> rel) {
        std::ifstream in(std::string(FACET_SOURCE_DIR) + "/" + rel, std::ios::binary);
        REQUIRE_MESSAGE(in, rel);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        manifest += rel + "\n" + llvm::toHex(llvm::SHA256::hash(llvm::arrayRefFromStringRef(bytes)), true) + "\n";
        ++files;
    }
    CHECK(files > 40);
    CHECK(std::string(codegenSourceList()).find("compiler/lowering/KernelEntries.cpp") != std::string::npos);
    CHECK(std::string(codegenSourceList()).find("compiler/models/ndf/GgxEmitter.cpp") != std::string::npos);
    std::string digest = llvm::toHex(llvm::SHA256::hash(llvm::arrayRefFromStringRef(manifest)), true);
    CHECK(digest == codegenSourceDigest());
}

}  // TEST_SUITE
