// energy = kulla_conty in the checker and the reference interpreter.
#include "EnergyTestUtil.h"

#include <cstdio>
#include <limits>

using namespace energy;

namespace {

std::string checkErrors(const std::string& text) {
    facet::DiagnosticEngine diags;
    facet::loadProgramText(text, "t.mat", diags);
    return diags.str();
}

Vec3<double> dirOf(double mu, double phi) {
    double s = std::sqrt(std::max(0.0, 1 - mu * mu));
    return {s * std::cos(phi), s * std::sin(phi), mu};
}

}  // namespace

TEST_SUITE("kulla_conty") {

TEST_CASE("checker: accepted pairs and clear errors") {
    CHECK(checkErrors("material m { ndf = ggx(0.3); masking = smith_height_correlated; energy = kulla_conty; }") == "");
    CHECK(checkErrors("material m { input r = 0.5; ndf = beckmann(r * r); masking = cook_torrance; energy = kulla_conty; }") == "");
    CHECK(checkErrors("material m { let g = 2 * 0.75; ndf = gtr(0.3, g); masking = neumann; energy = kulla_conty; }") == "");
    CHECK(checkErrors("material m { ndf = gaussian(0.3); masking = schlick_smith(0.1); energy = kulla_conty; }") == "");
    std::string ward = checkErrors("material m { ndf = ward(0.1, 0.2); energy = kulla_conty; }");
    CHECK(ward.find("t.mat:1:45: error: energy 'kulla_conty' needs a microfacet NDF") == 0);
    CHECK(ward.find("ndf 'ward' is a whole BRDF lobe") != std::string::npos);
    std::string gtr = checkErrors("material m { input g = 2; ndf = gtr(0.3, g); masking = neumann; energy = kulla_conty; }");
    CHECK(gtr.find("needs a constant gamma") != std::string::npos);
    CHECK(gtr.find("depends on input 'g'") != std::string::npos);
    std::string k = checkErrors(
        "material m { input r = 0.5; let k = r / 2; ndf = ggx(r); masking = schlick_smith(k); energy = kulla_conty; }");
    CHECK(k.find("needs a constant k") != std::string::npos);
    CHECK(k.find("depends on input 'r'") != std::string::npos);
    // A file with an unrelated error elsewhere does not crash the check.
    CHECK(checkErrors("material m { ndf = gtr(0.3, y); energy = kulla_conty; }").find("undefined name 'y'") !=
          std::string::npos);
}

TEST_CASE("f_ms in the interpreter: the SPEC formula from the table") {
    TestMaterial kc("input roughness = 0.5 in 0 .. 1; let alpha = roughness * roughness; ndf = ggx(alpha); "
                    "masking = smith_height_correlated; "
                    "fresnel = conductor(eta = rgb(0.14, 0.43, 1.38), k = rgb(3.697, 2.455, 1.914)); energy = kulla_conty;");
    TestMaterial none("input roughness = 0.5 in 0 .. 1; let alpha = roughness * roughness; ndf = ggx(alpha); "
                      "masking = smith_height_correlated; "
                      "fresnel = conductor(eta = rgb(0.14, 0.43, 1.38), k = rgb(3.697, 2.455, 1.914));");
    for (double rough : {0.1, 0.5, 0.9}) {
        auto r = kc.resolve({rough}), r0 = none.resolve({rough});
        double alpha = rough * rough;
        CHECK(r.energyAlpha == doctest::Approx(alpha).epsilon(1e-15));
        const facet::EnergyTable& t = *r.energyTable;
        double ecAvg = t.ecAvgAt(alpha);
        CHECK(r.ecAvg == ecAvg);
        for (int ch = 0; ch < 3; ++ch)
            CHECK(r.favg[ch] == doctest::Approx(facet::fresnelAverageConductor(r.fresnelArgs.channel(0, ch), r.fresnelArgs.channel(1, ch))).epsilon(1e-12));
        for (double mi : {0.02, 0.3, 0.8, 1.0})
            for (double mo : {0.05, 0.5, 1.0}) {
                Vec3<double> wi = dirOf(mi, 2.0), wo = dirOf(mo, 0.3);
                auto f = r.brdf(wi, wo), f0 = r0.brdf(wi, wo);
                for (int ch = 0; ch < 3; ++ch) {
                    double favg = r.favg[ch];
                    double expect = (t.ecAt(mi, alpha) * t.ecAt(mo, alpha)) / (kPi * ecAvg) * favg * favg *
                                    (1 - ecAvg) / (1 - favg * ecAvg);
                    INFO("rough=", rough, " mu_i=", mi, " mu_o=", mo, " ch=", ch);
                    CHECK(f[ch] - f0[ch] == doctest::Approx(expect).epsilon(1e-9));
                    CHECK(f[ch] > f0[ch]);
                }
                // reciprocity holds for f_ms too
                auto g = r.brdf(wo, wi);
                for (int ch = 0; ch < 3; ++ch) CHECK(g[ch] == doctest::Approx(f[ch]).epsilon(1e-12));
            }
    }
}

TEST_CASE("lookup roughness: blinn_phong, anisotropic, gtr, gaussian") {
    CHECK(TestMaterial("ndf = blinn_phong(30); masking = smith_separable; energy = kulla_conty;").resolve().energyAlpha ==
          doctest::Approx(std::sqrt(2.0 / 32)).epsilon(1e-15));
    CHECK(TestMaterial("ndf = beckmann(alpha_x = 0.1, alpha_y = 0.4); masking = smith_separable; energy = kulla_conty;")
              .resolve()
              .energyAlpha == doctest::Approx(0.2).epsilon(1e-15));
    auto g = TestMaterial("ndf = gtr(0.3, 1.5); masking = cook_torrance; energy = kulla_conty;").resolve();
    CHECK(g.energyAlpha == doctest::Approx(0.3).epsilon(1e-15));
    CHECK(g.energyTable->key.shape == std::vector<double>{1.5});
    CHECK(TestMaterial("ndf = gaussian(0.2); masking = neumann; energy = kulla_conty;").resolve().energyAlpha ==
          doctest::Approx(0.2).epsilon(1e-15));
}

TEST_CASE("an interpreter without a table builds the same one in memory") {
    facet::DiagnosticEngine diags;
    auto prog = facet::loadProgramText(
        "material m { ndf = beckmann(0.3); masking = smith_separable; fresnel = schlick(0.04); energy = kulla_conty; }",
        "t.mat", diags);
    REQUIRE(!diags.hasErrors());
    facet::Interpreter<double> lazy(prog.materials[0]);
    facet::Interpreter<double> given(prog.materials[0], memoryTables().getFor(prog.materials[0]));
    facet::Interpreter<long double> wide(prog.materials[0], memoryTables().getFor(prog.materials[0]));
    double wi[3] = {0.3, 0.1, std::sqrt(1 - 0.1)}, wo[3] = {-0.6, 0, 0.8};
    long double wil[3] = {wi[0], wi[1], wi[2]}, wol[3] = {wo[0], wo[1], wo[2]};
    auto a = lazy.eval(wi, wo, nullptr), b = given.eval(wi, wo, nullptr);
    auto c = wide.eval(wil, wol, nullptr);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(a.rgb[ch] == b.rgb[ch]);
        CHECK(double(c.rgb[ch]) == doctest::Approx(a.rgb[ch]).epsilon(1e-12));
    }
    // A table for another pair is a programming error.
    facet::EnergyTableKey other;
    other.ndf = &facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "ggx"));
    other.masking = &facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, "smith_height_correlated"));
    CHECK_THROWS_AS(facet::Interpreter<double>(prog.materials[0], memoryTables().get(other)), facet::InternalError);
}

