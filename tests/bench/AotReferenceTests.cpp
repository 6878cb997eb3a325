// AotReferenceTests: the hand-written AOT reference models (bench/aot) agree
// with the double interpreter on their material files (bench/models), and
// follow the batch conventions of SPEC section 2. If these drift apart, the
// JIT/AOT ratio of `facet bench` would compare different BRDFs.
#include "BenchRunner.h"
#include "BenchSamples.h"
#include "Checker.h"
#include "ReferenceComparison.h"
#include "ReferenceModels.h"

#include <doctest/doctest.h>

#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <sstream>

using namespace facet;

namespace {

std::string modelPath(const aot::ReferenceModel& m) {
    return std::string(FACET_SOURCE_DIR) + "/bench/models/" + m.modelFile;
}

CheckedProgram load(const std::string& path) {
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramFile(path, diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    REQUIRE(!p.materials.empty());
    return p;
}

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Outputs {
    std::vector<float> c[3];
    float* p[3];
    explicit Outputs(size_t n) {
        for (int k = 0; k < 3; ++k) c[k].assign(n, -1.0f), p[k] = c[k].data();
    }
};

// Max relative error of `out` against the interpreter (ReferenceComparison.h,
// as in `facet bench`), with the worst lane described.
double maxRelError(const CheckedMaterial& m, const LaneBatch& s, const Outputs& out, std::string& worst) {
    const float* const rgb[3] = {out.c[0].data(), out.c[1].data(), out.c[2].data()};
    ReferenceComparison cmp = compareWithReference(evaluateReference(m, s), rgb);
    if (cmp.worst.present)
        worst = fmt::format("lane {} ch {}: {} got {:.9g} want {:.17g}", cmp.worst.lane, cmp.worst.channel,
                            describeLane(m, s.wi(), s.wo(), s.inputs(), cmp.worst.lane), cmp.worst.got,
                            cmp.worst.want);
    return cmp.maxRel;
}

}  // namespace

TEST_SUITE("aot") {

TEST_CASE("every reference model has a material file with its tag and the same inputs") {
    for (const aot::ReferenceModel& model : aot::referenceModels()) {
        std::string name = model.name;
        CAPTURE(name);
        std::string path = modelPath(model);
        CheckedProgram p = load(path);
        const CheckedMaterial& m = p.materials.front();
        CHECK(bench::aotTagFor(readText(path), path, m, p.materials) == model.name);
        REQUIRE(m.slotCount == int(model.inputs.size()));
        for (int s = 0; s < m.slotCount; ++s) CHECK(m.slotName(s) == model.inputs[s]);
        CHECK(aot::findReferenceModel(model.name) == &model);
    }
    // A shipped material without a tag has no AOT twin.
    std::string gold = std::string(FACET_SOURCE_DIR) + "/materials/gold.mat";
    CheckedProgram p = load(gold);
    CHECK(bench::aotTagFor(readText(gold), gold, p.materials.front(), p.materials).empty());
}

TEST_CASE("AOT reference models match the interpreter within 1e-4 relative on random directions") {
    for (const aot::ReferenceModel& model : aot::referenceModels()) {
        std::string name = model.name;
        CAPTURE(name);
        CheckedProgram p = load(modelPath(model));
        const CheckedMaterial& m = p.materials.front();
        // The bench's regular sample (directions uniform over the
        // hemisphere, 5% below the horizon), with roughness in [0.1, 1]
        // (alpha >= 0.01): the AOT code computes its geometry in float, and
        // for smaller alpha the float rounding of the half vector (about
        // 6e-8 absolute) is amplified by 1/alpha^2 in D beyond 1e-4 near
        // the peak. `facet bench` reports that error on its own samples.
        for (uint64_t seed : {1u, 2u, 3u}) {
            LaneBatch s = bench::regularSample(m, 20000, seed);
            for (auto& column : s.slots)
                for (float& r : column) r = 0.1f + 0.9f * r;  // [0, 1] -> [0.1, 1]
            Outputs out(s.size());
            int64_t invalid = model.batch(int64_t(s.size()), s.wi(), s.wo(), s.inputs(), out.p);
            CHECK(invalid == 0);
            std::string worst;
            double err = maxRelError(m, s, out, worst);
            CHECK_MESSAGE(err <= 1e-4, fmt::format("max rel {:.3g} at {}", err, worst));
        }
    }
}

TEST_CASE("AOT defaults: a null inputs array or a null slot means the material's defaults") {
    for (const aot::ReferenceModel& model : aot::referenceModels()) {
        std::string name = model.name;
        CAPTURE(name);
        CheckedProgram p = load(modelPath(model));
        const CheckedMaterial& m = p.materials.front();
        LaneBatch s = bench::regularSample(m, 1000, 7);
        // Explicit defaults in every slot.
        std::vector<double> defaults = m.defaultSlots();
        for (int k = 0; k < m.slotCount; ++k) std::fill(s.slots[k].begin(), s.slots[k].end(), float(defaults[k]));
        s.finish();
        Outputs given(s.size()), none(s.size()), partial(s.size());
        model.batch(int64_t(s.size()), s.wi(), s.wo(), s.inputs(), given.p);
        model.batch(int64_t(s.size()), s.wi(), s.wo(), nullptr, none.p);
        std::vector<const float*> some(s.inputs(), s.inputs() + m.slotCount);
        some[0] = nullptr;
        model.batch(int64_t(s.size()), s.wi(), s.wo(), some.data(), partial.p);
        for (int c = 0; c < 3; ++c) {
            CHECK(given.c[c] == none.c[c]);
            CHECK(given.c[c] == partial.c[c]);
        }
        std::string worst;
        CHECK_MESSAGE(maxRelError(m, s, none, worst) <= 1e-4, worst);
    }
}

TEST_CASE("AOT conventions: invalid lanes are 0 and counted, below the horizon is 0 and valid") {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const aot::ReferenceModel& model : aot::referenceModels()) {
        std::string name = model.name;
        CAPTURE(name);
        // Lanes: ok, NaN wi, Inf wo, non-unit wi, below the horizon, NaN input, wi = -wo.
        std::vector<float> wx = {0.3f, nan, 0.0f, 0.0f, 0.6f, 0.3f, 0.6f}, wy = {0, 0, 0, 0, 0, 0, 0},
                           wz = {0.9539392f, 1, 1, 1.1f, -0.8f, 0.9539392f, 0.8f};
        std::vector<float> vx = {-0.2f, 0, inf, 0, 0, -0.2f, -0.6f}, vy = {0, 0, 0, 0, 0, 0, 0},
                           vz = {0.9797959f, 1, 1, 1, 1, 0.9797959f, -0.8f};
        size_t n = wx.size();
        std::vector<std::vector<float>> slots(model.inputs.size(), std::vector<float>(n, 0.3f));
        slots[0][5] = nan;
        std::vector<const float*> in;
        for (auto& s : slots) in.push_back(s.data());
        const float* wi[3] = {wx.data(), wy.data(), wz.data()};
        const float* wo[3] = {vx.data(), vy.data(), vz.data()};
        Outputs out(n);
        int64_t invalid = model.batch(int64_t(n), wi, wo, in.data(), out.p);
        CHECK(invalid == 4);  // NaN wi, Inf wo, non-unit wi, NaN input
        for (int c = 0; c < 3; ++c) {
            CHECK(out.c[c][0] > 0);
            for (size_t i = 1; i < n; ++i) CHECK(out.c[c][i] == 0.0f);
        }
    }
}

}  // TEST_SUITE
