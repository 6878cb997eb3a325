// Directional albedo with F = 1 (energy conservation of the single-scattering
// lobe), SPEC section 7 "energy <= 1 with F = 1":
//   A(wo) = Int f(wi, wo) (n.wi) dwi  <=  1
// for every NDF x masking pair the checker accepts, alpha in {0.05, 0.2, 0.5, 1},
// theta_o in {0, 30, 60, 80, 89} deg (and azimuths 0, 45, 90 deg when anisotropic).
//
// The integral is taken over the half vector h instead of wi (dwi =
// 4 (wo.h) dwh), because the lobe is centred on h = n with width alpha
// whatever wo is: theta_h runs on panels graded toward 0, and at each theta_h
// the azimuth covers exactly the h for which wi = 2 (wo.h) h - wo is above
// the horizon, so that cut is an end point of the azimuthal integral:
//   wi.z > 0  <=>  cos(phi_h - phi_o) > -cos(theta_o) cos(2 theta_h) / (sin(theta_o) sin(2 theta_h)).
// The full circle qualifies up to theta_h = (pi/2 - theta_o)/2 and none beyond
// (pi/2 + theta_o)/2; both are square-root kinks of the inner integral and get
// their own graded panels. Doubling every panel count changes no albedo by
// more than 2e-5, and the closed-form cases below agree to < 1e-6.
//
// Which models conserve energy (measured over all theta_o, alpha, NDFs):
//   - Smith variants with GGX and Beckmann: yes, by construction (G <= G1(wo)
//     and the weak white furnace Int G1 D (wo.h)+ = n.wo). Max 1 - 9e-15
//     (beckmann 0.05, theta_o = 30: the whole lobe is above the horizon and
//     unmasked).
//   - Smith variants with the catalog's other NDFs (student_t, epd, abc, sgd
//     at their typical shapes, isotropic; tabulated Lambda): yes. Max
//     1 - 9.5e-11 (epd 0.05 at normal incidence).
//   - cook_torrance (V-cavity, itself a valid masking), implicit, kelemen,
//     neumann: yes, for every NDF. Max 1 - 8e-15.
//   - ward (masking none, its own normalization): yes here. Max 0.99257.
//   - schlick_smith(k = alpha/2) with isotropic GGX, Beckmann, Blinn-Phong,
//     Gaussian and GTR gamma >= 2: yes. Max 0.99987.
//   - none: NO, A ~ 1/(2 cos theta_o) at grazing (max 28.89 at 89 deg).
//   - Smith variants with rough Blinn-Phong: NO, because the SPEC gives
//     Blinn-Phong the Beckmann Lambda, which is only an approximation
//     (an exact Lambda solves the weak furnace; this one does not for small
//     exponents). Max 1.6485 at alpha = 1 (exponent 0), 1.0929 at alpha = 0.5.
//   - schlick_smith(k = alpha/2) with heavy-tailed GTR (gamma <= 1.5) and
//     anisotropic NDFs: NO, Schlick's NDF-independent G1 cannot follow their
//     masking. Max 3.709.
// The non-conserving ones are pinned in their own test cases, not hidden.
#include "PhysicsUtil.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

using namespace physics;

