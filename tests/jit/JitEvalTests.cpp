// JIT evaluation tests: two compilers with two JITs in one process, a
// kernel's one-lane eval against its batch lanes, short and concurrent
// batches, float-subnormal cosines and the host's MXCSR, and lanes that
// model parameters make invalid.
#include "JitTestSupport.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <cfloat>
#include <thread>

using namespace facet;
using namespace facet::jittest;

TEST_CASE("two compilers with two JITs in one process give identical results") {
    Compiler a, b;
    auto ka = compile(a, kGold, "backend=simd;cache=off");
    auto kb = compile(b, kGold, "backend=simd;cache=off");
    Batch x(4099, 1), y(4099, 1);
    CHECK(x.run(*ka) == 0);
    CHECK(y.run(*kb) == 0);
    for (int c = 0; c < 3; ++c) CHECK(x.out[c] == y.out[c]);
    // The same material compiled twice in one compiler loads twice (one
    // dylib each) without symbol clashes, and releases independently.
    auto kc = compile(a, kGold, "backend=simd;cache=memory");
    kc->waitOptimized();  // a tiered compile fills the cache with its optimized code
    auto kd = compile(a, kGold, "backend=simd;cache=memory");
    CHECK(kd->origin() == "memory cache");
    kc.reset();
    Batch z(100, 1);
    z.run(*kd);
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < 100; ++i) CHECK(z.out[c][i] == x.out[c][i]);
}

TEST_CASE("a SIMD kernel's one-lane eval equals its batch lane, with few and with many input slots") {
    // Many: eleven rgb tints and a roughness, 34 slots, more than eval()
    // keeps on the stack.
    std::string many = "material many {\n    input roughness = 0.35 in 0 .. 1;\n";
    std::string f0 = "rgb(0.9, 0.6, 0.5)";
    for (int t = 0; t < 11; ++t) {
        many += fmt::format("    input tint{} = rgb(1, 0.98, 0.96) in 0 .. 1;\n", t);
        f0 += fmt::format(" * tint{}", t);
    }
    many += "    ndf = ggx(roughness * roughness);\n    masking = smith_height_correlated;\n";
    many += "    fresnel = schlick(f0 = " + f0 + ");\n}\n";
    Compiler compiler;
    for (const std::string& text : {std::string(kGold), many}) {
        // Optimized code: a one-lane call runs the one-lane body, which
        // gathers the lane's slots (4, and 34).
        auto k = compile(compiler, text, "backend=simd;cache=off;codegen=optimized");
        const int slots = k->inputCount();
        CHECK(slots == (text == many ? 34 : 4));
        // Lane 0 of every 7 is invalid (wi not unit): rgb 0 on both paths.
        Batch lanes(301, 5);
        for (size_t i = 0; i < lanes.size(); i += 7) lanes.dir[0][i] = 2.0f;
        std::mt19937 rng(9);
        std::uniform_real_distribution<float> u(0.5f, 1.0f);
        lanes.slots.resize(size_t(slots));
        for (int s = 1; s < slots; ++s)
            for (size_t i = 0; i < lanes.size(); ++i) lanes.slots[size_t(s)].push_back(u(rng));
        lanes.finish();
        std::vector<float> batchOut[3];
        for (auto& o : batchOut) o.assign(lanes.size(), -1.0f);
        float* rgb[3] = {batchOut[0].data(), batchOut[1].data(), batchOut[2].data()};
        CHECK(k->evalBatch(int64_t(lanes.size()), lanes.wi(), lanes.wo(), lanes.inputs(), rgb) == 43);
        std::vector<float> in(static_cast<size_t>(slots));
        for (size_t i = 0; i < lanes.size(); ++i) {
            float wi[3] = {lanes.dir[0][i], lanes.dir[1][i], lanes.dir[2][i]};
            float wo[3] = {lanes.dir[3][i], lanes.dir[4][i], lanes.dir[5][i]};
            for (int s = 0; s < slots; ++s) in[size_t(s)] = lanes.slots[size_t(s)][i];
            float one[3] = {-1, -1, -1};
            k->eval(wi, wo, in.data(), one);
            for (int c = 0; c < 3; ++c) CHECK(one[c] == batchOut[c][i]);
            if (i % 7 == 0) CHECK(one[0] == 0.0f);
            else CHECK(one[0] > 0.0f);
        }
        // inputs = NULL: every slot's default, as a batch without columns.
        float wi[3] = {lanes.dir[0][1], lanes.dir[1][1], lanes.dir[2][1]};
        float wo[3] = {lanes.dir[3][1], lanes.dir[4][1], lanes.dir[5][1]};
        float one[3], viaBatch[3];
        k->eval(wi, wo, nullptr, one);
        const float* wiP[3] = {&wi[0], &wi[1], &wi[2]};
        const float* woP[3] = {&wo[0], &wo[1], &wo[2]};
        float* out[3] = {&viaBatch[0], &viaBatch[1], &viaBatch[2]};
        CHECK(k->evalBatch(1, wiP, woP, nullptr, out) == 0);
        for (int c = 0; c < 3; ++c) CHECK(one[c] == viaBatch[c]);
        CHECK(one[0] > 0.0f);
    }
}

