// Values of the reference interpreter at hand-picked directions, against
// numbers computed independently of it: closed forms worked out by hand and
// evaluated with Python's math module (python3 -c, double precision), written
// next to each expected value with where it comes from. Each NDF, each
// masking model and each Fresnel model has at least one such value, and two
// full BRDF evaluations check that the terms are assembled as
// F G D / (4 n.wi n.wo).
//
// Where possible the independent value uses a different form of the formula
// than the SPEC's (slope-space NDFs in theta/phi, Snell-angle Fresnel
// equations, Born & Wolf's real conductor formula), so a shared algebra
// mistake cannot cancel out.
#include "PhysicsUtil.h"

#include <string>

using namespace physics;

namespace {

// |actual/expected - 1| <= tol, printed on failure.
void near(double actual, double expected, double tol, const char* what) {
    INFO(what, ": actual = ", actual, " expected = ", expected);
    CHECK(std::abs(actual - expected) <= tol * std::abs(expected));
}

const Vec3<double> kN{0, 0, 1};

}  // namespace

TEST_CASE("Hand values: NDFs D(m)") {
    SUBCASE("ggx") {
        Material g = makeMaterial("ndf = ggx(0.5);");
        // m = n: 1/(pi a^2) = 4/pi.
        near(g.D(kN), 1.2732395447351628, 1e-14, "ggx(0.5) at n: 4/pi");
        // theta = 45 deg: tan^2 = 1, cos^4 = 1/4, D = 1/(pi a^2 cos^4 (1 + tan^2/a^2)^2)
        // = 1/(pi 0.25 0.25 25) = 0.64/pi.
        near(g.D(dir(deg(45), 1.234)), 0.20371832715762606, 1e-13, "ggx(0.5) at 45 deg: 0.64/pi");
        Material a = makeMaterial("ndf = ggx(alpha_x = 0.2, alpha_y = 0.8);");
        near(a.D(kN), 1.9894367886486917, 1e-14, "ggx(0.2, 0.8) at n: 1/(pi 0.16)");
        // Slope form (Heitz 2014 eq. 85): 1/(pi ax ay cos^4 (1 + tan^2 (cos^2 phi/ax^2 + sin^2 phi/ay^2))^2),
        // theta = 30, phi = 60 deg.
        near(a.D(dir(deg(30), deg(60))), 0.29306125658508209, 1e-13, "ggx(0.2, 0.8) at theta 30 phi 60");
        Material t = makeMaterial("ndf = trowbridge_reitz(0.5);");  // the alias is the same NDF
        near(t.D(dir(deg(45), 0)), 0.20371832715762606, 1e-13, "trowbridge_reitz alias");
    }
    SUBCASE("beckmann") {
        Material b = makeMaterial("ndf = beckmann(0.5);");
        // theta = 45: exp(-tan^2/a^2)/(pi a^2 cos^4) = exp(-4)/(pi/16) = 16 e^-4/pi.
        near(b.D(dir(deg(45), 2.0)), 0.093280782880902191, 1e-13, "beckmann(0.5) at 45 deg");
        near(b.D(kN), 1.2732395447351628, 1e-14, "beckmann(0.5) at n: 1/(pi a^2)");
        Material a = makeMaterial("ndf = beckmann(alpha_x = 0.2, alpha_y = 0.8);");
        // exp(-tan^2 (cos^2 phi/ax^2 + sin^2 phi/ay^2))/(pi ax ay cos^4), theta = 30, phi = 60.
        near(a.D(dir(deg(30), deg(60))), 0.29797591719304528, 1e-13, "beckmann(0.2, 0.8) at theta 30 phi 60");
    }
    SUBCASE("blinn_phong") {
        // (e+2)/(2 pi) cos^e: e = 2 at 60 deg: (4/(2 pi)) (1/4) = 1/(2 pi).
        Material b = makeMaterial("ndf = blinn_phong(2);");
        near(b.D(dir(deg(60), 0.3)), 0.15915494309189535, 1e-14, "blinn_phong(2) at 60 deg: 1/(2 pi)");
        // e = 100 at n: 102/(2 pi) = 51/pi.
        Material c = makeMaterial("ndf = blinn_phong(100);");
        near(c.D(kN), 16.233804195373324, 1e-14, "blinn_phong(100) at n: 51/pi");
        // e = 0 is the uniform distribution 1/pi.
        Material u = makeMaterial("ndf = blinn_phong(beckmann_to_phong(1));");
        near(u.D(dir(deg(70), 0)), 0.31830988618379069, 1e-14, "blinn_phong(0): 1/pi");
    }
    SUBCASE("gtr") {
        // gamma = 1 (limit of the constant): c = (a^2 - 1)/(pi ln a^2); a = 0.5:
        // c = 0.75/(2 pi ln 2); D(n) = c/(a^2)^1 = c/0.25.
        Material g1 = makeMaterial("ndf = gtr(alpha = 0.5, gamma = 1);");
        near(g1.D(kN), 0.68883614139492777, 1e-13, "gtr(0.5, 1) at n");
        // theta = 60: c/(1 + (a^2 - 1) cos^2) = c/(1 - 0.75/4).
        near(g1.D(dir(deg(60), 0)), 0.21194958196767008, 1e-13, "gtr(0.5, 1) at 60 deg");
        // gamma = 2 is GGX: c = a^2/pi, D(n) = 1/(pi a^2) = 4/pi.
        Material g2 = makeMaterial("ndf = gtr(alpha = 0.5, gamma = 2);");
        near(g2.D(kN), 1.2732395447351628, 1e-13, "gtr(0.5, 2) = ggx at n");
        near(g2.D(dir(deg(45), 0)), 0.20371832715762606, 1e-13, "gtr(0.5, 2) = ggx at 45 deg");
        // gamma = 3: c = 2 (a^2 - 1)/(pi (1 - a^-4)) = 1.5/(15 pi) = 0.1/pi; D(n) = c/a^6 = 6.4/pi.
        Material g3 = makeMaterial("ndf = gtr(alpha = 0.5, gamma = 3);");
        near(g3.D(kN), 2.0371832715762603, 1e-13, "gtr(0.5, 3) at n: 6.4/pi");
        // gamma = 1.5, a = 0.2: c = 0.5 (0.04 - 1)/(pi (1 - 0.04^-0.5)) = 0.48/(4 pi) = 0.12/pi;
        // D(n) = c/0.04^1.5 = 0.12/(0.008 pi) = 15/pi.
        Material g15 = makeMaterial("ndf = gtr(alpha = 0.2, gamma = 1.5);");
        near(g15.D(kN), 4.7746482927568605, 1e-13, "gtr(0.2, 1.5) at n: 15/pi");
        // alpha = 1 (other limit): c = 1/pi and the denominator is 1: D = 1/pi everywhere.
        Material a1 = makeMaterial("ndf = gtr(alpha = 1, gamma = 1.5);");
        near(a1.D(dir(deg(80), 0)), 0.31830988618379069, 1e-14, "gtr(1, 1.5): 1/pi");
        Material a11 = makeMaterial("ndf = gtr(alpha = 1, gamma = 1);");  // both limits at once
        near(a11.D(dir(deg(10), 0)), 0.31830988618379069, 1e-14, "gtr(1, 1): 1/pi");
    }
    SUBCASE("gaussian") {
        // N(a) = 2 pi Int_0^{pi/2} exp(-t^2/a^2) cos t sin t dt. For small a, with
        // sin t cos t = t - (2/3) t^3 + (2/15) t^5 - ... and Int_0^inf t^(2k+1) e^(-t^2/a^2) dt
        // = k! a^(2k+2)/2:  N = pi a^2 (1 - 2a^2/3 + 4a^4/15 - ...). a = 0.01: D(n) = 1/N
        // = 3183.3110740873494 (the next term is ~a^6 ~ 1e-12 relative).
        Material g = makeMaterial("ndf = gaussian(0.01);");
        near(g.D(kN), 3183.3110740873494, 1e-11, "gaussian(0.01) at n: 1/N, series");
        // Shape: D(theta)/D(0) = exp(-theta^2/a^2) whatever N is; theta = a gives 1/e.
        near(g.D(dir(0.01, 0.7)) / g.D(kN), std::exp(-1.0), 1e-12, "gaussian(0.01) at theta = alpha");
        // a = 0.5 and 1: N by composite Simpson in Python (2e5 intervals on [0, pi/2]):
        // N(0.5) = 0.66670488287535445, N(1) = 1.7206123164427338.
        Material h = makeMaterial("ndf = gaussian(0.5);");
        near(h.D(kN), 1 / 0.66670488287535445, 1e-11, "gaussian(0.5) at n");
        near(h.D(dir(0.5, 0)), std::exp(-1.0) / 0.66670488287535445, 1e-11, "gaussian(0.5) at theta = 0.5");
        Material o = makeMaterial("ndf = gaussian(1);");
        near(o.D(kN), 1 / 1.7206123164427338, 1e-11, "gaussian(1) at n");
    }
    SUBCASE("ward (whole lobe: checked through brdf)") {
        // Ward 1992: exp(-tan^2 theta_h (cos^2 phi_h/ax^2 + sin^2 phi_h/ay^2))/(4 pi ax ay sqrt(n.wi n.wo)).
        // wi = wo = n: 1/(4 pi 0.09).
        Material w = makeMaterial("ndf = ward(0.3);");
        near(w.brdf(kN, kN)[0], 0.88419412828830746, 1e-14, "ward(0.3) at wi = wo = n");
        // wi at 60 deg in the xz plane, wo = n: h at 30 deg, phi_h = 0, tan^2 = 1/3:
        // exp(-(1/3)/0.09)/(4 pi 0.3 0.6 sqrt(0.5)).
        Material a = makeMaterial("ndf = ward(alpha_x = 0.3, alpha_y = 0.6);");
        near(a.brdf(dir(deg(60), 0), kN)[1], 0.015400490301631349, 1e-13, "ward(0.3, 0.6) phi_h = 0");
        // Same in the yz plane: phi_h = 90 deg selects alpha_y: exp(-(1/3)/0.36)/(...).
        near(a.brdf(dir(deg(60), deg(90)), kN)[2], 0.24768979198890828, 1e-13, "ward(0.3, 0.6) phi_h = 90");
    }
}

