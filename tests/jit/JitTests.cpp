// JIT tests: compilers and JITs side by side, thread safety, the kernel
// caches (memory, disk, corrupted files), specialization visible in the
// optimized IR, and vectorized math (no libm calls in SIMD kernels).
#include "BenchSamples.h"
#include "Checker.h"
#include "Interpreter.h"
#include "Jit.h"
#include "Kernel.h"
#include "KernelCacheFile.h"
#include "Lowering.h"
#include "Pipeline.h"
#include "ReferenceComparison.h"
#include "Specialize.h"

#include <doctest/doctest.h>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <atomic>
#include <cfloat>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <llvm/IR/Instructions.h>
#include <llvm/IR/Module.h>
#include <random>
#include <set>
#include <thread>

using namespace facet;

namespace {

const char* kGold = R"(
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

CompileOptions opts(const std::string& spec) {
    CompileOptions o;
    std::string err = CompileOptions::parse(spec, o);
    REQUIRE_MESSAGE(err.empty(), err);
    return o;
}

// The checked program of a material text that must have no errors.
CheckedProgram checkedText(const std::string& text) {
    DiagnosticEngine d;
    CheckedProgram p = loadProgramText(text, "t.mat", d);
    REQUIRE_MESSAGE(!d.hasErrors(), d.str());
    return p;
}

std::unique_ptr<Kernel> compile(Compiler& c, const std::string& text, const std::string& spec) {
    DiagnosticEngine d;
    auto k = c.compileText(text, "t.mat", "", opts(spec), d);
    REQUIRE_MESSAGE(k, d.str());
    return k;
}

// A two-body SIMD kernel and its float_first=off twin on one random batch
// (directions over the hemisphere, roughness from 0 to 1, both without
// invalid lanes): the two-body kernel's worst relative error against the
// interpreter, and how many channel values differ between the two kernels.
struct TwoBodyRun {
    double worst = 0;
    size_t differing = 0, lanes = 0;
};
TwoBodyRun runTwoBodies(const Kernel& twoBody, const Kernel& oneBody, const char* text) {
    CheckedProgram program = checkedText(text);
    Interpreter<double> interp(program.materials[0], nullptr);
    Batch a(1 << 14, 11), b(1 << 14, 11);
    CHECK(a.run(twoBody) == 0);
    CHECK(b.run(oneBody) == 0);
    TwoBodyRun r;
    r.lanes = a.size();
    for (size_t i = 0; i < a.size(); ++i) {
        EvalResult<double> ref = a.reference(interp, i);
        for (int ch = 0; ch < 3; ++ch) {
            r.differing += a.out[ch][i] != b.out[ch][i];
            r.worst = std::max(r.worst, relativeError(a.out[ch][i], ref.rgb[ch]));
        }
    }
    return r;
}

// Instructions of the optimized module's kernel functions.
size_t optimizedInstructionCount(const std::string& text, const InputBindings& bindings, bool simd) {
    DiagnosticEngine d;
    CompileOptions options;
    options.bindings = bindings;
    LoweringOptions lo;
    // One body: a float-first kernel adds the float body once the bound
    // inputs make the material qualify, which is not what is measured here.
    lo.variant.floatFirst = false;
    lo.emitScalar = !simd;
    lo.emitBatch = simd;
    lo.width = 16;
    Compiler compiler;
    PipelineRun run = PipelineRun::fromText(text, "t.mat", "", options);
    PipelineControl control;
    control.lowering = lo;
    control.stopAfter = PipelineStage::Optimized;
    REQUIRE_MESSAGE(compiler.runPipeline(run, control, FacetJit::Level::Optimized, d), d.str());
    const LoweredModule& mod = run.lowered;
    size_t count = 0;
    for (llvm::Function& f : *mod.module)
        if (!f.isDeclaration())
            for (llvm::BasicBlock& bb : f) count += bb.size();
    return count;
}

// The sampler's outputs over a Batch's wo and roughness columns with
// uniform numbers of a fixed seed: wi (3 n floats), pdf (n), weight (3 n).
std::vector<float> sampleOutputs(const Kernel& k, const Batch& lanes) {
    const size_t n = lanes.size();
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u01(0, 1);
    std::vector<float> u[3];
    for (auto& column : u)
        for (size_t i = 0; i < n; ++i) column.push_back(std::min(u01(rng), 0.99999994f));
    std::vector<float> out(7 * n, -1.0f);
    const float* wo[3] = {lanes.dir[3].data(), lanes.dir[4].data(), lanes.dir[5].data()};
    const float* uu[3] = {u[0].data(), u[1].data(), u[2].data()};
    const float* inputs[4] = {lanes.slots[0].data(), nullptr, nullptr, nullptr};
    float* wi[3] = {&out[0], &out[n], &out[2 * n]};
    float* weight[3] = {&out[4 * n], &out[5 * n], &out[6 * n]};
    CHECK(k.sampleBatch(int64_t(n), wo, uu, inputs, wi, &out[3 * n], weight) == 0);
    return out;
}

// Changes the byte at `offset` of a file.
void flipByte(const std::filesystem::path& path, uintmax_t offset) {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(std::streamoff(offset));
    char byte = 0;
    f.read(&byte, 1);
    f.seekp(std::streamoff(offset));
    byte ^= 0x5a;
    f.write(&byte, 1);
    REQUIRE(f.good());
}

std::string tempDir(const std::string& name) {
    auto dir = std::filesystem::temp_directory_path() / fmt::format("facet-test-{}-{}", name, ::getpid());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

}  // namespace

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
        auto k = compile(compiler, text, "backend=simd;cache=off");
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

TEST_CASE("short batches (n = 1 .. 17, partial chunks) give the long batch's bits, invalid lanes and statuses") {
    Compiler compiler;
    for (const char* spec : {"backend=simd;math=exact;cache=off", "backend=simd;math=fast;cache=off",
                             "backend=simd;math=exact;width=4;cache=off", "backend=simd;math=fast;width=16;cache=off"}) {
        CAPTURE(spec);
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

TEST_CASE("kernel cache file: a record reads back, and every damage or another key is refused") {
    CachedKernel record{std::string("\x7f" "ELF object bytes", 20), "fast", 3.5e-4};
    const std::string key = "material key", bytes = kernelCacheFileBytes(key, record);
    std::optional<CachedKernel> back = parseKernelCacheFile(bytes, key);
    REQUIRE(back);
    CHECK(back->object == record.object);
    CHECK(back->variant == "fast");
    CHECK(back->measuredError == 3.5e-4);
    CHECK(kernelCacheFileKey(bytes) == key);
    CHECK_FALSE(parseKernelCacheFile(bytes, "another key"));
    for (size_t cut = 0; cut < bytes.size(); ++cut) CHECK_FALSE(parseKernelCacheFile(bytes.substr(0, cut), key));
    CHECK_FALSE(parseKernelCacheFile(bytes + "x", key));
    std::string flipped = bytes;
    flipped.back() ^= 1;  // in the object: the checksum no longer matches
    CHECK_FALSE(parseKernelCacheFile(flipped, key));
    std::string magic = bytes;
    magic[0] = 'X';
    CHECK_FALSE(parseKernelCacheFile(magic, key));
    CHECK_FALSE(kernelCacheFileKey(magic));
}

TEST_CASE("disk cache: hit, and truncated or corrupted files are detected and recompiled") {
    std::string dir = tempDir("cache");
    Batch reference(1000, 3);
    {
        Compiler c;
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd");
        CHECK(k->origin() == "compiled");
        reference.run(*k);
    }
    std::vector<std::filesystem::path> files;
    for (auto& e : std::filesystem::directory_iterator(dir)) files.push_back(e.path());
    REQUIRE(files.size() == 1);
    auto reload = [&](const char* expectedOrigin) {
        Compiler c;  // a fresh process-like compiler: no memory cache
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd");
        CHECK(k->origin() == expectedOrigin);
        Batch b(1000, 3);
        b.run(*k);
        for (int ch = 0; ch < 3; ++ch) CHECK(b.out[ch] == reference.out[ch]);
    };
    reload("disk cache");
    auto size = std::filesystem::file_size(files[0]);
    std::filesystem::resize_file(files[0], size / 2);  // truncated
    reload("compiled");
    flipByte(files[0], size - 100);  // corrupted payload byte
    reload("compiled");
    reload("disk cache");  // rewritten by the recompile
    std::filesystem::remove_all(dir);
}

// The sampler's object is cached like eval's, under its own key: a second
// Compiler on the same directory links it without compiling, and a damaged
// sampler file is detected, recompiled and rewritten.
TEST_CASE("disk cache: the compiled sampler is cached, and a damaged sampler file is recompiled") {
    std::string dir = tempDir("sampler-cache");
    Batch lanes(1000, 5);
    std::vector<float> reference;
    std::set<std::filesystem::path> evalFiles;
    {
        Compiler c;
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd;codegen=optimized");
        for (auto& e : std::filesystem::directory_iterator(dir)) evalFiles.insert(e.path());
        REQUIRE(evalFiles.size() == 1);
        CHECK(k->samplerOrigin() == "compiled");
        CHECK(k->samplerTier() == "jit");
        reference = sampleOutputs(*k, lanes);
        // A second kernel of the same compiler: its memory cache.
        auto again = compile(c, kGold, "backend=simd;codegen=optimized");
        CHECK(again->samplerOrigin() == "memory cache");
        CHECK(sampleOutputs(*again, lanes) == reference);
    }
    std::vector<std::filesystem::path> samplerFiles;
    for (auto& e : std::filesystem::directory_iterator(dir))
        if (!evalFiles.count(e.path())) samplerFiles.push_back(e.path());
    REQUIRE(samplerFiles.size() == 1);
    const std::filesystem::path samplerFile = samplerFiles[0];
    CHECK((std::filesystem::status(samplerFile).permissions() & std::filesystem::perms::all) ==
          (std::filesystem::perms::owner_read | std::filesystem::perms::owner_write));
    auto reload = [&](const char* expectedOrigin) {
        Compiler c;  // a fresh process-like compiler: no memory cache
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd;codegen=optimized");
        CHECK(k->origin() == "disk cache");
        CHECK(k->samplerOrigin() == expectedOrigin);
        CHECK(sampleOutputs(*k, lanes) == reference);
    };
    reload("disk cache");
    auto size = std::filesystem::file_size(samplerFile);
    std::filesystem::resize_file(samplerFile, size / 2);  // truncated
    reload("compiled");
    reload("disk cache");  // rewritten by the recompile
    flipByte(samplerFile, size - 100);  // corrupted payload byte
    reload("compiled");
    reload("disk cache");
    // The trust rules of eval's files: a sampler file others can write is
    // refused, with the cache's one warning, and not loaded.
    std::filesystem::permissions(samplerFile, std::filesystem::perms::group_write, std::filesystem::perm_options::add);
    {
        Compiler c;
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd;codegen=optimized");
        CHECK(k->samplerOrigin() == "compiled");
        CHECK_MESSAGE(c.cacheWarning().find("is writable by group or others") != std::string::npos, c.cacheWarning());
        CHECK(sampleOutputs(*k, lanes) == reference);
    }
    std::filesystem::permissions(samplerFile, std::filesystem::perms::group_write, std::filesystem::perm_options::remove);
    reload("disk cache");
    // cache=memory and cache=off never write the directory.
    {
        Compiler c;
        c.setCacheDir(dir + "/memory");
        auto k = compile(c, kGold, "backend=simd;codegen=optimized;cache=memory");
        CHECK(k->samplerOrigin() == "compiled");
        CHECK(compile(c, kGold, "backend=simd;codegen=optimized;cache=memory")->samplerOrigin() == "memory cache");
        CHECK(compile(c, kGold, "backend=simd;codegen=optimized;cache=off")->samplerOrigin() == "compiled");
        CHECK_FALSE(std::filesystem::exists(dir + "/memory"));
    }
    std::filesystem::remove_all(dir);
}

// Where the cache's object passes every check of its file (owner, mode, key,
// checksum) but is not a sampler -- here eval's object under the sampler's
// key, as a buggy writer could leave it -- the kernel samples through the
// reference and says why, instead of switching silently.
TEST_CASE("disk cache: a sampler that does not link is reported, and the reference samples") {
    std::string dir = tempDir("sampler-broken");
    Batch lanes(500, 5);
    std::set<std::filesystem::path> evalFiles;
    {
        Compiler c;
        c.setCacheDir(dir);
        auto k = compile(c, kGold, "backend=simd;codegen=optimized");
        for (auto& e : std::filesystem::directory_iterator(dir)) evalFiles.insert(e.path());
        REQUIRE(k->samplerTier() == "jit");
        CHECK(k->samplerError() == "");
    }
    REQUIRE(evalFiles.size() == 1);
    std::filesystem::path samplerFile;
    for (auto& e : std::filesystem::directory_iterator(dir))
        if (!evalFiles.count(e.path())) samplerFile = e.path();
    REQUIRE(!samplerFile.empty());
    auto readAll = [](const std::filesystem::path& path) {
        std::ifstream f(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(f), {});
    };
    // The sampler's file with eval's object in it: a valid cache file (its
    // checksum matches) whose object lacks the sampler's entry points.
    std::string sampler = readAll(samplerFile), eval = readAll(*evalFiles.begin());
    std::optional<std::string> samplerKey = kernelCacheFileKey(sampler), evalKey = kernelCacheFileKey(eval);
    REQUIRE(samplerKey);
    REQUIRE(evalKey);
    std::optional<CachedKernel> samplerRecord = parseKernelCacheFile(sampler, *samplerKey);
    std::optional<CachedKernel> evalRecord = parseKernelCacheFile(eval, *evalKey);
    REQUIRE(samplerRecord);
    REQUIRE(evalRecord);
    CachedKernel wrong = *samplerRecord;
    wrong.object = evalRecord->object;
    std::string spliced = kernelCacheFileBytes(*samplerKey, wrong);
    {
        std::ofstream f(samplerFile, std::ios::binary | std::ios::trunc);
        f.write(spliced.data(), std::streamsize(spliced.size()));
        REQUIRE(f.good());
    }
    Compiler c;
    c.setCacheDir(dir);
    auto k = compile(c, kGold, "backend=simd;codegen=optimized");
    CHECK(k->origin() == "disk cache");
    CHECK(k->samplerTier() == "reference");
    CHECK(k->samplerOrigin() == "");
    const std::string& why = k->samplerError();
    CHECK_MESSAGE(why.find("the sampler from the disk cache failed") != std::string::npos, why);
    CHECK_MESSAGE(why.find("_sample_") != std::string::npos, why);
    // The reference still samples every lane.
    std::vector<float> out = sampleOutputs(*k, lanes);
    const size_t n = lanes.size();
    size_t positive = 0;
    for (size_t i = 0; i < n; ++i) {
        float pdf = out[3 * n + i];
        CHECK(std::isfinite(pdf));
        positive += pdf > 0;
    }
    CHECK(positive > n / 2);
    std::filesystem::remove_all(dir);
}

// A tolerance build loaded from a cache samples with the variant its search
// chose, as the kernel that ran the search does: the sampler of the math
// mode it chose, bit for bit, not the base variant's.
TEST_CASE("disk cache: a tolerance kernel's sampler uses the variant the search chose") {
    std::string dir = tempDir("sampler-tolerance");
    Batch lanes(2000, 6);
    const char* spec = "backend=simd;codegen=optimized;tolerance=1e-3";
    std::vector<float> searched;
    std::string variant;
    {
        Compiler c;
        c.setCacheDir(dir);
        auto k = compile(c, kGold, spec);
        variant = k->variant();
        searched = sampleOutputs(*k, lanes);
    }
    REQUIRE(variant == "fast");  // gold meets 1e-3 in fast mode: the base variant (exact) is not chosen
    Compiler c;
    c.setCacheDir(dir);
    auto cached = compile(c, kGold, spec);
    CHECK(cached->origin() == "disk cache");
    CHECK(cached->samplerOrigin() == "disk cache");
    CHECK(sampleOutputs(*cached, lanes) == searched);
    Compiler plain;
    plain.setCacheDir("");
    std::vector<float> fast = sampleOutputs(*compile(plain, kGold, "backend=simd;math=fast;cache=off"), lanes);
    std::vector<float> exact = sampleOutputs(*compile(plain, kGold, "backend=simd;cache=off"), lanes);
    CHECK(searched == fast);
    CHECK(searched != exact);
    std::filesystem::remove_all(dir);
}

TEST_CASE("cache keys separate options and bound values") {
    Compiler c;
    c.setCacheDir("");
    auto k1 = compile(c, kGold, "backend=simd;cache=memory;set.roughness=0.2");
    auto k2 = compile(c, kGold, "backend=simd;cache=memory;set.roughness=0.3");
    auto k3 = compile(c, kGold, "backend=simd;cache=memory;width=8");
    auto k4 = compile(c, kGold, "backend=simd;cache=memory;set.roughness=0.2;float_first=off");
    CHECK(k2->origin() == "compiled");
    CHECK(k3->origin() == "compiled");
    CHECK(k4->origin() == "compiled");
    CHECK(k3->width() == 8);
    float n[3] = {0, 0, 1}, a[3], b[3];
    k1->eval(n, n, nullptr, a);
    k2->eval(n, n, nullptr, b);
    CHECK(a[0] > b[0]);  // smoother surface, higher peak
}

TEST_CASE("specialization shrinks the optimized IR") {
    size_t unbound = optimizedInstructionCount(kGold, {}, true);
    size_t bound = optimizedInstructionCount(kGold, {{"roughness", {0.3}}, {"tint", {1.0}}}, true);
    MESSAGE("gold SIMD kernel: " << unbound << " instructions unbound, " << bound << " with roughness and tint bound");
    CHECK(bound < unbound);

    // Terms that cannot matter are removed: F = none and G = none.
    const char* full = "material m { input r = 0.5; ndf = beckmann(r); masking = smith_separable; fresnel = dielectric(1.5); }";
    const char* bare = "material m { input r = 0.5; ndf = beckmann(r); }";
    CHECK(optimizedInstructionCount(bare, {}, false) < optimizedInstructionCount(full, {}, false));

    // An rgb whose channels are provably equal is computed once.
    const char* gray = "material m { input r = 0.5; ndf = ggx(r); fresnel = conductor(eta = 0.2, k = 3.0); }";
    const char* color = "material m { input r = 0.5; ndf = ggx(r); fresnel = conductor(eta = rgb(0.2, 0.3, 0.4), k = 3.0); }";
    size_t grayCount = optimizedInstructionCount(gray, {}, false), colorCount = optimizedInstructionCount(color, {}, false);
    MESSAGE("gray conductor " << grayCount << " instructions, rgb conductor " << colorCount);
    CHECK(grayCount < colorCount);
}

TEST_CASE("SIMD kernels keep their math vectorized: no libm calls") {
    const char* text = R"(material b { input r = 0.4 in 0 .. 1; input e = 2;
        ndf = beckmann(r * r); masking = smith_height_correlated;
        fresnel = dielectric(1.5); diffuse = lambert(pow(r, e) * exp(-r) + log(1 + r)); })";
    std::string path = tempDir("ir") + "/b.mat";
    std::ofstream(path) << text;
    Compiler c;
    DiagnosticEngine d;
    CompileOptions o = opts("backend=simd");
    std::string ir = c.irText(path, "", o, true, Compiler::IrOutput::Optimized, d);
    REQUIRE_MESSAGE(!d.hasErrors(), d.str());
    size_t calls = 0, vectorOps = 0;
    // The host's width: 16 lanes with AVX-512, 8 with AVX2, else 4.
    const std::string hostVector = "<" + std::to_string(c.resolveWidth(o)) + " x float>";
    std::istringstream lines(ir);
    for (std::string line; std::getline(lines, line);) {
        size_t call = line.find(" call ");
        if (call != std::string::npos) {
            size_t at = line.find('@', call);
            INFO(line);
            CHECK(line.compare(at, 6, "@llvm.") == 0);  // only intrinsics
            ++calls;
        }
        if (line.find(hostVector) != std::string::npos) ++vectorOps;
    }
    CHECK(vectorOps > 50);
    CHECK(ir.find("@exp") == std::string::npos);
    CHECK(ir.find("@erfc") == std::string::npos);
    CHECK(ir.find("@pow") == std::string::npos);
}

TEST_CASE("option strings are validated") {
    CompileOptions o;
    CHECK(CompileOptions::parse("backend=simd; math=fast ;width=8;set.tint=1,0.5,0.25", o) == "");
    CHECK(o.width == 8);
    CHECK(o.math == MathMode::Fast);
    CHECK(o.bindings.at("tint") == std::vector<double>{1, 0.5, 0.25});
    CHECK(CompileOptions::parse("width=7", o) == "width '7' is not 4, 8 or 16");
    CHECK(CompileOptions::parse("tolerance=-1", o) == "tolerance '-1' is not a positive number");
    CHECK(CompileOptions::parse("set.x=nan", o) == "set.x: 'nan' is not a finite number");
    CHECK(CompileOptions::parse("colour=red", o).find("unknown option 'colour'") == 0);
    CHECK(CompileOptions::parse("float_first=off", o) == "");
    CHECK_FALSE(o.floatFirst);
    CHECK(CompileOptions::parse("float_first=maybe", o) == "float_first 'maybe' is not on or off");
    CHECK(o.codegen == CompileOptions::Codegen::Tiered);
    CHECK(CompileOptions::parse("codegen=quick", o) == "");
    CHECK(o.codegen == CompileOptions::Codegen::Quick);
    CHECK(CompileOptions::parse("codegen=fastest", o) == "codegen 'fastest' is not tiered, quick or optimized");
    Compiler c;
    DiagnosticEngine d;
    CHECK(c.compileText(kGold, "t.mat", "", opts("set.shine=1"), d) == nullptr);
    CHECK(d.str() == "t.mat:2:10: error: cannot bind 'shine': material 'gold' has no such input (inputs: roughness, tint)\n");
}

TEST_CASE("tolerance selection never returns a variant whose measured error exceeds the tolerance") {
    Compiler c;
    size_t checked = 0;
    for (const char* file : {"gold", "aluminium", "glass", "cook_torrance_classic", "legacy_blinn_phong", "satin_gaussian"}) {
        std::string path = fmt::format("{}/materials/{}.mat", FACET_SOURCE_DIR, file);
        for (double tol : {1e-2, 1e-3, 1e-5}) {
            DiagnosticEngine d;
            CompileOptions o = opts(fmt::format("backend=simd;cache=off;tolerance={}", tol));
            auto k = c.compileFile(path, "", o, d);
            REQUIRE_MESSAGE(k, d.str());
            INFO(file << " tolerance " << tol << " picked " << k->variant() << " measured " << k->measuredError());
            CHECK(k->measuredError() >= 0);
            CHECK(k->measuredError() <= tol);
            // The measurement is reproducible: measuring the chosen kernel
            // again gives the same number, with the quick code it was chosen
            // with and with the optimized code of its tier-up.
            CHECK(measureKernelError(*k, k->material()) == k->measuredError());
            k->waitOptimized();
            CHECK(k->codeTier() == "optimized");
            CHECK(measureKernelError(*k, k->material()) == k->measuredError());
            ++checked;
        }
    }
    CHECK(checked == 18);
    // Model substitutions are only picked when a tolerance allows them:
    // plain math=fast never uses Walter's Lambda or Schlick for a dielectric.
    DiagnosticEngine d;
    auto fast = c.compileFile(fmt::format("{}/materials/aluminium.mat", FACET_SOURCE_DIR), "", opts("math=fast;cache=off"), d);
    REQUIRE(fast);
    CHECK(fast->variant() == "fast");
}

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

TEST_CASE("guarded fast SIMD: unscaled Smith forms where the range guards allow, the plain fast body elsewhere") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(eta = 1.5); })";
    auto applies = [](const char* text, MathVariant variant = MathVariant::fast()) {
        CheckedProgram p = checkedText(text);
        return planLowering(p.materials[0], variant).batchBodies == BatchBodies::GuardedFast;
    };
    // Schlick from eta is not the float-first body's (it would round f0 in
    // float); where that body applies (Schlick with f0, no Fresnel term),
    // fast kernels take it instead.
    CHECK(applies(ggx));
    CHECK(applies(kGold));  // fast mode computes the conductor in float anyway
    CHECK_FALSE(applies(ggx, MathVariant::exact()));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = beckmann(r); }"));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = ggx(r, r * 0.5); fresnel = schlick(eta = 1.5); }"));  // anisotropic
    CHECK(applies("material m { ndf = ggx(0.3, 0.3); fresnel = schlick(eta = 1.5); }"));  // equal constants
    CHECK_FALSE(applies("material m { ndf = ggx(0.3); fresnel = schlick(f0 = 0.04); }"));  // float-first

    Compiler c;
    c.setCacheDir("");
    auto guarded = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off");
    auto plain = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off;float_first=off");

    // The guarded body ran (its values differ from the plain body's in many
    // lanes) and is within fast mode's accuracy (the plain body's worst is
    // ~1e-5 here).
    TwoBodyRun run = runTwoBodies(*guarded, *plain, ggx);
    MESSAGE("guarded fast vs interpreter: worst relative error " << run.worst << "; " << run.differing
                                                                 << " channel values differ from float_first=off");
    CHECK(run.worst < 1e-4);
    CHECK(run.differing > run.lanes / 4);

    // Lanes the guards reject come from the plain body, bit for bit, and do
    // not change their neighbours: a grazing lane (n.wi = 1e-8 < 1e-6) and
    // an invalid one (NaN); a lane below the horizon is 0 in both bodies.
    Batch g(16, 5);
    g.run(*guarded);
    std::vector<float> before[3] = {g.out[0], g.out[1], g.out[2]};
    g.dir[0][5] = 1.0f, g.dir[1][5] = 0.0f, g.dir[2][5] = 1e-8f;
    g.dir[4][9] = std::nanf("");
    g.dir[2][12] = -g.dir[2][12];
    CHECK(g.run(*guarded) == 1);
    Batch h = g;
    CHECK(h.run(*plain) == 1);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][5] == h.out[ch][5]);
        CHECK(g.out[ch][5] > 0.0f);
        CHECK(g.out[ch][9] == 0.0f);
        CHECK(g.out[ch][12] == 0.0f);
        for (int lane = 0; lane < 16; ++lane)
            if (lane != 5 && lane != 9 && lane != 12) CHECK(g.out[ch][lane] == before[ch][lane]);
    }
}

