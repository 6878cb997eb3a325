// JIT two-body kernel tests: SIMD kernels with a fast body and a precise
// one (MathVariant::floatFirst): the guarded fast body of math=fast and the
// float-first body of exact math, which lanes each body takes, and that
// both stay within their mode's accuracy.
#include "JitTestSupport.h"

#include "Lowering.h"
#include "ReferenceComparison.h"

#include <array>

using namespace facet;
using namespace facet::jittest;

namespace {

// A two-body SIMD kernel and its float_first=off twin on one random batch
// (directions over the hemisphere, roughness from 0 to 1, both without
// invalid lanes): the two-body kernel's worst relative error against the
// interpreter, and how many channel values differ between the two kernels.
struct TwoBodyRun {
    double worst = 0;
    size_t differing = 0, lanes = 0;
};
TwoBodyRun runTwoBodies(const Kernel& twoBody, const Kernel& oneBody, const char* text) {
    CheckedProgram program = checkedText(text);
    Interpreter<double> interp(program.materials[0], nullptr);
    Batch a(1 << 14, 11), b(1 << 14, 11);
    CHECK(a.run(twoBody) == 0);
    CHECK(b.run(oneBody) == 0);
    TwoBodyRun r;
    r.lanes = a.size();
    for (size_t i = 0; i < a.size(); ++i) {
        EvalResult<double> ref = a.reference(interp, i);
        for (int ch = 0; ch < 3; ++ch) {
            r.differing += a.out[ch][i] != b.out[ch][i];
            r.worst = std::max(r.worst, relativeError(a.out[ch][i], ref.rgb[ch]));
        }
    }
    return r;
}

}  // namespace

TEST_CASE("guarded fast SIMD: unscaled Smith forms where the range guards allow, the plain fast body elsewhere") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(eta = 1.5); })";
    auto applies = [](const char* text, MathVariant variant = MathVariant::fast()) {
        CheckedProgram p = checkedText(text);
        return planLowering(p.materials[0], variant).batchBodies == BatchBodies::GuardedFast;
    };
    // Schlick from eta is not the float-first body's (it would round f0 in
    // float); where that body applies (Schlick with f0, no Fresnel term),
    // fast kernels take it instead.
    CHECK(applies(ggx));
    CHECK(applies(kGold));  // fast mode computes the conductor in float anyway
    CHECK_FALSE(applies(ggx, MathVariant::exact()));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = beckmann(r); }"));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = ggx(r, r * 0.5); fresnel = schlick(eta = 1.5); }"));  // anisotropic
    CHECK(applies("material m { ndf = ggx(0.3, 0.3); fresnel = schlick(eta = 1.5); }"));  // equal constants
    CHECK_FALSE(applies("material m { ndf = ggx(0.3); fresnel = schlick(f0 = 0.04); }"));  // float-first

    Compiler c;
    c.setCacheDir("");
    auto guarded = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off");
    auto plain = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off;float_first=off");

    // The guarded body ran (its values differ from the plain body's in many
    // lanes) and is within fast mode's accuracy (the plain body's worst is
    // ~1e-5 here).
    TwoBodyRun run = runTwoBodies(*guarded, *plain, ggx);
    MESSAGE("guarded fast vs interpreter: worst relative error " << run.worst << "; " << run.differing
                                                                 << " channel values differ from float_first=off");
    CHECK(run.worst < 1e-4);
    CHECK(run.differing > run.lanes / 4);

    // Lanes the guards reject come from the plain body, bit for bit, and do
    // not change their neighbours: a grazing lane (n.wi = 1e-8 < 1e-6) and
    // an invalid one (NaN); a lane below the horizon is 0 in both bodies.
    Batch g(16, 5);
    g.run(*guarded);
    std::vector<float> before[3] = {g.out[0], g.out[1], g.out[2]};
    g.dir[0][5] = 1.0f, g.dir[1][5] = 0.0f, g.dir[2][5] = 1e-8f;
    g.dir[4][9] = std::nanf("");
    g.dir[2][12] = -g.dir[2][12];
    CHECK(g.run(*guarded) == 1);
    Batch h = g;
    CHECK(h.run(*plain) == 1);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][5] == h.out[ch][5]);
        CHECK(g.out[ch][5] > 0.0f);
        CHECK(g.out[ch][9] == 0.0f);
        CHECK(g.out[ch][12] == 0.0f);
        for (int lane = 0; lane < 16; ++lane)
            if (lane != 5 && lane != 9 && lane != 12) CHECK(g.out[ch][lane] == before[ch][lane]);
    }
}