#if defined(__x86_64__)
TEST_CASE("fast kernels read a float-subnormal cosine as 0, leave MXCSR alone, and give a flushing host the same bits") {
    // The plain fast bodies read a float-subnormal n.wi or n.wo as 0
    // (BodyPlan::subnormalCosinesAsZero), as a host's FTZ/DAZ would, rather
    // than setting FTZ/DAZ for every call. With neither, fast anisotropic
    // student_t at such a mirror pair (wi = (x, y, 7.2e-43), wo = (-x, -y,
    // 7.2e-43)) comes out 2.8e5 times the reference.
    Compiler compiler;
    const unsigned host = _mm_getcsr();
    // The control bits; the exception flags (bits 0-5) are sticky status
    // that the host's own conversions may raise.
    auto control = [] { return _mm_getcsr() & ~0x3fu; };
    const std::string studentT =
        "material t { input roughness = 0.5 in 0 .. 1; ndf = student_t(alpha_x = 0.05, alpha_y = roughness, gamma = 1.8);"
        " masking = none; }";
    for (const std::string& text : {std::string(kGold), studentT})
        for (const char* spec : {"backend=simd;math=fast;cache=off", "backend=simd;math=fast;width=8;cache=off",
                                 "backend=scalar;math=fast;cache=off"}) {
            CAPTURE(text);
            CAPTURE(spec);
            auto k = compile(compiler, text, spec);
            Batch subnormal(1003, 3);
            // Every fifth lane a mirror pair, every seventh a pair, whose
            // cosines are float-subnormal.
            for (size_t i = 0; i < subnormal.size(); ++i) {
                if (i % 5 == 0) {
                    subnormal.dir[0][i] = 0.764842212f, subnormal.dir[1][i] = 0.64421767f, subnormal.dir[2][i] = 7.2e-43f;
                    subnormal.dir[3][i] = -0.764842212f, subnormal.dir[4][i] = -0.64421767f, subnormal.dir[5][i] = 7.2e-43f;
                } else if (i % 7 == 0) {
                    subnormal.dir[2][i] = 1e-40f;
                    subnormal.dir[5][i] = 3e-39f;
                }
            }
            Batch zero = subnormal, flushed = subnormal;
            for (size_t i = 0; i < zero.size(); ++i)
                for (int d : {2, 5})
                    if (std::fabs(zero.dir[d][i]) < FLT_MIN) zero.dir[d][i] = 0.0f;
            const int64_t invalid = subnormal.run(*k);
            CHECK(control() == (host & ~0x3fu));
            CHECK(zero.run(*k) == invalid);
            _mm_setcsr(host | 0x8040u);
            CHECK(flushed.run(*k) == invalid);
            _mm_setcsr(host);
            Interpreter<double> interp(k->material());
            size_t mirrorChecked = 0;
            for (size_t i = 0; i < subnormal.size(); ++i)
                for (int c = 0; c < 3; ++c) {
                    CHECK(subnormal.out[c][i] == zero.out[c][i]);
                    CHECK(flushed.out[c][i] == zero.out[c][i]);
                    if (i % 5 == 0 && text == studentT) {
                        // A cosine of 0 is the horizon: the mirror pair's
                        // value is 0 or near the reference, never 2.8e5 times it.
                        EvalResult<double> ref = subnormal.reference(interp, i);
                        CHECK(subnormal.out[c][i] <= 1.001 * ref.rgb[c]);
                        ++mirrorChecked;
                    }
                }
            if (text == studentT) CHECK(mirrorChecked == 3 * 201);
        }
}
#endif

