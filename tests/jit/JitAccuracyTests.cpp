// JIT accuracy tests: kernels against the double interpreter where
// float arithmetic is most at risk: Fresnel near a critical angle or
// N = 1, student_t's tabulated Smith Lambda, Schlick's 1 - wo.h near
// mirror directions, Beckmann's double body at near-opposite directions,
// and GGX's Smith root for small and large alpha.
#include "JitTestSupport.h"

#include "Lowering.h"
#include "ReferenceComparison.h"

using namespace facet;
using namespace facet::jittest;

// Exact mode evaluates a constant-parameter dielectric/conductor Fresnel in
// float only away from its ill-conditioned regions (the critical angle of
// k = 0, eta < 1; N -> 1): these materials sit at or near them, and a sweep
// of wi.h across the critical angle (mirror pairs, h = n) must stay within
// the exact-mode accuracy of the rest of the kernel (1.7e-5 when the
// conductor with eta = 0.05, k = 0 was wrongly taken to float).
TEST_CASE("exact Fresnel near a critical angle or N = 1 keeps exact-mode accuracy") {
    const char* materials[] = {
        "material m { ndf = ggx(0.3); fresnel = conductor(eta = 0.05, k = rgb(0, 0.5, 8)); }",
        "material m { ndf = ggx(0.3); fresnel = conductor(eta = 1.02, k = 0.01); }",
        "material m { ndf = ggx(0.3); fresnel = dielectric(rgb(0.05, 0.7, 1.005)); }",
    };
    Compiler c;
    double worst = 0;
    for (const char* text : materials) {
        CheckedProgram p = checkedText(text);
        Interpreter<double> interp(p.materials[0]);
        auto k = compile(c, text, "backend=scalar;math=exact");
        // cos(theta) from 0.998 to 1 (eta = 0.05: critical at 0.99875) and
        // across the TIR edges of eta = 0.7 (0.714) in small steps.
        for (double cosT = 0.6; cosT < 1.0; cosT += cosT < 0.99 ? 1e-3 : 1e-6) {
            float sinT = float(std::sqrt(1 - cosT * cosT));
            float wi[3] = {sinT, 0, float(cosT)}, wo[3] = {-sinT, 0, float(cosT)}, got[3];
            k->eval(wi, wo, nullptr, got);
            double wiD[3] = {wi[0], wi[1], wi[2]}, woD[3] = {wo[0], wo[1], wo[2]};
            EvalResult<double> want = interp.eval(wiD, woD, nullptr);
            REQUIRE(want.valid);
            for (int ch = 0; ch < 3; ++ch) {
                double rel = relativeError(got[ch], want.rgb[ch]);
                worst = std::max(worst, rel);
                INFO(text, " cos ", cosT, " ch ", ch, " got ", got[ch], " want ", want.rgb[ch]);
                CHECK(rel < 2e-6);
            }
        }
    }
    MESSAGE("worst relative error near critical angles and N = 1: " << worst);
}

// student_t's Smith Lambda is a table (LambdaTable.h) that the kernel embeds
// and interpolates itself: each Smith form, iso- and anisotropic, with a
// per-lane alpha, scalar and SIMD, against the interpreter on directions
// down to 0.01 degree above the horizon.
TEST_CASE("student_t with Smith maskings: the kernel's tabulated Lambda agrees with the interpreter's") {
    const char* maskings[] = {"smith_separable", "smith_height_correlated", "smith_direction_correlated",
                              "smith_height_direction_correlated"};
    const char* ndfs[] = {"student_t(alpha, 1.7)", "student_t(alpha_x = alpha, alpha_y = 0.05, gamma = 9)"};
    const double thetas[] = {0, 0.3, 1.0, 1.4, 1.55, 1.5706};
    Compiler c;
    double worst = 0;
    int compared = 0;
    for (const char* ndf : ndfs)
        for (const char* masking : maskings) {
            std::string text = std::string("material m { input alpha = 0.3 in 0.001 .. 1; ndf = ") + ndf +
                               "; masking = " + masking + "; }";
            CheckedProgram p = checkedText(text);
            Interpreter<double> interp(p.materials[0]);
            for (const char* spec : {"backend=scalar;math=exact;cache=off", "backend=simd;math=exact;cache=off"}) {
                auto k = compile(c, text, spec);
                for (float alpha : {0.002f, 0.08f, 0.6f, 1.0f})
                    for (double ti : thetas)
                        for (double to : thetas) {
                            float wi[3] = {float(std::sin(ti)), 0, float(std::cos(ti))};
                            float wo[3] = {float(-std::sin(to) * 0.6), float(std::sin(to) * 0.8), float(std::cos(to))};
                            float got[3];
                            k->eval(wi, wo, &alpha, got);
                            double wiD[3] = {wi[0], wi[1], wi[2]}, woD[3] = {wo[0], wo[1], wo[2]}, in = alpha;
                            EvalResult<double> want = interp.eval(wiD, woD, &in);
                            REQUIRE(want.valid);
                            double rel = relativeError(got[0], want.rgb[0]);
                            INFO(text, " ", spec, " alpha ", alpha, " theta_i ", ti, " theta_o ", to, " got ", got[0],
                                 " want ", want.rgb[0]);
                            CHECK(rel < 1e-5);
                            worst = std::max(worst, rel);
                            ++compared;
                        }
            }
        }
    MESSAGE("student_t x Smith, JIT against the interpreter: ", compared, " values, worst relative error ", worst);
}