TEST_CASE("Hand values: Smith Lambda") {
    // GGX, a = 1, tan theta = 1: (-1 + sqrt(1 + a^2 tan^2))/2 = (sqrt 2 - 1)/2.
    Material g = makeMaterial("ndf = ggx(1);");
    near(g.lambda(dir(deg(45), 0.4)), 0.20710678118654757, 1e-14, "ggx Lambda a=1 tan=1");
    near(g.smithG1(dir(deg(45), 0.4), kN), 2 * (std::sqrt(2.0) - 1), 1e-14, "ggx G1 = 2(sqrt2 - 1)");
    CHECK(g.lambda(kN) == 0);  // nothing is masked at normal incidence
    // Anisotropic GGX (0.2, 0.8), v at theta 60, phi 30: alpha(v)^2 = cos^2 phi ax^2 + sin^2 phi ay^2
    // = 0.03 + 0.16 = 0.19, tan^2 = 3, x = 0.57, Lambda = (sqrt(1.57) - 1)/2.
    Material ga = makeMaterial("ndf = ggx(alpha_x = 0.2, alpha_y = 0.8);");
    near(ga.lambda(dir(deg(60), deg(30))), 0.12649820430708336, 1e-13, "ggx aniso Lambda");
    // Beckmann, a = cot(theta)/alpha = 1 (alpha 1, theta 45):
    // (erf(1) - 1)/2 + exp(-1)/(2 sqrt(pi)).
    Material b = makeMaterial("ndf = beckmann(1);");
    near(b.lambda(dir(deg(45), 0)), 0.02512727083000614, 1e-12, "beckmann Lambda a=1");
    // Beckmann alpha 0.5, theta 60: a = cot 60/0.5 = 2/sqrt 3.
    Material b5 = makeMaterial("ndf = beckmann(0.5);");
    near(b5.lambda(dir(deg(60), 1)), 0.013161894477007788, 1e-12, "beckmann Lambda alpha .5 theta 60");
    // Blinn-Phong e = 2: Beckmann Lambda at alpha = sqrt(2/(e+2)) = 1/sqrt 2; tan theta = sqrt 2
    // gives a = cot/alpha = 1, the same value as above.
    Material p = makeMaterial("ndf = blinn_phong(2);");
    near(p.lambda(dir(std::atan(std::sqrt(2.0)), 0)), 0.02512727083000614, 1e-12, "blinn_phong Lambda a=1");
    // G1 is zero on back-facing microfacets (chi+(v.m)).
    CHECK(g.smithG1(dir(deg(80), 0), dir(deg(30), kPi)) == 0);
}

