// The compiled whole-sphere lobes (compiler/lowering/LaneDielectric.cpp)
// against the double reference (DielectricLobe.h): every NDF of the catalog
// with a Smith Lambda x every Smith form, the interface from either side
// (eta and 1/eta) and the thin sheet, on directions drawn over the whole
// sphere, scalar and SIMD, exact and fast; importance transport; SPEC 11's
// hard cases on every backend and math mode (no NaN, Inf or negative value;
// exact within docs/numerics.md's bound). Their compensation:
// CompiledCompensationTests.cpp.
#include "TransmissionSupport.h"

#include "HardCases.h"
#include "Kernel.h"

#include <limits>

namespace {

using namespace transmission_test;

struct Compiled {
    facet::Compiler compiler;
    std::unique_ptr<facet::Kernel> compile(const std::string& text, const std::string& spec) {
        facet::CompileOptions options;
        REQUIRE(facet::CompileOptions::parse(spec, options) == "");
        facet::DiagnosticEngine diags;
        auto k = compiler.compileText(text, "glass.mat", "", options, diags);
        INFO(text, "\n", spec, "\n", diags.str());
        REQUIRE(k);
        return k;
    }
};

// The catalog's NDFs with a Smith Lambda (closed or tabulated), each by
// its examples, as material statements (inputs declared first).
std::vector<std::pair<std::string, std::string>> smithNdfs() {
    std::vector<std::pair<std::string, std::string>> out;
    for (const facet::ModelInfo* info : facet::catalogSlot(facet::ModelSlot::Ndf)) {
        const facet::NdfEntry& ndf = facet::ndfEntry(*info);
        if (ndf.wholeLobe || !(ndf.smith || ndf.tabulatedLambda)) continue;
        for (const facet::ModelExample& ex : ndf.examples) out.push_back({ex.inputs + " " + ex.extra, ex.stmt});
    }
    return out;
}

std::vector<std::string> smithMaskings() {
    std::vector<std::string> out;
    for (const facet::ModelInfo* info : facet::catalogSlot(facet::ModelSlot::Masking))
        if (facet::maskingEntry(*info).transmission) out.push_back(info->name);
    return out;
}

// |got - want| / max(|want|, 1e-30) per channel, the worst.
double channelError(const float got[3], const std::array<double, 3>& want) {
    double worst = 0;
    for (int ch = 0; ch < 3; ++ch)
        worst = std::max(worst, std::abs(got[ch] - want[ch]) / std::max(std::abs(want[ch]), 1e-30));
    return worst;
}

// The kernel against the reference on `count` pairs drawn over the whole
// sphere (rounded to float, as a host passes them); the worst relative error.
double worstOverSphere(const facet::Kernel& k, const facet::Interpreter<double>& ref,
                       const std::vector<double>& slots, int count, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::vector<float> in(slots.begin(), slots.end());
    double worst = 0;
    for (int n = 0; n < count; ++n) {
        V3 a = uniformSphere(rng), b = uniformSphere(rng);
        float wi[3] = {float(a.x), float(a.y), float(a.z)}, wo[3] = {float(b.x), float(b.y), float(b.z)}, got[3];
        k.eval(wi, wo, in.data(), got);
        double wiD[3] = {wi[0], wi[1], wi[2]}, woD[3] = {wo[0], wo[1], wo[2]};
        facet::EvalResult<double> want = ref.eval(wiD, woD, slots.data());
        REQUIRE(want.valid);
        double e = channelError(got, want.rgb);
        INFO("wi ", wi[0], " ", wi[1], " ", wi[2], " wo ", wo[0], " ", wo[1], " ", wo[2], " got ", got[0], " want ",
             want.rgb[0]);
        REQUIRE(std::isfinite(e));
        worst = std::max(worst, e);
    }
    return worst;
}

TEST_SUITE("compiled whole-sphere lobes") {

TEST_CASE("every NDF with a Smith Lambda x Smith form x eta and its inverse, thin sheet too: JIT against the reference") {
    Compiled c;
    double worstExact = 0, worstFast = 0;
    int configs = 0;
    for (const auto& [inputs, ndf] : smithNdfs())
        for (const std::string& masking : smithMaskings())
            for (const char* lobe : {"fresnel = dielectric(1.5); scatter = both;",
                                     "fresnel = dielectric(0.75); scatter = both;",
                                     "fresnel = dielectric(rgb(1.3, 1.5, 2.4)); thin = true; scatter = both;"}) {
                std::string text = fmt::format("material t {{ {} ndf = {}; masking = {}; {} }}\n", inputs, ndf,
                                               masking, lobe);
                facet::DiagnosticEngine diags;
                facet::CheckedProgram program = facet::loadProgramText(text, "glass.mat", diags);
                // An example whose tabulated Lambda's shape is an input has
                // no Smith masking (the checker says so); the NDF's other
                // examples cover it.
                if (diags.hasErrors() && diags.str().find("is tabulated") != std::string::npos) continue;
                INFO(text, diags.str());
                REQUIRE_FALSE(diags.hasErrors());
                const facet::CheckedMaterial& m = *program.find("t");
                facet::Interpreter<double> ref(m);
                const std::vector<double> slots = m.defaultSlots();
                // Every form with SIMD; scalar on the height-correlated one.
                const bool scalar = masking == "smith_height_correlated";
                for (const char* backend : {"simd", "scalar"}) {
                    if (std::string(backend) == "scalar" && !scalar) continue;
                    auto exact = c.compile(text, fmt::format("backend={};math=exact;cache=memory", backend));
                    auto fast = c.compile(text, fmt::format("backend={};math=fast;cache=memory", backend));
                    double e = worstOverSphere(*exact, ref, slots, 300, 7 + configs);
                    double f = worstOverSphere(*fast, ref, slots, 300, 7 + configs);
                    INFO(backend, " exact ", e, " fast ", f);
                    CHECK(e <= 1e-5);
                    CHECK(f <= 1e-3);
                    worstExact = std::max(worstExact, e), worstFast = std::max(worstFast, f);
                    ++configs;
                }
            }
    MESSAGE(configs << " configurations; worst relative error over the sphere: exact " << worstExact << ", fast "
                    << worstFast);
    CHECK(configs >= 60);
}

TEST_CASE("importance transport and scatter = transmit / reflect: the kernel follows the reference") {
    Compiled c;
    for (const char* scatter : {"both", "transmit"})
        for (facet::Transport transport : {facet::Transport::Radiance, facet::Transport::Importance}) {
            std::string text = glass("beckmann(0.4)", 1.33, "smith_separable", scatter);
            Reference ref(text, transport);
            std::string spec = std::string("backend=simd;math=exact;cache=memory") +
                               (transport == facet::Transport::Importance ? ";transport=importance" : "");
            auto k = c.compile(text, spec);
            INFO(std::string(scatter), " ", spec);
            CHECK(worstOverSphere(*k, *ref.interp, {}, 400, 91) <= 1e-5);
        }
    // A thin sheet that only transmits: nothing on wo's side.
    std::string sheet = "material t { ndf = ggx(0.2); masking = smith_height_correlated; fresnel = dielectric(1.5); "
                        "thin = true; scatter = transmit; }\n";
    auto k = c.compile(sheet, "backend=simd;math=exact;cache=memory");
    float wi[3] = {0.3f, 0.1f, 0.948683f}, below[3] = {0.3f, 0.1f, -0.948683f}, wo[3] = {-0.2f, 0.0f, 0.979796f};
    float same[3], across[3];
    k->eval(wi, wo, nullptr, same);
    k->eval(below, wo, nullptr, across);
    CHECK(same[0] == 0.0f);
    CHECK(across[0] > 0.0f);
    Reference ref(sheet);
    CHECK(relDiff(across[0], ref.f({0.3, 0.1, -0.948683}, {-0.2, 0.0, 0.979796})) <= 1e-5);
}

TEST_CASE("SPEC 11's hard cases on every backend and math mode: finite, non-negative, exact within the bound") {
    Compiled c;
    const char* materials[] = {
        "material t { ndf = ggx(0.3); masking = smith_height_correlated; fresnel = dielectric(1.5); scatter = both; }\n",
        "material t { ndf = beckmann(0.05); masking = smith_separable; fresnel = dielectric(1.0001); scatter = both; }\n",
        "material t { ndf = ggx(0.8); masking = smith_height_direction_correlated; fresnel = dielectric(0.7); scatter = both; }\n",
        "material t { input ior = 1.5 in 1 .. 3; ndf = student_t(0.4, 2.5); masking = smith_height_correlated; "
        "fresnel = dielectric(ior); scatter = transmit; }\n",
        "material t { ndf = ggx(0.5); masking = smith_height_correlated; fresnel = dielectric(rgb(1.2, 1.5, 3)); "
        "thin = true; }\n",
    };
    int cases = 0;
    double worst = 0;
    for (const char* text : materials) {
        facet::DiagnosticEngine diags;
        facet::CheckedProgram program = facet::loadProgramText(text, "hard.mat", diags);
        REQUIRE_FALSE(diags.hasErrors());
        const facet::CheckedMaterial& m = *program.find("t");
        facet::QuadReference quad(m);
        std::vector<facet::HardCase> hard = facet::hardCases(m);
        for (const char* spec : {"backend=scalar;math=exact", "backend=simd;math=exact", "backend=scalar;math=fast",
                                 "backend=simd;math=fast"}) {
            auto k = c.compile(text, std::string(spec) + ";cache=memory");
            const bool exact = std::string(spec).find("exact") != std::string::npos;
            // The whole sample as one batch (every lane of every width), then
            // each lane's value against the reference.
            const size_t n = hard.size();
            std::vector<float> dir[6], out[3], slotColumns[8];
            std::vector<uint8_t> status(n);
            for (const facet::HardCase& h : hard)
                for (int d = 0; d < 3; ++d) dir[d].push_back(float(h.wi[d])), dir[3 + d].push_back(float(h.wo[d]));
            for (int s = 0; s < m.slotCount; ++s)
                for (const facet::HardCase& h : hard) slotColumns[s].push_back(float(h.slots[s]));
            for (auto& o : out) o.assign(n, -1.0f);
            const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
            const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
            const float* inputs[8];
            for (int s = 0; s < m.slotCount; ++s) inputs[s] = slotColumns[s].data();
            float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
            int64_t invalid = k->evalBatch(int64_t(n), wi, wo, inputs, rgb, status.data());
            int64_t counted = 0;
            for (size_t i = 0; i < n; ++i) {
                const facet::HardCase& h = hard[i];
                INFO(spec, " ", facet::describeCase(m, h), " got ", out[0][i], " ", out[1][i], " ", out[2][i]);
                counted += status[i];
                for (int ch = 0; ch < 3; ++ch) REQUIRE((std::isfinite(out[ch][i]) && out[ch][i] >= 0));
                if (h.invalidInput) {
                    CHECK(status[i] == 1);
                    continue;
                }
                facet::QuadComparison q = quad.compare(h);
                if (!q.quadValid) continue;
                // Valid, unless float cannot hold the value (SPEC 2).
                const double most = std::max({q.q[0], q.q[1], q.q[2]});
                if (most > 0.5 * std::numeric_limits<float>::max()) continue;
                REQUIRE(status[i] == 0);
                if (!exact) continue;
                float got[3] = {out[0][i], out[1][i], out[2][i]};
                double e = channelError(got, q.q);
                if (e > 1e-5) {
                    // Ill-conditioned: within 16 kappa u, u = 2^-24.
                    double kappa = quad.condition(h);
                    INFO("relative error ", e, " kappa ", kappa);
                    CHECK(e <= 16 * kappa * 0x1p-24);
                } else {
                    worst = std::max(worst, e);
                }
                ++cases;
            }
            CHECK(invalid == counted);
        }
    }
    MESSAGE(cases << " exact hard-case lanes; worst well-conditioned relative error " << worst);
    CHECK(cases > 500);
}

// The compiled sampler against the reference's for the same u: the same
// branch, wi, pdf and weight; and the compiled pdf at the sample.
TEST_CASE("the compiled sampler and pdf draw what the reference draws, on both sides, for every sampled NDF") {
    Compiled c;
    std::vector<std::string> materials;
    for (const auto& [inputs, ndf] : smithNdfs())
        for (const char* lobe : {"masking = smith_height_correlated; fresnel = dielectric(1.5); scatter = both;",
                                 "masking = smith_separable; fresnel = dielectric(1.33); scatter = transmit;",
                                 "masking = smith_height_correlated; fresnel = dielectric(rgb(1.2, 1.5, 2)); thin = true;"})
            materials.push_back(fmt::format("material t {{ {} ndf = {}; {} }}\n", inputs, ndf, lobe));
    int compared = 0, branchFlips = 0, sampledMaterials = 0;
    double worstWi = 0, worstPdf = 0, worstWeight = 0, worstPdfCall = 0;
    for (const std::string& text : materials) {
        facet::DiagnosticEngine diags;
        facet::CheckedProgram program = facet::loadProgramText(text, "glass.mat", diags);
        if (diags.hasErrors()) continue;  // a tabulated Lambda's shape as an input (see above)
        const facet::CheckedMaterial& m = *program.find("t");
        auto ref = c.compile(text, "backend=interp;cache=memory");
        for (const char* spec : {"backend=simd;math=exact;cache=memory", "backend=scalar;math=exact;cache=memory"}) {
            auto k = c.compile(text, spec);
            if (k->samplerTier() != "jit") continue;  // an NDF without a sampler in IR samples through the reference
            REQUIRE(k->samplerError().empty());
            ++sampledMaterials;
            std::vector<float> slots;
            for (double v : m.defaultSlots()) slots.push_back(float(v));
            std::mt19937_64 rng(5 + compared);
            std::uniform_real_distribution<float> uniform(0, 1);
            for (int n = 0; n < 400; ++n) {
                V3 w = uniformSphere(rng);
                float wo[3] = {float(w.x), float(w.y), float(w.z)};
                float u[3] = {uniform(rng), uniform(rng), uniform(rng)};
                float wiR[3], wiK[3], pdfR, pdfK, wR[3], wK[3];
                bool okR = ref->sample(wo, u, slots.data(), wiR, &pdfR, wR);
                bool okK = k->sample(wo, u, slots.data(), wiK, &pdfK, wK);
                INFO(text, spec, " wo ", wo[0], " ", wo[1], " ", wo[2], " u ", u[0], " ", u[1], " ", u[2]);
                REQUIRE(okR == okK);
                if (!(pdfR > 0) || !(pdfK > 0)) {
                    CHECK((pdfR > 0) == (pdfK > 0));
                    continue;
                }
                if ((wiR[2] > 0) != (wiK[2] > 0)) {  // u[0] at the branch's edge, rounded either way
                    ++branchFlips;
                    continue;
                }
                double dWi = 0;
                for (int d = 0; d < 3; ++d) dWi = std::max(dWi, double(std::abs(wiR[d] - wiK[d])));
                worstWi = std::max(worstWi, dWi);
                worstPdf = std::max(worstPdf, relDiff(pdfR, pdfK));
                for (int ch = 0; ch < 3; ++ch) worstWeight = std::max(worstWeight, relDiff(wR[ch], wK[ch]));
                worstPdfCall = std::max(worstPdfCall, relDiff(k->pdf(wiK, wo, slots.data()), pdfK));
                CHECK(dWi <= 1e-5);
                CHECK(relDiff(pdfR, pdfK) <= 1e-4);
                ++compared;
            }
        }
    }
    MESSAGE(compared << " samples of " << sampledMaterials << " kernels: wi within " << worstWi << ", pdf "
                     << worstPdf << ", weight " << worstWeight << ", pdf() at the sample " << worstPdfCall << "; "
                     << branchFlips << " branch flips");
    CHECK(sampledMaterials >= 12);
    CHECK(worstWeight <= 1e-4);
    CHECK(worstPdfCall <= 1e-4);
    CHECK(branchFlips * 1000 <= compared);
}

}  // TEST_SUITE

}  // namespace