// Mirror directions wi = (s, 0, c), wo = (-s, 0, c): wo.h = c, q = 1 - c
// from 1e-7 to 0.4. Returns the worst relative error of the red channel
// against the interpreter over `kernels`.
static double worstNearMirror(const std::string& text, std::initializer_list<const char*> kernels) {
    CheckedProgram p = checkedText(text);
    Interpreter<double> interp(p.materials[0]);
    Compiler c;
    c.setCacheDir("");
    Batch b(4096, 11);
    for (size_t i = 0; i < b.size(); ++i) {
        double q = 1e-7 * std::pow(4e6, double(i) / double(b.size() - 1));
        double cosT = 1 - q, sinT = std::sqrt(q * (2 - q));
        b.dir[0][i] = float(sinT), b.dir[1][i] = 0, b.dir[2][i] = float(cosT);
        b.dir[3][i] = float(-sinT), b.dir[4][i] = 0, b.dir[5][i] = float(cosT);
    }
    double worst = 0;
    for (const char* spec : kernels) {
        auto k = compile(c, text, spec);
        CHECK(b.run(*k) == 0);
        for (size_t i = 0; i < b.size(); ++i) {
            EvalResult<double> want = b.reference(interp, i);
            REQUIRE(want.valid);
            worst = std::max(worst, relativeError(b.out[0][i], want.rgb[0]));
        }
    }
    return worst;
}

TEST_CASE("fast kernels: Schlick's 1 - wo.h from |wi + wo| stays within fast accuracy near wi = wo") {
    // Fast bodies take q = 1 - wo.h as 1 - |wi + wo|/2 when F is Schlick's
    // with f0 >= 1e-6 (LoweringPlan.cpp, HalfVectorForm::Estimated): q then
    // has an absolute error ~2e-7, which costs F at most 4 dq/q relative,
    // ~1e-5 at f0 = 1e-6 (q ~ 0.08). f0 = 0 keeps the cancellation-free
    // form, whose error stays at float rounding as q -> 0 (the cheap form
    // would give 5 dq/q there, 4e-5 at q = 0.025 where the F >= 1e-8 guard
    // stops). The plain body of the scalar kernel and the float-first SIMD
    // body, with the plain fast body for the lanes it distrusts.
    for (const char* f0 : {"1e-6", "0"}) {
        std::string text = fmt::format("material m {{ ndf = ggx(0.5); fresnel = schlick(f0 = {}); }}", f0);
        double worst = worstNearMirror(text, {"backend=simd;width=16;math=fast;cache=off", "backend=scalar;math=fast;cache=off"});
        MESSAGE("schlick f0 = " << std::string(f0) << ": worst relative error near wi = wo " << worst);
        CHECK(worst < (std::string(f0) == "0" ? 5e-6 : 2e-5));
    }
}

TEST_CASE("exact kernels: Schlick's 1 - wo.h from |wi + wo| in double stays at float rounding near wi = wo") {
    // The double body takes q = 1 - |wi + wo|/2 in double when F is
    // Schlick's with f0 >= 1e-12 (HalfVectorForm::Direct): dq ~ 2e-16 moves
    // F by at most 4 dq/q ~ 2e-13 at f0 = 1e-12 (q ~ 5e-3), where a float
    // |wi + wo| would give ~5e-5: the values stay within the output's float
    // rounding. The scalar kernel and a SIMD one without the float body.
    for (const char* f0 : {"1e-12", "0.04"}) {
        std::string text = fmt::format("material m {{ ndf = ggx(0.5); fresnel = schlick(f0 = {}); }}", f0);
        CheckedProgram p = checkedText(text);
        REQUIRE(planLowering(p.materials[0], MathVariant::exact()).scalarBody.halfVector == HalfVectorForm::Direct);
        for (const char* spec : {"backend=scalar;cache=off", "backend=simd;width=16;cache=off;float_first=off"}) {
            double worst = worstNearMirror(text, {spec});
            MESSAGE("schlick f0 = " << std::string(f0) << ", " << std::string(spec) << ": worst relative error near wi = wo " << worst);
            CHECK(worst < 1e-7);
        }
    }
}

