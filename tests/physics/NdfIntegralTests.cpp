// NDF integral identities of the reference interpreter (SPEC section 3):
//   normalization      Int D(m) (n.m) dw = 1
//   projected area     Int D(m) (v.m) dw = v.n          (signed v.m, over the hemisphere)
//   weak white furnace Int G1(v, m) D(m) (v.m)+ dw = v.n (Smith masking, Heitz 2014 eq. 43)
// for every NDF of the catalog except whole lobes (ward: not a distribution of normals),
// alpha in {0.05, 0.2, 0.5, 1.0}, anisotropic pairs, and view directions from
// normal to 89 degrees at several azimuths.
//
// Quadrature: theta on Gauss-Legendre panels graded geometrically toward
// theta = 0 (the peak, width ~alpha) and toward the angle where the azimuth
// range stops being the full circle (a square-root kink of the inner
// integral); phi over exactly the range where the integrand is non-zero, so
// that the (v.m)+ cut-off is an end point. The largest deviation measured
// is 5e-11 (normalization, projected area and GGX/Beckmann furnace alike)
// except for Student-T's heaviest tail, whose integrand goes like
// mz^(2 gamma - 3) at the horizon (gamma = 1.6: 2.6e-5); all far below the
// 1e-3 tolerance, so a failure here is the interpreter's, not the
// integrator's.
#include "PhysicsUtil.h"

#include <cstdio>
#include <string>
#include <vector>

using namespace physics;
using facet::catalogSlot;
using facet::ModelArgs;
using facet::ModelInfo;
using facet::ModelSlot;
using facet::NdfEntry;
using facet::ndfEntry;
using facet::paramIndex;

namespace {

const double kAlphas[] = {0.05, 0.2, 0.5, 1.0};
const double kThetaV[] = {0, 30, 60, 80, 89};  // degrees
const double kPhiV[] = {0, 45, 120};           // degrees
constexpr double kTol = 1e-3;

struct NdfCase {
    std::string label;   // material source of the ndf statement
    double scale;        // smallest roughness: width of the peak at theta = 0
    bool anisotropic;
    bool exactSmith;     // has a Smith Lambda (closed-form or tabulated) that is exact for it
    bool tabulated = false;  // that Lambda is tabulated (LambdaTable.h)
};

// Every NDF of the catalog (but whole lobes), at each roughness with its
// typical shape parameters, and anisotropic where it has alpha_x and alpha_y
// (also with the axes swapped, so that they cannot be confused without the
// test noticing; Blinn-Phong at the exponent matching Beckmann alpha); plus,
// by hand, the shape parameters across their range.
std::vector<NdfCase> ndfCases() {
    std::vector<NdfCase> out;
    const double pairs[][2] = {{0.05, 0.5}, {0.2, 1.0}, {0.5, 0.05}};
    for (const ModelInfo* m : catalogSlot(ModelSlot::Ndf)) {
        const NdfEntry& ndf = ndfEntry(*m);
        if (ndf.wholeLobe) continue;
        const bool exactSmith = facet::hasSmithLambda(ndf) && !*ndf.lambdaNote;
        for (double a : kAlphas)
            out.push_back({callOf(ndf, typicalArgsAtAlpha(ndf, a)), a, false, exactSmith, ndf.tabulatedLambda});
        const int ax = paramIndex(ndf, "alpha_x"), ay = paramIndex(ndf, "alpha_y");
        if (ax < 0 || ay < 0) continue;
        for (auto& p : pairs) {
            ModelArgs<double> args = typicalArgsAtAlpha(ndf, p[0]);
            args.set(ay, p[1]);
            out.push_back({callOf(ndf, args), std::min(p[0], p[1]), true, exactSmith, ndf.tabulatedLambda});
        }
    }
    for (double a : kAlphas) {
        for (double g : {1.0, 1.5, 10.0})
            out.push_back({"gtr(alpha = " + num(a) + ", gamma = " + num(g) + ")", a, false, true, true});
        for (double g : {1.6, 4.0})
            out.push_back({"student_t(alpha = " + num(a) + ", gamma = " + num(g) + ")", a, false, true, true});
    }
    return out;
}

Hemisphere grid(const NdfCase& c, double thetaV, double phiV) {
    Hemisphere h;
    std::vector<Special> sp = {{0, c.scale / 8}};
    // Where the v.m > 0 region stops covering the whole azimuth circle.
    if (thetaV > 0) sp.push_back({kPi / 2 - thetaV, 1e-5});
    // student_t's heavy tail: D ~ (n.m)^(2 gamma - 4) at the horizon, singular for gamma < 2.
    if (c.label.rfind("student_t", 0) == 0) sp.push_back({kPi / 2, 1e-12});
    h.thetaBreaks = gradedBreaks(0, kPi / 2, sp, 0.1);
    h.center = phiV;
    h.phiPanels = c.anisotropic ? 48 : 8;
    return h;
}

struct MaxErr {
    double err = 0;
    std::string where;
    void add(double e, const std::string& w) {
        if (e > err) {
            err = e;
            where = w;
        }
    }
};

}  // namespace

