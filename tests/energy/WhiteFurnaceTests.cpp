// White furnace and conductor series of the compensated BRDF.
//
// White furnace, F = 1: the total directional albedo
//   A(mu_o) = Int (f_ss + f_ms)(wi, wo) (n.wi) dwi
// is 1 within 1% for alpha in [0.05, 1], mu_o in [0.05, 1], GGX and Beckmann,
// smith_height_correlated and smith_separable. Algebra: the compensation lobe
// integrates to
//   Int f_ms (n.wi) dwi = (1 - E(mu_o)) / (pi (1 - E_avg)) * 2 pi Int (1 - E(mu)) mu dmu
//                       = (1 - E(mu_o)) (1 - E_avg) / (1 - E_avg) = 1 - E(mu_o),
// so A = E_true(mu_o) + 1 - E_table(mu_o): the deviation from 1 is exactly the
// table's interpolation error (EcAvg is the exact integral of the
// interpolated rows, KullaConty.h), plus the quadrature error of this test.
//
// Conductor: with a Fresnel term the lobe integrates to (exact, per channel)
//   Int f_ms (n.wi) dwi = (1 - E(mu_o)) F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),
// and its cosine-weighted hemispherical average over wo is
//   MS_avg = (1 - E_avg) F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) = Sum_{k>=1} F_avg^(k+1) (1 - E_avg)^k E_avg,
// exactly the bounces k >= 1 of Kulla & Conty's series F_avg E_avg Sum_k (F_avg (1 - E_avg))^k.
// Checked: (a) the identity, to 1e-5 (table E); (b) MS_avg measured from the
// BRDF (albedo with kulla_conty minus albedo without, independent quadrature
// over wi and wo) against the series tail with E_avg from an independent
// quadrature of the F = 1 lobe, within 1% (of max(tail, 0.01)); (c) the total hemispherical
// albedo against the whole series F_avg E_avg / (1 - F_avg (1 - E_avg)):
// this also assumes the single-scattering average is F_avg E_avg, which
// angle-dependent F breaks (masking removes the grazing microfacet
// incidences where F is largest): measured and reported, bounded at 5%.
#include "EnergyTestUtil.h"

#include <algorithm>
#include <cstdio>
#include <thread>
#include <vector>

using namespace energy;

namespace {

const double kAlphas[] = {0.05, 0.0575, 0.07, 0.085, 0.1, 0.13, 0.17, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0};
const double kMus[] = {0.05, 0.06, 0.075, 0.1, 0.13, 0.17, 0.2, 0.3, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0};

struct FurnaceRow {
    double alpha, mu, total, ss;
};

void whiteFurnace(const std::string& ndf, const std::string& masking) {
    TestMaterial kc("input alpha = 0.3 in 0.0001 .. 2; ndf = " + ndf + "(alpha); masking = " + masking +
                    "; energy = kulla_conty;");
    TestMaterial ss("input alpha = 0.3 in 0.0001 .. 2; ndf = " + ndf + "(alpha); masking = " + masking + ";");
    std::vector<FurnaceRow> rows;
    for (double a : kAlphas)
        for (double mu : kMus) rows.push_back({a, mu, 0, 0});
    std::vector<facet::ResolvedMaterial<double>> rk, rs;
    for (auto& r : rows) {
        rk.push_back(kc.resolve({r.alpha}));
        rs.push_back(ss.resolve({r.alpha}));
    }
    parallelFor(rows.size(), [&](size_t i) {
        double thetaO = std::acos(rows[i].mu);
        rows[i].total = albedo(rk[i], rows[i].alpha, thetaO);
        rows[i].ss = albedo(rs[i], rows[i].alpha, thetaO);
    });
    double maxDev = 0, maxSs = 0;
    const FurnaceRow* worst = nullptr;
    for (const FurnaceRow& r : rows) {
        INFO(ndf, " ", masking, " alpha=", r.alpha, " mu=", r.mu, " single scattering ", r.ss, " total ", r.total);
        CHECK(std::abs(r.total - 1) < 0.01);
        if (std::abs(r.total - 1) > maxDev) {
            maxDev = std::abs(r.total - 1);
            worst = &r;
        }
        maxSs = std::max(maxSs, 1 - r.ss);
    }
    REQUIRE(worst);
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "%s + %s: %zu (alpha, mu) in [0.05, 1]^2: max |A - 1| = %.2e at alpha %.4g mu %.4g "
                  "(single scattering alone loses up to %.4f)",
                  ndf.c_str(), masking.c_str(), rows.size(), maxDev, worst->alpha, worst->mu, maxSs);
    MESSAGE(buf);
    // The table's interpolation error is ~5e-4 (TableTests); 2e-3 leaves room for quadrature.
    CHECK(maxDev < 2e-3);
}

}  // namespace