TEST_CASE("beckmann's double body: near-opposite directions below float's |wi + wo|^2 range") {
    // Beckmann's double body takes D from wi + wo in double. With a constant
    // dielectric term, |wi + wo|, wo.h and 1 - wo.h are computed in float
    // (HalfVectorForm::InFloat), with |wi + wo|^2 clamped to FLT_MIN; with
    // Schlick's f0 = 0.04, in double (HalfVectorForm::Direct). Directions
    // grazing from opposite sides, wi + wo = (0, 0, 2z), reach |wi + wo|^2 =
    // 4e-74 where float has only 0: the values must still be the
    // interpreter's, on every exact backend.
    for (const char* fresnel : {"dielectric(1.5)", "schlick(f0 = 0.04)"}) {
        std::string text =
            fmt::format("material m {{ ndf = beckmann(0.3); masking = smith_separable; fresnel = {}; }}", fresnel);
        CheckedProgram p = checkedText(text);
        Interpreter<double> interp(p.materials[0]);
        Compiler c;
        c.setCacheDir("");
        const float zs[] = {1e-3f, 1e-10f, 1e-19f, 1e-20f, 1e-25f, 1e-30f, 1e-37f};
        for (const char* spec :
             {"backend=scalar;cache=off", "backend=simd;width=16;cache=off", "backend=simd;width=8;cache=off"}) {
            auto k = compile(c, text, spec);
            Batch b(16, 5);
            for (size_t i = 0; i < b.size(); ++i) {
                float z = zs[i % std::size(zs)], phi = 0.4f * float(i);
                b.dir[0][i] = std::cos(phi), b.dir[1][i] = std::sin(phi), b.dir[2][i] = z;
                b.dir[3][i] = -std::cos(phi), b.dir[4][i] = -std::sin(phi), b.dir[5][i] = z;
            }
            CHECK(b.run(*k) == 0);
            for (size_t i = 0; i < b.size(); ++i) {
                EvalResult<double> want = b.reference(interp, i);
                REQUIRE(want.valid);
                REQUIRE(want.rgb[0] > 0);
                double rel = std::abs(b.out[0][i] - want.rgb[0]) / want.rgb[0];
                INFO(fresnel, " ", std::string(spec), " n.w = ", b.dir[2][i], " got ", b.out[0][i], " want ", want.rgb[0]);
                CHECK(rel < 2e-6);
            }
        }
    }
}

TEST_CASE("GGX's Smith root from n.v alone only where the plan's alpha range allows it") {
    // R^2 = z^2 + a^2 (1 - z^2) needs a^2 <= 2 (GgxEmitter): near the
    // normal, 1 - z^2 carries z's rounding scaled by a^2 (that form gives
    // 2.3e-6 at alpha up to 10, 2.0e-5 up to 40). A roughness in 0 .. 1
    // squared takes it; an alpha input up to 40 keeps the components. Both stay within exact accuracy on every
    // backend, near the normal and at random directions.
    const char* small = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    const char* large = R"(material m {
        input alpha = 1 in 0 .. 40;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    CHECK(planLowering(checkedText(small).materials[0], MathVariant::exact()).param(ModelSlot::Ndf, 0).range.hi < 1.001);
    CHECK(planLowering(checkedText(large).materials[0], MathVariant::exact()).param(ModelSlot::Ndf, 0).range.hi >= 40);
    for (const char* text : {small, large}) {
        CheckedProgram program = checkedText(text);
        Interpreter<double> interp(program.materials[0], nullptr);
        Compiler c;
        c.setCacheDir("");
        const bool isLarge = text == large;
        // Half the lanes with both directions within 0.1 rad of the normal.
        Batch b(4096, 31);
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> uniform(0, 1);
        for (size_t i = 0; i < b.size(); i += 2)
            for (int d = 0; d < 2; ++d) {
                double theta = 0.1 * uniform(rng), phi = 6.283185307179586 * uniform(rng);
                b.dir[3 * d][i] = float(std::sin(theta) * std::cos(phi));
                b.dir[3 * d + 1][i] = float(std::sin(theta) * std::sin(phi));
                b.dir[3 * d + 2][i] = float(std::cos(theta));
            }
        for (size_t i = 0; i < b.size(); ++i)
            b.slots[0][i] = isLarge ? float(1 + 39 * uniform(rng)) : float(uniform(rng));
        for (const char* spec : {"backend=scalar;cache=off", "backend=simd;width=16;cache=off", "backend=simd;width=8;cache=off"}) {
            INFO(spec);
            auto k = compile(c, text, spec);
            CHECK(b.run(*k) == 0);
            double worst = 0;
            for (size_t i = 0; i < b.size(); ++i) {
                EvalResult<double> ref = b.reference(interp, i);
                REQUIRE(ref.valid);
                for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, relativeError(b.out[ch][i], ref.rgb[ch]));
            }
            std::string label = std::string(spec) + (isLarge ? ", alpha up to 40" : ", roughness squared");
            MESSAGE(label << ": worst relative error " << worst);
            CHECK(worst < 2e-6);
        }
    }
}
