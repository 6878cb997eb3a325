// JitFuzz: random well-formed materials (RandomMaterial) evaluated by every
// compiled backend on random lanes that include the hostile ones (NaN, Inf,
// subnormal and huge components, non-unit and grazing directions, inputs far
// outside their ranges), checked lane by lane against the double
// interpreter.
//
//   facet_jit_fuzz [--seed S] [--count N] [--lanes L]
//
// Per kernel and lane: the returned count equals the number of lanes the
// status array marks; a marked lane is 0; every output is finite and
// non-negative; a lane the interpreter rejects is marked; and on exact
// kernels a lane whose reference is a normal float in every channel (below
// 1e38) is not marked and is within 2e-3 relative of it (the differential
// tests' bound for every value).
// Prints the executions and every finding; exit 1 if there was one.
#include "DiffHarness.h"
#include "RandomMaterial.h"

#include "Checker.h"
#include "Kernel.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <random>
#include <string>

using namespace facet;
using namespace facet::test;

namespace {

// Replaces about a third of the lanes of `s` by hostile ones.
void addHostileLanes(Sample& s, std::mt19937_64& rng) {
    std::uniform_int_distribution<int> pick(0, 11);
    const float hostile[] = {NAN, INFINITY, -INFINITY, 1e-40f, -1e-45f, 3e38f, -3e38f, 0.0f, 1e-30f, 2.0f};
    std::uniform_int_distribution<int> value(0, int(std::size(hostile)) - 1);
    for (size_t i = 0; i < s.size(); ++i) {
        int kind = pick(rng);
        if (kind < 8) continue;
        if (kind == 8) {  // one hostile direction component
            s.dir[rng() % 6][i] = hostile[value(rng)];
        } else if (kind == 9) {  // grazing pair, tiny z of either sign
            float z = float(std::ldexp(1.0, -int(rng() % 140)));
            double phi = double(rng() % 6283) / 1000;
            float c = float(std::cos(phi)), sn = float(std::sin(phi));
            s.dir[0][i] = 1; s.dir[1][i] = 0; s.dir[2][i] = z;
            s.dir[3][i] = c; s.dir[4][i] = sn; s.dir[5][i] = (rng() & 1) ? z : -z;
        } else if (kind == 10 && !s.slots.empty()) {  // a hostile input
            s.slots[rng() % s.slots.size()][i] = hostile[value(rng)];
        } else {  // non-unit within or just beyond the tolerance
            float scale = (rng() & 1) ? 1.0009f : 1.0011f;
            for (int k = 0; k < 3; ++k) s.dir[k][i] *= scale;
        }
    }
}

struct Counters {
    long materials = 0, kernels = 0, lanes = 0, findings = 0;
};

void finding(Counters& c, const std::string& what) {
    if (++c.findings <= 50) std::printf("FINDING %s\n", what.c_str());
}

void checkKernel(const Kernel& k, const std::string& label, const Sample& s, bool exact, Counters& c) {
    const size_t n = s.size();
    std::vector<const float*> inputs;
    for (int slot = 0; slot < k.inputCount(); ++slot) inputs.push_back(s.slots[slot].data());
    std::vector<float> out[3];
    for (auto& o : out) o.assign(n, -1);
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    const float* wi[3] = {s.dir[0].data(), s.dir[1].data(), s.dir[2].data()};
    const float* wo[3] = {s.dir[3].data(), s.dir[4].data(), s.dir[5].data()};
    std::vector<uint8_t> status(n, 7);
    int64_t invalid = k.evalBatch(int64_t(n), wi, wo, inputs.empty() ? nullptr : inputs.data(), rgb, status.data());
    ++c.kernels;
    c.lanes += long(n);
    int64_t marked = 0;
    Interpreter<double> interp(k.material(), k.energyTable());
    std::vector<double> slots(std::max(1, k.inputCount()));
    for (size_t i = 0; i < n; ++i) {
        auto lane = [&] {
            return fmt::format("{} lane {}: wi ({:.9g}, {:.9g}, {:.9g}) wo ({:.9g}, {:.9g}, {:.9g})", label, i, wi[0][i],
                               wi[1][i], wi[2][i], wo[0][i], wo[1][i], wo[2][i]);
        };
        if (status[i] > 1) finding(c, lane() + ": status not written");
        marked += status[i] == 1;
        for (int ch = 0; ch < 3; ++ch)
            if (!std::isfinite(out[ch][i]) || out[ch][i] < 0 || (status[i] && out[ch][i] != 0))
                finding(c, fmt::format("{}: channel {} is {} with status {}", lane(), ch, out[ch][i], status[i]));
        double a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]};
        for (int slot = 0; slot < k.inputCount(); ++slot) slots[slot] = inputs[slot][i];
        EvalResult<double> ref = interp.eval(a, b, slots.data());
        if (!ref.valid && !status[i]) {
            finding(c, lane() + ": the interpreter rejects it, the kernel does not");
            continue;
        }
        if (!exact || !ref.valid) continue;
        // A lane is valid or invalid as a whole: one channel beyond float, or
        // near its limit (a float product on the way may overflow: within 1e38,
        // as measureKernelError allows), makes the whole lane invalid.
        if (status[i] && std::max({ref.rgb[0], ref.rgb[1], ref.rgb[2]}) > 1e38) continue;
        for (int ch = 0; ch < 3; ++ch) {
            double want = ref.rgb[ch];
            if (!(want >= FLT_MIN && want <= FLT_MAX)) continue;
            double got = out[ch][i];
            if (status[i] || std::fabs(got - want) > 2e-3 * want)
                finding(c, fmt::format("{}: channel {} is {:.9g} (status {}), the interpreter {:.17g}", lane(), ch,
                                       got, status[i], want));
        }
    }
    if (marked != invalid) finding(c, fmt::format("{}: returned {} invalid lanes, status marks {}", label, invalid, marked));
}

}  // namespace