TEST_SUITE("white_furnace") {
TEST_CASE("white furnace F = 1: GGX, height-correlated Smith") { whiteFurnace("ggx", "smith_height_correlated"); }
TEST_CASE("white furnace F = 1: GGX, separable Smith") { whiteFurnace("ggx", "smith_separable"); }
TEST_CASE("white furnace F = 1: Beckmann, height-correlated Smith") { whiteFurnace("beckmann", "smith_height_correlated"); }
TEST_CASE("white furnace F = 1: Beckmann, separable Smith") { whiteFurnace("beckmann", "smith_separable"); }

// The same at the shipped white_furnace.mat roughness range through an
// anisotropic material: documented approximation (alpha = sqrt(ax ay)), not
// part of the 1% guarantee; reported, and bounded loosely.
TEST_CASE("anisotropic GGX uses the table at sqrt(alpha_x alpha_y)") {
    TestMaterial kc("ndf = ggx(alpha_x = 0.2, alpha_y = 0.8); masking = smith_height_correlated; energy = kulla_conty;");
    facet::ResolvedMaterial<double> r = kc.resolve();
    CHECK(r.energyAlpha == doctest::Approx(0.4).epsilon(1e-12));
    double worst = 0;
    for (double mu : {0.1, 0.5, 1.0}) {
        // Azimuth 0 and 90 degrees of wo differ for an anisotropic lobe; phi = 0 only here.
        double a = albedo(r, 0.2, std::acos(mu));
        worst = std::max(worst, std::abs(a - 1));
    }
    MESSAGE("anisotropic GGX 0.2 x 0.8 (isotropic table at alpha = 0.4), phi_o = 0: max |A - 1| = ", worst,
            " (documented approximation; the 1% guarantee is for isotropic lobes)");
    CHECK(worst < 0.25);
}
}

