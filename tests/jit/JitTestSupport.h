// JitTestSupport: what the JIT tests (Jit*Tests.cpp) share: the gold
// material, random lanes over the hemisphere for it (Batch), and compiling
// with an option string where the test requires success.
#pragma once

#include "Checker.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "LaneBatch.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fmt/format.h>
#include <memory>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

namespace facet::jittest {

inline const char* const kGold = R"(
material gold {
    input roughness = 0.35 in 0 .. 1;
    input tint = rgb(1, 1, 1);
    let alpha = roughness * roughness;
    ndf = ggx(alpha);
    masking = smith_height_correlated;
    fresnel = conductor(eta = rgb(0.143, 0.374, 1.442) * tint, k = rgb(3.983, 2.385, 1.603));
}
)";

// Random lanes for a material whose input slot 0 is a roughness (kGold):
// directions over the upper hemisphere, roughness in [0, 1), drawn in float;
// plus the kernel's output columns.
struct Batch : LaneBatch {
    std::vector<float> out[3];
    explicit Batch(size_t count, uint64_t seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(0, 1);
        slots.resize(1);
        for (size_t i = 0; i < count; ++i) {
            for (int d = 0; d < 2; ++d) {
                float z = u(rng), phi = 6.2831853f * u(rng), r = std::sqrt(1 - z * z);
                dir[3 * d].push_back(r * std::cos(phi));
                dir[3 * d + 1].push_back(r * std::sin(phi));
                dir[3 * d + 2].push_back(z);
            }
            slots[0].push_back(u(rng));
        }
        for (auto& o : out) o.assign(count, 0.0f);
        finish();
    }
    int64_t run(const Kernel& k, size_t begin = 0, size_t count = SIZE_MAX) {
        count = std::min(count, size() - begin);
        const float* wi[3] = {&dir[0][begin], &dir[1][begin], &dir[2][begin]};
        const float* wo[3] = {&dir[3][begin], &dir[4][begin], &dir[5][begin]};
        const float* inputs[4] = {&slots[0][begin], nullptr, nullptr, nullptr};
        float* rgb[3] = {&out[0][begin], &out[1][begin], &out[2][begin]};
        return k.evalBatch(int64_t(count), wi, wo, inputs, rgb);
    }
    // The double interpreter's value for lane i, with the same input slot
    // as run() (the roughness; unused by a material without inputs).
    EvalResult<double> reference(const Interpreter<double>& interp, size_t i) const {
        double wi[3] = {dir[0][i], dir[1][i], dir[2][i]}, wo[3] = {dir[3][i], dir[4][i], dir[5][i]};
        double in[1] = {slots[0][i]};
        return interp.eval(wi, wo, in);
    }
};

inline CompileOptions opts(const std::string& spec) {
    CompileOptions o;
    std::string err = CompileOptions::parse(spec, o);
    REQUIRE_MESSAGE(err.empty(), err);
    return o;
}

// The checked program of a material text that must have no errors.
inline CheckedProgram checkedText(const std::string& text) {
    DiagnosticEngine d;
    CheckedProgram p = loadProgramText(text, "t.mat", d);
    REQUIRE_MESSAGE(!d.hasErrors(), d.str());
    return p;
}

inline std::unique_ptr<Kernel> compile(Compiler& c, const std::string& text, const std::string& spec) {
    DiagnosticEngine d;
    auto k = c.compileText(text, "t.mat", "", opts(spec), d);
    REQUIRE_MESSAGE(k, d.str());
    return k;
}

// A fresh, empty directory under the system's temporary directory, named
// for the test and the process.
inline std::string tempDir(const std::string& name) {
    auto dir = std::filesystem::temp_directory_path() / fmt::format("facet-test-{}-{}", name, ::getpid());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

}  // namespace facet::jittest