TEST_CASE("guarded fast SIMD: a small alpha keeps the guarded body away from the peak, the plain body at it") {
    // The guarded fast body sums the unit directions rounded to float: h is
    // off by ~1e-7 / |wi + wo|, which matters only where D is steep in
    // theta_h (GgxEmitter). At alpha = 1.44e-4 and random directions D is
    // flat (theta_h >> alpha): the guarded body keeps those lanes. At a
    // mirror pair with n.wi = 1e-4 and theta_h = 1e-5 the rounding alone
    // moves D by 0.35%: that lane is the plain body's, within 1e-5.
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(eta = 1.5); })";
    Compiler c;
    c.setCacheDir("");
    auto guarded = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off");
    auto plain = compile(c, ggx, "backend=simd;width=16;math=fast;cache=off;float_first=off");
    CheckedProgram program = checkedText(ggx);
    Interpreter<double> interp(program.materials[0], nullptr);

    Batch g(16, 7);
    for (float& r : g.slots[0]) r = 0.012f;
    const int peak = 5;
    g.dir[0][peak] = -0.416146845f, g.dir[1][peak] = 0.909297407f, g.dir[2][peak] = 9.99999975e-05f;
    g.dir[3][peak] = 0.416146845f, g.dir[4][peak] = -0.909297407f, g.dir[5][peak] = 9.16770659e-05f;
    Batch h = g;
    CHECK(g.run(*guarded) == 0);
    CHECK(h.run(*plain) == 0);
    int kept = 0;
    for (int lane = 0; lane < 16; ++lane)
        if (lane != peak) kept += g.out[0][lane] != h.out[0][lane] || g.out[1][lane] != h.out[1][lane];
    // 8 here (the others round alike in both bodies); distrusting every
    // lane with alpha (wo.h) < 5e-4, a bound over all theta_h, gives 0.
    MESSAGE(kept << " of 15 lanes away from the peak differ from the plain body");
    CHECK(kept >= 4);
    EvalResult<double> ref = g.reference(interp, peak);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][peak] == h.out[ch][peak]);
        CHECK(relativeError(g.out[ch][peak], ref.rgb[ch]) < 1e-5);
    }
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