namespace {

// The Kulla-Conty series with a conductor Fresnel.
void conductorSeries(const std::string& ndf, const std::string& masking, const std::string& fresnel,
                     const char* what) {
    const double alphas[] = {0.05, 0.2, 0.5, 1.0};
    const std::string lobe = "input alpha = 0.3 in 0.0001 .. 2; ndf = " + ndf + "(alpha); masking = " + masking + ";";
    TestMaterial kc(lobe + "fresnel = " + fresnel + "; energy = kulla_conty;");
    TestMaterial ss(lobe + "fresnel = " + fresnel + ";");
    TestMaterial white(lobe);
    // mu_o quadrature for hemispherical averages 2 Int A(mu) mu dmu: A(mu) is
    // smooth in s = sqrt(mu) (E falls steeply at grazing), so mu = s^2.
    const physics::GaussLegendre g(24);
    std::vector<double> s(g.x.size());
    for (size_t i = 0; i < g.x.size(); ++i) s[i] = (g.x[i] + 1) / 2;
    auto average = [&](const std::vector<std::array<double, 3>>& a, int ch) {
        double avg = 0;  // 2 Int A mu dmu = 2 Int A s^2 2s ds
        for (size_t i = 0; i < g.x.size(); ++i) avg += g.w[i] / 2 * a[i][ch] * 4 * std::pow(s[i], 3);
        return avg;
    };
    double worstTail = 0, worstTotal = 0, worstLobe = 0;
    for (double alpha : alphas) {
        facet::ResolvedMaterial<double> r = kc.resolve({alpha}), r0 = ss.resolve({alpha}), rw = white.resolve({alpha});
        std::vector<std::array<double, 3>> a(g.x.size()), a0(g.x.size()), aw(g.x.size());
        parallelFor(g.x.size(), [&](size_t i) {
            double thetaO = std::acos(s[i] * s[i]);
            a[i] = albedoRgb(r, alpha, thetaO);
            a0[i] = albedoRgb(r0, alpha, thetaO);
            aw[i] = albedoRgb(rw, alpha, thetaO);
        });
        double eAvg = average(aw, 0);  // independent E_avg
        double ecAvg = r.energyTable->ecAvgAt(alpha);
        for (int ch = 0; ch < 3; ++ch) {
            double total = average(a, ch), single = average(a0, ch);
            double favg = r.favg[ch];
            double tail = (1 - eAvg) * favg * favg * eAvg / (1 - favg * (1 - eAvg));
            double series = favg * eAvg / (1 - favg * (1 - eAvg));
            // Relative to the tail, with a floor of 1e-4 absolute: at small alpha the tail is
            // ~1e-3 and both albedo quadratures carry ~1e-5 each.
            double relTail = std::abs((total - single) - tail) / std::max(tail, 1e-2),
                   relTotal = std::abs(total / series - 1);
            char buf[320];
            std::snprintf(buf, sizeof buf,
                          "%s alpha=%g ch=%d: F_avg %.4f E_avg %.5f (table %.5f) | MS_avg %.5f vs tail %.5f (%.1e) | "
                          "total %.5f vs series %.5f (%+.2f%%), single scattering %.5f vs F_avg E_avg %.5f",
                          what, alpha, ch, favg, eAvg, 1 - ecAvg, total - single, tail, relTail, total, series,
                          100 * (total / series - 1), single, favg * eAvg);
            INFO(buf);
            MESSAGE(buf);
            CHECK(relTail < 0.01);
            CHECK(relTotal < 0.05);
            worstTail = std::max(worstTail, relTail);
            worstTotal = std::max(worstTotal, relTotal);
        }
        // (a) The exact identity: Int f_ms (n.wi) dwi = (1 - E(mu_o)) F_avg^2 E_avg / (1 - F_avg (1 - E_avg)).
        // f_ms depends on n.wi only: 2 pi Int f_ms(mu_i) mu_i dmu_i, mu_i = t^2, one 4-point panel per table cell in t.
        for (double muO : {0.05, 0.3, 1.0}) {
            for (int ch = 0; ch < 3; ++ch) {
                double integral = 0;
                int cells = r.energyTable->muCount - 1;
                for (int c = 0; c < cells; ++c) {
                    double t0 = double(c) / cells, t1 = double(c + 1) / cells;
                    for (size_t k = 0; k < 4; ++k) {
                        static const double x4[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                                     0.8611363115940526};
                        static const double w4[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                                     0.3478548451374538};
                        double t = (t0 + t1) / 2 + (t1 - t0) / 2 * x4[k];
                        double muI = t * t;
                        double fms = facet::kullaContyBrdf(r, muI, muO)[ch];
                        integral += w4[k] * (t1 - t0) / 2 * 2 * kPi * fms * muI * 2 * t;
                    }
                }
                double expect = r.energyTable->ecAt(muO, alpha) * facet::kullaContyFresnelTerm(r.favg[ch], ecAvg);
                INFO(std::string(what), " alpha=", alpha, " mu_o=", muO, " channel ", ch);
                CHECK(integral == doctest::Approx(expect).epsilon(1e-5));
                worstLobe = std::max(worstLobe, std::abs(integral / expect - 1));
            }
        }
    }
    MESSAGE(std::string(what), ": MS_avg vs the series tail: max relative deviation ", worstTail,
            "; total vs F_avg E_avg / (1 - F_avg (1 - E_avg)): ", worstTotal, "; lobe identity: ", worstLobe);
}

}  // namespace

TEST_SUITE("conductor") {
TEST_CASE("conductor gold, GGX height-correlated: Kulla-Conty series") {
    conductorSeries("ggx", "smith_height_correlated",
                    "conductor(eta = rgb(0.14, 0.43, 1.38), k = rgb(3.697, 2.455, 1.914))", "gold ggx");
}
TEST_CASE("conductor copper, Beckmann separable: Kulla-Conty series") {
    conductorSeries("beckmann", "smith_separable",
                    "conductor(eta = rgb(0.22, 1.02, 1.24), k = rgb(3.747, 2.577, 2.397))", "copper beckmann");
}
}