// Quick code runs a one-lane call as a partial vector; optimized code in the
// batch entry's one-lane body (LoweringPlan::oneLaneBody), which must give
// the lane the bits it gets in a vector.
TEST_CASE("short batches (n = 1 .. 17, partial chunks, one-lane bodies) give the long batch's bits, invalid lanes and statuses") {
    Compiler compiler;
    for (const char* spec : {"backend=simd;math=exact;cache=off;codegen=quick", "backend=simd;math=fast;cache=off;codegen=quick",
                             "backend=simd;math=exact;width=4;cache=off;codegen=optimized",
                             "backend=simd;math=fast;width=16;cache=off;codegen=optimized",
                             "backend=simd;math=exact;width=8;cache=off;codegen=optimized",
                             "backend=simd;math=fast;width=8;cache=off;codegen=optimized"}) {
        std::string specText = spec;  // (CAPTURE prints a const char* as its address)
        CAPTURE(specText);
        auto k = compile(compiler, kGold, spec);
        Batch whole(17 * 18 / 2, 21), pieces(17 * 18 / 2, 21);
        // Every fifth lane invalid: a wo that is not unit.
        size_t bad = 0;
        for (size_t i = 0; i < whole.size(); i += 5, ++bad) whole.dir[5][i] = pieces.dir[5][i] = 3.0f;
        std::vector<uint8_t> wholeStatus(whole.size(), 7), pieceStatus(whole.size(), 7);
        const float* wi[3] = {whole.dir[0].data(), whole.dir[1].data(), whole.dir[2].data()};
        const float* wo[3] = {whole.dir[3].data(), whole.dir[4].data(), whole.dir[5].data()};
        const float* in[4] = {whole.slots[0].data(), nullptr, nullptr, nullptr};
        float* rgb[3] = {whole.out[0].data(), whole.out[1].data(), whole.out[2].data()};
        CHECK(k->evalBatch(int64_t(whole.size()), wi, wo, in, rgb, wholeStatus.data()) == int64_t(bad));
        size_t begin = 0;
        int64_t invalid = 0;
        for (size_t n = 1; n <= 17; begin += n, ++n) {
            const float* pwi[3] = {&pieces.dir[0][begin], &pieces.dir[1][begin], &pieces.dir[2][begin]};
            const float* pwo[3] = {&pieces.dir[3][begin], &pieces.dir[4][begin], &pieces.dir[5][begin]};
            const float* pin[4] = {&pieces.slots[0][begin], nullptr, nullptr, nullptr};
            float* prgb[3] = {&pieces.out[0][begin], &pieces.out[1][begin], &pieces.out[2][begin]};
            invalid += k->evalBatch(int64_t(n), pwi, pwo, pin, prgb, &pieceStatus[begin]);
        }
        REQUIRE(begin == whole.size());
        CHECK(invalid == int64_t(bad));
        CHECK(pieceStatus == wholeStatus);
        for (int c = 0; c < 3; ++c) CHECK(pieces.out[c] == whole.out[c]);
        for (size_t i = 0; i < whole.size(); ++i) CHECK(wholeStatus[i] == (i % 5 == 0 ? 1 : 0));
    }
}