TEST_CASE("float-first exact SIMD: float where a lane is well-conditioned, the precise body elsewhere") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    auto applies = [](const char* text) {
        CheckedProgram p = checkedText(text);
        return planLowering(p.materials[0], MathVariant::exact()).batchBodies == BatchBodies::FloatFirst;
    };
    CHECK(applies(ggx));
    CHECK_FALSE(applies(kGold));  // conductor eta is an input: ill-conditioned regions possible
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = beckmann(r); }"));
    CHECK_FALSE(applies("material m { input r = 0.5; ndf = ggx(r); fresnel = schlick(eta = r + 1); }"));
    CHECK(applies("material m { input r = 0.5; ndf = ggx(exp(r) - 1); }"));

    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=16;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=16;cache=off;float_first=off");
    DiagnosticEngine d;

    // The float values differ from the precise ones in many lanes (so the
    // float body ran) and stay within exact-mode accuracy of the interpreter.
    TwoBodyRun run = runTwoBodies(*floatFirst, *precise, ggx);
    MESSAGE("float-first vs interpreter: worst relative error " << run.worst << "; " << run.differing
                                                                << " channel values differ from float_first=off");
    CHECK(run.worst < 2e-6);
    CHECK(run.differing > run.lanes / 4);

    // The material's own arithmetic is evaluated in double in the float
    // body too: alpha = 0.5 - x^2 cancels at x = 0.707 (float: 1.3e-4 error).
    const char* cancel = "material m { input x = 0.5; ndf = ggx(-x^2 + 0.5); }";
    auto cancelKernel = compile(c, cancel, "backend=simd;width=16;cache=off");
    CheckedProgram cancelProgram = loadProgramText(cancel, "t.mat", d);
    Interpreter<double> cancelInterp(cancelProgram.materials[0], nullptr);
    Batch x(4096, 3);
    for (size_t i = 0; i < x.size(); ++i) x.slots[0][i] = 0.7f + 0.0071f * float(i) / float(x.size());
    CHECK(x.run(*cancelKernel) == 0);
    double worstCancel = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        EvalResult<double> ref = x.reference(cancelInterp, i);
        if (ref.valid) worstCancel = std::max(worstCancel, relativeError(x.out[0][i], ref.rgb[0]));
    }
    MESSAGE("alpha = 0.5 - x^2 near x = 0.707: worst relative error " << worstCancel);
    CHECK(worstCancel < 2e-6);

    // An ill-conditioned lane (n.wi = 1e-8, grazing) is computed by the
    // precise body, bit for bit, and does not change its neighbours.
    Batch g(16, 5);
    g.run(*floatFirst);
    std::vector<float> before[3] = {g.out[0], g.out[1], g.out[2]};
    g.dir[0][5] = 1.0f, g.dir[1][5] = 0.0f, g.dir[2][5] = 1e-8f;
    CHECK(g.run(*floatFirst) == 0);
    float graze[3];
    float wi5[3] = {1.0f, 0.0f, 1e-8f}, wo5[3] = {g.dir[3][5], g.dir[4][5], g.dir[5][5]}, r5[1] = {g.slots[0][5]};
    precise->eval(wi5, wo5, r5, graze);
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(g.out[ch][5] == graze[ch]);
        CHECK(g.out[ch][5] > 0.0f);
        for (int lane = 0; lane < 16; ++lane)
            if (lane != 5) CHECK(g.out[ch][lane] == before[ch][lane]);
    }
}

