// ReferenceComparisonTests: the one definition of a kernel's error against the
// reference (runtime/ReferenceComparison.h) on values whose errors are known.
#include "Checker.h"
#include "ReferenceComparison.h"

#include <doctest/doctest.h>

#include <cfloat>
#include <cmath>

using namespace facet;

TEST_SUITE("reference comparison") {

TEST_CASE("relative error: absolute floor, FLT_MIN divisor, non-finite outputs") {
    CHECK(relativeError(1.0, 1.0) == 0.0);
    CHECK(relativeError(1.5, 1.0) == doctest::Approx(0.5));
    CHECK(relativeError(-1.0, 2.0) == doctest::Approx(1.5));
    // Differences at or below the floor are exact, whatever the reference.
    CHECK(relativeError(1e-31, 0.0) == 0.0);
    CHECK(relativeError(5e-31, 4e-31) == 0.0);
    // Above it, a zero reference divides by FLT_MIN: finite and huge.
    double huge = relativeError(1e-20, 0.0);
    CHECK(std::isfinite(huge));
    CHECK(huge == doctest::Approx(1e-20 / double(FLT_MIN)));
    CHECK(std::isinf(relativeError(NAN, 1.0)));
    CHECK(std::isinf(relativeError(INFINITY, 1.0)));
    CHECK(beyondFloatRange(1e39));
    CHECK(!beyondFloatRange(double(FLT_MAX)));
}

TEST_CASE("ulp distance on the float line") {
    CHECK(floatUlpDistance(1.0f, 1.0f) == 0);
    CHECK(floatUlpDistance(1.0f, std::nextafter(1.0f, 2.0f)) == 1);
    CHECK(floatUlpDistance(0.0f, -0.0f) == 0);
    CHECK(floatUlpDistance(-FLT_TRUE_MIN, FLT_TRUE_MIN) == 2);
    CHECK(floatUlpDistance(1.0f, 2.0f) == double(1 << 23));
}

TEST_CASE("a comparison counts, skips and finds the worst value") {
    ReferenceValues ref;
    // Lane 0 exact, lane 1 off by 1e-3 on green, lane 2 NaN on blue, lane 3
    // a reference beyond float range on red (skipped), negative elsewhere.
    double want[4][3] = {{0.5, 0.25, 1.0}, {0.5, 0.25, 1.0}, {0.5, 0.25, 1.0}, {1e40, 0.25, 1.0}};
    float got[3][4] = {{0.5f, 0.5f, 0.5f, 0.0f}, {0.25f, 0.25025f, 0.25f, -0.25f}, {1.0f, 1.0f, NAN, 1.0f}};
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 4; ++i) ref.rgb[c].push_back(want[i][c]);
    ref.valid.assign(4, 1);
    const float* const rgb[3] = {got[0], got[1], got[2]};
    ReferenceComparison cmp = compareWithReference(ref, rgb);
    CHECK(cmp.values == 12);
    CHECK(cmp.skipped == 1);
    CHECK(cmp.rel.size() == 11);
    CHECK(cmp.nonFinite == 1);
    CHECK(cmp.negative == 1);
    CHECK(std::isinf(cmp.maxRel));
    REQUIRE(cmp.worst.present);
    CHECK(cmp.worst.lane == 2);
    CHECK(cmp.worst.channel == 2);
    // 9 values exact (the float rounding of 0.25025 included below 1e-3).
    CHECK(cmp.countWithin(0.0) == 8);
    CHECK(cmp.countWithin(1.1e-3) == 9);
    CHECK(cmp.quantile(0.5) == 0.0);
    CHECK(std::isinf(cmp.quantile(1.0)));
    CHECK(cmp.maxUlp >= 1);
}

TEST_CASE("the reference of a batch is the interpreter's, 0 on invalid lanes") {
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramText("material m { input r = 0.5 in 0 .. 1; ndf = ggx(r); fresnel = schlick(0.04); }",
                                       "m.mat", diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    const CheckedMaterial& m = p.materials.front();
    LaneBatch batch;
    batch.slots.resize(1);
    double up[3] = {0, 0, 1}, tilted[3] = {0.6, 0, 0.8}, below[3] = {0, 0.6, -0.8};
    batch.push(up, tilted, {0.5});
    batch.push(below, tilted, {0.5});
    batch.finish();
    ReferenceValues ref = evaluateReference(m, batch);
    REQUIRE(ref.size() == 2);
    CHECK(ref.valid[0]);
    CHECK(ref.rgb[0][0] > 0);
    CHECK(ref.rgb[0][0] == ref.rgb[2][0]);  // Schlick 0.04 is grey
    // Below the horizon: valid, f = 0.
    CHECK(ref.valid[1]);
    CHECK(ref.rgb[1][1] == 0.0);
    CHECK(describeLane(m, batch.wi(), batch.wo(), batch.inputs(), 0) == "wi=(0,0,1) wo=(0.600000024,0,0.800000012) r=0.5");
}

}