namespace {

const double kAlphas[] = {0.05, 0.2, 0.5, 1.0};
const double kThetaO[] = {0, 30, 60, 80, 89};  // degrees
constexpr double kQuadTol = 1e-3;              // allowance for A <= 1

struct NdfCase {
    std::string family;  // ggx, beckmann, ...
    std::string source;  // ndf statement
    double scale;        // smallest roughness (peak width)
    double k;            // schlick_smith k = alpha/2 (Karis 2013: Schlick fit of Smith-GGX)
    bool anisotropic;
    double gamma = 0;    // gtr only
    bool byHand = true;  // listed below with the forms the test cases name; else from the catalog
};

std::vector<NdfCase> ndfCases() {
    std::vector<NdfCase> out;
    for (double a : kAlphas) {
        out.push_back({"ggx", "ggx(" + num(a) + ")", a, a / 2, false});
        out.push_back({"beckmann", "beckmann(" + num(a) + ")", a, a / 2, false});
        out.push_back({"blinn_phong", "blinn_phong(beckmann_to_phong(" + num(a) + "))", a, a / 2, false});
        for (double g : {1.0, 1.5, 2.0, 3.0})
            out.push_back({"gtr", "gtr(alpha = " + num(a) + ", gamma = " + num(g) + ")", a, a / 2, false, g});
        out.push_back({"gaussian", "gaussian(" + num(a) + ")", a, a / 2, false});
        out.push_back({"ward", "ward(" + num(a) + ")", a, a / 2, false});
    }
    const double pairs[][2] = {{0.05, 0.5}, {0.2, 1.0}};
    for (auto& p : pairs)
        for (const char* ndf : {"ggx", "beckmann", "ward"})
            out.push_back({ndf, std::string(ndf) + "(alpha_x = " + num(p[0]) + ", alpha_y = " + num(p[1]) + ")",
                           std::min(p[0], p[1]), std::sqrt(p[0] * p[1]) / 2, true});
    // Every other NDF of the catalog, isotropic at its typical shape
    // parameters (the entry's argsAtAlpha), so that a new NDF is covered
    // without editing this list.
    std::set<std::string> listed;
    for (const NdfCase& c : out) listed.insert(c.family);
    for (const facet::ModelInfo* m : facet::catalogSlot(facet::ModelSlot::Ndf)) {
        const facet::NdfEntry& ndf = facet::ndfEntry(*m);
        if (listed.count(ndf.name)) continue;
        for (double a : kAlphas)
            out.push_back({ndf.name, callOf(ndf, typicalArgsAtAlpha(ndf, a)), a, a / 2, false, 0, false});
    }
    return out;
}

const std::vector<std::string> kSmith = {"smith_separable", "smith_height_correlated", "smith_direction_correlated",
                                         "smith_height_direction_correlated"};
const std::vector<std::string> kMaskings = {"none", "implicit", "cook_torrance", "kelemen", "neumann",
                                            "schlick_smith", "smith_separable", "smith_height_correlated",
                                            "smith_direction_correlated", "smith_height_direction_correlated"};

std::string maskingSource(const std::string& masking, const NdfCase& c) {
    return masking == "schlick_smith" ? "schlick_smith(" + num(c.k) + ")" : masking;
}

// A(wo) with F = 1 (fresnel defaults to none), by quadrature over h.
double albedo(const Material& m, double scale, bool anisotropic, double thetaO, double phiO) {
    Vec3<double> wo = dir(thetaO, phiO);
    double thetaFull = (kPi / 2 - thetaO) / 2, thetaEnd = (kPi / 2 + thetaO) / 2;
    Hemisphere h;
    h.thetaBreaks = gradedBreaks(0, thetaEnd, {{0, scale / 8}, {thetaFull, 1e-4}, {thetaEnd, 1e-4}}, 0.08);
    h.center = phiO;
    h.phiPanels = anisotropic ? 32 : 8;
    auto hw = [&](double th) {
        return halfWidth(-std::cos(thetaO) * std::cos(2 * th), std::sin(thetaO) * std::sin(2 * th));
    };
    auto f = [&](const Vec3<double>& hv) {
        double oh = dot(wo, hv);
        Vec3<double> wi{2 * oh * hv.x - wo.x, 2 * oh * hv.y - wo.y, 2 * oh * hv.z - wo.z};
        if (wi.z <= 0) return 0.0;  // round-off at the cut
        return m.brdf(wi, wo)[0] * wi.z * 4 * oh;
    };
    return integrateHemisphere(f, hw, h);
}

struct Row {
    NdfCase ndf;
    std::string masking;
    double thetaO, phiO;  // degrees
    double a;
};

// The albedo of every accepted NDF x masking pair at every wo, computed once
// (in parallel: the integrals are independent and the resolved materials are
// plain values) and shared by the test cases below.
const std::vector<Row>& table() {
    static const std::vector<Row> rows = [] {
        std::vector<Row> out;
        std::vector<Material> mats;
        for (const NdfCase& c : ndfCases())
            for (const std::string& mk : kMaskings) {
                std::string body = "ndf = " + c.source + "; masking = " + maskingSource(mk, c) + ";";
                if (!checkerAccepts(body)) continue;
                Material m = makeMaterial(body);
                std::vector<double> phis = c.anisotropic ? std::vector<double>{0, 45, 90} : std::vector<double>{0};
                for (double to : kThetaO)
                    for (double po : phis) {
                        if (to == 0 && po != 0) continue;
                        out.push_back({c, mk, to, po, 0});
                        mats.push_back(m);
                    }
            }
        unsigned nt = std::clamp(std::thread::hardware_concurrency(), 1u, 8u);
        std::vector<std::thread> pool;
        for (unsigned t = 0; t < nt; ++t)
            pool.emplace_back([&, t] {
                for (size_t i = t; i < out.size(); i += nt)
                    out[i].a = albedo(mats[i], out[i].ndf.scale, out[i].ndf.anisotropic, deg(out[i].thetaO),
                                      deg(out[i].phiO));
            });
        for (auto& th : pool) th.join();
        return out;
    }();
    return rows;
}

std::string where(const Row& r) {
    return r.ndf.source + " masking=" + r.masking + " theta_o=" + num(r.thetaO) + " phi_o=" + num(r.phiO);
}

// Looks up one measured albedo.
double lookup(const std::string& source, const std::string& masking, double thetaO, double phiO = 0) {
    for (const Row& r : table())
        if (r.ndf.source == source && r.masking == masking && r.thetaO == thetaO && r.phiO == phiO) return r.a;
    FAIL("no albedo row for ", source, " ", masking, " ", thetaO);
    return 0;
}

// Checks A <= 1 + kQuadTol for every row that `select` picks; reports the maximum.
template <typename Select>
void checkConserving(const char* what, const Select& select) {
    double maxA = 0, minA = 1e300;
    std::string at;
    int n = 0;
    for (const Row& r : table()) {
        if (!select(r)) continue;
        ++n;
        INFO(where(r), " albedo = ", r.a);
        CHECK(r.a <= 1 + kQuadTol);
        CHECK(r.a > 0);
        if (r.a > maxA) {
            maxA = r.a;
            at = where(r);
        }
        minA = std::min(minA, r.a);
    }
    CHECK(n > 0);
    char buf[96];
    std::snprintf(buf, sizeof buf, "max %.10f (1 %+.2e), min %.10f", maxA, maxA - 1, minA);
    MESSAGE(std::string(what), ": ", n, " albedos, ", std::string(buf), " (max at ", at, ")");
}

bool isSmith(const std::string& mk) { return std::find(kSmith.begin(), kSmith.end(), mk) != kSmith.end(); }
bool roughBlinnPhong(const NdfCase& c) { return c.family == "blinn_phong" && c.scale > 0.2; }
bool schlickFails(const NdfCase& c) { return c.anisotropic || (c.family == "gtr" && c.gamma <= 1.5); }

}  // namespace