TEST_CASE("guarded fast SIMD: a small alpha keeps the guarded body away from the peak, the plain body at it") {
    // The guarded fast body sums the unit directions rounded to float: h is
    // off by ~1e-7 / |wi + wo|, which matters only where D is steep in
    // theta_h (GgxEmitter). At alpha = 1.44e-4 and random directions D is
    // flat (theta_h >> alpha): the guarded body keeps those lanes. At a
    // mirror pair with n.wi = 1e-4 and theta_h = 1e-5 the rounding alone
    // moves D by 0.35%: that lane is the plain body's, within 1e-5.
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(eta = 1.5); })";
    Compiler c;
    c.setCacheDir("");
    auto guarded = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off");
    auto plain = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off;float_first=off");
    CheckedProgram program = checkedText(ggx);
    Interpreter<double> interp(program.materials[0], nullptr);

    Batch g(16, 7);
    for (float& r : g.slots[0]) r = 0.012f;
    const int peak = 5;
    g.dir[0][peak] = -0.416146845f, g.dir[1][peak] = 0.909297407f, g.dir[2][peak] = 9.99999975e-05f;
    g.dir[3][peak] = 0.416146845f, g.dir[4][peak] = -0.909297407f, g.dir[5][peak] = 9.16770659e-05f;
    Batch h = g;
    CHECK(g.run(*guarded) == 0);
    CHECK(h.run(*plain) == 0);
    int kept = 0;
    for (int lane = 0; lane < 16; ++lane)
        if (lane != peak) kept += g.out[0][lane] != h.out[0][lane] || g.out[1][lane] != h.out[1][lane];
    // 8 here (the others round alike in both bodies); distrusting every
    // lane with alpha (wo.h) < 5e-4, a bound over all theta_h, gives 0.
    MESSAGE(kept << " of 15 lanes away from the peak differ from the plain body");
    CHECK(kept >= 4);
    EvalResult<double> ref = g.reference(interp, peak);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][peak] == h.out[ch][peak]);
        CHECK(relativeError(g.out[ch][peak], ref.rgb[ch]) < 1e-5);
    }
}

TEST_CASE("float-first exact SIMD: float where a lane is well-conditioned, the precise body elsewhere") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    auto applies = [](const char* text) {
        CheckedProgram p = checkedText(text);
        return planLowering(p.materials[0], MathVariant::exact()).batchBodies == BatchBodies::FloatFirst;
    };
    CHECK(applies(ggx));
    CHECK_FALSE(applies(kGold));  // conductor eta is an input: ill-conditioned regions possible
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = beckmann(r); }"));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = ggx(r); fresnel = schlick(eta = r + 1); }"));
    CHECK(applies("material m { input r = 0.5; ndf = ggx(exp(r) - 1); }"));

    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=16;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=16;cache=off;float_first=off");
    DiagnosticEngine d;

    // The float values differ from the precise ones in many lanes (so the
    // float body ran) and stay within exact-mode accuracy of the interpreter.
    TwoBodyRun run = runTwoBodies(*floatFirst, *precise, ggx);
    MESSAGE("float-first vs interpreter: worst relative error " << run.worst << "; " << run.differing
                                                                << " channel values differ from float_first=off");
    CHECK(run.worst < 2e-6);
    CHECK(run.differing > run.lanes / 4);

    // The material's own arithmetic is evaluated in double in the float
    // body too: alpha = 0.5 - x^2 cancels at x = 0.707 (float: 1.3e-4 error).
    const char* cancel = "material m { input x = 0.5; ndf = ggx(-x^2 + 0.5); }";
    auto cancelKernel = compile(c, cancel, "backend=simd;width=16;cache=off");
    CheckedProgram cancelProgram = loadProgramText(cancel, "t.mat", d);
    Interpreter<double> cancelInterp(cancelProgram.materials[0], nullptr);
    Batch x(4096, 3);
    for (size_t i = 0; i < x.size(); ++i) x.slots[0][i] = 0.7f + 0.0071f * float(i) / float(x.size());
    CHECK(x.run(*cancelKernel) == 0);
    double worstCancel = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        EvalResult<double> ref = x.reference(cancelInterp, i);
        if (ref.valid) worstCancel = std::max(worstCancel, relativeError(x.out[0][i], ref.rgb[0]));
    }
    MESSAGE("alpha = 0.5 - x^2 near x = 0.707: worst relative error " << worstCancel);
    CHECK(worstCancel < 2e-6);

    // An ill-conditioned lane (n.wi = 1e-8, grazing) is computed by the
    // precise body, bit for bit, and does not change its neighbours.
    Batch g(16, 5);
    g.run(*floatFirst);
    std::vector<float> before[3] = {g.out[0], g.out[1], g.out[2]};
    g.dir[0][5] = 1.0f, g.dir[1][5] = 0.0f, g.dir[2][5] = 1e-8f;
    CHECK(g.run(*floatFirst) == 0);
    float graze[3];
    float wi5[3] = {1.0f, 0.0f, 1e-8f}, wo5[3] = {g.dir[3][5], g.dir[4][5], g.dir[5][5]}, r5[1] = {g.slots[0][5]};
    precise->eval(wi5, wo5, r5, graze);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][5] == graze[ch]);
        CHECK(g.out[ch][5] > 0.0f);
        for (int lane = 0; lane < 16; ++lane)
            if (lane != 5) CHECK(g.out[ch][lane] == before[ch][lane]);
    }
}

