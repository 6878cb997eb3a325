// The EXR table cache (compiler/tables/TableCache.h): round trip with
// metadata, missing / stale / corrupt files rebuilt, memory sharing, and
// thread safety (one build per key, two caches on one directory).
#include "EnergyTestUtil.h"
#include "../ScratchDir.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>
#include <unistd.h>

using namespace energy;
namespace fs = std::filesystem;
using facet::EnergyTableKey;
using facet::TableCache;

using facet::test::ScratchDir;

namespace {

// Reads the float pixels of an EXR, lets `edit` change them, and writes the
// file back with the same spec (metadata included).
template <typename Edit>
void editPixels(const std::string& path, const Edit& edit) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    OIIO::ImageSpec spec = in->spec();
    std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels);
    REQUIRE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()));
    in->close();
    edit(spec, px);
    auto out = OIIO::ImageOutput::create(path);
    REQUIRE(out);
    REQUIRE(out->open(path, spec));
    REQUIRE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    out->close();
}

EnergyTableKey ggx() {
    EnergyTableKey k;
    k.ndf = &facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "ggx"));
    k.masking = &facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, "smith_height_correlated"));
    return k;
}

EnergyTableKey beckmann() {
    EnergyTableKey k;
    k.ndf = &facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "beckmann"));
    k.masking = &facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, "smith_separable"));
    return k;
}

bool sameValues(const facet::EnergyTable& a, const facet::EnergyTable& b) {
    return a.ec == b.ec && a.ecAvg == b.ecAvg && a.muCount == b.muCount && a.alphaCount == b.alphaCount;
}

const TableCache::Event& lastEvent(const TableCache& c) {
    static thread_local std::vector<TableCache::Event> events;
    events = c.events();
    REQUIRE(!events.empty());
    return events.back();
}

}  // namespace

TEST_SUITE("cache") {

TEST_CASE("EXR round trip keeps every value and the metadata") {
    ScratchDir dir("energy");
    auto t = memoryTables().get(ggx());
    std::string path = (dir.path / "t.exr").string();
    REQUIRE(facet::writeEnergyTableExr(*t, path) == "");
    facet::TableFileResult r = facet::readEnergyTableExr(path, &t->key);
    INFO(r.message);
    REQUIRE(r.status == facet::TableFileStatus::Ok);
    CHECK(sameValues(*r.table, *t));
    CHECK(r.table->key == t->key);
    CHECK(r.table->origin == "disk");
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    CHECK(spec.format == OIIO::TypeDesc::FLOAT);
    std::vector<std::string> names = spec.channelnames;  // EXR stores channels sorted by name
    std::sort(names.begin(), names.end());
    CHECK(names == std::vector<std::string>{"E", "Eavg", "Ec", "EcAvg"});
    CHECK(spec.get_string_attribute("facet:ndf") == "ggx");
    CHECK(spec.get_string_attribute("facet:masking") == "smith_height_correlated");
    CHECK(spec.get_int_attribute("facet:version") == facet::kEnergyTableVersion);
    CHECK(spec.get_int_attribute("facet:mu_count") == facet::EnergyTable::kMuCount);
    CHECK(spec.get_string_attribute("facet:quadrature") == facet::EnergyQuadrature{}.describe());
    CHECK(!std::string(spec.get_string_attribute("facet:alpha_axis")).empty());
    // A gtr / schlick_smith key keeps its constants.
    EnergyTableKey g;
    g.ndf = &facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "gtr"));
    g.masking = &facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, "schlick_smith"));
    g.shape = {1.5, 0.125};
    auto tg = std::make_shared<facet::EnergyTable>(*t);
    tg->key = g;
    REQUIRE(facet::writeEnergyTableExr(*tg, path) == "");
    facet::TableFileResult rg = facet::readEnergyTableExr(path, &g);
    CHECK(rg.status == facet::TableFileStatus::Ok);
    CHECK(facet::readEnergyTableExr(path, &t->key).status == facet::TableFileStatus::Stale);
}