// The albedo table enumerates the pairs the checker accepts; make sure that
// set is the intended one (SPEC section 3: Smith masking needs the NDF's
// Lambda, closed-form or tabulated, which every NDF here has, gtr up to a
// constant gamma of 10; ward is a whole lobe and takes masking none only),
// so that a checker change cannot silently drop pairs from the energy checks.
TEST_CASE("Albedo: the checker accepts exactly the intended NDF x masking pairs") {
    for (const char* ndf : {"ggx(0.3)", "beckmann(0.3)", "blinn_phong(20)", "gtr(alpha = 0.3, gamma = 1.5)",
                            "gtr(alpha = 0.3, gamma = 3)", "gaussian(0.3)", "ward(0.3)"}) {
        std::string n = ndf;
        bool ward = n.rfind("ward", 0) == 0;
        for (const std::string& mk : kMaskings) {
            bool expected = !ward || mk == "none";
            std::string body = "ndf = " + n + "; masking = " + (mk == "schlick_smith" ? "schlick_smith(0.1)" : mk) + ";";
            INFO(body);
            CHECK(checkerAccepts(body) == expected);
        }
    }
    CHECK_FALSE(checkerAccepts("ndf = gtr(alpha = 0.3, gamma = 11); masking = smith_separable;"));
    // 36 NDF cases x 10 maskings + 6 ward x 1; every other NDF of the
    // catalog takes every masking.
    std::set<std::pair<std::string, std::string>> listed, others;
    std::set<std::string> otherSources;
    for (const Row& r : table()) {
        (r.ndf.byHand ? listed : others).insert({r.ndf.source, r.masking});
        if (!r.ndf.byHand) otherSources.insert(r.ndf.source);
    }
    CHECK(listed.size() == 36 * 10 + 6);
    CHECK(otherSources.size() >= 4 * std::size(kAlphas));  // student_t, epd, abc, sgd
    CHECK(others.size() == otherSources.size() * kMaskings.size());
}

