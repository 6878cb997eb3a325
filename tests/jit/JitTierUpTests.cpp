// JIT tier-up tests (codegen=tiered): the quick code computes the optimized
// code's bits, kernels switch while batches run, the caches get only
// optimized objects, and a Compiler destroyed with tier-ups queued.
#include "JitTestSupport.h"

#include "BenchSamples.h"

#include <atomic>
#include <cstring>
#include <thread>

using namespace facet;
using namespace facet::jittest;

namespace {

// Outputs and invalid-lane counts of `k` on a sample, bit for bit.
struct SampleOutput {
    int64_t invalid = 0;
    std::vector<float> rgb[3];
    bool operator==(const SampleOutput& o) const {
        for (int c = 0; c < 3; ++c)
            if (std::memcmp(rgb[c].data(), o.rgb[c].data(), rgb[c].size() * sizeof(float)) != 0) return false;
        return invalid == o.invalid;
    }
};
SampleOutput runSample(const Kernel& k, const LaneBatch& s) {
    SampleOutput r;
    float* out[3];
    for (int c = 0; c < 3; ++c) r.rgb[c].assign(s.size(), -1.0f), out[c] = r.rgb[c].data();
    r.invalid = k.evalBatch(int64_t(s.size()), s.wi(), s.wo(), s.inputs(), out);
    return r;
}
// The sampler's outputs on a sample's wo and inputs, with u from `seed`
// (every eighth lane at the edges 0 and 1 - 2^-24), bit for bit.
struct SamplerBits {
    int64_t invalid = 0;
    std::vector<float> values[7];  // wi, pdf, weight
    bool operator==(const SamplerBits& o) const {
        for (int c = 0; c < 7; ++c)
            if (std::memcmp(values[c].data(), o.values[c].data(), values[c].size() * sizeof(float)) != 0) return false;
        return invalid == o.invalid;
    }
};
SamplerBits runSampler(const Kernel& k, const LaneBatch& s, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> uniform(0, 1);
    std::vector<float> u[3];
    for (size_t i = 0; i < s.size(); ++i)
        for (int c = 0; c < 3; ++c) u[c].push_back(i % 8 == 0 ? (c == 1 ? 1 - 0x1p-24f : 0.0f) : std::min(uniform(rng), 1 - 0x1p-24f));
    SamplerBits r;
    float* out[7];
    for (int c = 0; c < 7; ++c) r.values[c].assign(s.size(), -1.0f), out[c] = r.values[c].data();
    const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
    r.invalid = k.sampleBatch(int64_t(s.size()), s.wo(), uP, s.inputs(), out, out[3], out + 4);
    return r;
}

}  // namespace

// Tiered compilation is only sound if the quick code computes exactly what
// the optimized code does: every shipped and bench material, SIMD exact and
// fast and scalar exact, on the bench's regular sample and on the hard-case
// sample (grazing, degenerate and non-finite lanes; the two-body kernels'
// precise bodies); the SIMD samplers of codegen=quick and =optimized on the
// same lanes and u. Skipping Reassociate/InstCombine in the quick middle end
// for a fast kernel with contract flags fails this (plastic).
TEST_CASE("tiered compile: the quick code and the optimized code give the same bits") {
    Compiler c;
    size_t kernels = 0, samplers = 0;
    std::vector<std::string> files;
    for (const char* dir : {"materials", "bench/models"})
        for (auto& e : std::filesystem::directory_iterator(std::string(FACET_SOURCE_DIR) + "/" + dir))
            if (e.path().extension() == ".mat") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    for (const std::string& file : files) {
        DiagnosticEngine d;
        CheckedProgram program = loadProgramFile(file, d);
        REQUIRE_MESSAGE(!d.hasErrors(), d.str());
        for (const CheckedMaterial& m : program.materials) {
            LaneBatch regular = bench::regularSample(m, 4096, 77), hard = bench::hardCaseSample(m);
            for (const char* row : {"backend=simd;math=exact", "backend=simd;math=fast", "backend=scalar;math=exact"}) {
                INFO(m.name << " " << row);
                auto build = [&](const char* codegen) {
                    DiagnosticEngine diags;
                    auto k = c.compileMaterial(m, opts(fmt::format("{};cache=off;codegen={}", row, codegen)), diags);
                    REQUIRE_MESSAGE(k, diags.str());
                    return k;
                };
                auto quick = build("quick"), optimized = build("optimized"), tiered = build("tiered");
                CHECK(quick->codeTier() == "quick");
                CHECK(optimized->codeTier() == "optimized");
                CHECK(optimized->tierUpMillis() == 0);
                SampleOutput tieredFirst = runSample(*tiered, hard);  // quick or optimized by now
                tiered->waitOptimized();
                CHECK(tiered->codeTier() == "optimized");
                CHECK(tiered->tierUpError() == "");
                CHECK(tiered->tierUpMillis() > 0);
                for (const LaneBatch* s : {&regular, &hard}) {
                    SampleOutput want = runSample(*optimized, *s);
                    CHECK(runSample(*quick, *s) == want);
                    CHECK(runSample(*tiered, *s) == want);
                }
                CHECK(tieredFirst == runSample(*optimized, hard));
                // The sampler is compiled at the kernel's level too (quick
                // only under codegen=quick); SIMD rows, where both levels
                // schedule and allocate registers differently.
                // (A combination of lobes is sampled by the reference.)
                if (std::string_view(row).starts_with("backend=simd") &&
                    plannedSpecularSampling(m) != SpecularSampling::None) {
                    REQUIRE(quick->samplerTier() == "jit");
                    REQUIRE(optimized->samplerTier() == "jit");
                    for (const LaneBatch* s : {&regular, &hard})
                        CHECK(runSampler(*quick, *s, 91) == runSampler(*optimized, *s, 91));
                    ++samplers;
                }
                ++kernels;
            }
        }
    }
    // 28 materials x 3 rows; the 24 of one lobe have a compiled sampler (2
    // SIMD rows each), the bench's rough glass among them.
    CHECK(kernels == 84);
    CHECK(samplers == 48);
}

