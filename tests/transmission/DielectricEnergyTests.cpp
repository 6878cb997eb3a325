// Energy compensation of the lobes that scatter over the whole sphere
// (SPEC 11, compiler/reference/DielectricEnergy.h):
// - the interface tables' albedo (visible normals, both branches per facet)
//   is Int f |n.wi| dwi over the sphere, integrated independently on a grid;
// - compensated, a non-absorbing rough interface keeps R + T within 1% of 1
//   from outside and from inside for alpha <= 1 and 1.05 <= eta <= 3 (and
//   without compensation it does not: the test can fail);
// - a compensated thin sheet the same;
// - generalized reciprocity holds with the compensation, radiance and
//   importance transport;
// - the sampler's mixture passes chi-square over the whole sphere, and a
//   pdf that leaves the compensation out must fail.
#include "QuadMath.h"
#include "ChiSquare.h"
#include "DielectricEnergy.h"
#include "DielectricLobe.h"
#include "KullaConty.h"
#include "Sampling.h"
#include "TransmissionSupport.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

using namespace transmission_test;

namespace {

// The text of a rough interface (or sheet) with alpha an input `a`.
std::string compensatedText(const std::string& ndf, const std::string& masking, double eta, bool compensate,
                            bool thin) {
    return fmt::format(
        "material t {{ input a = 0.3 in 0.0001 .. 1; ndf = {}(a); masking = {}; fresnel = dielectric({}); "
        "energy = {}; scatter = both; thin = {}; }}\n",
        ndf, masking, eta, compensate ? "kulla_conty" : "none", thin ? "true" : "false");
}

// Its reference: one interpreter, and one pair of tables, serves every alpha.
struct Compensated : Reference {
    Compensated(const std::string& ndf, const std::string& masking, double eta, bool compensate, bool thin,
                facet::Transport transport)
        : Reference(compensatedText(ndf, masking, eta, compensate, thin), transport) {}
    facet::ResolvedMaterial<double> lobeAt(double alpha) const { return interp->resolve(&alpha); }
    double f(const V3& wi, const V3& wo, double alpha) const {
        double i[3] = {wi.x, wi.y, wi.z}, o[3] = {wo.x, wo.y, wo.z};
        facet::EvalResult<double> e = interp->eval(i, o, &alpha);
        return e.valid ? e.rgb[0] : NAN;  // (a NaN fails every comparison it reaches)
    }
    // R + T from wo: Int f |n.wi| dwi (the power scattered in importance
    // transport), adaptively to 1e-6 per cell (1e-4 in all).
    double albedo(const V3& wo, double alpha) const {
        facet::SphereGrid grid = facet::SphereGrid::equalArea(16, 32);
        facet::PdfFunction integrand = [&](const V3& wi) { return f(wi, wo, alpha) * std::abs(wi.z); };
        double sum = 0;
        for (double cell : facet::integrateCells(grid, integrand, 1e-6)) sum += cell;
        return sum;
    }
};

facet::EnergyTableKey interfaceKey(const char* ndf, const char* masking, double eta) {
    facet::EnergyTableKey key;
    key.ndf = &facet::ndfEntry(*facet::findModel(facet::ModelSlot::Ndf, ndf));
    key.masking = &facet::maskingEntry(*facet::findModel(facet::ModelSlot::Masking, masking));
    key.interfaceEta = eta;
    return key;
}

}  // namespace

