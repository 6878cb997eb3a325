// The compiled mixture sampler of combinations of lobes (SPEC 10;
// compiler/lowering/CombinationSampling.cpp) against the reference's
// (compiler/reference/LobeSampling.cpp): the shipped combinations and the
// lobes corpus (inputs at their defaults). For the same u both pick the same
// lobe and give the same wi, pdf and weight; the JIT samples follow the
// reference mixture pdf (chi-square); a pdf 1% too large is caught.
#include "SamplingCheck.h"

#include "Checker.h"
#include "Kernel.h"
#include "Interpreter.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <filesystem>
#include <random>

namespace {

using namespace sampling_test;

struct CombinationCase {
    std::string path, name;
    std::shared_ptr<facet::CheckedProgram> program;
    const facet::CheckedMaterial* material = nullptr;
};

// Every material that combines lobes and compiles with its inputs per lane.
std::vector<CombinationCase> combinationCases() {
    std::vector<CombinationCase> out;
    for (const char* dir : {FACET_SOURCE_DIR "/materials", FACET_SOURCE_DIR "/tests/corpus/values/lobes"}) {
        std::vector<std::string> files;
        for (const auto& e : std::filesystem::directory_iterator(dir))
            if (e.path().extension() == ".mat") files.push_back(e.path().string());
        std::sort(files.begin(), files.end());
        for (const std::string& f : files) {
            facet::DiagnosticEngine diags;
            auto program = std::make_shared<facet::CheckedProgram>(facet::loadProgramFile(f, diags));
            REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
            for (const facet::CheckedMaterial& m : program->materials)
                if (m.combinesLobes() && facet::compiledBackendsRefuse(m).empty())
                    out.push_back({f, m.name, program, &m});
        }
    }
    return out;
}

std::unique_ptr<facet::Kernel> compileCase(facet::Compiler& compiler, const CombinationCase& c, const char* options) {
    facet::CompileOptions o;
    REQUIRE(facet::CompileOptions::parse(std::string(options) + ";cache=memory;codegen=quick", o) == "");
    facet::DiagnosticEngine diags;
    auto k = compiler.compileMaterial(*c.material, o, diags);
    INFO(c.path, " ", c.name, "\n", diags.str());
    REQUIRE(k);
    REQUIRE(k->samplerTier() == "jit");
    return k;
}

V3 viewAt(double degrees) {
    double t = degrees * std::numbers::pi / 180;
    return {std::sin(t) * std::cos(0.3), std::sin(t) * std::sin(0.3), std::cos(t)};
}

}  // namespace

TEST_CASE("combination sampling: the same u gives the reference's lobe, wi, pdf and weight") {
    facet::Compiler compiler;
    std::vector<CombinationCase> cases = combinationCases();
    REQUIRE(cases.size() >= 8);
    int compared = 0, far = 0;
    for (const CombinationCase& c : cases) {
        auto kernel = compileCase(compiler, c, "backend=simd;math=exact");
        facet::Interpreter<double> interp(*c.material);
        std::vector<double> slots = c.material->defaultSlots();
        std::vector<float> slotsF(slots.begin(), slots.end());
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> uni(0, 1);
        for (int i = 0; i < 400; ++i) {
            V3 wo = viewAt(89 * uni(rng));
            double u[3] = {uni(rng), uni(rng), uni(rng)};
            double wod[3] = {wo.x, wo.y, wo.z};
            float wof[3] = {float(wo.x), float(wo.y), float(wo.z)}, uf[3] = {float(u[0]), float(u[1]), float(u[2])};
            for (int k = 0; k < 3; ++k) u[k] = uf[k], wod[k] = wof[k];  // both see the same float inputs
            facet::SampleResult<double> ref = interp.sample(wod, u, slots.data());
            float wi[3], pdf, weight[3];
            bool ok = kernel->sample(wof, uf, slotsF.data(), wi, &pdf, weight);
            REQUIRE(ok == ref.valid);
            ++compared;
            double dw = std::max({std::abs(wi[0] - ref.wi.x), std::abs(wi[1] - ref.wi.y), std::abs(wi[2] - ref.wi.z)});
            double dp = std::abs(pdf - ref.pdf) / std::max(ref.pdf, 1e-30);
            double dwt = 0;
            for (int k = 0; k < 3; ++k) dwt = std::max(dwt, std::abs(weight[k] - ref.weight[k]) / std::max(std::abs(ref.weight[k]), 1e-6));
            // A u0 at a leaf boundary may pick the neighbour in float: rare.
            if (dw > 1e-4 || dp > 1e-3 || dwt > 1e-3) ++far;
        }
    }
    MESSAGE(fmt::format("{} samples of {} combinations; {} differ from the reference beyond 1e-4 / 1e-3", compared,
                        cases.size(), far));
    CHECK(far <= compared / 500);
}

