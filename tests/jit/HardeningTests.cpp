// Hardening: the disk cache's trust model (CacheFiles.h) as the kernel and
// table caches apply it, the per-lane status of the batch call, and extreme
// model parameters that must give the interpreter's value or an invalid lane.
#include "CacheFiles.h"
#include "Checker.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "ReferenceComparison.h"
#include "TableCache.h"
#include "../ScratchDir.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sys/stat.h>
#include <unistd.h>

using namespace facet;
namespace fs = std::filesystem;

using facet::test::ScratchDir;

namespace {

const char* kLambert = "material m { ndf = ggx(0.5); diffuse = lambert(rgb(0.2, 0.4, 0.6)); }";

struct Compiled {
    std::unique_ptr<Kernel> kernel;
    std::string warning;
};

// Compiles `text` with the option string `options`.
std::unique_ptr<Kernel> compileWith(Compiler& c, const std::string& text, const std::string& options) {
    CompileOptions o;
    REQUIRE(CompileOptions::parse(options, o).empty());
    DiagnosticEngine d;
    auto k = c.compileText(text, "x.mat", "", o, d);
    REQUIRE_MESSAGE(k, d.str());
    return k;
}

// Compiles kLambert with a fresh Compiler (no memory cache) on `dir`.
Compiled compileIn(const std::string& dir, const char* options = "backend=simd;codegen=optimized") {
    Compiler c;
    c.setCacheDir(dir);
    Compiled r;
    r.kernel = compileWith(c, kLambert, options);
    r.warning = c.cacheWarning();
    return r;
}

std::vector<fs::path> entries(const fs::path& dir) {
    std::vector<fs::path> out;
    for (auto& e : fs::directory_iterator(dir)) out.push_back(e.path());
    return out;
}

// Fills the cache in `dir` with kLambert's kernel; returns the entry's path.
fs::path cachedEntry(const fs::path& dir) {
    compileIn(dir.string());
    return entries(dir).at(0);
}

// A fresh compile on `dir` neither loads from it nor stays quiet about why.
void expectRefused(const fs::path& dir, const std::string& because) {
    Compiled r = compileIn(dir.string());
    CHECK(r.kernel->origin() == "compiled");
    CHECK_MESSAGE(r.warning.find(because) != std::string::npos, r.warning);
}

float evalNormal(const Kernel& k) {
    float n[3] = {0, 0, 1}, rgb[3];
    k.eval(n, n, nullptr, rgb);
    return rgb[0];
}

}  // namespace