// The float bodies hand the lanes whose validity they cannot decide to the
// precise body (the sampler's, on |w|^2 - 1 rounded to float; the
// evaluation's isotropic one, every lane not within 1e-4 of unit length in
// |wi|^2 + |wo|^2): at the unit tolerance's bounds, both bodies (and eval
// and sample) call the same lanes invalid as the all-double kernel.
TEST_CASE("float-first exact SIMD: directions at the unit tolerance's bounds are valid exactly as in double") {
    const char* ggx = R"(material m { ndf = ggx(0.3); masking = smith_height_correlated; fresnel = schlick(0.04); })";
    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=8;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=8;cache=off;float_first=off");
    // Directions scaled to |w|^2 within ~1e-9 of (1 -+ 1e-3)^2, rounded to
    // float; the valid lanes are the ones the double test accepts.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> uniform(0, 1);
    const double bounds[2] = {(1 - 1e-3) * (1 - 1e-3), (1 + 1e-3) * (1 + 1e-3)};
    const size_t n = 4096;
    std::array<std::vector<float>, 3> wo, wi, u;
    std::vector<uint8_t> expectInvalid;
    int atRoundedBound = 0;
    for (size_t i = 0; i < n; ++i) {
        double z = 0.2 + 0.8 * uniform(rng), phi = 6.283185307179586 * uniform(rng), r = std::sqrt(1 - z * z);
        double bound = bounds[i % 2], scale = std::sqrt(bound * (1 + 2e-9 * (uniform(rng) - 0.5)));
        float w[3] = {float(r * std::cos(phi) * scale), float(r * std::sin(phi) * scale), float(z * scale)};
        double len2 = double(w[0]) * w[0] + double(w[1]) * w[1] + double(w[2]) * w[2];
        expectInvalid.push_back(len2 < bounds[0] || len2 > bounds[1]);
        atRoundedBound += float(len2 - 1) == float(bound - 1);
        for (int k = 0; k < 3; ++k) wo[k].push_back(w[k]), u[k].push_back(0.25f * float(k + 1));
        wi[0].push_back(0.6f), wi[1].push_back(0.0f), wi[2].push_back(0.8f);
    }
    MESSAGE(atRoundedBound << " of " << n << " lanes with |w|^2 - 1 at a rounded bound");
    CHECK(atRoundedBound > 10);
    const float* woP[3] = {wo[0].data(), wo[1].data(), wo[2].data()};
    const float* wiP[3] = {wi[0].data(), wi[1].data(), wi[2].data()};
    const float* uP[3] = {u[0].data(), u[1].data(), u[2].data()};
    std::array<std::vector<float>, 3> rgb, wiOut, weight;
    std::vector<float> pdf(n);
    for (int k = 0; k < 3; ++k) rgb[k].resize(n), wiOut[k].resize(n), weight[k].resize(n);
    float* rgbP[3] = {rgb[0].data(), rgb[1].data(), rgb[2].data()};
    float* wiOutP[3] = {wiOut[0].data(), wiOut[1].data(), wiOut[2].data()};
    float* weightP[3] = {weight[0].data(), weight[1].data(), weight[2].data()};
    const int64_t expected = std::count(expectInvalid.begin(), expectInvalid.end(), 1);
    CHECK(expected > int64_t(n / 4));
    CHECK(expected < int64_t(3 * n / 4));
    for (const Kernel* k : {floatFirst.get(), precise.get()}) {
        std::vector<uint8_t> status(n, 7);
        CHECK(k->evalBatch(int64_t(n), wiP, woP, nullptr, rgbP, status.data()) == expected);
        CHECK(status == expectInvalid);
        CHECK(k->sampleBatch(int64_t(n), woP, uP, nullptr, wiOutP, pdf.data(), weightP) == expected);
        for (size_t i = 0; i < n; ++i) CHECK((pdf[i] > 0) == !expectInvalid[i]);
    }
}

