// Lobe tests (SPEC 10): the checked form of lobe blocks and `bsdf`, and the
// reference's combinations of lobes held against the one-lobe materials
// they are made of (a sum of two lobes is the sum of the two materials'
// values, a scale and a mix likewise), with inputs read through weights.
#include "Checker.h"
#include "Interpreter.h"
#include "Specialize.h"

#include <doctest/doctest.h>

#include <array>
#include <string>

using namespace facet;

namespace {

CheckedProgram checkText(const std::string& text) {
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramText(text, "lobes.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    return p;
}

// The model statements of two lobes, used as two one-lobe materials
// (kParts) and as the lobes of a combination (combined()), so that each
// combination below can be compared with its parts.
const std::string kSpecStatements = R"(
        ndf = ggx(rough * rough);
        masking = smith_height_correlated;
        fresnel = schlick(rgb(0.9, 0.6, 0.3));
)";
const std::string kBaseStatements = R"(
        ndf = beckmann(0.6);
        masking = smith_height_correlated;
        fresnel = dielectric(eta = 1.5);
        diffuse = lambert(rgb(0.2, 0.5, 0.8));
)";
const std::string kParts = "material spec {\n    input rough = 0.4 in 0 .. 1;\n" + kSpecStatements +
                           "}\nmaterial base {\n" + kBaseStatements + "}\n";

std::string combined(const std::string& bsdf) {
    return "material combo {\n    input rough = 0.4 in 0 .. 1;\n    input w = 0.3 in 0 .. 1;\n    lobe spec {" +
           kSpecStatements + "    }\n    lobe base {" + kBaseStatements + "    }\n    bsdf = " + bsdf + ";\n}\n";
}

// The lobe `spec` of kParts as the one lobe of a lobe block.
const std::string kSpecAlone =
    "material alone {\n    input rough = 0.4 in 0 .. 1;\n    lobe spec {" + kSpecStatements + "    }\n    bsdf = spec;\n}\n";

std::array<double, 3> evalOf(const CheckedMaterial& m, const std::array<double, 3>& wi,
                             const std::array<double, 3>& wo, const double* slots = nullptr) {
    EvalResult<double> r = Interpreter<double>(m).eval(wi.data(), wo.data(), slots);
    REQUIRE(r.valid);
    return r.rgb;
}

// A few direction pairs: near normal, off-specular, grazing.
const std::array<std::array<double, 3>, 2> kPairs[] = {
    {{{0.0, 0.0, 1.0}, {0.6, 0.0, 0.8}}},
    {{{-0.48, 0.36, 0.8}, {0.6, 0.0, 0.8}}},
    {{{0.28, -0.96, 0.0001}, {-0.8, 0.0, 0.6}}},
};

}  // namespace

