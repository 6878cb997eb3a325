// Chi-square of the whole-sphere sampler (DielectricLobe.h) for every NDF
// with a visible-normal sampler (ggx, beckmann, blinn_phong, student_t),
// every Smith form with a transmission form, eta in {1.05, 1.5, 2.4} and
// their inverses, wo on both sides; a pdf whose refraction lacks the eta'^2
// of dm/dwi must fail. The quick case runs blinn_phong and student_t at one
// eta (ggx and beckmann are swept in DielectricLobeTests.cpp); the sweep
// runs in the long tier (ctest -R transmission_sampling_sweep).
#include "QuadMath.h"
#include "ChiSquare.h"
#include "DielectricLobe.h"
#include "Sampling.h"
#include "TransmissionSupport.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

using namespace transmission_test;

namespace {

struct SweepCounts {
    int configs = 0, wrongRejected = 0, wrongTried = 0;
};

// One configuration: the sampler against its pdf, the integral against the
// share of draws with a direction, and (where asked) the wrong Jacobian.
void checkConfig(const std::string& ndf, double alpha, double eta, const std::string& masking, double side,
                 int tests, bool tryWrong, SweepCounts& counts) {
    using namespace sampling_test;
    CheckSettings settings;
    settings.samples = 100000;
    settings.level = facet::sidakLevel(0.01, tests);
    Reference ref(glass(ndf, eta, masking));
    V3 wo = direction(alpha > 0.5 ? 65 : 35, 0.8);
    wo.z *= side;
    facet::SphereGrid grid = transmissionGrid(wo, alpha, eta);
    auto sampler = [&](const std::array<double, 3>& u) { return facet::sampleDielectricLobe(ref.lobe, wo, u); };
    facet::PdfFunction pdf = [&](const V3& wi) { return facet::dielectricLobePdf(ref.lobe, wi, wo); };
    CheckOutcome out = checkSampler(sampler, pdf, grid, settings);
    INFO(fmt::format("{} {} eta {:.4f} wo.z {:.3f}: {}", ndf, masking, eta, wo.z, out.describe()));
    CHECK(out.chi2.failure == "");
    double drawn = 1 - double(out.noSample) / settings.samples;
    CHECK(std::abs(out.integral - drawn) <= 4 * std::sqrt(drawn * (1 - drawn) / settings.samples) + 1e-4);
    if (tryWrong) {
        double relative = wo.z > 0 ? eta : 1 / eta;
        facet::PdfFunction wrong = [&](const V3& wi) {
            double p = facet::dielectricLobePdf(ref.lobe, wi, wo);
            return wi.z * wo.z < 0 ? p / (relative * relative) : p;
        };
        CheckSettings shape = settings;
        shape.renormalize = true;
        ++counts.wrongTried;
        counts.wrongRejected += checkSampler(sampler, wrong, grid, shape).chi2.failure != "";
    }
    ++counts.configs;
}

// The NDF written with roughness alpha.
std::string ndfAt(const std::string& name, double alpha) {
    if (name == "blinn_phong") return fmt::format("blinn_phong(beckmann_to_phong({}))", alpha);
    if (name == "student_t") return fmt::format("student_t({}, 3)", alpha);
    return fmt::format("{}({})", name, alpha);
}

}  // namespace

TEST_SUITE("dielectric sampling sweep") {

TEST_CASE("quick: blinn_phong and student_t refract through their visible-normal samplers") {
    SweepCounts counts;
    const int tests = 2 * 2 * 2;
    for (const char* ndf : {"blinn_phong", "student_t"})
        for (double eta : {1.5, 1 / 1.5})
            for (double side : {1.0, -1.0})
                checkConfig(ndfAt(ndf, 0.4), 0.4, eta, "smith_height_correlated", side, tests, true, counts);
    CHECK(counts.configs == tests);
    CHECK(counts.wrongRejected == counts.wrongTried);
}

TEST_CASE("sweep: every NDF with a visible-normal sampler x Smith form x eta and its inverse x both sides") {
    SweepCounts counts;
    const char* ndfs[] = {"ggx", "beckmann", "blinn_phong", "student_t"};
    const char* maskings[] = {"smith_separable", "smith_height_correlated", "smith_direction_correlated",
                              "smith_height_direction_correlated"};
    const double etas[] = {1.05, 1.5, 2.4, 1 / 1.05, 1 / 1.5, 1 / 2.4};
    const int tests = 4 * 2 * 4 * 6 * 2;
    for (const char* ndf : ndfs)
        for (double alpha : {0.1, 0.6})
            for (const char* masking : maskings)
                for (double eta : etas)
                    for (double side : {1.0, -1.0})
                        checkConfig(ndfAt(ndf, alpha), alpha, eta, masking, side, tests,
                                    eta == 1.5 || eta == 1 / 1.5, counts);
    CHECK(counts.configs == tests);
    CHECK(counts.wrongRejected == counts.wrongTried);
}

}  // TEST_SUITE
