// Interpreter unit tests: BRDF values at configurations where every term has
// a closed form that can be worked out by hand, plus the SPEC 2 rules for
// invalid lanes and directions below the horizon.
//
// The expected values are computed in this file from the textbook formulas
// (not by calling the interpreter's own term functions), so a wrong constant,
// a swapped argument or a missing factor in the reference shows up here. The
// interpreter is the reference every compiled evaluator is tested against,
// which is why it gets its own hand-checked values.
#include "Checker.h"
#include "Interpreter.h"
#include "TestUtil.h"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

using namespace facet;
using namespace facet::test;

namespace {

struct Compiled {
    CheckedProgram prog;
    const CheckedMaterial& material() const { return prog.materials.at(0); }
};

Compiled compile(const std::string& body) {
    DiagnosticEngine diags;
    Compiled c{loadProgramText(inMaterial(body), "t.mat", diags)};
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    return c;
}

EvalResult<double> eval(const Compiled& c, std::array<double, 3> wi, std::array<double, 3> wo,
                        const double* slots = nullptr) {
    return Interpreter<double>(c.material()).eval(wi.data(), wo.data(), slots);
}

const std::array<double, 3> N = {0, 0, 1};
const double kS60 = std::sqrt(3.0) / 2;  // sin 60 deg; cos 60 deg = 0.5
// Mirror pair at 60 deg from the normal: h = n, wi.h = 0.5.
const std::array<double, 3> W60 = {kS60, 0, 0.5}, W60m = {-kS60, 0, 0.5};

void checkRgb(const EvalResult<double>& r, double er, double eg, double eb, double rel = 1e-12) {
    REQUIRE(r.valid);
    CHECK_MESSAGE(near(r.rgb[0], er, rel), r.rgb[0], " vs ", er);
    CHECK_MESSAGE(near(r.rgb[1], eg, rel), r.rgb[1], " vs ", eg);
    CHECK_MESSAGE(near(r.rgb[2], eb, rel), r.rgb[2], " vs ", eb);
}

}  // namespace