// The float bodies hand the lanes whose validity they cannot decide to the
// precise body (the sampler's, on |w|^2 - 1 rounded to float; the
// evaluation's isotropic one, every lane not within 1e-4 of unit length in
// |wi|^2 + |wo|^2): at the unit tolerance's bounds, both bodies (and eval
// and sample) call the same lanes invalid as the all-double kernel.
TEST_CASE("float-first exact SIMD: directions at the unit tolerance's bounds are valid exactly as in double") {
    const char* ggx = R"(material m { ndf = ggx(0.3); masking = smith_height_correlated; fresnel = schlick(0.04); })";
    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=8;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=8;cache=off;float_first=off");
    // Directions scaled to |w|^2 within ~1e-9 of (1 -+ 1e-3)^2, rounded to
    // float; the valid lanes are the ones the double test accepts.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> uniform(0, 1);
    const double bounds[2] = {(1 - 1e-3) * (1 - 1e-3), (1 + 1e-3) * (1 + 1e-3)};
    const size_t n = 4096;
    std::array<std::vector<float>, 3> wo, wi, u;
    std::vector<uint8_t> expectInvalid;
    int atRoundedBound = 0;
    for (size_t i = 0; i < n; ++i) {
        double z = 0.2 + 0.8 * uniform(rng), phi = 6.283185307179586 * uniform(rng), r = std::sqrt(1 - z * z);
        double bound = bounds[i % 2], scale = std::sqrt(bound * (1 + 2e-9 * (uniform(rng) - 0.5)));
        float w[3] = {float(r * std::cos(phi) * scale), float(r * std::sin(phi) * scale), float(z * scale)};
        double len2 = double(w[0]) * w[0] + double(w[1]) * w[1] + double(w[2]) * w[2];
        expectInvalid.push_back(len2 < bounds[0] || len2 > bounds[1]);
        atRoundedBound += float(len2 - 1) == float(bound - 1);
        for (int k = 0; k < 3; ++k) wo[k].push_back(w[k]), u[k].push_back(0.25f * float(k + 1));
        wi[0].push_back(0.6f), wi[1].push_back(0.0f), wi[2].push_back(0.8f);
    }
    MESSAGE(atRoundedBound << " of " << n << " lanes with |w|^2 - 1 at a rounded bound");
    CHECK(atRoundedBound > 10);
    const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
    const float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
    const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
    std::array<std::vector<float>, 3> rgb, wiOut, weight;
    std::vector<float> pdf(n);
    for (int k = 0; k < 3; ++k) rgb[k].resize(n), wiOut[k].resize(n), weight[k].resize(n);
    float* rgbP[3] = {rgb[0].data(), rgb[1].data(), rgb[2].data()};
    float* wiOutP[3] = {wiOut[0].data(), wiOut[1].data(), wiOut[2].data()};
    float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
    const int64_t expected = std::count(expectInvalid.begin(), expectInvalid.end(), 1);
    CHECK(expected > int64_t(n / 4));
    CHECK(expected < int64_t(3 * n / 4));
    for (const Kernel* k : {floatFirst.get(), precise.get()}) {
        std::vector<uint8_t> status(n, 7);
        CHECK(k->evalBatch(int64_t(n), wiP, woP, nullptr, rgbP, status.data()) == expected);
        CHECK(status == expectInvalid);
        CHECK(k->sampleBatch(int64_t(n), woP, uP, nullptr, wiOutP, pdf.data(), weightP) == expected);
        for (size_t i = 0; i < n; ++i) CHECK((pdf[i] > 0) == !expectInvalid[i]);
    }
}

