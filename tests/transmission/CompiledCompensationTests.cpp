// The compiled compensation of whole-sphere lobes (energy = kulla_conty;
// compiler/lowering/WholeSphereEnergy.cpp) against the double reference
// (DielectricEnergy.h): eval over the whole sphere for interfaces seen from
// either side and thin sheets, every scatter mode and both transports;
// the compiled sampler against the reference's for the same u, both
// branches of the mixture; the white furnace from both sides measured with
// the compiled sampler alone; SPEC 11's hard cases; and the one case the
// compiled backends still refuse.
#include "TransmissionSupport.h"

#include "DielectricEnergy.h"
#include "HardCases.h"
#include "Kernel.h"

#include <limits>

namespace {

using namespace transmission_test;

std::unique_ptr<facet::Kernel> compileKernel(facet::Compiler& compiler, const std::string& text,
                                             const std::string& spec) {
    facet::CompileOptions options;
    REQUIRE(facet::CompileOptions::parse(spec, options) == "");
    facet::DiagnosticEngine diags;
    auto k = compiler.compileText(text, "frosted.mat", "", options, diags);
    INFO(text, "\n", spec, "\n", diags.str());
    REQUIRE(k);
    return k;
}

std::string compensated(const std::string& ndf, const std::string& masking, const std::string& fresnel,
                        const std::string& scatter) {
    return fmt::format("material t {{ ndf = {}; masking = {}; fresnel = dielectric({}); {} energy = kulla_conty; }}\n",
                       ndf, masking, fresnel, scatter);
}

// The materials: GGX and Beckmann interfaces from outside (eta > 1) and from
// the denser side (eta < 1), a rough and a smooth one, the three scatter
// modes, and thin sheets (rgb eta).
std::vector<std::string> compensatedMaterials() {
    return {
        compensated("ggx(0.6)", "smith_height_correlated", "1.5", "scatter = both;"),
        compensated("ggx(0.25)", "smith_separable", "0.7", "scatter = both;"),
        compensated("beckmann(0.8)", "smith_height_correlated", "1.33", "scatter = transmit;"),
        compensated("ggx(0.9)", "smith_height_correlated", "2.4", "scatter = reflect;"),
        compensated("ggx(0.7)", "smith_height_correlated", "rgb(1.3, 1.5, 2.4)", "thin = true; scatter = both;"),
        compensated("beckmann(0.5)", "smith_separable", "1.45", "thin = true; scatter = transmit;"),
    };
}

// |got - want| / max(|want|, 1e-30), the worst channel.
double channelError(const float got[3], const std::array<double, 3>& want) {
    double worst = 0;
    for (int ch = 0; ch < 3; ++ch)
        worst = std::max(worst, std::abs(got[ch] - want[ch]) / std::max(std::abs(want[ch]), 1e-30));
    return worst;
}

TEST_SUITE("compiled whole-sphere compensation") {

TEST_CASE("eval: interfaces from either side and thin sheets, every scatter mode, both transports, against the reference") {
    facet::Compiler compiler;
    double worstExact = 0, worstFast = 0;
    int configs = 0;
    for (const std::string& text : compensatedMaterials())
        for (facet::Transport transport : {facet::Transport::Radiance, facet::Transport::Importance}) {
            Reference ref(text, transport);
            std::string uncompensated = text;
            uncompensated.erase(uncompensated.find(" energy = kulla_conty;"), 22);
            Reference plain(uncompensated, transport);
            const std::string t = transport == facet::Transport::Importance ? ";transport=importance" : "";
            for (const char* backend : {"simd", "scalar"}) {
                auto exact = compileKernel(compiler, text, fmt::format("backend={};math=exact;cache=memory{}", backend, t));
                auto fast = compileKernel(compiler, text, fmt::format("backend={};math=fast;cache=memory{}", backend, t));
                std::mt19937_64 rng(17 + configs);
                double e = 0, f = 0, withCompensation = 0;
                for (int n = 0; n < 400; ++n) {
                    V3 a = uniformSphere(rng), b = uniformSphere(rng);
                    float wi[3] = {float(a.x), float(a.y), float(a.z)}, wo[3] = {float(b.x), float(b.y), float(b.z)};
                    float gotE[3], gotF[3];
                    exact->eval(wi, wo, nullptr, gotE);
                    fast->eval(wi, wo, nullptr, gotF);
                    double wiD[3] = {wi[0], wi[1], wi[2]}, woD[3] = {wo[0], wo[1], wo[2]};
                    facet::EvalResult<double> want = ref.interp->eval(wiD, woD, nullptr);
                    REQUIRE(want.valid);
                    INFO(text, backend, t, " wi ", wi[0], " ", wi[1], " ", wi[2], " wo ", wo[0], " ", wo[1], " ",
                         wo[2], " got ", gotE[0], " want ", want.rgb[0]);
                    REQUIRE(std::isfinite(channelError(gotE, want.rgb)));
                    e = std::max(e, channelError(gotE, want.rgb));
                    f = std::max(f, channelError(gotF, want.rgb));
                    // The pairs whose value the compensation changes by more
                    // than the bound: most of the sphere, away from the
                    // single-scattering peaks (a reflect-only lobe keeps
                    // the fewest: 93 of the pairs at eta 2.4).
                    facet::EvalResult<double> single = plain.interp->eval(wiD, woD, nullptr);
                    withCompensation += relDiff(single.rgb[0], want.rgb[0]) > 1e-3;
                }
                INFO(text, backend, t, " exact ", e, " fast ", f);
                CHECK(e <= 1e-5);
                CHECK(f <= 1e-3);
                CHECK(withCompensation > 50);
                worstExact = std::max(worstExact, e), worstFast = std::max(worstFast, f);
                ++configs;
            }
        }
    MESSAGE(configs << " configurations; worst relative error over the sphere: exact " << worstExact << ", fast "
                    << worstFast);
    CHECK(configs == 24);
}


// The compiled sampler against the reference's for the same u: below the
// compensation's probability both draw the cosine lobe, above it the
// single scattering; the same wi, pdf (the mixture's) and weight.
TEST_CASE("the compiled sampler draws what the reference draws, from both branches of the mixture") {
    facet::Compiler compiler;
    int compared = 0, fromCompensation = 0, branchFlips = 0;
    double worstWi = 0, worstPdf = 0, worstWeight = 0, worstPdfCall = 0;
    for (const std::string& text : compensatedMaterials()) {
        Reference reference(text);
        auto ref = compileKernel(compiler, text, "backend=interp;cache=memory");
        for (const char* spec : {"backend=simd;math=exact;cache=memory", "backend=scalar;math=exact;cache=memory"}) {
            auto k = compileKernel(compiler, text, spec);
            REQUIRE(k->samplerTier() == "jit");
            std::mt19937_64 rng(29 + compared);
            std::uniform_real_distribution<float> uniform(0, 1);
            for (int n = 0; n < 500; ++n) {
                V3 w = uniformSphere(rng);
                float wo[3] = {float(w.x), float(w.y), float(w.z)};
                float u[3] = {uniform(rng), uniform(rng), uniform(rng)};
                float wiR[3], wiK[3], pdfR, pdfK, wR[3], wK[3];
                bool okR = ref->sample(wo, u, nullptr, wiR, &pdfR, wR);
                bool okK = k->sample(wo, u, nullptr, wiK, &pdfK, wK);
                INFO(text, spec, " wo ", wo[0], " ", wo[1], " ", wo[2], " u ", u[0], " ", u[1], " ", u[2]);
                REQUIRE(okR == okK);
                if (!(pdfR > 0) || !(pdfK > 0)) {
                    CHECK((pdfR > 0) == (pdfK > 0));
                    continue;
                }
                if ((wiR[2] > 0) != (wiK[2] > 0)) {  // u[0] at a branch's edge, rounded either way
                    ++branchFlips;
                    continue;
                }
                const V3 woV{wo[0], wo[1], wo[2]};
                fromCompensation += u[0] < facet::compensationProbability(reference.lobe, woV);
                double dWi = 0;
                for (int d = 0; d < 3; ++d) dWi = std::max(dWi, double(std::abs(wiR[d] - wiK[d])));
                worstWi = std::max(worstWi, dWi);
                worstPdf = std::max(worstPdf, relDiff(pdfR, pdfK));
                for (int ch = 0; ch < 3; ++ch) worstWeight = std::max(worstWeight, relDiff(wR[ch], wK[ch]));
                worstPdfCall = std::max(worstPdfCall, relDiff(k->pdf(wiK, wo, nullptr), pdfK));
                CHECK(dWi <= 1e-5);
                CHECK(relDiff(pdfR, pdfK) <= 1e-4);
                ++compared;
            }
        }
    }
    MESSAGE(compared << " samples (" << fromCompensation << " from the compensation): wi within " << worstWi
                     << ", pdf " << worstPdf << ", weight " << worstWeight << ", pdf() at the sample " << worstPdfCall
                     << "; " << branchFlips << " branch flips");
    CHECK(fromCompensation * 10 >= compared);  // both branches are exercised
    CHECK(worstWeight <= 1e-4);
    CHECK(worstPdfCall <= 1e-4);
    CHECK(branchFlips * 1000 <= compared);
}

// The compiled kernels alone: the mean sampler weight at wo is R + T (in
// importance transport, power), 1 within SPEC 11's 1% for a non-absorbing
// interface from both sides; without compensation the same estimate falls
// short, which the estimate must see (else it could not fail).
TEST_CASE("white furnace from both sides with the compiled sampler: 1 within 1% with compensation, less without") {
    facet::Compiler compiler;
    const std::string text = compensated("ggx(0.8)", "smith_height_correlated", "1.5", "scatter = both;");
    std::string plain = text;
    plain.erase(plain.find(" energy = kulla_conty;"), 22);
    auto k = compileKernel(compiler, text, "backend=simd;math=exact;cache=memory;transport=importance");
    auto kPlain = compileKernel(compiler, plain, "backend=simd;math=exact;cache=memory;transport=importance");
    const int64_t n = 1 << 18;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<float> uniform(0, 1);
    std::vector<float> u[3], wiOut[3], pdf(n), weight[3];
    for (int d = 0; d < 3; ++d) {
        u[d].resize(n);
        for (float& x : u[d]) x = uniform(rng);
        wiOut[d].resize(n), weight[d].resize(n);
    }
    double worst = 0, leastLoss = 1;
    for (double theta : {0.0, 45.0, 80.0, 100.0, 135.0, 180.0}) {
        V3 w = direction(theta, 0.3);
        std::vector<float> wo[3] = {std::vector<float>(n, float(w.x)), std::vector<float>(n, float(w.y)),
                                    std::vector<float>(n, float(w.z))};
        auto meanWeight = [&](const facet::Kernel& kernel) {
            const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
            const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
            float* wiP[3] = {wiOut[0].data(), wiOut[1].data(), wiOut[2].data()};
            float* wP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
            REQUIRE(kernel.sampleBatch(n, woP, uP, nullptr, wiP, pdf.data(), wP) == 0);
            double sum = 0;
            for (int64_t i = 0; i < n; ++i) sum += weight[0][size_t(i)];
            return sum / double(n);
        };
        double albedo = meanWeight(*k), single = meanWeight(*kPlain);
        INFO("theta_o ", theta, ": R + T ", albedo, " without compensation ", single);
        CHECK(std::abs(albedo - 1) <= 0.01);
        worst = std::max(worst, std::abs(albedo - 1));
        leastLoss = std::min(leastLoss, 1 - single);
        CHECK(single < albedo);
    }
    MESSAGE("compiled furnace, GGX alpha 0.8, eta 1.5, both sides: |1 - (R + T)| <= " << worst
                                                                                    << "; uncompensated loss >= " << leastLoss);
    CHECK(leastLoss > 0.01);
}

TEST_CASE("SPEC 11's hard cases with compensation on every backend and math mode: finite, non-negative, valid") {
    facet::Compiler compiler;
    int lanes = 0;
    for (const std::string& text : {compensatedMaterials()[0], compensatedMaterials()[4]}) {
        facet::DiagnosticEngine diags;
        facet::CheckedProgram program = facet::loadProgramText(text, "hard.mat", diags);
        REQUIRE_FALSE(diags.hasErrors());
        const facet::CheckedMaterial& m = *program.find("t");
        facet::Interpreter<double> ref(m);
        std::vector<facet::HardCase> hard = facet::hardCases(m);
        for (const char* spec : {"backend=scalar;math=exact", "backend=simd;math=exact", "backend=scalar;math=fast",
                                 "backend=simd;math=fast"}) {
            auto k = compileKernel(compiler, text, std::string(spec) + ";cache=memory");
            const bool exact = std::string(spec).find("exact") != std::string::npos;
            for (const facet::HardCase& h : hard) {
                if (h.invalidInput) continue;
                float wi[3] = {float(h.wi[0]), float(h.wi[1]), float(h.wi[2])};
                float wo[3] = {float(h.wo[0]), float(h.wo[1]), float(h.wo[2])}, got[3];
                k->eval(wi, wo, nullptr, got);
                INFO(spec, " ", facet::describeCase(m, h), " got ", got[0], " ", got[1], " ", got[2]);
                for (float x : got) REQUIRE((std::isfinite(x) && x >= 0));
                double wiD[3] = {wi[0], wi[1], wi[2]}, woD[3] = {wo[0], wo[1], wo[2]};
                facet::EvalResult<double> want = ref.eval(wiD, woD, nullptr);
                // Exact kernels hold the differential bound wherever the
                // compensation is most of the value (the single-scattering
                // part's conditioning is transmission_compiled's).
                if (exact && want.valid && want.rgb[0] > 0 && want.rgb[0] < 1e30) CHECK(channelError(got, want.rgb) <= 1e-3);
                ++lanes;
            }
        }
    }
    MESSAGE(lanes << " hard-case lanes");
    CHECK(lanes > 200);
}

TEST_CASE("the compiled backends refuse a compensated sheet whose index is an input, naming it") {
    facet::Compiler compiler;
    facet::CompileOptions simd;
    REQUIRE(facet::CompileOptions::parse("backend=simd;cache=memory", simd) == "");
    const std::string text = "material t { input ior = 1.5 in 1 .. 3; ndf = ggx(0.3); masking = smith_height_correlated; "
                             "fresnel = dielectric(ior); thin = true; energy = kulla_conty; }\n";
    facet::DiagnosticEngine diags;
    CHECK(compiler.compileText(text, "sheet.mat", "", simd, diags) == nullptr);
    INFO(diags.str());
    CHECK(diags.str().find("lobe 't' scatters below the surface (thin = true) with energy = kulla_conty and an index "
                           "that reads input 'ior'") != std::string::npos);
    CHECK(diags.str().find("--set ior=VALUE") != std::string::npos);
    // Bound, it compiles.
    REQUIRE(facet::CompileOptions::parse("backend=simd;cache=memory;set.ior=1.4", simd) == "");
    facet::DiagnosticEngine bound;
    CHECK(compiler.compileText(text, "sheet.mat", "", simd, bound) != nullptr);
}

}  // TEST_SUITE

}  // namespace
