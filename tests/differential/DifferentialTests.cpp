// Differential tests (OSL-testsuite style): every material, re-run under
// each backend (scalar; SIMD at widths 4, 8 and 16), against the same double
// interpreter reference, on 100k random direction pairs and the hard-case
// directions; plus >= 2000 random materials across all model combinations.
// SIMD kernels run with float_first=off, where scalar and SIMD agree within
// 4 ulp, and again float-first (the default) where the material allows it:
// that run is held to the same error statistics against the interpreter,
// but not to the ulp agreement (its trusted lanes are computed in float).
#include "DiffHarness.h"
#include "RandomMaterial.h"

#include "Checker.h"
#include "Specialize.h"

#include <doctest/doctest.h>
#include <filesystem>
#include <fmt/format.h>

using namespace facet;
using namespace facet::test;

namespace {

std::vector<std::string> materialFiles() {
    std::vector<std::string> files;
    for (const char* dir : {FACET_SOURCE_DIR "/materials", FACET_SOURCE_DIR "/tests/corpus"}) {
        if (!std::filesystem::exists(dir)) continue;
        for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
            if (entry.path().extension() == ".mat") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    return files;
}

// Random materials are compiled with quick codegen: the same bits as
// optimized code (JitTierUpTests, "tiered compile"), compiled once; the
// shipped materials with optimized codegen, the code a renderer runs once
// a tiered kernel has tiered up. (Tiered codegen here would compile both and
// compare whichever the background thread had swapped in by then.)
CompileOptions differentialOptions(Backend b, int width, bool floatFirst = false,
                                   CompileOptions::Codegen codegen = CompileOptions::Codegen::Optimized) {
    CompileOptions o;
    o.backend = b;
    o.width = width;
    o.floatFirst = floatFirst;
    o.cache = CompileOptions::Cache::Memory;
    o.codegen = codegen;
    return o;
}
constexpr auto kQuick = CompileOptions::Codegen::Quick;

void checkStats(const DiffStats& stats, const std::string& what) {
    std::string why;
    bool ok = stats.ok(why);
    INFO(what << ": " << why);
    CHECK(ok);
}

}  // namespace

TEST_CASE("every shipped and corpus material agrees with the interpreter on every backend") {
    Compiler compiler;
    size_t materials = 0, floatFirstMaterials = 0, boundMaterials = 0;
    double worst = 0, worstFloatFirst = 0;
    for (const std::string& path : materialFiles()) {
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramFile(path, diags);
        if (diags.hasErrors()) continue;  // error cases of the corpus
        for (const CheckedMaterial& checked : program.materials) {
            ++materials;
            // A material the compiled backends take only with constant layer
            // parameters (compiledBackendsRefuse) is compiled as a user would:
            // every input bound to its default (`--set`), and compared with the
            // interpreter of that bound material.
            InputBindings defaults;
            const bool bindDefaults = !compiledBackendsRefuse(checked).empty();
            if (bindDefaults)
                for (const CheckedInput& in : checked.inputs)
                    defaults[in.name] = std::vector<double>(in.defaultValue.begin(),
                                                            in.defaultValue.begin() + in.slotCount());
            DiagnosticEngine bindDiags;
            const CheckedMaterial bound = bindDefaults ? specializeMaterial(checked, defaults, bindDiags) : checked;
            REQUIRE_MESSAGE(!bindDiags.hasErrors(), bindDiags.str());
            const CheckedMaterial& m = bound;
            boundMaterials += bindDefaults;
            auto optionsFor = [&](Backend b, int width, bool floatFirst = false) {
                CompileOptions o = differentialOptions(b, width, floatFirst);
                o.bindings = defaults;
                return o;
            };
            LaneBatch random = randomSample(m, 100000, 42 + materials);
            LaneBatch hard = hardSample(m);
            // One reference per sample for all the material's kernels.
            std::optional<ReferenceValues> randomRef, hardRef;
            std::unique_ptr<Kernel> scalar;
            struct Run { Backend backend; int width; };
            for (Run run : {Run{Backend::Scalar, 0}, Run{Backend::Simd, 4}, Run{Backend::Simd, 8}, Run{Backend::Simd, 16}}) {
                DiagnosticEngine kd;
                auto kernel = compiler.compileFile(path, m.name, optionsFor(run.backend, run.width), kd);
                REQUIRE_MESSAGE(kernel, kd.str());
                DiffStats stats;
                compare(*kernel, m, random, stats, &randomRef);
                compare(*kernel, m, hard, stats, &hardRef);
                if (run.backend == Backend::Scalar) {
                    scalar = std::move(kernel);
                } else {
                    compareUlp(*scalar, *kernel, random, stats);
                    compareUlp(*scalar, *kernel, hard, stats);
                }
                worst = std::max(worst, stats.maxRel);
                checkStats(stats, fmt::format("{} material {} backend {} width {}", path, m.name,
                                              backendName(run.backend), run.width));
            }
            if (planLowering(m, MathVariant::exact()).batchBodies == BatchBodies::FloatFirst) {
                ++floatFirstMaterials;
                DiagnosticEngine kd;
                auto kernel = compiler.compileFile(path, m.name, optionsFor(Backend::Simd, 16, true), kd);
                REQUIRE_MESSAGE(kernel, kd.str());
                DiffStats stats;
                compare(*kernel, m, random, stats, &randomRef);
                compare(*kernel, m, hard, stats, &hardRef);
                worstFloatFirst = std::max(worstFloatFirst, stats.maxRel);
                checkStats(stats, fmt::format("{} material {} SIMD16 float-first", path, m.name));
                // Float-first keeps exact-mode accuracy (all-double kernels: 1.1e-6).
                CHECK_MESSAGE(stats.maxRel < 4e-6, path << " " << m.name << " float-first: " << stats.worst);
            }
        }
    }
    MESSAGE(fmt::format("{} materials compared ({} with their inputs bound); worst relative error {:.3g}; "
                        "float-first SIMD16 on {} of them, worst {:.3g}", materials, boundMaterials, worst,
                        floatFirstMaterials, worstFloatFirst));
    CHECK(materials >= 10);
    CHECK(floatFirstMaterials >= 3);
}

TEST_CASE("random materials agree across interpreter, scalar and SIMD") {
    Compiler compiler;
    const int count = 2000;
    const int widths[] = {4, 8, 16};
    double worst = 0, worstFloatFirst = 0;
    int failures = 0, floatFirstCount = 0;
    for (int i = 0; i < count && failures < 20; ++i) {
        RandomMaterial rm = randomMaterial(1234, i);
        DiagnosticEngine diags;
        CheckedProgram program = loadProgramText(rm.text, "random.mat", diags);
        REQUIRE_MESSAGE(!diags.hasErrors(), rm.text << diags.str());
        const CheckedMaterial& m = program.materials.front();
        LaneBatch s = randomSample(m, 1500, 99 + i);
        DiagnosticEngine kd;
        auto scalar = compiler.compileText(rm.text, "random.mat", "", differentialOptions(Backend::Scalar, 0, false, kQuick), kd);
        auto simd = compiler.compileText(rm.text, "random.mat", "", differentialOptions(Backend::Simd, widths[i % 3], false, kQuick), kd);
        REQUIRE_MESSAGE((scalar && simd), kd.str() << rm.text);
        DiffStats stats;
        std::optional<ReferenceValues> ref;
        compare(*scalar, m, s, stats, &ref);
        compare(*simd, m, s, stats, &ref);
        compareUlp(*scalar, *simd, s, stats);
        worst = std::max(worst, stats.maxRel);
        std::string why;
        if (!stats.ok(why)) {
            ++failures;
            FAIL_CHECK("random material " << i << " (" << rm.combination << ") width " << widths[i % 3] << ": "
                                          << why << "\n" << rm.text);
        }
        if (planLowering(m, MathVariant::exact()).batchBodies == BatchBodies::FloatFirst) {
            ++floatFirstCount;
            auto floatFirst = compiler.compileText(rm.text, "random.mat", "", differentialOptions(Backend::Simd, widths[i % 3], true, kQuick), kd);
            REQUIRE_MESSAGE(floatFirst, kd.str() << rm.text);
            DiffStats ff;
            compare(*floatFirst, m, s, ff, &ref);
            worstFloatFirst = std::max(worstFloatFirst, ff.maxRel);
            if (!ff.ok(why) || !(ff.maxRel < 4e-6)) {
                if (why.empty()) why = fmt::format("relative error {:.3g} beyond 4e-6: {}", ff.maxRel, ff.worst);
                ++failures;
                FAIL_CHECK("random material " << i << " (" << rm.combination << ") float-first width " << widths[i % 3]
                                              << ": " << why << "\n" << rm.text);
            }
        }
    }
    MESSAGE(fmt::format("{} random materials over {} combinations; worst relative error {:.3g}; float-first on {}, "
                        "worst {:.3g}", count, randomMaterialCombinationCount(), worst, floatFirstCount, worstFloatFirst));
    CHECK(floatFirstCount >= 20);
}