TEST_SUITE("lobes") {

TEST_CASE("a material without lobe blocks is one implicit lobe") {
    CheckedProgram p = checkText(kParts);
    const CheckedMaterial& m = p.materials.at(0);
    REQUIRE(m.lobes.size() == 1);
    CHECK(m.lobes[0].implicit);
    CHECK(!m.combinesLobes());
    CHECK(std::string(m.singleLobe().ndf.model->name) == "ggx");
}

TEST_CASE("lobe blocks and bsdf build the combination tree") {
    CheckedProgram p = checkText(combined("layer(spec, 0.5 * base, weight = w) + mix(spec, base, 0.25)"));
    const CheckedMaterial& m = p.materials.at(0);
    REQUIRE(m.lobes.size() == 2);
    CHECK(m.lobes[0].name == "spec");
    CHECK(!m.lobes[1].implicit);
    CHECK(m.combinesLobes());
    CHECK(printBsdf(m, m.bsdfRoot()) == "(layer(spec, (0.5 * base), weight = w) + mix(spec, base, 0.25))");
    const BsdfNode& root = m.bsdfRoot();
    CHECK(root.kind == BsdfKind::Sum);
    CHECK(m.bsdf.at(size_t(root.a)).kind == BsdfKind::Layer);
    CHECK(m.bsdf.at(size_t(root.b)).kind == BsdfKind::Mix);
    // `bsdf = NAME;` alone is one lobe: the compiled backends take it.
    CheckedProgram one = checkText(kSpecAlone);
    CHECK(!one.materials.at(0).combinesLobes());
    CHECK(std::string(one.materials.at(0).singleLobe().ndf.model->name) == "ggx");
}

TEST_CASE("a diffuse lobe needs no ndf") {
    CheckedProgram p = checkText(R"(
material m {
    lobe coat { ndf = ggx(0.1); fresnel = dielectric(eta = 1.5); }
    lobe base { diffuse = lambert(0.5); }
    bsdf = coat + base;
}
material lambert_only { ndf = ggx(0.1); fresnel = none; diffuse = lambert(0.5); }
)");
    const CheckedMaterial& m = p.materials.at(0);
    CHECK(!m.lobes[1].hasNdf());
    // At wi far from the mirror direction of wo the coat contributes ~0;
    // the diffuse lobe alone is rho / pi there.
    std::array<double, 3> f = evalOf(m, {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0});
    std::array<double, 3> coatOnly = evalOf(p.materials.at(1), {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0});
    (void)coatOnly;
    EvalResult<double> grazing = Interpreter<double>(m).eval(std::array<double, 3>{0.6, 0.0, 0.8}.data(),
                                                             std::array<double, 3>{0.0, 0.6, 0.8}.data(), nullptr);
    REQUIRE(grazing.valid);
    CHECK(f[0] > 0.5 / 3.141592653589793);
    CHECK(grazing.rgb[0] >= 0.5 / 3.141592653589793);
}

TEST_CASE("sum, scale and mix equal the same sums of the one-lobe materials") {
    CheckedProgram parts = checkText(kParts);
    const CheckedMaterial& spec = parts.materials.at(0);
    const CheckedMaterial& base = parts.materials.at(1);
    CheckedProgram sum = checkText(combined("spec + base"));
    CheckedProgram scaled = checkText(combined("rgb(0.5, 2, 0) * spec + base * w"));
    CheckedProgram mixed = checkText(combined("mix(spec, base, w)"));
    CheckedProgram clamped = checkText(combined("mix(spec, base, 3 * w + 1) + (w - 1) * base"));
    // Slots of the combined materials: rough = 0.4, w = 0.3 (the defaults),
    // then w = 0.8 given explicitly.
    const double slotsW8[2] = {0.4, 0.8};
    for (const auto& [wi, wo] : kPairs) {
        CAPTURE(wi[2]);
        std::array<double, 3> s = evalOf(spec, wi, wo), b = evalOf(base, wi, wo);
        std::array<double, 3> fSum = evalOf(sum.materials[0], wi, wo);
        std::array<double, 3> fScaled = evalOf(scaled.materials[0], wi, wo);
        std::array<double, 3> fMixed = evalOf(mixed.materials[0], wi, wo);
        std::array<double, 3> fMixed8 = evalOf(mixed.materials[0], wi, wo, slotsW8);
        std::array<double, 3> fClamped = evalOf(clamped.materials[0], wi, wo);
        const double scale[3] = {0.5, 2, 0};
        for (int ch = 0; ch < 3; ++ch) {
            CHECK(fSum[ch] == doctest::Approx(s[ch] + b[ch]).epsilon(1e-14));
            CHECK(fScaled[ch] == doctest::Approx(scale[ch] * s[ch] + 0.3 * b[ch]).epsilon(1e-14));
            CHECK(fMixed[ch] == doctest::Approx(0.7 * s[ch] + 0.3 * b[ch]).epsilon(1e-14));
            CHECK(fMixed8[ch] == doctest::Approx(0.2 * s[ch] + 0.8 * b[ch]).epsilon(1e-14));
            // T = 1.9 clamps to 1 (base alone); the weight w - 1 < 0 clamps to 0.
            CHECK(fClamped[ch] == doctest::Approx(b[ch]).epsilon(1e-14));
        }
    }
}

TEST_CASE("a one-lobe material evaluates exactly as before lobes existed") {
    // `bsdf = spec;` over the same lobe: the same numbers to the bit.
    CheckedProgram parts = checkText(kParts);
    CheckedProgram alone = checkText(kSpecAlone);
    for (const auto& [wi, wo] : kPairs) {
        std::array<double, 3> a = evalOf(parts.materials[0], wi, wo), b = evalOf(alone.materials[0], wi, wo);
        for (int ch = 0; ch < 3; ++ch) CHECK(a[ch] == b[ch]);
    }
}

TEST_CASE("only what a lobe or a weight reads invalidates a lane") {
    CheckedProgram p = checkText(combined("mix(spec, base, w)"));
    const CheckedMaterial& m = p.materials.at(0);
    CheckedMaterial::Reads reads = m.readByModels();
    CHECK(reads.inputs == std::vector<bool>{true, true});
    const double nanWeight[2] = {0.4, std::numeric_limits<double>::quiet_NaN()};
    std::array<double, 3> wi{0, 0, 1}, wo{0.6, 0, 0.8};
    CHECK(!Interpreter<double>(m).eval(wi.data(), wo.data(), nanWeight).valid);
    CheckedProgram unread = checkText(combined("spec + 0.5 * base"));
    CHECK(unread.materials.at(0).readByModels().inputs == std::vector<bool>{true, false});
    CHECK(Interpreter<double>(unread.materials.at(0)).eval(wi.data(), wo.data(), nanWeight).valid);
}

// SPEC 10, "Specialization": with the weights constant (written so, or
// bound), a lobe whose weight is 0 is dropped and a weight of 1 disappears
// (BsdfFolding.h); the folded material gives the same numbers, to the bit,
// as the combination it came from with the same values. Weights that are
// not all 0 or all 1, or not constant, stay.
TEST_CASE("specialization folds constant weights: a lobe weighted 0 is dropped, a weight of 1 disappears") {
    struct Case {
        const char* bsdf;
        double w;  // bound when >= 0
        const char* folded;
    };
    const Case cases[] = {
        {"0 * spec + base", -1, "base"},
        {"1 * spec + base", -1, "(spec + base)"},
        {"rgb(1, 1, 1) * spec + 0 * base", -1, "spec"},
        {"mix(spec, base, w)", 0, "spec"},
        {"mix(spec, base, w)", 1, "base"},
        {"layer(spec, base, weight = w)", 0, "base"},
        {"layer(spec, base, weight = w)", 1, "layer(spec, base)"},
        {"w * spec + base", 0, "base"},
        {"rgb(0, 0, 1) * spec + base", -1, "((rgb(0, 0, 1) * spec) + base)"},
        {"mix(spec, base, w)", -1, "mix(spec, base, w)"},
        {"mix(0 * spec, base, w)", -1, "mix((0 * spec), base, w)"},
        {"0 * spec + 0 * base", -1, "((0 * spec) + (0 * base))"},  // nothing at all: as written
    };
    for (const Case& c : cases) {
        std::string bsdf = c.bsdf;
        CAPTURE(bsdf);
        CAPTURE(c.w);
        CheckedProgram p = checkText(combined(c.bsdf));
        const CheckedMaterial& written = p.materials.at(0);
        DiagnosticEngine d;
        InputBindings bind;
        if (c.w >= 0) bind["w"] = {c.w};
        CheckedMaterial folded = specializeMaterial(written, bind, d);
        REQUIRE(!d.hasErrors());
        CHECK(printBsdf(folded, folded.bsdfRoot()) == c.folded);
        // Every lobe left is referred to; a combination folded to one lobe
        // is a one-lobe material (what the compiled backends lower alone).
        for (const CheckedLobe& lobe : folded.lobes)
            CHECK(std::string(c.folded).find(lobe.name) != std::string::npos);
        CHECK(folded.combinesLobes() == (folded.bsdf.size() != 1));
        const double writtenSlots[2] = {0.4, c.w >= 0 ? c.w : 0.3};
        const double foldedSlots[2] = {0.4, 0.3};
        for (const auto& [wi, wo] : kPairs) {
            std::array<double, 3> a = evalOf(written, wi, wo, writtenSlots), b = evalOf(folded, wi, wo, foldedSlots);
            for (int ch = 0; ch < 3; ++ch) CHECK(a[ch] == b[ch]);
        }
    }
}

}  // TEST_SUITE