TEST_SUITE("interpreter") {

TEST_CASE("GGX at normal incidence: D(n) = 1/(pi a^2), f = D/4") {
    // wi = wo = n: h = n, G = 1 (masking none), F = 1, n.wi = n.wo = 1.
    for (double a : {0.05, 0.3, 0.5, 1.0}) {
        CAPTURE(a);
        Compiled c = compile(fmt::format("ndf = ggx({});", a));
        double f = 1 / (kPi * a * a) / 4;
        checkRgb(eval(c, N, N), f, f, f);
    }
}

TEST_CASE("GGX mirror at 60 deg, height-correlated Smith, Schlick F") {
    // h = n so D = 1/(pi a^2). Lambda(v) = (sqrt(1 + a^2 tan^2) - 1)/2 with
    // tan^2(60) = 3; G = 1/(1 + 2 Lambda). F = f0 + (1 - f0)(1 - 0.5)^5.
    // f = F D G / (4 cos^2 60) = F D G.
    const double a = 0.5, f0 = 0.04;
    Compiled c = compile("ndf = ggx(0.5);\nmasking = smith_height_correlated;\nfresnel = schlick(f0 = 0.04);");
    double D = 1 / (kPi * a * a);
    double lambda = (std::sqrt(1 + a * a * 3) - 1) / 2;
    double G = 1 / (1 + 2 * lambda);
    double F = f0 + (1 - f0) / 32;  // = 0.07
    CHECK(F == doctest::Approx(0.07));
    double f = F * D * G / (4 * 0.5 * 0.5);
    checkRgb(eval(c, W60, W60m), f, f, f);
    // The uncorrelated form: G = 1/(1 + Lambda)^2.
    Compiled sep = compile("ndf = ggx(0.5);\nmasking = smith_separable;\nfresnel = schlick(f0 = 0.04);");
    double fs = F * D / ((1 + lambda) * (1 + lambda));
    checkRgb(eval(sep, W60, W60m), fs, fs, fs);
}

TEST_CASE("Beckmann with a tilted half vector: exp(-tan^2/a^2) / (pi a^2 cos^4)") {
    // wi at 60 deg, wo = n: h is at 30 deg, tan^2 = 1/3, cos^4 = 9/16,
    // wi.h = cos 30. Masking none, F none: f = D / (4 * 0.5 * 1).
    const double a = 0.4;
    Compiled c = compile("ndf = beckmann(0.4);");
    double D = std::exp(-(1.0 / 3) / (a * a)) / (kPi * a * a * 9.0 / 16);
    double f = D / (4 * 0.5);
    checkRgb(eval(c, W60, N), f, f, f, 1e-12);
}

TEST_CASE("anisotropic GGX: alpha_x and alpha_y act along t and b") {
    // h tilted towards +x by 30 deg (as above): mx^2 = 1/4, my = 0, mz^2 = 3/4.
    // D = 1 / (pi ax ay (mx^2/ax^2 + mz^2)^2); swapping ax and ay changes it.
    const double ax = 0.2, ay = 0.6;
    Compiled c = compile("ndf = ggx(alpha_x = 0.2, alpha_y = 0.6);");
    double t = 0.25 / (ax * ax) + 0.75;
    double D = 1 / (kPi * ax * ay * t * t);
    checkRgb(eval(c, W60, N), D / 2, D / 2, D / 2);
    Compiled swapped = compile("ndf = ggx(alpha_x = 0.6, alpha_y = 0.2);");
    double t2 = 0.25 / (ay * ay) + 0.75;
    double D2 = 1 / (kPi * ax * ay * t2 * t2);
    checkRgb(eval(swapped, W60, N), D2 / 2, D2 / 2, D2 / 2);
}

TEST_CASE("Fresnel at normal incidence: conductor, dielectric, Schlick from eta") {
    // Conductor: ((n-1)^2 + k^2) / ((n+1)^2 + k^2) per channel (gold's indices).
    Compiled gold = compile(
        "ndf = ggx(1);\nfresnel = conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603));");
    auto R = [](double n, double k) { return ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k); };
    double D4 = 1 / kPi / 4;  // GGX alpha = 1 at n, over 4
    checkRgb(eval(gold, N, N), R(0.143, 3.983) * D4, R(0.374, 2.385) * D4, R(1.442, 1.603) * D4);
    // Dielectric eta = 1.5: ((1.5-1)/(1.5+1))^2 = 0.04.
    Compiled glass = compile("ndf = ggx(1);\nfresnel = dielectric(1.5);");
    checkRgb(eval(glass, N, N), 0.04 * D4, 0.04 * D4, 0.04 * D4);
    // Schlick from eta gives the same f0 at normal incidence.
    Compiled sch = compile("ndf = ggx(1);\nfresnel = schlick(eta = 1.5);");
    checkRgb(eval(sch, N, N), 0.04 * D4, 0.04 * D4, 0.04 * D4);
}

TEST_CASE("dielectric with eta < 1: total internal reflection gives F = 1") {
    // At wi.h = cos 60 = 0.5 and eta = 0.5: sin^2 t = 0.75 / 0.25 = 3 > 1.
    Compiled c = compile("ndf = ggx(0.5);\nfresnel = dielectric(0.5);");
    double f = 1 / (kPi * 0.25) / (4 * 0.25);
    checkRgb(eval(c, W60, W60m), f, f, f);
}

TEST_CASE("Lambert base adds albedo/pi, rgb input per slot") {
    Compiled c = compile("input albedo = rgb(0.2, 0.4, 0.6);\nndf = ggx(0.5);\ndiffuse = lambert(albedo);");
    double spec = 1 / (kPi * 0.25) / 4;
    checkRgb(eval(c, N, N), spec + 0.2 / kPi, spec + 0.4 / kPi, spec + 0.6 / kPi);
    double slots[3] = {1, 0, 0.5};
    checkRgb(eval(c, N, N, slots), spec + 1 / kPi, spec, spec + 0.5 / kPi);
}