TEST_SUITE("hardening") {

TEST_CASE("cache: files 0600 and directories 0700 whatever the umask; the entry is reused") {
    ScratchDir scratch("modes");
    std::string root = scratch.str() + "/a/b";
    mode_t old = ::umask(0);
    Compiled first = compileIn(root);
    ::umask(old);
    CHECK(first.kernel->origin() == "compiled");
    CHECK(first.warning == "");
    struct stat st;
    REQUIRE(::stat(root.c_str(), &st) == 0);
    CHECK((st.st_mode & 0777) == 0700);
    REQUIRE(::stat((scratch.str() + "/a").c_str(), &st) == 0);
    CHECK((st.st_mode & 0777) == 0700);
    auto files = entries(root);
    REQUIRE(files.size() == 1);  // no temporary file left behind
    CHECK(files[0].extension() == ".fko");
    REQUIRE(::stat(files[0].c_str(), &st) == 0);
    CHECK((st.st_mode & 0777) == 0600);
    CHECK(compileIn(root).kernel->origin() == "disk cache");
}

TEST_CASE("cache: a group- or world-writable directory is refused with one warning, and the run goes on") {
    for (mode_t mode : {mode_t(0770), mode_t(0707), mode_t(01777)}) {
        ScratchDir scratch("writable");
        Compiled warm = compileIn(scratch.str());  // a valid entry, written while the mode was 0700
        float want = evalNormal(*warm.kernel);
        REQUIRE(::chmod(scratch.path.c_str(), mode) == 0);
        Compiled r = compileIn(scratch.str());
        CHECK(r.kernel->origin() == "compiled");  // not loaded from there
        CHECK(r.warning.find("is writable by group or others") != std::string::npos);
        CHECK(evalNormal(*r.kernel) == want);
        CHECK(entries(scratch.path).size() == 1);  // nothing written either
    }
}

TEST_CASE("cache: a file another user owns or others can write is not loaded") {
    ScratchDir scratch("owner");
    fs::path entry = cachedEntry(scratch.path);
    REQUIRE(::chmod(entry.c_str(), 0620) == 0);
    expectRefused(scratch.path, "is writable by group or others (mode 0620)");
    REQUIRE(::chmod(entry.c_str(), 0600) == 0);
    CHECK(compileIn(scratch.str()).kernel->origin() == "disk cache");
    if (::geteuid() == 0 && ::chown(entry.c_str(), 65534, 65534) == 0) {
        expectRefused(scratch.path, "is owned by uid 65534");
    }
}

TEST_CASE("cache: a symlink at an entry is not followed, read or written through") {
    ScratchDir scratch("symlink");
    fs::path entry = cachedEntry(scratch.path);
    // The victim is a valid cache file elsewhere: following the link would load it.
    ScratchDir elsewhere("victim");
    fs::path outside = elsewhere.path / "victim";
    fs::copy_file(entry, outside);
    fs::remove(entry);
    fs::create_symlink(outside, entry);
    auto before = fs::file_size(outside);
    expectRefused(scratch.path, "is a symlink");
    CHECK(fs::is_symlink(fs::symlink_status(entry)));  // not replaced
    CHECK(fs::file_size(outside) == before);
}

TEST_CASE("cache: a FIFO at an entry neither hangs nor is used") {
    ScratchDir scratch("fifo");
    fs::path entry = cachedEntry(scratch.path);
    fs::remove(entry);
    REQUIRE(::mkfifo(entry.c_str(), 0600) == 0);
    expectRefused(scratch.path, "is a FIFO");  // would block in open() if it read the FIFO
}

TEST_CASE("cache: a header length beyond the file is rejected before anything is allocated") {
    ScratchDir scratch("length");
    fs::path entry = cachedEntry(scratch.path);
    std::string bytes;
    {
        std::ifstream in(entry, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    REQUIRE(bytes.size() > 16);
    uint64_t huge = uint64_t(250) << 20;
    std::memcpy(&bytes[8], &huge, 8);  // the key's length field
    {
        std::ofstream out(entry, std::ios::binary | std::ios::trunc);
        out << bytes;
    }
    Compiled r = compileIn(scratch.str());
    CHECK(r.kernel->origin() == "compiled");
    CHECK(r.warning == "");  // corrupt, not distrusted: rewritten
    CHECK(compileIn(scratch.str()).kernel->origin() == "disk cache");
}

TEST_CASE("cache: an empty FACET_CACHE_DIR means no disk cache, for tables too") {
    const char* old = std::getenv("FACET_CACHE_DIR");
    std::string saved = old ? old : "";
    ::setenv("FACET_CACHE_DIR", "", 1);
    CHECK(defaultCacheRoot() == "");
    CHECK(defaultTableCacheDir() == "");
    {
        Compiler c;
        CHECK(c.cacheDir() == "");
    }
    if (old) ::setenv("FACET_CACHE_DIR", saved.c_str(), 1);
    else ::unsetenv("FACET_CACHE_DIR");
}

TEST_CASE("table cache: a Compiler writes the Lambda table, a second loads it and computes the same bits") {
    ScratchDir scratch("lambda");
    const char* old = std::getenv("FACET_CACHE_DIR");
    std::string saved = old ? old : "";
    ::setenv("FACET_CACHE_DIR", scratch.str().c_str(), 1);
    // gamma 2.25: no other test of this binary uses it, so the first
    // Compiler builds the table itself.
    const char* text = "material m { input alpha = 0.3 in 0.001 .. 1; ndf = student_t(alpha, 2.25); "
                       "masking = smith_height_correlated; }";
    const fs::path file = scratch.path / "tables" / "lambda_student_t_g2.25.bin";
    auto evalAll = [&](Compiler& c) {
        auto k = compileWith(c, text, "backend=simd;codegen=optimized;cache=off");
        std::vector<float> out;
        for (float alpha : {0.01f, 0.3f, 1.0f})
            for (double t : {0.0, 0.7, 1.3, 1.5, 1.5703}) {
                float wi[3] = {float(std::sin(t)), 0, float(std::cos(t))}, wo[3] = {-0.6f, 0, 0.8f}, rgb[3];
                k->eval(wi, wo, &alpha, rgb);
                out.push_back(rgb[0]);
            }
        return out;
    };
    auto lambdaEvent = [](const Compiler& c) {
        for (const TableCache::Event& e : c.tables().events())
            if (e.key == "lambda_student_t_g2.25") return e;
        FAIL("no Lambda table event");
        return TableCache::Event{};
    };
    std::vector<float> first, second;
    {
        Compiler a;
        first = evalAll(a);
        TableCache::Event e = lambdaEvent(a);
        CHECK(e.action == "built");
        CHECK(e.reason == "missing");
        CHECK(e.writeError == "");
        CHECK(fs::exists(file));
        struct stat st;
        REQUIRE(::stat(file.c_str(), &st) == 0);
        CHECK((st.st_mode & 0777) == 0600);
    }
    {
        Compiler b;
        second = evalAll(b);
        CHECK(lambdaEvent(b).action == "disk");
    }
    REQUIRE(first.size() == second.size());
    CHECK(std::memcmp(first.data(), second.data(), first.size() * sizeof(float)) == 0);
    CHECK(std::any_of(first.begin(), first.end(), [](float v) { return v > 0; }));
    if (old) ::setenv("FACET_CACHE_DIR", saved.c_str(), 1);
    else ::unsetenv("FACET_CACHE_DIR");
}

TEST_CASE("table cache: a group-writable directory is refused; the table is built in memory") {
    ScratchDir scratch("tables");
    REQUIRE(::chmod(scratch.path.c_str(), 0775) == 0);
    std::vector<std::string> warnings;
    auto dir = std::make_shared<CacheDirectory>(scratch.str(), [&](const std::string& m) { warnings.push_back(m); });
    TableCache cache(dir, "tables");
    EnergyTableKey key;
    key.ndf = &ndfEntry(modelNamed(ModelSlot::Ndf, "ggx"));
    key.masking = &maskingEntry(modelNamed(ModelSlot::Masking, "smith_height_correlated"));
    auto table = cache.get(key);
    REQUIRE(table);
    CHECK(table->validate() == "");
    REQUIRE(warnings.size() == 1);
    CHECK(warnings[0].find("is writable by group or others") != std::string::npos);
    CHECK(cache.events().at(0).reason.rfind("refused: ", 0) == 0);
    CHECK(entries(scratch.path).empty());
    // A second table: no second warning.
    key.ndf = &ndfEntry(modelNamed(ModelSlot::Ndf, "beckmann"));
    cache.get(key);
    CHECK(warnings.size() == 1);
}

TEST_CASE("atomic writes go through a fresh temporary file, never through a planted name") {
    ScratchDir scratch("atomic");
    ScratchDir elsewhere("planted");
    fs::path target = elsewhere.path / "target";
    { std::ofstream(target) << "keep"; }
    // Whatever temporary name a writer might pick, a symlink at the entry
    // itself is replaced by the rename, not written through.
    fs::create_symlink(target, scratch.path / "entry");
    CHECK(writeFileAtomically((scratch.path / "entry").string(), "new") == "");
    CHECK(!fs::is_symlink(fs::symlink_status(scratch.path / "entry")));
    std::string kept;
    std::ifstream(target) >> kept;
    CHECK(kept == "keep");
    struct stat st;
    REQUIRE(::stat((scratch.path / "entry").c_str(), &st) == 0);
    CHECK((st.st_mode & 0777) == 0600);
    CHECK(entries(scratch.path).size() == 1);
}

// ---- per-lane status -----------------------------------------------------------

TEST_CASE("status: one byte per lane, the same on every backend, matching the count") {
    const char* plastic = R"(
material plastic {
    input roughness = 0.4 in 0 .. 1;
    ndf = ggx(roughness * roughness);
    masking = smith_height_correlated;
    fresnel = schlick(eta = 1.49);
    diffuse = lambert(0.5);
}
)";
    // Lanes: valid; NaN; non-unit; Inf input; grazing pair whose value
    // (about 1.9e41 in double) float cannot hold; valid with roughness 1.
    std::vector<float> wx = {0, NAN, 0, 0, 1, 0.6f}, wy = {0, 0, 0, 0, 0, 0}, wz = {1, 1, 2, 1, 1e-40f, 0.8f};
    std::vector<float> ox = {0, 0, 0, 0, -1, -0.6f}, oy = {0, 0, 0, 0, 0, 0}, oz = {1, 1, 1, 1, 1e-40f, 0.8f};
    std::vector<float> rough = {0.4f, 0.4f, 0.4f, INFINITY, 0.5f, 1.0f};
    const std::vector<uint8_t> expected = {0, 1, 1, 1, 1, 0};
    const float* wi[3] = {wx.data(), wy.data(), wz.data()};
    const float* wo[3] = {ox.data(), oy.data(), oz.data()};
    const float* inputs[1] = {rough.data()};
    Compiler c;
    c.setCacheDir("");
    // (Exact kernels: fast ones read the subnormal cosine 1e-40 as 0, a
    // valid horizon lane there.)
    for (std::string backend : {"backend=interp", "backend=scalar", "backend=simd", "backend=simd;float_first=off"}) {
        CAPTURE(backend);
        auto k = compileWith(c, plastic, backend);
        std::vector<float> r(6, -1), g(6, -1), b(6, -1);
        float* rgb[3] = {r.data(), g.data(), b.data()};
        std::vector<uint8_t> status(6, 7);
        CHECK(k->evalBatch(6, wi, wo, inputs, rgb, status.data()) == 2 + 1 + 1);
        CHECK(status == expected);
        for (size_t i = 0; i < 6; ++i)
            if (status[i]) CHECK((r[i] == 0 && g[i] == 0 && b[i] == 0));
            else CHECK((std::isfinite(r[i]) && r[i] > 0));
        CHECK(k->evalBatch(0, wi, wo, inputs, rgb, status.data()) == 0);
        CHECK(k->evalBatch(-1, wi, wo, inputs, rgb, status.data()) == -1);
    }
}

// ---- extreme model parameters ----------------------------------------------------

TEST_CASE("extreme alphas: the interpreter's value where float holds it, else 0 and invalid") {
    const char* materials[] = {"material a { ndf = ggx(1e30); }",
                               "material b { ndf = ggx(alpha_x = 1e30, alpha_y = 1e-30); }",
                               "material c { ndf = ggx(alpha_x = 1e-30, alpha_y = 1e30); }"};
    // Grazing pairs (where these NDFs put values float can hold) and ordinary ones.
    std::vector<std::array<double, 6>> pairs;
    for (double e : {1e-3, 1e-6, 1e-10, 1e-13, 1e-20, 1e-30, 1e-38}) {
        double s = std::sqrt(1 - e * e);
        pairs.push_back({s, 0, e, -s, 0, e});
        pairs.push_back({s, 0, e, 0, s, e});
        pairs.push_back({0, s, e, 0, -s, e});
        pairs.push_back({s, 0, e, -0.6 * s, 0.8 * s, e});
        pairs.push_back({0, 0, 1, s, 0, e});
    }
    pairs.push_back({0, 0, 1, 0, 0, 1});
    pairs.push_back({0.6, 0, 0.8, -0.6, 0, 0.8});
    const size_t n = pairs.size();
    std::vector<float> dir[6];
    for (auto& p : pairs)
        for (int k = 0; k < 6; ++k) dir[k].push_back(float(p[k]));
    const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
    const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
    Compiler c;
    c.setCacheDir("");
    size_t inFloat = 0;
    for (const char* text : materials) {
        DiagnosticEngine d;
        CheckedProgram program = loadProgramText(text, "x.mat", d);
        REQUIRE(!d.hasErrors());
        Interpreter<double> interp(program.materials[0], nullptr);
        for (std::string backend : {"backend=scalar", "backend=simd", "backend=simd;float_first=off", "backend=interp"}) {
            CAPTURE(text);
            CAPTURE(backend);
            auto k = compileWith(c, text, backend);
            std::vector<float> out[3];
            for (auto& v : out) v.assign(n, -1);
            float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
            std::vector<uint8_t> status(n);
            k->evalBatch(int64_t(n), wi, wo, nullptr, rgb, status.data());
            for (size_t i = 0; i < n; ++i) {
                CAPTURE(i);
                double a[3] = {dir[0][i], dir[1][i], dir[2][i]}, b[3] = {dir[3][i], dir[4][i], dir[5][i]};
                EvalResult<double> ref = interp.eval(a, b, nullptr);
                REQUIRE(ref.valid);
                double want = ref.rgb[0];
                if (want > FLT_MAX) {
                    CHECK(status[i] == 1);
                    CHECK(out[0][i] == 0);
                } else {
                    inFloat += want >= FLT_MIN;
                    CHECK(status[i] == 0);
                    // Normal floats to 1e-5 relative; below, within a subnormal step.
                    CHECK(std::fabs(out[0][i] - want) <= std::max(1e-5 * want, 1.5e-45));
                }
            }
        }
    }
    CHECK(inFloat > 40);  // the cases reach values float holds, not only 0
}

}  // TEST_SUITE

TEST_SUITE("hardening") {

// A long let chain (each step rounds in float) must not drift: the exact SIMD
// kernel keeps the expressions in double, as the scalar kernel does. 3900
// steps is about as long as the checker's compute budget allows
// (ComputeCost.h); in float the chain would drift by ~1e-5.
TEST_CASE("a 3900-step let chain: exact SIMD agrees with the scalar kernel and the interpreter") {
    std::string text = "material chain {\n    input roughness = 0.5 in 0.1 .. 1;\n    let a0 = roughness;\n";
    const int steps = 3900;
    for (int i = 1; i <= steps; ++i) text += fmt::format("    let a{} = a{} * 1.0000001;\n", i, i - 1);
    text += fmt::format("    ndf = ggx(a{} * a{} * 0.5);\n    fresnel = schlick(f0 = 0.04);\n}}\n", steps, steps);
    Compiler c;
    c.setCacheDir("");
    DiagnosticEngine d;
    CheckedProgram program = loadProgramText(text, "chain.mat", d);
    REQUIRE_MESSAGE(!d.hasErrors(), d.str());
    Interpreter<double> interp(program.materials[0], nullptr);
    const size_t n = 512;
    std::vector<float> dir[6], rough(n);
    for (size_t i = 0; i < n; ++i) {
        double ti = 0.0015 * double(i), to = 0.001 * double(i), po = 0.05 * double(i);
        double v[6] = {std::sin(ti), 0, std::cos(ti), std::sin(to) * std::cos(po), std::sin(to) * std::sin(po), std::cos(to)};
        for (int k = 0; k < 6; ++k) dir[k].push_back(float(v[k]));
        rough[i] = float(0.1 + 0.9 * double(i) / double(n));
    }
    const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
    const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
    const float* inputs[1] = {rough.data()};
    double worst = 0;
    for (std::string backend : {"backend=simd;codegen=quick;cache=off", "backend=scalar;codegen=quick;cache=off"}) {
        CAPTURE(backend);
        auto k = compileWith(c, text, backend);
        std::vector<float> out[3];
        for (auto& v : out) v.assign(n, 0);
        float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
        REQUIRE(k->evalBatch(int64_t(n), wi, wo, inputs, rgb) == 0);
        for (size_t i = 0; i < n; ++i) {
            double a[3] = {dir[0][i], dir[1][i], dir[2][i]}, b[3] = {dir[3][i], dir[4][i], dir[5][i]}, in[1] = {rough[i]};
            EvalResult<double> ref = interp.eval(a, b, in);
            worst = std::max(worst, relativeError(out[0][i], ref.rgb[0]));
        }
    }
    // The exact kernels' usual agreement; a float chain drifts by ~1e-5.
    CHECK(worst < 2e-6);
}

}  // TEST_SUITE