// The isotropic float body corrects the pair's lengths in float
// (LaneEmitter::floatPairCorrections): the difference of the two
// corrections from (wi - wo).(wi + wo). On nearly opposite directions of
// slightly different lengths, where that difference decides h, it must
// stay as accurate as the double corrections were; lanes further from
// unit length go to the precise body, bit for bit.
TEST_CASE("float-first exact SIMD: nearly opposite directions of slightly different lengths") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    CheckedProgram program = checkedText(ggx);
    CHECK(planLowering(program.materials[0], MathVariant::exact()).batchBody.floatPairCorrections);
    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=16;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=16;cache=off;float_first=off");
    Interpreter<double> interp(program.materials[0], nullptr);
    // Elevations from 1e-3 to 0.3 rad, azimuths pi -+ 0.01 apart, each
    // direction scaled by 1 + e with |e| up to 2e-5 (float body) or 2e-4
    // (|wi|^2 + |wo|^2 - 2 beyond 1e-4: precise body); alpha from 1e-3 to 0.5.
    Batch b(8192, 17), reference(8192, 17);
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> uniform(0, 1);
    std::vector<bool> farFromUnit(b.size());
    for (size_t i = 0; i < b.size(); ++i) {
        auto elevation = [&] { return std::exp(std::log(1e-3) + uniform(rng) * std::log(300.0)); };
        double ei = elevation(), eo = elevation(), phi = 6.283185307179586 * uniform(rng);
        double phiI = phi + 3.141592653589793 + 0.02 * (uniform(rng) - 0.5);
        farFromUnit[i] = i % 4 == 0;
        double spread = farFromUnit[i] ? 2e-4 : 2e-5;
        double si = 1 + spread * (2 * uniform(rng) - 1), so = 1 + spread * (2 * uniform(rng) - 1);
        double wi[3] = {std::cos(ei) * std::cos(phiI) * si, std::cos(ei) * std::sin(phiI) * si, std::sin(ei) * si};
        double wo[3] = {std::cos(eo) * std::cos(phi) * so, std::cos(eo) * std::sin(phi) * so, std::sin(eo) * so};
        for (int k = 0; k < 3; ++k) b.dir[k][i] = float(wi[k]), b.dir[3 + k][i] = float(wo[k]);
        double len2[2] = {0, 0};
        for (int k = 0; k < 3; ++k) len2[0] += double(b.dir[k][i]) * b.dir[k][i], len2[1] += double(b.dir[3 + k][i]) * b.dir[3 + k][i];
        if (farFromUnit[i]) farFromUnit[i] = std::abs(len2[0] - 1) + std::abs(len2[1] - 1) > 1.01e-4;
        b.slots[0][i] = float(std::sqrt(std::exp(std::log(1e-3) + uniform(rng) * std::log(500.0))));
        for (int k = 0; k < 6; ++k) reference.dir[k][i] = b.dir[k][i];
        reference.slots[0][i] = b.slots[0][i];
    }
    CHECK(b.run(*floatFirst) == 0);
    CHECK(reference.run(*precise) == 0);
    double worst = 0;
    size_t fromFloat = 0, far = 0;
    for (size_t i = 0; i < b.size(); ++i) {
        EvalResult<double> ref = b.reference(interp, i);
        REQUIRE(ref.valid);
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) {
            worst = std::max(worst, relativeError(b.out[ch][i], ref.rgb[ch]));
            same = same && b.out[ch][i] == reference.out[ch][i];
        }
        fromFloat += !same;
        if (farFromUnit[i]) {
            ++far;
            CHECK(same);
        }
    }
    MESSAGE("nearly opposite pairs: worst relative error " << worst << "; " << fromFloat << " of " << b.size()
                                                           << " lanes from the float body, " << far << " far from unit length");
    CHECK(worst < 2e-6);
    CHECK(fromFloat > b.size() / 2);
    CHECK(far > b.size() / 8);
}
