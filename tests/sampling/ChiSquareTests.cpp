// Chi-square goodness of fit and normalization of the reference sampler
// (SPEC 8) over the catalog's combinations, and the tests of the test: a
// deliberately wrong pdf must be rejected.
#include "SamplingCases.h"
#include "SamplingCheck.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <set>

namespace {

using namespace sampling_test;

constexpr double kPi = std::numbers::pi;
constexpr double kLevel = 0.01;                 // family-wise significance
constexpr double kNormalizationTolerance = 1e-4;
constexpr double kRoughness[4] = {0.01, 0.1, 0.5, 1};
constexpr double kViewDegrees[4] = {0, 45, 80, 89.9};
constexpr double kViewAzimuth = 0.3;  // off the principal axes of the anisotropic lobes
// The sixteen (roughness, view) pairs are spread over the combinations of
// each lobe (one NDF form, with or without compensation: its maskings and
// diffuse variants, which share its sampler): every combination runs
// kRunsPerCombination pairs, more where the lobe has too few combinations to
// cover all sixteen, and consecutive runs step through the pairs by 5 (prime
// to 16) so that one combination's runs differ in roughness and view.
constexpr int kPairs = 16;
constexpr int kRunsPerCombination = 2;
constexpr int kPairStep = 5;
constexpr int kSamples = 100000;

V3 viewAt(double degrees) {
    double t = degrees * kPi / 180;
    return {std::sin(t) * std::cos(kViewAzimuth), std::sin(t) * std::sin(kViewAzimuth), std::cos(t)};
}

struct Run {
    const Combo* combo;
    int roughness, view;
    int index;
};

std::vector<Run> plan() {
    std::vector<Run> runs;
    const std::vector<Combo>& all = combos();
    auto sameLobe = [](const Combo& a, const Combo& b) {
        return a.ndf == b.ndf && a.anisotropic == b.anisotropic && a.compensated == b.compensated;
    };
    for (size_t first = 0; first < all.size();) {
        size_t end = first;
        while (end < all.size() && sameLobe(all[first], all[end])) ++end;
        // A tabulated Smith Lambda only changes G (the sampler is the NDF's,
        // checked with the NDF's other maskings): one run per such pair.
        auto tabulated = [&](size_t c) { return all[c].ndf->tabulatedLambda && all[c].masking->smith; };
        size_t counted = 0;
        for (size_t c = first; c < end; ++c) counted += !tabulated(c);
        int perCombination =
            std::max(kRunsPerCombination, counted ? int((kPairs + counted - 1) / counted) : 1);
        int pair = 0;
        for (size_t c = first; c < end; ++c)
            for (int r = 0; r < (tabulated(c) ? 1 : perCombination); ++r, ++pair) {
                int k = pair * kPairStep % kPairs;
                runs.push_back({&all[c], k / 4, k % 4, int(runs.size())});
            }
        first = end;
    }
    return runs;
}

// The wrong-pdf tests below and the plan share one family.
constexpr int kExtraTests = 2;

}  // namespace

TEST_CASE("sampling: chi-square and normalization over the catalog's combinations") {
    std::vector<Run> runs = plan();
    double level = sidakLevel(kLevel, int(runs.size()) + kExtraTests);
    MESSAGE(fmt::format("{} combinations, {} runs of {} samples, per-test level {:.3g}", combos().size(), runs.size(),
                        kSamples, level));
    std::set<std::string> ndfs, maskings;
    // FACET_SAMPLING_ONLY=text runs only the combinations whose name holds it.
    const char* only = std::getenv("FACET_SAMPLING_ONLY");
    for (const Run& run : runs) {
        const Combo& c = *run.combo;
        if (only && c.name().find(only) == std::string::npos) continue;
        double alpha = kRoughness[run.roughness], theta = kViewDegrees[run.view];
        std::string error;
        auto m = makeMaterial(c, alpha, run.index, "schlick(0.5)", &error);
        INFO(c.name(), " alpha ", alpha, " theta_o ", theta, "\n", error);
        REQUIRE(m);
        REQUIRE(m->resolved.valid);
        CheckSettings s;
        s.samples = kSamples;
        s.level = level;
        s.seed = 1000 + uint64_t(run.index);
        CheckOutcome out = checkMaterial(m->resolved, viewAt(theta), s);
        INFO(out.describe());
        CHECK(out.chi2.failure == "");
        CHECK(std::abs(out.integral - 1) <= kNormalizationTolerance);
        if (only) MESSAGE(c.name(), " alpha ", alpha, " theta_o ", theta, ": ", out.describe());
        ndfs.insert(c.ndf->name);
        maskings.insert(c.masking->name);
    }
    // Every NDF and every masking of the catalog took part.
    for (const facet::ModelInfo* n : facet::catalogSlot(facet::ModelSlot::Ndf)) CHECK(ndfs.count(n->name) == 1);
    for (const facet::ModelInfo* n : facet::catalogSlot(facet::ModelSlot::Masking)) CHECK(maskings.count(n->name) == 1);
}

// The tests of the test: the same check with a pdf that is wrong on purpose.
TEST_CASE("sampling: a wrong pdf is rejected") {
    double level = sidakLevel(kLevel, int(plan().size()) + kExtraTests);
    const Combo* combo = nullptr;
    for (const Combo& c : combos())
        if (c.ndf->visibleNormals && c.masking->smith && c.diffuse && !c.anisotropic && !c.compensated) combo = &c;
    REQUIRE(combo);
    auto m = makeMaterial(*combo, 0.5);
    REQUIRE(m);
    const facet::ResolvedMaterial<double>& r = m->resolved;
    REQUIRE(facet::visibleNormalSampling(r));
    V3 wo = viewAt(45);
    CheckSettings s;
    s.samples = kSamples;
    s.level = level;

    SUBCASE("the right pdf passes") {
        CheckOutcome out = checkMaterial(r, wo, s);
        MESSAGE(out.describe());
        CHECK(out.chi2.failure == "");
        CHECK(std::abs(out.integral - 1) <= kNormalizationTolerance);
    }
    SUBCASE("scaled by 1.01: the normalization check fails") {
        CheckOutcome out = checkMaterial(r, wo, s, [&](const V3& wi) { return 1.01 * facet::brdfPdf(r, wi, wo); });
        MESSAGE(out.describe());
        CHECK(std::abs(out.integral - 1) > kNormalizationTolerance);
        CHECK(std::abs(out.integral - 1.01) < kNormalizationTolerance);
    }
    SUBCASE("without the Jacobian 1/(4 wo.m): both checks fail, the chi-square even on the renormalized shape") {
        auto wrong = [&](const V3& wi) {
            V3 s{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
            double len = std::sqrt(s.x * s.x + s.y * s.y + s.z * s.z);
            V3 h{s.x / len, s.y / len, s.z / len};
            double p = facet::specularProbability(r, wo);
            return p * facet::specularNormalPdf(r, wo, h) + (1 - p) * std::max(wi.z, 0.0) / kPi;
        };
        CheckOutcome out = checkMaterial(r, wo, s, wrong);
        MESSAGE(out.describe());
        CHECK(std::abs(out.integral - 1) > kNormalizationTolerance);
        s.renormalize = true;
        CheckOutcome shape = checkMaterial(r, wo, s, wrong);
        MESSAGE(shape.describe());
        CHECK(shape.chi2.failure != "");
    }
}
