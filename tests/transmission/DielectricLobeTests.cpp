// The reference of the lobes that scatter over the whole sphere (SPEC 11,
// compiler/reference/DielectricLobe.h) against what they must equal and
// conserve:
// - Walter et al. 2007's f_t and f_r, written out here with absolute
//   indices and std::beta for the height-correlated masking (independently
//   of the reference's wo-frame form);
// - generalized reciprocity f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2 over
//   random pairs on the whole sphere, radiance and importance transport;
// - the transmission masking: the single-scattering share of the random
//   walk on the dielectric microsurface (MicrosurfaceWalk.h) that leaves
//   through the surface equals Int f_t |n.wi| dwi (importance transport) with
//   Heitz's Beta-function form; pbrt-v4's 1 / (1 + Li + Lo) must fail it;
// - energy: Int f |n.wi| dwi <= 1 from both sides, near 1 for small alpha;
// - the sampler: chi-square over the whole sphere against the pdf, weight =
//   f |n.wi| / pdf, and a pdf without the refraction's Jacobian must fail;
// - no NaN, Inf or negative value at the critical angle, wi = -wo, grazing on
//   either side, eta near 1 and large; double within 1e-9 of __float128.
#include "QuadMath.h"
#include "ChiSquare.h"
#include "Checker.h"
#include "DielectricLobe.h"
#include "Interpreter.h"
#include "HardCases.h"
#include "Kernel.h"
#include "MicrosurfaceWalk.h"
#include "SamplingCheck.h"
#include "Specialize.h"
#include "Sampling.h"
#include "TransmissionSupport.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

using namespace transmission_test;