TEST_CASE("NDF normalization: Int D(m) (n.m) dw = 1 for every NDF except ward") {
    MaxErr worst;
    for (const NdfCase& c : ndfCases()) {
        Material m = makeMaterial("ndf = " + c.label + ";");
        double integral = integrateHemisphere([&](const Vec3<double>& mm) { return m.D(mm) * mm.z; },
                                              [](double) { return kPi; }, grid(c, 0, 0));
        INFO(c.label, " integral = ", integral);
        CHECK(std::abs(integral - 1) < kTol);
        worst.add(std::abs(integral - 1), c.label);
    }
    MESSAGE("max |Int D cos - 1| = ", worst.err, " (", worst.where, ")");
}

// GTR's normalization constant has removable singularities at gamma = 1 and
// alpha = 1 (0/0 in the SPEC form). The interpreter must be continuous there:
// D at gamma = 1 +- 1e-6 and alpha = 1 +- 1e-6 must approach the limit value.
TEST_CASE("NDF normalization: GTR is continuous through its limits gamma = 1 and alpha = 1") {
    Vec3<double> ms[] = {{0, 0, 1}, dir(deg(30), 0), dir(deg(70), 1)};
    for (double a : {0.05, 0.2, 0.5, 1.0}) {
        Material lim = makeMaterial("ndf = gtr(alpha = " + num(a) + ", gamma = 1);");
        for (double g : {1 - 1e-6, 1 + 1e-6}) {
            Material near = makeMaterial("ndf = gtr(alpha = " + num(a) + ", gamma = " + num(g) + ");");
            for (auto& m : ms) {
                INFO("alpha = ", a, " gamma = ", g);
                CHECK(std::abs(near.D(m) / lim.D(m) - 1) < 1e-5);
            }
        }
    }
    for (double g : {1.0, 1.5, 2.0, 3.0}) {
        Material lim = makeMaterial("ndf = gtr(alpha = 1, gamma = " + num(g) + ");");
        for (double a : {1 - 1e-6, 1 + 1e-6}) {
            Material near = makeMaterial("ndf = gtr(alpha = " + num(a) + ", gamma = " + num(g) + ");");
            for (auto& m : ms) {
                INFO("alpha = ", a, " gamma = ", g);
                // alpha = 1 is the uniform distribution D = 1/pi (c = 1/pi, denominator 1).
                CHECK(std::abs(lim.D(m) * kPi - 1) < 1e-15);
                CHECK(std::abs(near.D(m) / lim.D(m) - 1) < 1e-5);
            }
        }
    }
}

TEST_CASE("NDF projected area: Int D(m) (v.m) dw = v.n for every NDF except ward") {
    MaxErr worst;
    for (const NdfCase& c : ndfCases()) {
        Material m = makeMaterial("ndf = " + c.label + ";");
        for (double tv : kThetaV)
            for (double pv : kPhiV) {
                if (tv == 0 && pv != 0) continue;
                Vec3<double> v = dir(deg(tv), deg(pv));
                // Signed v.m over the whole hemisphere: the smooth integrand
                // needs no cut, only the peak grading.
                Hemisphere h = grid(c, 0, deg(pv));
                double integral = integrateHemisphere([&](const Vec3<double>& mm) { return m.D(mm) * dot(v, mm); },
                                                      [](double) { return kPi; }, h);
                INFO(c.label, " theta_v = ", tv, " phi_v = ", pv, " integral = ", integral, " v.n = ", v.z);
                CHECK(std::abs(integral - v.z) < kTol);
                worst.add(std::abs(integral - v.z), c.label + " theta_v=" + num(tv) + " phi_v=" + num(pv));
            }
    }
    MESSAGE("max |Int D (v.m) - v.n| = ", worst.err, " (", worst.where, ")");
}