TEST_SUITE("dielectric energy") {

TEST_CASE("the interface table's albedo is Int f |n.wi| dwi over the sphere, from both sides") {
    for (double eta : {1.5, 2.4})
        for (double side : {1.0, -1.0}) {
            Compensated plain("ggx", "smith_height_correlated", eta, false, false, facet::Transport::Importance);
            facet::EnergyTableKey key = interfaceKey("ggx", "smith_height_correlated", side > 0 ? eta : 1 / eta);
            for (double alpha : {0.2, 0.7})
                for (double theta : {0.0, 60.0, 85.0}) {
                    V3 wo = direction(theta, 0.0);
                    double table = facet::directionalAlbedo(key, wo.z, alpha);
                    wo.z *= side;
                    double sphere = plain.albedo(wo, alpha);
                    INFO("eta ", eta, " side ", side, " alpha ", alpha, " theta ", theta, ": table ", table,
                         " sphere ", sphere);
                    CHECK(std::abs(table - sphere) <= 1e-3);
                    CHECK(sphere <= 1 + 1e-4);
                }
        }
}

TEST_CASE("compensated, R + T stays within 1% of 1 from outside and from inside; uncompensated it does not") {
    double worst = 0, worstPlain = 0;
    std::string where;
    struct Case {
        const char *ndf, *masking;
        double eta;
    };
    for (Case c : {Case{"ggx", "smith_height_correlated", 1.05}, Case{"ggx", "smith_height_correlated", 1.5},
                   Case{"ggx", "smith_height_correlated", 3.0}, Case{"beckmann", "smith_separable", 2.4}}) {
            auto [ndf, masking, eta] = c;
            Compensated ms(ndf, masking, eta, true, false, facet::Transport::Importance);
            Compensated plain(ndf, masking, eta, false, false, facet::Transport::Importance);
            for (double alpha : {0.2, 1.0})
                for (double side : {1.0, -1.0})
                    for (double theta : {0.0, 60.0, 88.0}) {
                        V3 wo = direction(theta, 0.7);
                        wo.z *= side;
                        double e = ms.albedo(wo, alpha);
                        if (std::abs(1 - e) > worst) {
                            worst = std::abs(1 - e);
                            where = fmt::format("{} {} eta {} alpha {} theta {} side {}", ndf, masking, eta, alpha,
                                                theta, side);
                        }
                        if (alpha == 1.0) worstPlain = std::max(worstPlain, 1 - plain.albedo(wo, alpha));
                        INFO(ndf, " ", masking, " eta ", eta, " alpha ", alpha, " theta ", theta, " side ", side,
                             ": R + T = ", e);
                        CHECK(std::abs(1 - e) <= 0.01);
                    }
        }
    MESSAGE(fmt::format("compensated: largest |1 - (R + T)| {:.5f} ({}); uncompensated at alpha 1: largest loss {:.4f}",
                        worst, where, worstPlain));
    CHECK(worstPlain > 0.05);  // the single-scattering lobe alone loses energy
}

TEST_CASE("a compensated thin sheet keeps R + T within 1% of 1 on both sides") {
    Compensated sheet("ggx", "smith_height_correlated", 1.5, true, true, facet::Transport::Importance);
    Compensated plain("ggx", "smith_height_correlated", 1.5, false, true, facet::Transport::Importance);
    double worstPlain = 0;
    for (double alpha : {0.3, 1.0})
        for (double theta : {0.0, 60.0, 85.0})
            for (double side : {1.0, -1.0}) {
                V3 wo = direction(theta, 0.2);
                wo.z *= side;
                double e = sheet.albedo(wo, alpha);
                INFO("alpha ", alpha, " theta ", theta, " side ", side, ": R + T = ", e);
                CHECK(std::abs(1 - e) <= 0.01);
                worstPlain = std::max(worstPlain, 1 - plain.albedo(wo, alpha));
            }
    CHECK(worstPlain > 0.05);
}

TEST_CASE("generalized reciprocity with the compensation, radiance and importance") {
    std::mt19937_64 rng(29);
    for (double eta : {1.5, 1 / 1.5})
        for (bool thin : {false, true})
            for (auto transport : {facet::Transport::Radiance, facet::Transport::Importance}) {
                Compensated ref("ggx", "smith_height_correlated", eta, true, thin, transport);
                for (double alpha : {0.3, 0.9}) {
                    facet::ResolvedMaterial<double> lobe = ref.lobeAt(alpha);
                    int compensated = 0;
                    for (int k = 0; k < 100; ++k) {
                        V3 wi = uniformSphere(rng), wo = uniformSphere(rng);
                        double ni = wi.z > 0 || thin ? 1 : eta, no = wo.z > 0 || thin ? 1 : eta;
                        double a = ref.f(wi, wo, alpha), b = ref.f(wo, wi, alpha);
                        double left = transport == facet::Transport::Radiance ? a / (no * no) : a / (ni * ni);
                        double right = transport == facet::Transport::Radiance ? b / (ni * ni) : b / (no * no);
                        INFO("eta ", eta, " thin ", thin, " alpha ", alpha);
                        CHECK(relDiff(left, right) <= 1e-8);
                        compensated += facet::wholeSphereCompensation(lobe, wi, wo)[0] > 0;
                    }
                    // The compensation is there: it vanishes only where a
                    // share is 0 (eta < 1: from the rarer inside it all
                    // crosses, since x_i = x_o A_o / (eta^2 A_i) reached 1).
                    CHECK(compensated >= 60);
                }
            }
}

TEST_CASE("sampling the compensated lobe: chi-square over the whole sphere; a pdf without the compensation fails") {
    using namespace sampling_test;
    CheckSettings settings;
    settings.samples = 200000;
    const int tests = 2 * 2 * 2;
    settings.level = facet::sidakLevel(0.01, tests);
    std::mt19937_64 rng(31);
    for (bool thin : {false, true})
        for (double alpha : {0.5, 1.0})
            for (double side : {1.0, -1.0}) {
                const double eta = 1.5;
                Compensated ref("ggx", "smith_height_correlated", eta, true, thin, facet::Transport::Radiance);
                facet::ResolvedMaterial<double> lobe = ref.lobeAt(alpha);
                V3 wo = direction(70, 0.8);
                wo.z *= side;
                facet::SphereGrid grid = transmissionGrid(wo, alpha, eta);
                auto sampler = [&](const std::array<double, 3>& u) { return facet::sampleDielectricLobe(lobe, wo, u); };
                facet::PdfFunction pdf = [&](const V3& wi) { return facet::dielectricLobePdf(lobe, wi, wo); };
                CheckOutcome out = checkSampler(sampler, pdf, grid, settings);
                INFO("thin ", thin, " alpha ", alpha, " side ", side, ": ", out.describe());
                CHECK(out.chi2.failure == "");
                // The density integrates to what the sampler returns a direction for.
                double drawn = 1 - double(out.noSample) / settings.samples;
                CHECK(std::abs(out.integral - drawn) <= 4 * std::sqrt(drawn * (1 - drawn) / settings.samples) + 1e-4);
                // Without the compensation's share the shape is wrong.
                double p = facet::compensationProbability(lobe, wo);
                CHECK(p > 0.02);
                facet::PdfFunction wrong = [&](const V3& wi) {
                    return facet::dielectricLobePdf(lobe, wi, wo) - p * facet::compensationPdf(lobe, wi, wo);
                };
                CheckSettings shape = settings;
                shape.renormalize = true;
                CHECK(checkSampler(sampler, wrong, grid, shape).chi2.failure != "");
                std::uniform_real_distribution<double> uniform(0, 1);
                for (int k = 0; k < 100; ++k) {
                    facet::SampleResult<double> s = sampler({uniform(rng), uniform(rng), uniform(rng)});
                    if (!(s.pdf > 0)) continue;
                    CHECK(relDiff(s.weight[0], ref.f(s.wi, wo, alpha) * std::abs(s.wi.z) / s.pdf) <= 1e-9);
                }
            }
}

}  // TEST_SUITE