// The isotropic float body corrects the pair's lengths in float
// (LaneEmitter::floatPairCorrections): the difference of the two
// corrections from (wi - wo).(wi + wo). On nearly opposite directions of
// slightly different lengths, where that difference decides h, it must
// stay as accurate as the double corrections were; lanes further from
// unit length go to the precise body, bit for bit.
TEST_CASE("float-first exact SIMD: nearly opposite directions of slightly different lengths") {
    const char* ggx = R"(material m {
        input roughness = 0.4 in 0 .. 1;
        let alpha = roughness * roughness;
        ndf = ggx(alpha); masking = smith_height_correlated; fresnel = schlick(f0 = rgb(0.95, 0.64, 0.54)); })";
    CheckedProgram program = checkedText(ggx);
    CHECK(planLowering(program.materials[0], MathVariant::exact()).batchBody.floatPairCorrections);
    Compiler c;
    c.setCacheDir("");
    auto floatFirst = compile(c, ggx, "backend=simd;width=16;cache=off");
    auto precise = compile(c, ggx, "backend=simd;width=16;cache=off;float_first=off");
    Interpreter<double> interp(program.materials[0], nullptr);
    // Elevations from 1e-3 to 0.3 rad, azimuths pi -+ 0.01 apart, each
    // direction scaled by 1 + e with |e| up to 2e-5 (float body) or 2e-4
    // (|wi|^2 + |wo|^2 - 2 beyond 1e-4: precise body); alpha from 1e-3 to 0.5.
    Batch b(8192, 17), reference(8192, 17);
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> uniform(0, 1);
    std::vector<bool> farFromUnit(b.size());
    for (size_t i = 0; i < b.size(); ++i) {
        auto elevation = [&] { return std::exp(std::log(1e-3) + uniform(rng) * std::log(300.0)); };
        double ei = elevation(), eo = elevation(), phi = 6.283185307179586 * uniform(rng);
        double phiI = phi + 3.141592653589793 + 0.02 * (uniform(rng) - 0.5);
        farFromUnit[i] = i % 4 == 0;
        double spread = farFromUnit[i] ? 2e-4 : 2e-5;
        double si = 1 + spread * (2 * uniform(rng) - 1), so = 1 + spread * (2 * uniform(rng) - 1);
        double wi[3] = {std::cos(ei) * std::cos(phiI) * si, std::cos(ei) * std::sin(phiI) * si, std::sin(ei) * si};
        double wo[3] = {std::cos(eo) * std::cos(phi) * so, std::cos(eo) * std::sin(phi) * so, std::sin(eo) * so};
        for (int k = 0; k < 3; ++k) b.dir[k][i] = float(wi[k]), b.dir[3 + k][i] = float(wo[k]);
        double len2[2] = {0, 0};
        for (int k = 0; k < 3; ++k) len2[0] += double(b.dir[k][i]) * b.dir[k][i], len2[1] += double(b.dir[3 + k][i]) * b.dir[3 + k][i];
        if (farFromUnit[i]) farFromUnit[i] = std::abs(len2[0] - 1) + std::abs(len2[1] - 1) > 1.01e-4;
        b.slots[0][i] = float(std::sqrt(std::exp(std::log(1e-3) + uniform(rng) * std::log(500.0))));
        for (int k = 0; k < 6; ++k) reference.dir[k][i] = b.dir[k][i];
        reference.slots[0][i] = b.slots[0][i];
    }
    CHECK(b.run(*floatFirst) == 0);
    CHECK(reference.run(*precise) == 0);
    double worst = 0;
    size_t fromFloat = 0, far = 0;
    for (size_t i = 0; i < b.size(); ++i) {
        EvalResult<double> ref = b.reference(interp, i);
        REQUIRE(ref.valid);
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) {
            worst = std::max(worst, relativeError(b.out[ch][i], ref.rgb[ch]));
            same = same && b.out[ch][i] == reference.out[ch][i];
        }
        fromFloat += !same;
        if (farFromUnit[i]) {
            ++far;
            CHECK(same);
        }
    }
    MESSAGE("nearly opposite pairs: worst relative error " << worst << "; " << fromFloat << " of " << b.size()
                                                           << " lanes from the float body, " << far << " far from unit length");
    CHECK(worst < 2e-6);
    CHECK(fromFloat > b.size() / 2);
    CHECK(far > b.size() / 8);
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
                if (std::string_view(row).starts_with("backend=simd")) {
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
    CHECK(kernels == 72);
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