// Renderer threads keep evaluating while the tier-up switches the entry
// points: every batch, before, during and after, equals the serial result.
TEST_CASE("tiered compile: batches running across the switch to optimized code") {
    Compiler c;
    Batch serial(1 << 15, 5);
    serial.run(*compile(c, kGold, "backend=simd;cache=off;codegen=optimized"));
    auto k = compile(c, kGold, "backend=simd;cache=off");
    std::atomic<int> mismatches{0}, batches{0};
    auto worker = [&] {
        Batch b(1 << 15, 5);
        do {
            b.run(*k);
            for (int ch = 0; ch < 3; ++ch) mismatches += b.out[ch] != serial.out[ch];
            ++batches;
        } while (k->codeTier() == "quick");
        b.run(*k);  // one more on the optimized code
        for (int ch = 0; ch < 3; ++ch) mismatches += b.out[ch] != serial.out[ch];
    };
    std::thread t1(worker), t2(worker);
    t1.join();
    t2.join();
    MESSAGE(batches.load() << " batches ran before the switch was seen");
    CHECK(k->codeTier() == "optimized");
    CHECK(mismatches == 0);
}

// The caches hold optimized code only: a tiered compile fills them from its
// tier-up, even when the kernel is released before that is done.
TEST_CASE("tiered compile: the caches get the optimized object, also for a released kernel") {
    std::string dir = tempDir("tiered");
    Batch reference(1000, 9);
    reference.run(*[&] {
        Compiler c;
        c.setCacheDir("");
        return compile(c, kGold, "backend=simd;cache=off;codegen=optimized");
    }());
    {
        Compiler c;
        c.setCacheDir(dir);
        compile(c, kGold, "backend=simd").reset();  // released at once
        c.finishTierUps();
        auto hit = compile(c, kGold, "backend=simd");
        CHECK(hit->origin() == "memory cache");
        CHECK(hit->codeTier() == "optimized");
        CHECK(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()) == 1);
    }
    Compiler fresh;
    fresh.setCacheDir(dir);
    auto k = compile(fresh, kGold, "backend=simd");
    CHECK(k->origin() == "disk cache");
    CHECK(k->codeTier() == "optimized");
    Batch b(1000, 9);
    b.run(*k);
    for (int ch = 0; ch < 3; ++ch) CHECK(b.out[ch] == reference.out[ch]);
    // cache=off: nothing is stored, and a released kernel's tier-up is skipped.
    Compiler off;
    off.setCacheDir(dir + "/off");
    compile(off, kGold, "backend=simd;cache=off").reset();
    off.finishTierUps();
    CHECK_FALSE(std::filesystem::exists(dir + "/off"));
    std::filesystem::remove_all(dir);
}

// A Compiler destroyed with tier-ups queued waits for the running one and
// drops the rest (cache=off: nothing outlives the compiler): their kernels
// keep working on the quick code and stop waiting. (Static Compilers, as in
// the C API, are destroyed by exit().) The disk cache test above covers the
// other case: a compiler destroyed right after a compile still writes it.
TEST_CASE("tiered compile: destroying the compiler with tier-ups queued") {
    std::vector<std::unique_ptr<Kernel>> kernels;
    Batch reference(512, 4);
    {
        Compiler c;
        reference.run(*compile(c, kGold, "backend=simd;cache=off;codegen=optimized"));
        // The tier-ups, one at a time on the other thread, fall behind the
        // quick compiles: 4-7 of 12 were done when this was written.
        for (int i = 0; i < 24; ++i) kernels.push_back(compile(c, kGold, "backend=simd;cache=off"));
    }
    size_t optimized = 0;
    for (auto& k : kernels) {
        k->waitOptimized();  // returns: optimized, or dropped
        if (k->codeTier() == "optimized") {
            ++optimized;
            CHECK(k->tierUpError() == "");
        } else {
            CHECK(k->tierUpError() == "not optimized: the compiler was destroyed first");
        }
        Batch b(512, 4);
        CHECK(b.run(*k) == 0);
        for (int ch = 0; ch < 3; ++ch) CHECK(b.out[ch] == reference.out[ch]);
    }
    MESSAGE(optimized << " of 24 tier-ups ran before the compiler was destroyed");
    CHECK(optimized < kernels.size());  // the last ones were still queued
}