TEST_CASE("combination sampling: chi-square of the JIT samples against the reference mixture pdf") {
    facet::Compiler compiler;
    std::vector<CombinationCase> cases = combinationCases();
    const double level = 0.01 / double(cases.size() + 1);
    int index = 0;
    for (const CombinationCase& c : cases) {
        auto kernel = compileCase(compiler, c, "backend=simd;math=exact");
        facet::Interpreter<double> interp(*c.material);
        std::vector<double> slots = c.material->defaultSlots();
        std::vector<float> slotsF(slots.begin(), slots.end());
        const double theta = 20 + 25 * (index % 3);
        V3 view = viewAt(theta);
        float wo[3] = {float(view.x), float(view.y), float(view.z)};
        double wod[3] = {wo[0], wo[1], wo[2]};
        Sampler sampler = [&](const std::array<double, 3>& u) {
            float uf[3] = {float(u[0]), float(u[1]), float(u[2])};
            for (float& x : uf) x = x < 1 ? x : 1 - 0x1p-24f;
            float wi[3], pdf, weight[3];
            SampleResult<double> s;
            s.valid = kernel->sample(wo, uf, slotsF.data(), wi, &pdf, weight);
            s.wi = {wi[0], wi[1], wi[2]};
            s.pdf = pdf;
            return s;
        };
        PdfFunction pdf = [&](const V3& wi) {
            double w[3] = {wi.x, wi.y, wi.z};
            return interp.pdf(w, wod, slots.data()).pdf;
        };
        // The grid graded toward the mirror direction from the sharpest lobe.
        facet::ResolvedBsdf<double> r = interp.resolveAll(slots.data());
        const facet::ResolvedMaterial<double>* sharp = nullptr;
        double sharpest = 1e9;
        for (const auto& lobe : r.lobes)
            if (lobe.ndf) {
                auto a = lobe.ndf->equivalentAlphas(lobe.ndfArgs);
                if (std::min(a[0], a[1]) < sharpest) sharpest = std::min(a[0], a[1]), sharp = &lobe;
            }
        REQUIRE(sharp);
        V3 wv{wod[0], wod[1], wod[2]};
        CheckSettings s;
        s.samples = 100000;
        s.level = level;
        s.seed = 900 + uint64_t(index);
        s.normalizationTolerance = 1e-3;
        CheckOutcome out = checkSampler(sampler, pdf, lobeGrid(*sharp, wv), s);
        INFO(c.path, " ", c.name, " theta ", theta, "\n", out.describe());
        CHECK(out.chi2.failure == "");
        CHECK(std::abs(out.integral - 1) <= 1e-3);
        if (index == 0) {  // a wrong pdf must fail
            PdfFunction scaled = [&](const V3& wi) { return 1.05 * pdf(wi); };
            CheckOutcome wrong = checkSampler(sampler, scaled, lobeGrid(*sharp, wv), s);
            CHECK((std::abs(wrong.integral - 1) > 1e-3 || wrong.chi2.failure != ""));
        }
        ++index;
    }
    MESSAGE(fmt::format("{} chi-square runs of the compiled mixture sampler, per-test level {:.3g}", index, level));
}