TEST_CASE("F = 1: the coloured term is 1 and f_ms is the bare compensation lobe") {
    auto r = TestMaterial("ndf = ggx(0.6); masking = smith_height_correlated; energy = kulla_conty;").resolve();
    CHECK(r.favg[0] == 1);
    CHECK(facet::kullaContyFresnelTerm(1.0, r.ecAvg) == doctest::Approx(1).epsilon(1e-15));
}

TEST_CASE("hard cases: never NaN, infinite or negative") {
    const char* bodies[] = {
        "input a = 0.3 in 0 .. 10; ndf = ggx(a); masking = smith_height_correlated; fresnel = conductor(eta = 0.2, k = 3); energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = beckmann(a); masking = smith_separable; fresnel = dielectric(1.5); energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = beckmann(alpha_x = a, alpha_y = a * 1e4); masking = smith_height_correlated; energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = blinn_phong(beckmann_to_phong(a)); masking = smith_height_correlated; energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = gtr(a, 1); masking = schlick_smith(0.1); fresnel = dielectric(0.7); energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = gaussian(a); masking = none; fresnel = schlick(1); energy = kulla_conty;",
        "input a = 0.3 in 0 .. 10; ndf = ggx(a); masking = kelemen; energy = kulla_conty; diffuse = lambert(0.5);",
    };
    const double alphas[] = {0, 1e-4, 1e-3, 0.01, 1, 2, 10};
    const double cosines[] = {0, 1e-7, 1e-4, 1e-2, 0.5, 1};
    int evaluated = 0;
    for (const char* body : bodies) {
        TestMaterial m(body);
        for (double a : alphas) {
            double slots[1] = {a};
            for (double ci : cosines)
                for (double co : cosines)
                    for (double phi : {0.0, 1e-7, 1.0, kPi}) {
                        Vec3<double> wi = dirOf(ci, phi), wo = dirOf(co, 0);
                        double wia[3] = {wi.x, wi.y, wi.z}, woa[3] = {wo.x, wo.y, wo.z};
                        auto r = m.interp->eval(wia, woa, slots);
                        ++evaluated;
                        for (int ch = 0; ch < 3; ++ch) {
                            INFO(body, " alpha=", a, " ci=", ci, " co=", co, " phi=", phi);
                            CHECK(std::isfinite(r.rgb[ch]));
                            CHECK(r.rgb[ch] >= 0);
                        }
                    }
        }
        // Non-finite input: invalid lane, f = 0.
        double nan[1] = {std::numeric_limits<double>::quiet_NaN()};
        double wi[3] = {0, 0, 1}, wo[3] = {0, 0, 1};
        auto r = m.interp->eval(wi, wo, nan);
        CHECK(!r.valid);
        CHECK(r.rgb[0] == 0);
    }
    MESSAGE(evaluated, " hard-case evaluations");
}

TEST_CASE("shipped materials using kulla_conty check and evaluate") {
    int found = 0;
    for (const char* name : {"gold.mat", "rough_ceramic.mat", "copper.mat", "white_furnace.mat"}) {
        std::string path = std::string(FACET_SOURCE_DIR) + "/materials/" + name;
        facet::DiagnosticEngine diags;
        facet::CheckedProgram prog = facet::loadProgramFile(path, diags);
        INFO(path, "\n", diags.str());
        REQUIRE(!diags.hasErrors());
        const facet::CheckedMaterial& m = prog.materials[0];
        if (!m.singleLobe().compensatesEnergy()) continue;
        ++found;
        facet::Interpreter<double> interp(m, memoryTables().getFor(m));
        double wi[3] = {0.6, 0, 0.8}, wo[3] = {-0.6, 0, 0.8};
        auto r = interp.eval(wi, wo, nullptr);
        CHECK(r.valid);
        CHECK(r.rgb[0] > 0);
    }
    CHECK(found >= 2);
}

}  // TEST_SUITE