TEST_CASE("missing, then disk; memory sharing; stale, corrupt and unreadable files are rebuilt") {
    ScratchDir dir("energy");
    std::string path;
    {
        TableCache c(dir.path.string());
        path = c.pathFor(ggx());
        CHECK(!fs::exists(path));
        auto t1 = c.get(ggx());
        CHECK(lastEvent(c).action == "built");
        CHECK(fs::exists(path));
        MESSAGE("build of ", t1->key.name(), " through the cache: ", lastEvent(c).millis, " ms");
        auto t2 = c.get(ggx());
        CHECK(t1 == t2);  // same object from memory
        CHECK(c.events().size() == 1);
        CHECK(sameValues(*t1, *memoryTables().get(ggx())));
    }
    auto reference = memoryTables().get(ggx());
    // A new cache loads the file.
    {
        TableCache c(dir.path.string());
        auto t = c.get(ggx());
        CHECK(lastEvent(c).action == "disk");
        CHECK(sameValues(*t, *reference));
    }
    auto rebuiltBecause = [&](const char* status) {
        TableCache c(dir.path.string());
        auto t = c.get(ggx());
        const TableCache::Event& e = lastEvent(c);
        INFO("event: ", e.action, " / ", e.reason);
        CHECK(e.action == "rebuilt");
        CHECK(e.reason.rfind(status, 0) == 0);
        CHECK(e.writeError == "");
        CHECK(sameValues(*t, *reference));
        // and the rewritten file is good again
        CHECK(facet::readEnergyTableExr(path, &reference->key).status == facet::TableFileStatus::Ok);
    };
    SUBCASE("stale: another pair's table under this name") {
        auto other = memoryTables().get(beckmann());
        REQUIRE(facet::writeEnergyTableExr(*other, path) == "");
        rebuiltBecause("stale");
    }
    SUBCASE("stale: another grid") {
        auto small = facet::buildEnergyTable(ggx(), {}, 0, 16, 8);
        REQUIRE(facet::writeEnergyTableExr(*small, path) == "");
        rebuiltBecause("stale");
    }
    SUBCASE("corrupt: a NaN pixel") {
        editPixels(path, [](const OIIO::ImageSpec& spec, std::vector<float>& px) {
            px[(5 * spec.width + 7) * 4 + 1] = std::nanf("");
        });
        rebuiltBecause("corrupt");
    }
    SUBCASE("corrupt: one value changed (E + Ec no longer 1 / EcAvg no longer the row integral)") {
        editPixels(path, [](const OIIO::ImageSpec& spec, std::vector<float>& px) {
            auto index = [&](const char* name) {
                return int(std::find(spec.channelnames.begin(), spec.channelnames.end(), name) -
                           spec.channelnames.begin());
            };
            REQUIRE(index("Ec") < 4);
            REQUIRE(index("E") < 4);
            size_t p = (20 * spec.width + 30) * 4;
            px[p + index("Ec")] += 0.01f;
            px[p + index("E")] -= 0.01f;  // still E + Ec = 1: caught by the row integral
        });
        rebuiltBecause("corrupt");
    }
    SUBCASE("unreadable: truncated file") {
        auto size = fs::file_size(path);
        fs::resize_file(path, size / 2);
        rebuiltBecause("unreadable");
    }
    SUBCASE("unreadable: garbage bytes") {
        std::ofstream(path, std::ios::binary | std::ios::trunc) << "this is not an EXR file";
        rebuiltBecause("unreadable");
    }
}

TEST_CASE("a memory-only cache never touches the disk") {
    TableCache c("");
    CHECK(c.pathFor(ggx()) == "");
    auto t = c.get(ggx());
    CHECK(lastEvent(c).action == "built");
    CHECK(sameValues(*t, *memoryTables().get(ggx())));
}

TEST_CASE("threads: one build per key, two caches on one directory") {
    ScratchDir dir("energy");
    TableCache a(dir.path.string()), b(dir.path.string());
    std::vector<std::shared_ptr<const facet::EnergyTable>> got(8);
    std::vector<std::thread> pool;
    for (int i = 0; i < 8; ++i)
        pool.emplace_back([&, i] { got[i] = (i % 2 ? b : a).get(i < 4 ? ggx() : beckmann()); });
    for (auto& t : pool) t.join();
    // Within one cache, every request for a key gets the same object.
    CHECK(got[0] == got[2]);
    CHECK(got[1] == got[3]);
    CHECK(got[4] == got[6]);
    CHECK(got[5] == got[7]);
    CHECK(sameValues(*got[0], *got[1]));
    CHECK(sameValues(*got[4], *got[5]));
    // One load or build per key per cache.
    CHECK(a.events().size() == 2);
    CHECK(b.events().size() == 2);
    // Both files are valid whichever cache wrote last; no temporary files left.
    CHECK(facet::readEnergyTableExr(a.pathFor(ggx()), nullptr).status == facet::TableFileStatus::Ok);
    CHECK(facet::readEnergyTableExr(a.pathFor(beckmann()), nullptr).status == facet::TableFileStatus::Ok);
    int files = 0;
    for (auto& e : fs::directory_iterator(dir.path)) {
        ++files;
        CHECK(e.path().extension() == ".exr");
        CHECK(e.path().filename().string()[0] != '.');
    }
    CHECK(files == 2);
}

TEST_CASE("default directory follows FACET_CACHE_DIR") {
    const char* old = std::getenv("FACET_CACHE_DIR");
    std::string saved = old ? old : "";
    ::setenv("FACET_CACHE_DIR", "/tmp/facet-x", 1);
    CHECK(facet::defaultTableCacheDir() == "/tmp/facet-x/tables");
    if (old) ::setenv("FACET_CACHE_DIR", saved.c_str(), 1);
    else ::unsetenv("FACET_CACHE_DIR");
}

}  // TEST_SUITE