// The projected-area identity holds for the SIGNED v.m. With the clamped
// (v.m)+ the integral also counts the back-facing microfacets and exceeds v.n:
// Int D (v.m)+ = v.n + Int D (v.m)-. For the uniform distribution (GGX,
// alpha = 1: D = 1/pi) Int_{H+} max(0, -v.m) dw = pi (1 - cos theta_v)/2 (the
// sky-view factor of a plane tilted by pi - theta_v), so
// Int D (v.m)+ dw = (1 + cos theta_v)/2 exactly. At theta_v = 89 deg that is
// 0.5087, not v.n = 0.0175. Masking (G1) is what removes the back-facing part:
// see the weak white furnace below.
TEST_CASE("NDF projected area: the clamped (v.m)+ form is NOT v.n (back-facing facets count)") {
    Material m = makeMaterial("ndf = ggx(1);");
    NdfCase c{"ggx(1)", 1.0, false, true};
    for (double tv : kThetaV) {
        Vec3<double> v = dir(deg(tv), 0);
        double clamped = integrateHemisphere(
            [&](const Vec3<double>& mm) { return m.D(mm) * std::max(0.0, dot(v, mm)); },
            [&](double th) { return halfWidth(-std::cos(deg(tv)) * std::cos(th), std::sin(deg(tv)) * std::sin(th)); },
            grid(c, deg(tv), 0));
        INFO("theta_v = ", tv, " clamped = ", clamped);
        CHECK(std::abs(clamped - (1 + v.z) / 2) < 1e-6);
        if (tv >= 30) CHECK(clamped - v.z > 0.05);  // clearly not v.n
    }
}

// Heitz 2014 eq. 43: a Smith Lambda is the exact solution of this identity
// for its NDF. GGX and Beckmann Lambdas are exact (also anisotropic, with
// alpha(v) projected on the azimuth of v).
// For the NDFs without a closed form (student_t, epd, gtr, gaussian, abc,
// sgd), G1 comes from the tabulated Lambda (LambdaTable.h); every Smith form
// uses that one G1, so this covers each of their Smith pairs.
TEST_CASE("Weak white furnace: Int G1(v,m) D(m) (v.m)+ dw = v.n, every NDF with a Smith Lambda (iso and aniso)") {
    MaxErr worst, tabulated;
    for (const NdfCase& c : ndfCases()) {
        if (!c.exactSmith) continue;
        Material m = makeMaterial("ndf = " + c.label + ";");
        for (double tv : kThetaV)
            for (double pv : kPhiV) {
                if (tv == 0 && pv != 0) continue;
                Vec3<double> v = dir(deg(tv), deg(pv));
                double integral = integrateHemisphere(
                    [&](const Vec3<double>& mm) { return m.smithG1(v, mm) * m.D(mm) * std::max(0.0, dot(v, mm)); },
                    [&](double th) {
                        return halfWidth(-std::cos(deg(tv)) * std::cos(th), std::sin(deg(tv)) * std::sin(th));
                    },
                    grid(c, deg(tv), deg(pv)));
                INFO(c.label, " theta_v = ", tv, " phi_v = ", pv, " integral = ", integral, " v.n = ", v.z);
                CHECK(std::abs(integral - v.z) < kTol);
                worst.add(std::abs(integral - v.z), c.label + " theta_v=" + num(tv) + " phi_v=" + num(pv));
                // gamma = 1.6 excepted: this rule misses the horizon sliver below
                // 1e-12 rad of its D ~ (n.m)^-0.8, ~6e-4 of the integral at alpha = 1
                // (tests/energy checks its Lambda with a rule built for that singularity).
                bool studentT16 = c.label.rfind("student_t", 0) == 0 && c.label.find("gamma = 1.6") != std::string::npos;
                if (c.tabulated && !studentT16)
                    tabulated.add(std::abs(integral - v.z), c.label + " theta_v=" + num(tv) + " phi_v=" + num(pv));
            }
    }
    MESSAGE("max |Int G1 D (v.m)+ - v.n| = ", worst.err, " (", worst.where, ")");
    MESSAGE("max |Int G1 D (v.m)+ - v.n| (tabulated Lambdas) = ", tabulated.err, " (", tabulated.where, ")");
    CHECK(tabulated.err < 1e-4);
}

