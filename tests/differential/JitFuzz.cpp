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
// 1e38) is not marked and is within 1e-5 relative of it (exact mode's bound
// on the hard-case sample: a non-unit direction's renormalization or a
// grazing lane that drifts by 1e-3 must be a finding).
// Each material gets a batch of L-31..L lanes (L = --lanes, default 256), so
// that SIMD kernels of every width also run a partial last chunk, and every
// array a kernel reads or writes ends where an inaccessible page begins
// (GuardedArray): the kernels are machine code that no sanitizer
// instruments, and a read or write past the last lane faults there.
// Prints every finding (the first 50) and, at the end, the totals: materials,
// kernels, lanes (summed over kernels), findings and wall time. Exit 1 if
// there was a finding, 2 on a usage error.
#include "DiffHarness.h"
#include "RandomMaterial.h"

#include "Checker.h"
#include "Kernel.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <memory>
#include <random>
#include <string>
#include <sys/mman.h>
#include <unistd.h>

using namespace facet;
using namespace facet::test;

namespace {

// Replaces about a third of the lanes of `s` by hostile ones.
void addHostileLanes(LaneBatch& s, std::mt19937_64& rng) {
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

// A copy of n values of T that ends exactly where a PROT_NONE page begins.
template <typename T>
class GuardedArray {
public:
    GuardedArray(const T* values, size_t n) {
        const size_t page = size_t(sysconf(_SC_PAGESIZE)), bytes = n * sizeof(T);
        const size_t span = (bytes + page - 1) / page * page;
        length_ = span + page;
        void* p = mmap(nullptr, length_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) fail("mmap");
        base_ = static_cast<char*>(p);
        if (mprotect(base_ + span, page, PROT_NONE) != 0) fail("mprotect");
        data_ = reinterpret_cast<T*>(base_ + span - bytes);
        if (bytes) std::memcpy(data_, values, bytes);
    }
    GuardedArray(const GuardedArray&) = delete;
    GuardedArray& operator=(const GuardedArray&) = delete;
    ~GuardedArray() { munmap(base_, length_); }
    T* data() const { return data_; }

private:
    [[noreturn]] static void fail(const char* call) {
        std::fprintf(stderr, "facet_jit_fuzz: %s: %s\n", call, std::strerror(errno));
        std::exit(1);
    }
    char* base_ = nullptr;
    size_t length_ = 0;
    T* data_ = nullptr;
};

struct Counters {
    long materials = 0, kernels = 0, lanes = 0, findings = 0;
};

void finding(Counters& c, const std::string& what) {
    if (++c.findings <= 50) std::printf("FINDING %s\n", what.c_str());
}

void checkKernel(const Kernel& k, const std::string& label, const LaneBatch& s, bool exact, Counters& c) {
    const size_t n = s.size();
    std::vector<std::unique_ptr<GuardedArray<float>>> arrays;  // directions, then slots
    for (const auto& d : s.dir) arrays.push_back(std::make_unique<GuardedArray<float>>(d.data(), n));
    std::vector<const float*> slotPointers;
    for (int slot = 0; slot < k.inputCount(); ++slot) {
        arrays.push_back(std::make_unique<GuardedArray<float>>(s.slots[slot].data(), n));
        slotPointers.push_back(arrays.back()->data());
    }
    GuardedArray<const float*> inputsArray(slotPointers.data(), slotPointers.size());
    const float* const* inputs = slotPointers.empty() ? nullptr : inputsArray.data();
    const std::vector<float> unwritten(n, -1);
    GuardedArray<float> outArrays[3] = {{unwritten.data(), n}, {unwritten.data(), n}, {unwritten.data(), n}};
    float* rgb[3] = {outArrays[0].data(), outArrays[1].data(), outArrays[2].data()};
    const float* out[3] = {rgb[0], rgb[1], rgb[2]};
    const float* wi[3] = {arrays[0]->data(), arrays[1]->data(), arrays[2]->data()};
    const float* wo[3] = {arrays[3]->data(), arrays[4]->data(), arrays[5]->data()};
    const std::vector<uint8_t> unmarked(n, 7);
    GuardedArray<uint8_t> statusArray(unmarked.data(), n);
    const uint8_t* status = statusArray.data();
    int64_t invalid = k.evalBatch(int64_t(n), wi, wo, inputs, rgb, statusArray.data());
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
            // kHardCaseBoundExact (apps/verify/Verify.h), which this target
            // does not link: the sanitized build would mix runtimes.
            if (status[i] || std::fabs(got - want) > 1e-5 * want)
                finding(c, fmt::format("{}: channel {} is {:.9g} (status {}), the interpreter {:.17g}", lane(), ch,
                                       got, status[i], want));
        }
    }
    if (marked != invalid) finding(c, fmt::format("{}: returned {} invalid lanes, status marks {}", label, invalid, marked));
}

// A whole decimal number, at least `min`, into `out`; false for anything else.
bool parseCount(const char* text, unsigned long long min, unsigned long long& out) {
    if (!*text || *text == '-' || *text == '+') return false;
    char* end = nullptr;
    errno = 0;
    out = std::strtoull(text, &end, 10);
    return errno == 0 && *end == '\0' && out >= min;
}

}  // namespace

int main(int argc, char** argv) {
    unsigned long long seed = 1, count = 100, lanes = 256;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        bool ok = i + 1 < argc;
        if (ok && a == "--seed") ok = parseCount(argv[++i], 0, seed);
        else if (ok && a == "--count") ok = parseCount(argv[++i], 0, count) && count <= INT_MAX;
        else if (ok && a == "--lanes") ok = parseCount(argv[++i], 1, lanes) && lanes <= (1u << 20);
        else ok = false;
        if (!ok) {
            std::fprintf(stderr, "facet_jit_fuzz: bad argument '%s'\n"
                                 "usage: facet_jit_fuzz [--seed S] [--count N] [--lanes L] (L in 1..1048576)\n",
                         argv[i]);
            return 2;
        }
    }
    const auto start = std::chrono::steady_clock::now();
    Compiler compiler;
    compiler.setCacheDir("");
    Counters c;
    std::mt19937_64 rng(seed);
    static const char* const kBackends[][2] = {{"scalar", "backend=scalar;codegen=quick;cache=off"},
                                               {"simd", "backend=simd;codegen=quick;cache=off"},
                                               {"simd/ff-off", "backend=simd;float_first=off;codegen=quick;cache=off"},
                                               {"simd/fast", "backend=simd;math=fast;codegen=quick;cache=off"}};
    for (long m = 0; m < long(count); ++m) {
        RandomMaterial rm = randomMaterial(seed, int(m));
        DiagnosticEngine d;
        CheckedProgram program = loadProgramText(rm.text, "random.mat", d);
        if (d.hasErrors()) {
            finding(c, fmt::format("material {} ({}) does not check: {}", m, rm.combination, d.str()));
            continue;
        }
        ++c.materials;
        // L-31..L lanes: every remainder modulo 4, 8 and 16 occurs.
        const size_t batch = size_t(lanes - rng() % std::min(lanes, 32ull));
        LaneBatch s = randomSample(program.materials[0], batch, seed * 1000003 + uint64_t(m));
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
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("facet_jit_fuzz: seed %llu: %ld materials, %ld kernels, %ld lanes, %ld findings, %.1f s\n", seed,
                c.materials, c.kernels, c.lanes, c.findings, seconds);
    return c.findings ? 1 : 0;
}