TEST_CASE("Albedo <= 1 (F = 1): Smith maskings with GGX and Beckmann, iso and aniso") {
    checkConserving("smith x {ggx, beckmann}", [](const Row& r) {
        return isSmith(r.masking) && (r.ndf.family == "ggx" || r.ndf.family == "beckmann");
    });
}

TEST_CASE("Albedo <= 1 (F = 1): Smith maskings with GTR and Gaussian (tabulated Lambda)") {
    checkConserving("smith x {gtr (gamma <= 3), gaussian}", [](const Row& r) {
        return isSmith(r.masking) && (r.ndf.family == "gtr" || r.ndf.family == "gaussian");
    });
}

TEST_CASE("Albedo <= 1 (F = 1): Smith maskings with the other NDFs of the catalog (exact tabulated Lambda)") {
    checkConserving("smith x {student_t, epd, abc, sgd, ...}",
                    [](const Row& r) { return isSmith(r.masking) && !r.ndf.byHand; });
}

TEST_CASE("Albedo <= 1 (F = 1): Smith maskings with Blinn-Phong for exponent >= 48 (alpha <= 0.2)") {
    checkConserving("smith x blinn_phong(alpha <= 0.2)", [](const Row& r) {
        return isSmith(r.masking) && r.ndf.family == "blinn_phong" && !roughBlinnPhong(r.ndf);
    });
}

TEST_CASE("Albedo <= 1 (F = 1): cook_torrance, implicit, kelemen, neumann with every NDF") {
    checkConserving("{cook_torrance, implicit, kelemen, neumann} x all", [](const Row& r) {
        return r.masking == "cook_torrance" || r.masking == "implicit" || r.masking == "kelemen" ||
               r.masking == "neumann";
    });
}

TEST_CASE("Albedo <= 1 (F = 1): ward (whole lobe, masking none), iso and aniso") {
    checkConserving("ward", [](const Row& r) { return r.ndf.family == "ward"; });
}

TEST_CASE("Albedo <= 1 (F = 1): schlick_smith(alpha/2) with isotropic GGX, Beckmann, Blinn-Phong, Gaussian, GTR gamma >= 2") {
    checkConserving("schlick_smith (conserving set)",
                    [](const Row& r) {
                        return r.masking == "schlick_smith" && r.ndf.byHand && !schlickFails(r.ndf);
                    });
}

// The uniform distribution D = 1/pi (GGX alpha = 1, GTR alpha = 1 for any
// gamma, Blinn-Phong exponent 0) makes the albedo integral one-dimensional in
// wi (dwi = 2 pi dmu for integrands of mu alone), giving closed forms that pin
// both the interpreter and this quadrature (mu_o = cos theta_o):
//   none:            A = (1/(4 pi mu_o)) Int dwi = 1/(2 mu_o)
//   implicit:        A = (1/(4 pi)) Int mu dwi = 1/4
//   neumann:         A = (1/(2 mu_o)) Int_0^1 min(mu, mu_o) dmu = (1 - mu_o/2)/2
//   smith_separable (G1 = 2mu/(1+mu) for GGX alpha = 1):
//                    A = 2 (1 - ln 2)/(1 + mu_o)
//   smith_height_correlated (G = 2 mu mu_o/(mu + mu_o)):
//                    A = 1 - mu_o ln((1 + mu_o)/mu_o)
//   schlick_smith(0.5) has G1 = 2mu/(1+mu), the exact GGX alpha = 1 G1, so it
//   equals smith_separable; kelemen at mu_o = 1 has G = mu/cos^2(theta_i/2) =
//   2mu/(1+mu) as well: both 1 - ln 2 = 0.30685 at normal incidence.
TEST_CASE("Albedo closed forms for the uniform distribution (GGX alpha = 1)") {
    for (double to : kThetaO) {
        double mu = std::cos(deg(to));
        INFO("theta_o = ", to);
        CHECK(std::abs(lookup("ggx(1)", "none", to) - 1 / (2 * mu)) < 1e-6 / mu);
        CHECK(std::abs(lookup("ggx(1)", "implicit", to) - 0.25) < 1e-6);
        // neumann's G = min(n.wi, n.wo) has a kink along n.wi = n.wo inside
        // the domain, which costs the quadrature up to ~1e-5.
        CHECK(std::abs(lookup("ggx(1)", "neumann", to) - (1 - mu / 2) / 2) < 2e-5);
        CHECK(std::abs(lookup("ggx(1)", "smith_separable", to) - 2 * (1 - std::log(2.0)) / (1 + mu)) < 1e-6);
        CHECK(std::abs(lookup("ggx(1)", "schlick_smith", to) - 2 * (1 - std::log(2.0)) / (1 + mu)) < 1e-6);
        CHECK(std::abs(lookup("ggx(1)", "smith_height_correlated", to) - (1 - mu * std::log((1 + mu) / mu))) < 1e-6);
        for (double g : {1.0, 1.5, 2.0, 3.0})
            CHECK(std::abs(lookup("gtr(alpha = 1, gamma = " + num(g) + ")", "none", to) - 1 / (2 * mu)) < 1e-6 / mu);
        CHECK(std::abs(lookup("blinn_phong(beckmann_to_phong(1))", "implicit", to) - 0.25) < 1e-6);
    }
    CHECK(std::abs(lookup("ggx(1)", "kelemen", 0) - (1 - std::log(2.0))) < 1e-6);
}

