// JIT cache tests: the kernel cache file format, the disk cache (hits,
// truncated, corrupted and untrusted files), the samplers' cache entries,
// and what the cache keys separate.
#include "JitTestSupport.h"

#include "KernelCacheFile.h"

#include <fstream>
#include <set>

using namespace facet;
using namespace facet::jittest;

namespace {

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

}  // namespace

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