TEST_CASE("Hand values: masking G") {
    // Directions in the xz plane: wi at 60 deg, wo = n -> h at 30 deg,
    // n.wi = 0.5, n.wo = 1, wo.h = cos 30.
    const Vec3<double> wi60 = dir(deg(60), 0);
    auto G = [](const std::string& masking, const std::string& ndf, Vec3<double> wi, Vec3<double> wo) {
        Material m = makeMaterial("ndf = " + ndf + "; masking = " + masking + ";");
        Vec3<double> h = normalize({wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
        return m.G(wi, wo, h);
    };
    CHECK(G("none", "ggx(0.3)", wi60, kN) == 1);
    near(G("implicit", "ggx(0.3)", wi60, kN), 0.5, 1e-15, "implicit: (n.wi)(n.wo)");
    near(G("neumann", "gaussian(0.3)", wi60, kN), 0.5, 1e-15, "neumann: 0.5*1/max(0.5,1)");
    // kelemen: (n.wi)(n.wo)/(wo.h)^2 = 0.5/cos^2 30 = 2/3.
    near(G("kelemen", "gtr(alpha = 0.3, gamma = 1.5)", wi60, kN), 2.0 / 3, 1e-15, "kelemen 2/3");
    // schlick_smith(k): G1(c) = c/(c(1-k)+k): k = 0.25, c = 0.5 -> 0.5/0.625 = 0.8; G1(1) = 1.
    near(G("schlick_smith(0.25)", "beckmann(0.3)", wi60, kN), 0.8, 1e-15, "schlick_smith 0.8");
    // cook_torrance: min(1, 2 (n.h)(n.wo)/(wo.h), 2 (n.h)(n.wi)/(wo.h)).
    //   wi = wo at 60 deg (h = wi): min(1, 2 cos^2 60) = 0.5.
    near(G("cook_torrance", "ggx(0.3)", wi60, wi60), 0.5, 1e-15, "V-cavity retro 60");
    //   wi 60, wo = n: terms 2 and 1 -> 1.
    near(G("cook_torrance", "ggx(0.3)", wi60, kN), 1, 1e-15, "V-cavity unshadowed");
    //   wi 80, wo 40 (same plane): h at 60, wo.h = cos 20: min(1, cos40/cos20, cos80/cos20) = cos80/cos20.
    near(G("cook_torrance", "blinn_phong(10)", dir(deg(80), 0), dir(deg(40), 0)), 0.18479253090409542, 1e-14,
         "V-cavity cos80/cos20");
    near(G("cook_torrance", "blinn_phong(10)", dir(deg(40), 0), dir(deg(80), 0)), 0.18479253090409542, 1e-14,
         "V-cavity cos80/cos20 swapped");

    // Smith variants, GGX alpha = 1, wi at 45 deg (phi 0), wo at 45 deg (phi 90):
    // Lambda = (sqrt2 - 1)/2 for both, G1 = 2(sqrt2 - 1), azimuth difference pi/2,
    // lambda(pi/2) = 4.41 (pi/2)/(4.41 (pi/2) + 1) = 0.87385224148382468.
    const Vec3<double> a = dir(deg(45), 0), b = dir(deg(45), deg(90)), c = dir(deg(60), deg(90));
    // separable 1/(1+L)^2, height 1/(1+2L) = 1/sqrt2, direction lam G1^2 + (1-lam) G1,
    // height-direction 1/(1 + L + lam L).
    near(G("smith_separable", "ggx(1)", a, b), 0.68629150101523972, 1e-14, "separable 45/45");
    near(G("smith_height_correlated", "ggx(1)", a, b), 0.70710678118654746, 1e-14, "height 45/45");
    near(G("smith_direction_correlated", "ggx(1)", a, b), 0.7042215913541976, 1e-14, "direction 45/45");
    near(G("smith_height_direction_correlated", "ggx(1)", a, b), 0.72041567665391815, 1e-14, "height-dir 45/45");
    // wo at 60 deg instead (Lambda_o = (sqrt(1+3) - 1)/2 = 1/2, G1o = 2/3): exercises min/max.
    near(G("smith_separable", "ggx(1)", a, c), 0.55228474983079345, 1e-14, "separable 45/60");
    near(G("smith_height_correlated", "ggx(1)", a, c), 0.58578643762690497, 1e-14, "height 45/60");
    near(G("smith_direction_correlated", "ggx(1)", a, c), 0.56671377225442243, 1e-14, "direction 45/60");
    near(G("smith_height_direction_correlated", "ggx(1)", a, c), 0.59489081888194129, 1e-14, "height-dir 45/60");
    // Back-facing h (wi.h <= 0) gives G = 0 for the Smith forms.
    Material s = makeMaterial("ndf = ggx(0.3); masking = smith_height_correlated;");
    CHECK(s.G(wi60, kN, dir(deg(50), kPi)) == 0);
}

TEST_CASE("Hand values: Fresnel F(cos)") {
    auto F = [](const std::string& fresnel, double c, int ch = 0) {
        return makeMaterial("ndf = ggx(0.3); fresnel = " + fresnel + ";").F(c, ch);
    };
    CHECK(F("none", 0.3) == 1);
    // schlick: f0 + (1 - f0)(1 - c)^5 at c = 0.5: 0.04 + 0.96/32 = 0.07; 0.5 + 0.5/32 = 0.515625.
    near(F("schlick(rgb(0.04, 0.5, 1))", 0.5, 0), 0.07, 1e-15, "schlick f0 .04");
    near(F("schlick(rgb(0.04, 0.5, 1))", 0.5, 1), 0.515625, 1e-15, "schlick f0 .5");
    near(F("schlick(rgb(0.04, 0.5, 1))", 0.5, 2), 1, 1e-15, "schlick f0 1");
    // schlick(eta): f0 = ((eta-1)/(eta+1))^2 = 0.04 for eta = 1.5; 1 at grazing.
    near(F("schlick(eta = 1.5)", 1), 0.04, 1e-15, "schlick eta 1.5 normal");
    near(F("schlick(eta = 1.5)", 0), 1, 1e-15, "schlick eta 1.5 grazing");
    // dielectric, eta = 1.5: normal incidence ((n-1)/(n+1))^2 = 0.04.
    near(F("dielectric(1.5)", 1), 0.04, 1e-14, "dielectric normal");
    // 45 deg from the Snell-angle forms Rs = sin^2(ti-tt)/sin^2(ti+tt),
    // Rp = tan^2(ti-tt)/tan^2(ti+tt), sin tt = sin ti/n (Python): 0.050239911012235954.
    near(F("dielectric(1.5)", std::cos(deg(45))), 0.050239911012235954, 1e-13, "dielectric 45 deg");
    // Brewster angle tan ti = n: Rp = 0 and Rs = ((n^2-1)/(n^2+1))^2 = (5/13)^2, F = 25/338.
    near(F("dielectric(1.5)", 1 / std::sqrt(1 + 1.5 * 1.5)), 25.0 / 338, 1e-13, "dielectric Brewster");
    // eta < 1: total internal reflection beyond the critical angle asin(1/1.5) = 41.8 deg.
    CHECK(F("dielectric(1/1.5)", 0.5) == 1);  // 60 deg
    CHECK(F("dielectric(1/1.5)", std::cos(deg(45))) == 1);
    near(F("dielectric(1/1.5)", 1), 0.04, 1e-14, "dielectric 1/1.5 normal");  // same as 1.5 at normal
    // eta = 1: no interface, no reflection.
    CHECK(std::abs(F("dielectric(1)", 0.7)) < 1e-16);
    // conductor at normal incidence: ((n-1)^2 + k^2)/((n+1)^2 + k^2); gold-like red channel
    // n = 0.143, k = 3.983: 0.96668751220826976.
    const std::string gold = "conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603))";
    near(F(gold, 1, 0), 0.96668751220826976, 1e-13, "conductor normal");
    // 60 deg from the real-arithmetic conductor formulas (Born & Wolf; pbrt 3 FrConductor):
    // 2a^2 = sqrt((n^2-k^2-s^2)^2 + 4n^2k^2) + (n^2-k^2-s^2), 2b^2 = ... - (...),
    // Rs = (a^2+b^2-2a c+c^2)/(a^2+b^2+2a c+c^2),
    // Rp = Rs (a^2+b^2-2a s t+s^2 t^2)/(a^2+b^2+2a s t+s^2 t^2), s = sin, t = tan.
    near(F(gold, 0.5, 0), 0.96221985142761934, 1e-12, "conductor 60 deg");
    // n = 1.5, k = 1 at 80 deg (same formulas): 0.52467408135743399.
    near(F("conductor(eta = 1.5, k = 1)", std::cos(deg(80))), 0.52467408135743399, 1e-12, "conductor k=1 80 deg");
    // k = 0 is the dielectric: 45 deg value as above.
    near(F("conductor(eta = 1.5, k = 0)", std::cos(deg(45))), 0.050239911012235954, 1e-13, "conductor k=0");
}

TEST_CASE("Hand values: full BRDF f = F G D / (4 n.wi n.wo)") {
    // wi at 60 deg in the xz plane, wo = n: h at 30 deg, wi.h = cos 30, n.wi n.wo = 0.5.
    const Vec3<double> wi = dir(deg(60), 0);
    // GGX 0.5: D = 1/(pi a^2 cos^4 30 (1 + tan^2 30/a^2)^2) = 0.41575168807678786;
    // height-correlated with Lambda_o = 0: G = 1/(1 + (sqrt(1 + 0.25*3) - 1)/2) = 0.86100174808612073;
    // schlick f0 0.04: F = 0.04 + 0.96 (1 - cos 30)^5 = 0.040041436543139373;
    // f = F G D/(4 * 0.5) = 0.0071666749772772431.
    Material g = makeMaterial(
        "input roughness = 0.7071067811865476; let a = roughness * roughness;"
        " ndf = ggx(a); masking = smith_height_correlated; fresnel = schlick(0.04);");
    near(g.brdf(wi, kN)[0], 0.0071666749772772431, 1e-12, "ggx hc schlick");
    // Beckmann 0.3, separable, conductor gold (red): D = exp(-tan^2 30/0.09)/(pi 0.09 cos^4 30),
    // Lambda_i at a = cot 60/0.3, F from the Born & Wolf formulas at 30 deg:
    // f = 0.07481136871238532.
    Material b = makeMaterial(
        "ndf = beckmann(0.3); masking = smith_separable;"
        " fresnel = conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603));");
    near(b.brdf(wi, kN)[0], 0.07481136871238532, 1e-12, "beckmann separable conductor");
    // Lambert base adds albedo/pi; below the horizon everything is 0.
    Material l = makeMaterial("ndf = ggx(0.5); diffuse = lambert(0.5);");
    near(l.brdf(kN, kN)[0], 1.2732395447351628 / 4 + 0.5 / kPi, 1e-14, "ggx at n,n + lambert: D/4 + 0.5/pi");
    CHECK(l.brdf(dir(deg(100), 0), kN)[0] == 0);
}