// masking = none drops shadowing entirely, so the 1/(4 n.wi n.wo) of the
// microfacet BRDF is not compensated: A grows like 1/cos(theta_o). This is the
// physics of G = 1, not a bug. Measured: 28.65 for the uniform distribution at
// 89 deg (= 1/(2 cos 89 deg), see above), 28.89 for ggx(0.2, 1) at 89 deg,
// phi_o = 90 deg; every rough NDF exceeds 1 from theta_o = 60-80 deg on.
TEST_CASE("Albedo EXCEEDS 1 with masking = none (no shadowing: A ~ 1/(2 cos theta_o))") {
    double maxA = 0;
    std::string at;
    for (const Row& r : table())
        if (r.masking == "none" && r.ndf.family != "ward" && r.ndf.byHand && r.a > maxA) {
            maxA = r.a;
            at = where(r);
        }
    MESSAGE("masking none: max albedo ", maxA, " at ", at);
    CHECK(std::abs(maxA - 28.888181298) < 1e-4);
    CHECK(at == "ggx(alpha_x = 0.20000000000000001, alpha_y = 1) masking=none theta_o=89 phi_o=90");
    // At normal incidence the lobe loses only what falls below the horizon, so none is still <= 1 there.
    for (const Row& r : table())
        if (r.masking == "none" && r.thetaO == 0) CHECK(r.a <= 1 + kQuadTol);
    // Every NDF exceeds 1 at 89 deg for alpha = 1.
    for (const char* src : {"ggx(1)", "beckmann(1)", "blinn_phong(beckmann_to_phong(1))", "gaussian(1)"})
        CHECK(lookup(src, "none", 89) > 10);
}