// A combination of lobes (a layer plus a weighted lobe, the roughness of
// the latter an input) in optimized code: its one-lane body is every lobe
// at one lane, guarded as in the vector, so one-lane calls give the bits of
// the long batch too.
TEST_CASE("a combination's one-lane calls give its long batch's bits") {
    const char* text = R"(material coated {
        input roughness = 0.3 in 0 .. 1;
        lobe coat { ndf = ggx(0.05); masking = smith_height_correlated; fresnel = dielectric(1.5); }
        lobe base { ndf = beckmann(0.4); masking = smith_separable; fresnel = schlick(f0 = rgb(0.9, 0.6, 0.3));
                    diffuse = lambert(rgb(0.2, 0.3, 0.1)); }
        lobe sheen { ndf = ggx(roughness); masking = smith_height_correlated; fresnel = schlick(f0 = 0.04); }
        bsdf = layer(coat, base) + 0.5 * sheen;
    })";
    Compiler compiler;
    for (const char* spec : {"backend=simd;math=exact;cache=off;codegen=optimized",
                             "backend=simd;math=fast;width=8;cache=off;codegen=optimized"}) {
        CAPTURE(spec);
        auto k = compile(compiler, text, spec);
        REQUIRE(k->inputCount() == 1);
        Batch whole(64, 33), alone(64, 33);
        for (size_t i = 0; i < whole.size(); i += 9) whole.dir[0][i] = alone.dir[0][i] = 2.0f;  // invalid lanes
        CHECK(whole.run(*k) == 8);
        int64_t invalid = 0;
        for (size_t i = 0; i < alone.size(); ++i) invalid += alone.run(*k, i, 1);
        CHECK(invalid == 8);
        for (int c = 0; c < 3; ++c) CHECK(alone.out[c] == whole.out[c]);
        size_t lit = 0;
        for (size_t i = 0; i < whole.size(); ++i) lit += whole.out[0][i] > 0;
        CHECK(lit > 40);
    }
}

TEST_CASE("concurrent batches from two threads on one kernel equal the serial result") {
    Compiler compiler;
    auto k = compile(compiler, kGold, "backend=simd;cache=off");
    Batch serial(200000, 2), parallel(200000, 2);
    serial.run(*k);
    std::thread t1([&] { parallel.run(*k, 0, 100003); });
    std::thread t2([&] { parallel.run(*k, 100003); });
    t1.join();
    t2.join();
    for (int c = 0; c < 3; ++c) CHECK(serial.out[c] == parallel.out[c]);
}

TEST_CASE("model parameters that can be NaN or overflow float still make their lanes invalid") {
    // The plan leaves a parameter's tests out only where its range shows
    // them dead (ValueRange.h); these arguments can be NaN (sqrt of a
    // negative) or beyond float (x^2 of a finite float).
    const char* nanText = R"(material m { input x = 0.25 in -1 .. 1; ndf = ggx(sqrt(x)); })";
    const char* overflowText = R"(material m { input x = 0.5; ndf = ggx(x * x); })";
    CHECK(planLowering(checkedText(nanText).materials[0], MathVariant::exact()).param(ModelSlot::Ndf, 0).testNaN);
    CHECK(planLowering(checkedText(overflowText).materials[0], MathVariant::exact()).param(ModelSlot::Ndf, 0).testFloatRange);
    Compiler c;
    c.setCacheDir("");
    for (const char* spec : {"backend=scalar;cache=off", "backend=simd;width=16;cache=off",
                             "backend=simd;width=16;math=fast;cache=off"}) {
        CAPTURE(spec);
        Batch b(64, 3);
        for (size_t i = 0; i < b.size(); ++i) b.slots[0][i] = i % 4 == 1 ? -0.5f : 0.25f;
        CHECK(b.run(*compile(c, nanText, spec)) == 16);
        for (size_t i = 0; i < b.size(); ++i) {
            bool bad = i % 4 == 1;
            for (int ch = 0; ch < 3; ++ch) CHECK((b.out[ch][i] == 0.0f) == bad);
        }
        for (size_t i = 0; i < b.size(); ++i) b.slots[0][i] = i % 8 == 3 ? 1e20f : 0.5f;
        CHECK(b.run(*compile(c, overflowText, spec)) == 8);
    }
}