TEST_CASE("Blinn-Phong, GTR and Ward at h = n") {
    // Blinn-Phong: D(n) = (e + 2) / (2 pi).
    Compiled bp = compile("ndf = blinn_phong(30);");
    double dbp = 32 / (2 * kPi) / 4;
    checkRgb(eval(bp, N, N), dbp, dbp, dbp);
    // GTR with gamma = 2 is GGX: D(n) = 1/(pi a^2).
    Compiled g2 = compile("ndf = gtr(0.3, 2);");
    double dg2 = 1 / (kPi * 0.09) / 4;
    checkRgb(eval(g2, N, N), dg2, dg2, dg2, 1e-10);
    // GTR gamma = 1: c = (a^2 - 1) / (pi ln a^2), D(n) = c / a^2.
    Compiled g1 = compile("ndf = gtr(0.3, 1);");
    double c1 = (0.09 - 1) / (kPi * std::log(0.09));
    checkRgb(eval(g1, N, N), c1 / 0.09 / 4, c1 / 0.09 / 4, c1 / 0.09 / 4, 1e-10);
    // Ward at h = n, mirror 60 deg: 1 / (4 pi ax ay sqrt(ci co)), F = 1.
    Compiled w = compile("ndf = ward(0.2, 0.3);");
    double fw = 1 / (4 * kPi * 0.2 * 0.3 * 0.5);
    checkRgb(eval(w, W60, W60m), fw, fw, fw);
}

TEST_CASE("inputs are clamped to their declared range") {
    Compiled c = compile("input a = 0.5 in 0.1 .. 1;\nndf = ggx(a);");
    double above[1] = {7}, below[1] = {-3};
    double f1 = 1 / kPi / 4, f01 = 1 / (kPi * 0.01) / 4;
    checkRgb(eval(c, N, N, above), f1, f1, f1);
    checkRgb(eval(c, N, N, below), f01, f01, f01, 1e-10);
}

TEST_CASE("SPEC 2: below the horizon is 0 (also the Lambert term); bad lanes are invalid and 0") {
    Compiled c = compile("input a = 0.5;\nndf = ggx(a);\ndiffuse = lambert(0.5);");
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (auto [wi, wo] : {std::pair{std::array<double, 3>{0.6, 0, -0.8}, N}, std::pair{N, std::array<double, 3>{0, 0, -1}},
                          std::pair{std::array<double, 3>{1, 0, 0}, N}}) {
        EvalResult<double> r = eval(c, wi, wo);
        CHECK(r.valid);
        CHECK(r.rgb == std::array<double, 3>{0, 0, 0});
    }
    // Non-finite or non-unit (beyond 1e-3) directions, NaN/Inf inputs.
    for (auto wi : {std::array<double, 3>{nan, 0, 1}, std::array<double, 3>{0, inf, 1}, std::array<double, 3>{0, 0, 1.01},
                    std::array<double, 3>{0, 0, 0}}) {
        EvalResult<double> r = eval(c, wi, N);
        CHECK(!r.valid);
        CHECK(r.rgb == std::array<double, 3>{0, 0, 0});
    }
    for (double bad : {nan, inf, -inf}) {
        double slots[1] = {bad};
        EvalResult<double> r = eval(c, N, N, slots);
        CHECK(!r.valid);
        CHECK(r.rgb == std::array<double, 3>{0, 0, 0});
    }
    // Within the 1e-3 tolerance the direction is accepted and renormalized.
    EvalResult<double> r = eval(c, {0, 0, 1.0005}, N);
    double f = 1 / (kPi * 0.25) / 4 + 0.5 / kPi;
    checkRgb(r, f, f, f);
}

}  // TEST_SUITE