// Blinn-Phong has no closed-form Smith Lambda; the SPEC (after Walter et al.
// 2007) gives it the Beckmann Lambda at alpha = sqrt(2/(e+2)). That is an
// approximation, so the weak white furnace holds only approximately, well
// for large exponents and badly for small ones. Measured integral - v.n:
//   alpha 0.05 (e = 798): <= 9.0e-6 (theta_v = 89, 5e-4 relative)
//   alpha 0.2  (e = 48):  <= 5.8e-4 (theta_v = 80), 2.3e-4 at 89 (1.3% relative)
//   alpha 0.5  (e = 6):   7.5e-3 at 60, 1.0e-2 at 80  -> exceeds 1e-3
//   alpha 1    (e = 0):   up to 0.156 at 60           -> exceeds 1e-3
// The excess is physics of the SPEC's choice of Lambda, not an interpreter
// bug: for e = 0 the NDF is uniform (D = 1/pi), G1 = 1/(1 + Lambda_B(v)) does
// not depend on m, and the integral has the closed form
//   (1 + cos theta_v) / (2 (1 + Lambda_B(theta_v)))   (Int_{H+} (v.m)+ dw / pi, sky-view factor)
// with Lambda_B the Beckmann alpha = 1 Lambda at a = cot theta_v; values by
// Python (math.erf): 30: 0.9321218205551578, 60: 0.6561731979148001,
// 80: 0.27302730312625617, 89: 0.03052456693409499. The exact Lambda of the
// uniform distribution, (1/cos - 1)/2 (GGX alpha = 1), would give v.n.
TEST_CASE("Weak white furnace: Blinn-Phong with the Beckmann Lambda (approximate: holds only for large exponents)") {
    auto furnace = [](const std::string& ndf, double alpha, double tvDeg) {
        Material m = makeMaterial("ndf = " + ndf + ";");
        NdfCase c{ndf, alpha, false, true};
        double tv = deg(tvDeg);
        Vec3<double> v = dir(tv, 0);
        return integrateHemisphere(
            [&](const Vec3<double>& mm) { return m.smithG1(v, mm) * m.D(mm) * std::max(0.0, dot(v, mm)); },
            [&](double th) { return halfWidth(-std::cos(tv) * std::cos(th), std::sin(tv) * std::sin(th)); },
            grid(c, tv, 0));
    };
    double worst = 0;
    for (double a : {0.05, 0.2})
        for (double tv : kThetaV) {
            double i = furnace("blinn_phong(beckmann_to_phong(" + num(a) + "))", a, tv);
            INFO("alpha = ", a, " theta_v = ", tv, " integral = ", i);
            CHECK(std::abs(i - std::cos(deg(tv))) < kTol);
            worst = std::max(worst, std::abs(i - std::cos(deg(tv))));
        }
    MESSAGE("blinn_phong alpha <= 0.2: max |Int G1 D (v.m)+ - v.n| = ", worst);
    // Exponent 0: closed form above (independent of the quadrature and of the interpreter).
    const double tvs[] = {30, 60, 80, 89};
    const double e0[] = {0.9321218205551578, 0.6561731979148001, 0.27302730312625617, 0.03052456693409499};
    // alpha = 0.5 (exponent 6): measured, pinned (quadrature error < 1e-9).
    const double e6[] = {0.8661181545, 0.5074807482, 0.1839626034, 0.01922123325};
    for (int k = 0; k < 4; ++k) {
        INFO("theta_v = ", tvs[k]);
        double i0 = furnace("blinn_phong(beckmann_to_phong(1))", 1.0, tvs[k]);
        CHECK(std::abs(i0 - e0[k]) < 1e-9);
        double i6 = furnace("blinn_phong(beckmann_to_phong(0.5))", 0.5, tvs[k]);
        CHECK(std::abs(i6 - e6[k]) < 1e-9);
        CHECK(i0 > std::cos(deg(tvs[k])));  // energy is created, never lost
        CHECK(i6 > std::cos(deg(tvs[k])));
    }
}