// Blinn-Phong with Smith masking uses the Beckmann Lambda at
// alpha = sqrt(2/(e+2)) (SPEC section 3, after Walter et al. 2007). That
// Lambda solves the weak white furnace only for Beckmann; for Blinn-Phong it
// is an approximation that is good for large exponents and poor for small
// ones. For e = 0 the NDF is uniform, whose exact Lambda is GGX alpha = 1's
// (1/mu - 1)/2, much larger at grazing than the Beckmann alpha = 1 Lambda: G1
// is overestimated and energy is created. Measured maxima (theta_o = 89 deg):
//   alpha = 1 (e = 0):  separable 1.30398, height 1.63726, direction 1.38192, height-direction 1.64851
//   alpha = 0.5 (e = 6): separable 1.05604, height 1.09238, direction 1.05913, height-direction 1.09288
// For e = 0 the separable and height-correlated values are one-dimensional
// integrals, computed independently in Python (Simpson, 2e5 intervals, math.erfc):
//   separable:  A = G1(mu_o)/(2 mu_o) Int_0^1 G1(mu) dmu, Int_0^1 G1 = 0.7585588844289969
//   height:     A = (1/(2 mu_o)) Int_0^1 dmu / (1 + Lambda(mu) + Lambda(mu_o))
//   theta_o = 80: 1.01621878763108, 1.1164275589211616; 89: 1.30397537102347, 1.637263932888943.
TEST_CASE("Albedo EXCEEDS 1 for Smith masking with rough Blinn-Phong (Beckmann Lambda is approximate)") {
    const std::string bp1 = "blinn_phong(beckmann_to_phong(1))", bp05 = "blinn_phong(beckmann_to_phong(0.5))";
    CHECK(std::abs(lookup(bp1, "smith_separable", 80) - 1.01621878763108) < 1e-6);
    CHECK(std::abs(lookup(bp1, "smith_height_correlated", 80) - 1.1164275589211616) < 1e-6);
    CHECK(std::abs(lookup(bp1, "smith_separable", 89) - 1.30397537102347) < 1e-6);
    CHECK(std::abs(lookup(bp1, "smith_height_correlated", 89) - 1.637263932888943) < 1e-6);
    // Pinned measurements (quadrature error < 2e-5).
    CHECK(std::abs(lookup(bp1, "smith_direction_correlated", 89) - 1.38192) < 1e-4);
    CHECK(std::abs(lookup(bp1, "smith_height_direction_correlated", 89) - 1.64851) < 1e-4);
    CHECK(std::abs(lookup(bp05, "smith_separable", 89) - 1.05604) < 1e-4);
    CHECK(std::abs(lookup(bp05, "smith_height_correlated", 89) - 1.09238) < 1e-4);
    CHECK(std::abs(lookup(bp05, "smith_direction_correlated", 89) - 1.05913) < 1e-4);
    CHECK(std::abs(lookup(bp05, "smith_height_direction_correlated", 89) - 1.09288) < 1e-4);
    double maxA = 0;
    for (const Row& r : table())
        if (isSmith(r.masking) && roughBlinnPhong(r.ndf)) maxA = std::max(maxA, r.a);
    MESSAGE("smith x blinn_phong(alpha >= 0.5): max albedo ", maxA);
    CHECK(std::abs(maxA - 1.64851) < 1e-4);
}

// schlick_smith's G1(v) = (n.v)/((n.v)(1-k)+k) ignores the NDF: with k =
// alpha/2 it tracks Smith-GGX for isotropic lobes, but it under-masks at
// grazing angles the heavy-tailed GTR (gamma = 1, 1.5: D ~ 1/theta^2 tails
// that a Smith Lambda would mask strongly) and anisotropic lobes viewed along
// their rough axis (k is fixed from sqrt(ax ay)). Measured maxima, theta_o = 89:
//   gtr(0.05, 1) 3.70929, gtr(0.2, 1) 1.88594, gtr(0.5, 1) 1.03881, gtr(0.05, 1.5) 1.41354,
//   ggx(0.05, 0.5) 2.51752 (phi_o = 90), beckmann(0.05, 0.5) 1.47845 (phi_o = 90).
TEST_CASE("Albedo EXCEEDS 1 for schlick_smith(alpha/2) with heavy-tailed GTR and anisotropic NDFs") {
    auto a = [](const std::string& src, double phi = 0) { return lookup(src, "schlick_smith", 89, phi); };
    CHECK(std::abs(a("gtr(alpha = 0.050000000000000003, gamma = 1)") - 3.70929) < 1e-4);
    CHECK(std::abs(a("gtr(alpha = 0.20000000000000001, gamma = 1)") - 1.88594) < 1e-4);
    CHECK(std::abs(a("gtr(alpha = 0.5, gamma = 1)") - 1.03881) < 1e-4);
    CHECK(std::abs(a("gtr(alpha = 0.050000000000000003, gamma = 1.5)") - 1.41354) < 1e-4);
    CHECK(std::abs(a("ggx(alpha_x = 0.050000000000000003, alpha_y = 0.5)", 90) - 2.51752) < 1e-4);
    CHECK(std::abs(a("beckmann(alpha_x = 0.050000000000000003, alpha_y = 0.5)", 90) - 1.47845) < 1e-4);
    double maxA = 0;
    for (const Row& r : table())
        if (r.masking == "schlick_smith" && schlickFails(r.ndf)) maxA = std::max(maxA, r.a);
    MESSAGE("schlick_smith x {gtr gamma <= 1.5, anisotropic}: max albedo ", maxA);
    CHECK(std::abs(maxA - 3.70929) < 1e-4);
}