namespace {

// ---- Walter et al. 2007 with absolute indices, for GGX ----------------------

double ggxD(const V3& m, double a) {
    if (m.z <= 0) return 0;
    double t2 = (m.x * m.x + m.y * m.y) / (m.z * m.z), c4 = m.z * m.z * m.z * m.z;
    double k = a * a + t2;
    return a * a / (kPi * c4 * k * k);
}

double ggxLambda(const V3& v, double a) {
    double c = std::abs(v.z), t2 = (1 - c * c) / (c * c);
    return (std::sqrt(1 + a * a * t2) - 1) / 2;
}

// Unpolarized Fresnel from the s and p amplitudes, light on the side of
// index n1 at cos c toward the side n2.
double fresnel(double c, double n1, double n2) {
    double s2t = n1 * n1 / (n2 * n2) * (1 - c * c);
    if (s2t >= 1) return 1;
    double ct = std::sqrt(1 - s2t);
    double rs = (n1 * c - n2 * ct) / (n1 * c + n2 * ct), rp = (n2 * c - n1 * ct) / (n2 * c + n1 * ct);
    return (rs * rs + rp * rp) / 2;
}

// Its transmittance from the amplitude transmission coefficients, T =
// (n2 ct / n1 c) (ts^2 + tp^2) / 2 (not 1 - F: exact where F nears 1).
double transmittance(double c, double n1, double n2) {
    double s2t = n1 * n1 / (n2 * n2) * (1 - c * c);
    if (s2t >= 1) return 0;
    double ct = std::sqrt(1 - s2t);
    double ts = 2 * n1 * c / (n1 * c + n2 * ct), tp = 2 * n1 * c / (n2 * c + n1 * ct);
    return n2 * ct / (n1 * c) * (ts * ts + tp * tp) / 2;
}

enum class Masking { HeightCorrelatedBeta, Pbrt, Separable };

// f(wi, wo) of a GGX dielectric interface, radiance transport.
double walterGgx(const V3& wi, const V3& wo, double a, double eta, Masking masking) {
    double ni = wi.z > 0 ? 1 : eta, no = wo.z > 0 ? 1 : eta;
    double li = ggxLambda(wi, a), lo = ggxLambda(wo, a);
    double G = masking == Masking::Separable ? 1 / ((1 + li) * (1 + lo))
               : masking == Masking::Pbrt    ? 1 / (1 + li + lo)
                                             : 0;
    if (wi.z * wo.z > 0) {  // reflection on either side
        V3 h{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
        double len = std::sqrt(dot(h, h));
        h = {h.x / len, h.y / len, h.z / len};
        if (h.z < 0) h = {-h.x, -h.y, -h.z};
        if (masking == Masking::HeightCorrelatedBeta) G = 1 / (1 + li + lo);
        double c = std::abs(dot(wo, h));
        return fresnel(c, no, no == 1 ? eta : 1) * ggxD(h, a) * G / (4 * std::abs(wi.z * wo.z));
    }
    V3 ht{-(ni * wi.x + no * wo.x), -(ni * wi.y + no * wo.y), -(ni * wi.z + no * wo.z)};
    double len = std::sqrt(dot(ht, ht));
    ht = {ht.x / len, ht.y / len, ht.z / len};
    if (ht.z < 0) ht = {-ht.x, -ht.y, -ht.z};
    double ih = dot(wi, ht), oh = dot(wo, ht);
    if (ih * wi.z <= 0 || oh * wo.z <= 0) return 0;
    if (masking == Masking::HeightCorrelatedBeta) G = std::beta(1 + li, 1 + lo);
    double outsideCos = wo.z > 0 ? oh : ih;
    double T = transmittance(outsideCos, 1, eta);
    double denom = ni * ih + no * oh;
    return std::abs(ih * oh / (wi.z * wo.z)) * no * no * T * G * ggxD(ht, a) / (denom * denom);
}

}  // namespace

TEST_SUITE("dielectric lobe") {

TEST_CASE("f is Walter et al.'s f_r and f_t with Heitz's transmission masking, on both sides") {
    std::mt19937_64 rng(3);
    for (double eta : {1.05, 1.5, 2.4, 1 / 1.5}) {
        for (double alpha : {0.1, 0.4, 0.9}) {
            Reference hc(glass(fmt::format("ggx({})", alpha), eta));
            Reference sep(glass(fmt::format("ggx({})", alpha), eta, "smith_separable"));
            int transmitted = 0, reflected = 0;
            std::uniform_real_distribution<double> uniform(0, 1);
            for (int k = 0; k < 400; ++k) {
                V3 wo = uniformSphere(rng), wi = uniformSphere(rng);
                if (k % 2) {  // half the pairs from the sampler: the narrow lobes are hit too
                    facet::SampleResult<double> s =
                        facet::sampleDielectricLobe(hc.lobe, wo, {uniform(rng), uniform(rng), uniform(rng)});
                    if (s.pdf > 0) wi = s.wi;
                }
                double want = walterGgx(wi, wo, alpha, eta, Masking::HeightCorrelatedBeta);
                double got = hc.f(wi, wo);
                INFO("eta ", eta, " alpha ", alpha, " wi ", wi.x, " ", wi.y, " ", wi.z, " wo ", wo.x, " ", wo.y, " ",
                     wo.z);
                // 1e-9: where the outside direction nears the critical angle
                // (eta < 1), T's square-root edge amplifies the roundings of m.
                CHECK(relDiff(got, want) <= 1e-9);
                CHECK(relDiff(sep.f(wi, wo), walterGgx(wi, wo, alpha, eta, Masking::Separable)) <= 1e-9);
                if (want > 0) (wi.z * wo.z < 0 ? transmitted : reflected)++;
            }
            CHECK(transmitted > 50);
            CHECK(reflected > 50);
        }
    }
}

TEST_CASE("pbrt-v4's f up to its transmission masking: the same f_r, f_t in the ratio of the two G") {
    // pbrt-v4's DielectricBxDF::f (radiance mode) takes G = 1 / (1 + Li + Lo)
    // for transmission too; Facet's height-correlated form there is
    // B(1 + Li, 1 + Lo). With that one factor divided out they agree.
    std::mt19937_64 rng(5);
    const double alpha = 0.35, eta = 1.5;
    Reference ref(glass("ggx(0.35)", eta));
    for (int k = 0; k < 1000; ++k) {
        V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
        double pbrt = walterGgx(wi, wo, alpha, eta, Masking::Pbrt);
        double ratio = 1;
        if (wi.z * wo.z < 0) {
            double li = ggxLambda(wi, alpha), lo = ggxLambda(wo, alpha);
            ratio = std::beta(1 + li, 1 + lo) * (1 + li + lo);
        }
        CHECK(relDiff(ref.f(wi, wo), pbrt * ratio) <= 1e-11);
    }
}

TEST_CASE("generalized reciprocity over the whole sphere, radiance and importance") {
    std::mt19937_64 rng(11);
    for (const char* ndf : {"ggx(0.3)", "beckmann(0.5)", "ggx(alpha_x = 0.2, alpha_y = 0.7)", "gtr(0.4, 1.5)"})
        for (const char* masking : {"smith_separable", "smith_height_correlated", "smith_direction_correlated",
                                    "smith_height_direction_correlated"})
            for (double eta : {1.05, 1.5, 2.4, 1 / 1.05, 1 / 1.5, 1 / 2.4})
                for (auto transport : {facet::Transport::Radiance, facet::Transport::Importance}) {
                    Reference ref(glass(ndf, eta, masking), transport);
                    int nonzero = 0;
                    for (int k = 0; k < 60; ++k) {
                        V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
                        double ni = wi.z > 0 ? 1 : eta, no = wo.z > 0 ? 1 : eta;
                        // Radiance: f(wi, wo) / no^2 = f(wo, wi) / ni^2; importance the other way.
                        double a = ref.f(wi, wo), b = ref.f(wo, wi);
                        double left = transport == facet::Transport::Radiance ? a / (no * no) : a / (ni * ni);
                        double right = transport == facet::Transport::Radiance ? b / (ni * ni) : b / (no * no);
                        INFO(std::string(ndf), " ", std::string(masking), " eta ", eta);
                        CHECK(relDiff(left, right) <= 1e-8);  // the two directions' roundings in m
                        nonzero += a > 0;
                    }
                    CHECK(nonzero > 10);
                }
}

namespace {

// The shares of `walks` walks from wo (above) that leave after one event:
// through the surface, and back above it.
struct SingleScattering {
    double transmitted = 0, reflected = 0;
};
SingleScattering walkOnce(const facet::MicrosurfaceWalk& walk, const V3& wo, int64_t walks, uint64_t seed) {
    int64_t through = 0, back = 0;
    for (int64_t k = 0; k < walks; ++k) {
        facet::WalkRandom random(seed, uint64_t(k));
        facet::WalkSample s = walk.sample(wo, random);
        if (s.order != 1) continue;
        through += s.transmitted;
        back += !s.transmitted && s.weight[0] > 0;
    }
    return {double(through) / double(walks), double(back) / double(walks)};
}

}  // namespace

TEST_CASE("the walk's single transmission is Heitz's Beta-function masking, not 1 / (1 + Li + Lo)") {
    // The walk on the dielectric microsurface (MicrosurfaceWalk, a particle
    // from wo) leaves through the surface after one event with probability
    // Int f_t(wi, wo) |n.wi| dwi in importance transport.
    const double alpha = 0.8, eta = 1.5;
    Reference ref(glass("ggx(0.8)", eta), facet::Transport::Importance);
    facet::MicrosurfaceWalk walk(ref.lobe);
    for (double theta : {30.0, 70.0}) {
        V3 wo = direction(theta, 0.4);
        const int64_t walks = 1000000;
        double p = walkOnce(walk, wo, walks, 17).transmitted, se = std::sqrt(p * (1 - p) / double(walks));
        double beta = integrate([&](const V3& wi) { return wi.z < 0 ? ref.f(wi, wo) * -wi.z : 0.0; });
        facet::PdfFunction pbrtForm = [&](const V3& wi) {
            if (wi.z >= 0) return 0.0;
            double li = ggxLambda(wi, alpha), lo = ggxLambda(wo, alpha);
            return ref.f(wi, wo) * -wi.z / (std::beta(1 + li, 1 + lo) * (1 + li + lo));
        };
        double pbrt = integrate(pbrtForm);
        MESSAGE(fmt::format("theta_o {}: walk {:.5f} +- {:.5f}, Beta form {:.5f}, 1/(1+Li+Lo) {:.5f}", theta, p, se,
                            beta, pbrt));
        CHECK(std::abs(p - beta) <= 4 * se + 1e-4);
        CHECK(std::abs(p - pbrt) > 10 * se);
    }
}

TEST_CASE("energy from both sides: Int f |n.wi| dwi is the walk's single scattering, <= 1, near 1 when smooth") {
    // Importance transport: E(wo) = Int f(wi, wo) |n.wi| dwi is the share of
    // a particle arriving along -wo that leaves after one event, which the
    // walk on the dielectric microsurface counts. From inside, the walk runs
    // from above on the interface of index 1/eta (the same boundary seen
    // from the other side).
    for (double eta : {1.05, 1.5, 2.4}) {
        for (double alpha : {0.05, 0.3, 0.8}) {
            std::string ndf = fmt::format("ggx({})", alpha);
            Reference ref(glass(ndf, eta), facet::Transport::Importance);
            for (double side : {1.0, -1.0}) {
                Reference seenFrom(glass(ndf, side > 0 ? eta : 1 / eta));
                facet::MicrosurfaceWalk walk(seenFrom.lobe);
                for (double theta : {0.0, 45.0, 80.0}) {
                    V3 wo = direction(theta, 0.3);
                    const int64_t walks = 100000;
                    SingleScattering once = walkOnce(walk, wo, walks, 41);
                    double p = once.transmitted + once.reflected, se = std::sqrt(p * (1 - p) / double(walks));
                    V3 view{wo.x, wo.y, wo.z * side};
                    double e = integrate([&](const V3& wi) { return ref.f(wi, view) * std::abs(wi.z); },
                                         alpha < 0.1 ? 64 : 32, alpha < 0.1 ? 128 : 64);
                    INFO("eta ", eta, " alpha ", alpha, " theta ", theta, " side ", side, ": E = ", e, ", walk ", p,
                         " +- ", se);
                    CHECK(std::abs(e - p) <= 4 * se + 3e-4);
                    CHECK(e <= 1 + 1e-4);
                    if (alpha < 0.1 && theta < 60) CHECK(e >= 0.99);
                }
            }
        }
    }
}

TEST_CASE("sampling: chi-square over the whole sphere, weight = f |n.wi| / pdf, and a wrong Jacobian fails") {
    using namespace sampling_test;
    int configs = 0;
    const int tests = 2 * 2 * 6 * 2 * 2;
    CheckSettings settings;
    settings.samples = 100000;  // (the long tier's sweep runs every Smith form and NDF)
    settings.level = facet::sidakLevel(0.01, tests);
    std::mt19937_64 rng(23);
    for (const char* ndf : {"ggx", "beckmann"})
        for (double alpha : {0.1, 0.6})
            for (double eta : {1.05, 1.5, 2.4, 1 / 1.05, 1 / 1.5, 1 / 2.4})
                for (const char* masking : {"smith_separable", "smith_height_correlated"})
                    for (double side : {1.0, -1.0}) {
                        Reference ref(glass(fmt::format("{}({})", ndf, alpha), eta, masking));
                        V3 wo = direction(alpha > 0.5 ? 70 : 35, 0.8);
                        wo.z *= side;
                        facet::SphereGrid grid = transmissionGrid(wo, alpha, eta);
                        auto sampler = [&](const std::array<double, 3>& u) {
                            return facet::sampleDielectricLobe(ref.lobe, wo, u);
                        };
                        facet::PdfFunction pdf = [&](const V3& wi) { return facet::dielectricLobePdf(ref.lobe, wi, wo); };
                        CheckOutcome out = checkSampler(sampler, pdf, grid, settings);
                        std::string what = fmt::format("{}({}) {} eta {:.4f} wo.z {:.3f}: {}", ndf, alpha, masking,
                                                       eta, wo.z, out.describe());
                        INFO(what);
                        CHECK(out.chi2.failure == "");
                        // The density integrates to what the sampler returns a direction for.
                        double drawn = 1 - double(out.noSample) / settings.samples;
                        CHECK(std::abs(out.integral - drawn) <= 4 * std::sqrt(drawn * (1 - drawn) / settings.samples) + 1e-4);
                        CHECK(out.integral >= 0.8);  // rough and grazing: many reflections fall past the horizon
                        // A pdf whose refraction lacks the eta'^2 of dm/dwi.
                        if (eta == 1.5 || eta == 1 / 1.5) {
                            double relative = wo.z > 0 ? eta : 1 / eta;
                            facet::PdfFunction wrong = [&](const V3& wi) {
                                double p = facet::dielectricLobePdf(ref.lobe, wi, wo);
                                return wi.z * wo.z < 0 ? p / (relative * relative) : p;
                            };
                            CheckSettings shape = settings;
                            shape.renormalize = true;  // the shape alone, not only the normalization
                            CHECK(checkSampler(sampler, wrong, grid, shape).chi2.failure != "");
                        }
                        // weight = f |n.wi| / pdf, and pdf() finds the sample's density.
                        std::uniform_real_distribution<double> uniform(0, 1);
                        for (int k = 0; k < 50; ++k) {
                            std::array<double, 3> u{uniform(rng), uniform(rng), uniform(rng)};
                            facet::SampleResult<double> s = sampler(u);
                            if (!(s.pdf > 0)) continue;
                            double f = ref.f(s.wi, wo);
                            CHECK(relDiff(s.weight[0], f * std::abs(s.wi.z) / s.pdf) <= 1e-9);
                            CHECK(relDiff(s.pdf, facet::dielectricLobePdf(ref.lobe, s.wi, wo)) <= 1e-7);
                        }
                        ++configs;
                    }
    CHECK(configs == tests);
}

TEST_CASE("hard cases: critical angle, wi = -wo, grazing on both sides, eta near 1 and large") {
    // Every value finite and >= 0 in float, double and __float128; double
    // within 1e-9 of __float128 (relative, where the value is not far below
    // the smallest normal double).
    std::vector<std::pair<V3, V3>> pairs;
    auto add = [&](V3 wi, V3 wo) { pairs.push_back({wi, wo}), pairs.push_back({wo, wi}); };
    for (double eta : {1.5, 2.4}) {
        double critical = std::asin(1 / eta);
        for (double d : {-1e-12, 0.0, 1e-12, 1e-6}) {
            V3 inside = direction(180 - (critical + d) * 180 / kPi, 0.2);  // wo inside at the critical angle
            add(direction(89.9999, 0.2 + kPi), inside);
            add(direction(60, 0.2 + kPi), inside);
            add({-inside.x, -inside.y, inside.z}, inside);  // its mirror, inside
        }
    }
    for (double theta : {0.0, 30.0, 89.0, 89.999999}) {
        V3 wo = direction(theta, 1.1);
        add({-wo.x, -wo.y, -wo.z}, wo);  // straight through
        V3 near = direction(180 - theta - 1e-7, 1.1 + kPi);
        add(near, wo);
        add({wo.x, wo.y, -wo.z}, wo);  // mirrored through the surface
    }
    for (double z : {1e-7, 1e-15, 1e-300}) {
        double r = std::sqrt(1 - z * z);
        add({r, 0, z}, {0.3, 0.1, -std::sqrt(1 - 0.1)});
        add({r, 0, -z}, {0.3, 0.1, std::sqrt(1 - 0.1)});
        add({r, 0, -z}, {-r, 0, z});
        add({r, 0, z}, {-r, 0, -z});
    }
    int compared = 0;
    for (const char* ndf : {"ggx(0.0001)", "ggx(0.01)", "ggx(0.3)", "beckmann(0.3)", "ggx(1)"})
        for (double eta : {1.0005, 1.001, 1.05, 1.5, 2.4, 3.0, 10.0, 1 / 1.5, 0.9995})
            for (const char* masking : {"smith_separable", "smith_height_correlated"})
                for (bool thin : {false, true}) {
                    std::string text = glass(ndf, eta, masking);
                    if (thin) text = fmt::format("material t {{ ndf = {}; masking = {}; fresnel = dielectric({}); "
                                                 "thin = true; scatter = both; }}\n",
                                                 ndf, masking, eta);
                    facet::DiagnosticEngine diags;
                    facet::CheckedProgram program = facet::loadProgramText(text, "hard.mat", diags);
                    REQUIRE_FALSE(diags.hasErrors());
                    const facet::CheckedMaterial& m = *program.find("t");
                    facet::Interpreter<float> fl(m);
                    facet::Interpreter<double> db(m);
                    facet::Interpreter<__float128> quad(m);
                    for (const auto& [wi, wo] : pairs) {
                        float fi[3] = {float(wi.x), float(wi.y), float(wi.z)}, fo[3] = {float(wo.x), float(wo.y), float(wo.z)};
                        double di[3] = {wi.x, wi.y, wi.z}, dout[3] = {wo.x, wo.y, wo.z};
                        __float128 qi[3] = {wi.x, wi.y, wi.z}, qo[3] = {wo.x, wo.y, wo.z};
                        auto f = fl.eval(fi, fo, nullptr);
                        auto d = db.eval(di, dout, nullptr);
                        auto q = quad.eval(qi, qo, nullptr);
                        INFO(text, " wi ", wi.x, " ", wi.y, " ", wi.z, " wo ", wo.x, " ", wo.y, " ", wo.z);
                        REQUIRE(d.valid);
                        REQUIRE(q.valid);
                        REQUIRE(f.valid);
                        // How far the exact f moves when the directions move by a
                        // double's rounding (a narrow lobe near the critical angle
                        // is steep there): the bound on top of 1e-9.
                        double sensitivity = 0;
                        for (int k = 0; k < 6; ++k) {
                            __float128 pi[3] = {qi[0], qi[1], qi[2]}, po[3] = {qo[0], qo[1], qo[2]};
                            __float128* w = k < 3 ? pi : po;
                            w[k % 3] += (k % 2 ? -1 : 1) * 0x1p-53 * (w[k % 3] == 0 ? 1e-300 : double(w[k % 3]));
                            auto moved = quad.eval(pi, po, nullptr);
                            if (moved.valid) sensitivity = std::max(sensitivity, relDiff(double(moved.rgb[0]), double(q.rgb[0])));
                        }
                        for (int ch = 0; ch < 3; ++ch) {
                            CHECK(std::isfinite(f.rgb[ch]));
                            CHECK(f.rgb[ch] >= 0);
                            CHECK(d.rgb[ch] >= 0);
                            double qd = double(q.rgb[ch]);
                            if (qd > 1e-280 || d.rgb[ch] > 1e-280) {
                                INFO("sensitivity ", sensitivity);
                                CHECK(relDiff(d.rgb[ch], qd) <= 1e-9 + 16 * sensitivity);
                                ++compared;
                            }
                        }
                    }
                }
    CHECK(compared > 1000);
}

TEST_CASE("thin sheet: the reflection lobe with R' = 2F/(1+F) on either side, its mirror with T' = (1-F)/(1+F)") {
    std::mt19937_64 rng(29);
    for (double eta : {1.33, 1.5, 2.4}) {
        Reference sheet(fmt::format("material t {{ ndf = ggx(0.3); masking = smith_height_correlated; "
                                    "fresnel = dielectric({}); thin = true; scatter = both; }}\n",
                                    eta));
        Reference coat(fmt::format("material t {{ ndf = ggx(0.3); masking = smith_height_correlated; "
                                   "fresnel = dielectric({}); }}\n",
                                   eta));
        for (int k = 0; k < 300; ++k) {
            V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
            V3 i{wi.x, wi.y, std::abs(wi.z)}, o{wo.x, wo.y, std::abs(wo.z)};
            V3 h{i.x + o.x, i.y + o.y, i.z + o.z};
            double len = std::sqrt(dot(h, h));
            double F = fresnel(len / 2, 1, eta);
            double lobe = coat.f(i, o) / F;  // D G / (4 ci co)
            double want = (wi.z * wo.z > 0 ? 2 * F / (1 + F) : (1 - F) / (1 + F)) * lobe;
            CHECK(relDiff(sheet.f(wi, wo), want) <= 1e-12);
            CHECK(relDiff(sheet.f(wi, wo), sheet.f(wo, wi)) <= 1e-12);
        }
    }
}

TEST_CASE("thin sheet: the F = 1 lobe's energy, sampling fits its pdf, and swapped R' and T' fail") {
    using namespace sampling_test;
    Reference sheet("material t { ndf = ggx(0.4); masking = smith_height_correlated; "
                    "fresnel = dielectric(rgb(1.4, 1.5, 1.6)); thin = true; scatter = both; }\n");
    Reference white("material t { ndf = ggx(0.4); masking = smith_height_correlated; }\n");
    for (double side : {1.0, -1.0}) {
        V3 wo = direction(50, 0.5);
        wo.z *= side;
        // R' + T' = 1: the sheet keeps what the F = 1 reflection lobe keeps.
        double e = integrate([&](const V3& wi) { return sheet.f(wi, wo) * std::abs(wi.z); });
        V3 above{wo.x, wo.y, std::abs(wo.z)};
        double lobe = integrate([&](const V3& wi) { return wi.z > 0 ? white.f(wi, above) * wi.z : 0.0; });
        CHECK(e == doctest::Approx(lobe).epsilon(1e-4));
        CHECK(e <= 1);
        CheckSettings settings;
        settings.samples = 200000;
        settings.level = 0.01 / 4;
        auto sampler = [&](const std::array<double, 3>& u) { return facet::sampleDielectricLobe(sheet.lobe, wo, u); };
        facet::SphereGrid grid = facet::SphereGrid::equalArea(36, 72);
        CheckOutcome out = checkSampler(sampler, [&](const V3& wi) { return facet::dielectricLobePdf(sheet.lobe, wi, wo); },
                                        grid, settings);
        INFO(out.describe());
        CHECK(out.chi2.failure == "");
        // Reflection and transmission probabilities swapped (same lobe shape).
        facet::PdfFunction swapped = [&](const V3& wi) {
            V3 mirrored{wi.x, wi.y, -wi.z};
            return facet::dielectricLobePdf(sheet.lobe, mirrored, wo);
        };
        CHECK(checkSampler(sampler, swapped, grid, settings).chi2.failure != "");
    }
}

TEST_CASE("scatter = transmit keeps the transmitted pairs only") {
    std::mt19937_64 rng(31);
    Reference both(glass("ggx(0.3)", 1.5));
    Reference through(glass("ggx(0.3)", 1.5, "smith_height_correlated", "transmit"));
    for (int k = 0; k < 200; ++k) {
        V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
        CHECK(through.f(wi, wo) == (wi.z * wo.z < 0 ? both.f(wi, wo) : 0.0));
    }
}

TEST_CASE("the APIs: backend=interp evaluates and samples it, transport=importance, SIMD evaluates it too") {
    facet::CompileOptions o;
    CHECK(facet::CompileOptions::parse("transport=photons", o) == "transport 'photons' is not radiance or importance");
    REQUIRE(facet::CompileOptions::parse("backend=interp;cache=memory;transport=importance", o) == "");
    CHECK(o.canonical().find(";transport=importance") != std::string::npos);
    facet::Compiler compiler;
    const std::string text = glass("ggx(0.3)", 1.5);
    facet::DiagnosticEngine diags;
    auto importance = compiler.compileText(text, "glass.mat", "", o, diags);
    REQUIRE(importance);
    facet::CompileOptions plain;  // parse() sets only what the string gives
    REQUIRE(facet::CompileOptions::parse("backend=interp;cache=memory", plain) == "");
    auto radiance = compiler.compileText(text, "glass.mat", "", plain, diags);
    REQUIRE(radiance);
    // A transmitted pair, wi inside: radiance carries 1/eta^2 against importance.
    float wi[3] = {-0.2f, -0.1f, -0.974679f}, wo[3] = {0.4f, 0.1f, 0.910494f}, rgbR[3], rgbI[3];
    radiance->eval(wi, wo, nullptr, rgbR);
    importance->eval(wi, wo, nullptr, rgbI);
    Reference ref(text);
    V3 i{wi[0], wi[1], wi[2]}, w{wo[0], wo[1], wo[2]};
    double li = std::sqrt(dot(i, i)), lw = std::sqrt(dot(w, w));
    double want = ref.f({i.x / li, i.y / li, i.z / li}, {w.x / lw, w.y / lw, w.z / lw});
    CHECK(relDiff(rgbR[0], want) <= 1e-6);
    CHECK(relDiff(rgbI[0], want * 1.5 * 1.5) <= 1e-6);
    // Sampling through the kernel: directions on both sides, weight = f |n.wi| / pdf.
    int below = 0, above = 0;
    std::mt19937_64 rng(37);
    std::uniform_real_distribution<float> uniform(0, 1);
    for (int k = 0; k < 2000; ++k) {
        float u[3] = {uniform(rng), uniform(rng), uniform(rng)}, s[3], pdf, weight[3], f[3];
        if (!radiance->sample(wo, u, nullptr, s, &pdf, weight) || !(pdf > 0)) continue;
        (s[2] < 0 ? below : above)++;
        radiance->eval(s, wo, nullptr, f);
        CHECK(relDiff(weight[0], f[0] * std::abs(s[2]) / pdf) <= 1e-4);
    }
    CHECK(below > 1000);  // at 24 degrees glass transmits ~95%
    CHECK(above > 20);
    // A compiled kernel evaluates and samples it (CompiledLobeTests.cpp has
    // the rest): the reference's sample for the same u.
    facet::CompileOptions simd;
    REQUIRE(facet::CompileOptions::parse("backend=simd;cache=memory", simd) == "");
    auto compiled = compiler.compileText(text, "glass.mat", "", simd, diags);
    REQUIRE(compiled);
    float rgbC[3];
    compiled->eval(wi, wo, nullptr, rgbC);
    CHECK(relDiff(rgbC[0], want) <= 1e-5);
    float u[3] = {0.3f, 0.6f, 0.2f}, sI[3], sC[3], pdfI, pdfC, wI[3], wC[3];
    REQUIRE(radiance->sample(wo, u, nullptr, sI, &pdfI, wI));
    REQUIRE(compiled->sample(wo, u, nullptr, sC, &pdfC, wC));
    for (int d = 0; d < 3; ++d) CHECK(std::abs(sC[d] - sI[d]) <= 1e-5);
    CHECK(relDiff(pdfC, pdfI) <= 1e-5);
}

TEST_CASE("the printed material (ir --stages, the cache key) keeps scatter and thin, and reads back the same") {
    Reference sheet("material t { ndf = ggx(0.4); masking = smith_height_correlated; "
                    "fresnel = dielectric(1.45); thin = true; scatter = transmit; }\n");
    std::string printed = facet::printMaterial(*sheet.program.find("t"));
    CHECK(printed.find("    scatter = transmit;\n") != std::string::npos);
    CHECK(printed.find("    thin = true;\n") != std::string::npos);
    Reference again(printed);
    std::mt19937_64 rng(43);
    for (int k = 0; k < 50; ++k) {
        V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
        CHECK(again.f(wi, wo) == sheet.f(wi, wo));
    }
    Reference reflecting(glass("ggx(0.3)", 1.5, "smith_height_correlated", "reflect"));
    CHECK(facet::printMaterial(*reflecting.program.find("t")).find("scatter") == std::string::npos);
}

}  // TEST_SUITE

TEST_CASE("the hard-case sample of a whole-sphere material holds SPEC 11's pairs; a reflecting one does not") {
    auto labels = [](const std::string& text) {
        facet::DiagnosticEngine diags;
        facet::CheckedProgram program = facet::loadProgramText(text, "hard.mat", diags);
        REQUIRE_FALSE(diags.hasErrors());
        std::vector<std::string> out;
        for (const facet::HardCase& c : facet::hardCases(*program.find("t"))) out.push_back(c.label);
        return out;
    };
    auto count = [](const std::vector<std::string>& all, const std::string& needle) {
        return std::count_if(all.begin(), all.end(), [&](const std::string& l) { return l.find(needle) != l.npos; });
    };
    std::vector<std::string> glassCases = labels(glass("ggx(0.3)", 1.5));
    CHECK(count(glassCases, "critical angle") == 20);  // 5 offsets x (grazing, mirror) x both orders
    CHECK(count(glassCases, "wi = -wo") == 8);
    CHECK(count(glassCases, "across") == 12);
    std::vector<std::string> mirrorCases =
        labels("material t { ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(1.5); }\n");
    CHECK(count(mirrorCases, "critical angle") == 0);
    CHECK(count(mirrorCases, "wi = -wo") == 0);
}