int main(int argc, char** argv) {
    uint64_t seed = 1;
    long count = 100;
    size_t lanes = 256;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (i + 1 < argc && a == "--seed") seed = std::strtoull(argv[++i], nullptr, 10);
        else if (i + 1 < argc && a == "--count") count = std::strtol(argv[++i], nullptr, 10);
        else if (i + 1 < argc && a == "--lanes") lanes = size_t(std::strtoul(argv[++i], nullptr, 10));
        else {
            std::fprintf(stderr, "usage: facet_jit_fuzz [--seed S] [--count N] [--lanes L]\n");
            return 2;
        }
    }
    Compiler compiler;
    compiler.setCacheDir("");
    Counters c;
    std::mt19937_64 rng(seed);
    static const char* const kBackends[][2] = {{"scalar", "backend=scalar;codegen=quick;cache=off"},
                                               {"simd", "backend=simd;codegen=quick;cache=off"},
                                               {"simd/ff-off", "backend=simd;float_first=off;codegen=quick;cache=off"},
                                               {"simd/fast", "backend=simd;math=fast;codegen=quick;cache=off"}};
    for (long m = 0; m < count; ++m) {
        RandomMaterial rm = randomMaterial(seed, int(m));
        DiagnosticEngine d;
        CheckedProgram program = loadProgramText(rm.text, "random.mat", d);
        if (d.hasErrors()) {
            finding(c, fmt::format("material {} ({}) does not check: {}", m, rm.combination, d.str()));
            continue;
        }
        ++c.materials;
        Sample s = randomSample(program.materials[0], lanes, seed * 1000003 + uint64_t(m));
        addHostileLanes(s, rng);
        for (const auto& [name, options] : kBackends) {
            CompileOptions o;
            static const char* const kWidths[] = {";width=4", ";width=8", ";width=16"};
            std::string spec = std::string(options) + (std::string(name).rfind("simd", 0) == 0 ? kWidths[rng() % 3] : "");
            if (!CompileOptions::parse(spec, o).empty()) return 2;
            std::unique_ptr<Kernel> k = compiler.compileText(rm.text, "random.mat", "", o, d);
            if (!k) {
                finding(c, fmt::format("material {} ({}) does not compile for {}: {}", m, rm.combination, name, d.str()));
                continue;
            }
            checkKernel(*k, fmt::format("material {} ({}) {}", m, rm.combination, name), s,
                        std::string(name).find("fast") == std::string::npos, c);
        }
    }
    std::printf("facet_jit_fuzz: seed %llu: %ld materials, %ld kernels, %ld lanes, %ld findings\n",
                (unsigned long long)seed, c.materials, c.kernels, c.lanes, c.findings);
    return c.findings ? 1 : 0;
}
