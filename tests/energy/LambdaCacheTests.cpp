// The Lambda tables on disk (compiler/tables/TableCache.h, LambdaTableFile.cpp):
// the file round trip is bit-exact; a cold cache writes the file and a second
// cache loads it; truncated, damaged, wrong and stale files are rebuilt with
// the reason; a memory-only or refused cache writes nothing. One gamma
// throughout: the process builds its table once (~0.5 s), the rest is I/O.
#include "LambdaTable.h"
#include "TableCache.h"
#include "../ScratchDir.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;
using facet::LambdaTable;
using facet::TableCache;
using facet::TableFileStatus;

using facet::test::ScratchDir;

namespace {

const facet::NdfEntry& studentT() { return facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "student_t")); }
const std::vector<double> kShape = {2.5};

bool sameBits(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

std::string readAll(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void writeAll(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    ::chmod(path.c_str(), 0600);
}

TableCache::Event lastEvent(const TableCache& c) {
    std::vector<TableCache::Event> events = c.events();
    REQUIRE(!events.empty());
    return events.back();
}

}  // namespace

TEST_SUITE("lambda cache") {

TEST_CASE("Lambda table file: the nodes round-trip bit for bit, the header names the table") {
    auto table = facet::lambdaTable(studentT(), kShape);
    std::string bytes = facet::encodeLambdaTable(*table);
    CHECK(bytes.rfind("facet lambda table\nkind smith_lambda\nversion " + std::to_string(facet::kLambdaTableVersion) +
                          "\nkey student_t_g2.5\n",
                      0) == 0);
    CHECK(bytes.find("\nshape 2.5\n") != std::string::npos);
    CHECK(bytes.find("\ncount 4128\n") != std::string::npos);
    CHECK(facet::lambdaTableFileName(studentT(), kShape) == "lambda_student_t_g2.5.bin");
    facet::LambdaTableFileResult r = facet::decodeLambdaTable(bytes, "t.bin", &studentT(), &kShape);
    INFO(r.message);
    REQUIRE(r.status == TableFileStatus::Ok);
    CHECK(sameBits(r.table->z, table->z));
    CHECK(r.table->ndf == &studentT());
    CHECK(r.table->shape == kShape);
    CHECK(r.table->origin == "disk");
    CHECK(r.table->buildMillis == table->buildMillis);
    // Another gamma's table under this name is stale, not used.
    std::vector<double> other = {3.0};
    facet::LambdaTableFileResult s = facet::decodeLambdaTable(bytes, "t.bin", &studentT(), &other);
    CHECK(s.status == TableFileStatus::Stale);
    CHECK(s.message.find("expected student_t_g3") != std::string::npos);
}

}  // TEST_SUITE

namespace {

// The disk layer's round trip and recovery for the table of (ndf, shape),
// named `key`; `other` is another shape value whose table is stale here.
void checkCacheRecovery(const facet::NdfEntry& ndf, const std::vector<double>& shape, const std::string& key,
                        const std::vector<double>& other, const std::string& otherKey) {
    ScratchDir dir("lambda");
    auto reference = facet::lambdaTable(ndf, shape);
    std::string path;
    {
        TableCache c(dir.path.string());
        path = c.lambdaPathFor(ndf, shape);
        CHECK(fs::path(path).filename() == "lambda_" + key + ".bin");
        auto t = c.getLambda(ndf, shape);
        TableCache::Event e = lastEvent(c);
        CHECK(e.key == "lambda_" + key);
        CHECK(e.action == "built");
        CHECK(e.reason.rfind("missing", 0) == 0);
        CHECK(e.writeError == "");
        CHECK(fs::exists(path));
        CHECK(sameBits(t->z, reference->z));
        CHECK(c.getLambda(ndf, shape) == t);  // once per cache
        CHECK(c.events().size() == 1);
    }
    {
        TableCache c(dir.path.string());
        auto t = c.getLambda(ndf, shape);
        TableCache::Event e = lastEvent(c);
        CHECK(e.action == "disk");
        CHECK(sameBits(t->z, reference->z));
        MESSAGE(key, ": Lambda table loaded from disk in ", e.millis, " ms (built in ", reference->buildMillis, " ms)");
    }
    const std::string good = readAll(path);
    auto rebuiltBecause = [&](const char* status, const char* detail) {
        TableCache c(dir.path.string());
        auto t = c.getLambda(ndf, shape);
        TableCache::Event e = lastEvent(c);
        INFO("event: ", e.action, " / ", e.reason);
        CHECK(e.action == "rebuilt");
        CHECK(e.reason.rfind(status, 0) == 0);
        CHECK(e.reason.find(detail) != std::string::npos);
        CHECK(e.writeError == "");
        CHECK(sameBits(t->z, reference->z));
        CHECK(readAll(path) == good);  // rewritten
    };
    const size_t nodes = good.find("\n\n") + 2;
    auto patchNode = [&](int i, double v) {
        // A node changed and the checksum fixed up: only the values can tell.
        LambdaTable copy = *reference;
        copy.z[i] = v;
        writeAll(path, facet::encodeLambdaTable(copy));
    };
    SUBCASE("corrupt: truncated") {
        writeAll(path, good.substr(0, good.size() - 100));
        rebuiltBecause("corrupt", ("bytes of nodes, expected " + std::to_string(reference->z.size() * 8)).c_str());
    }
    SUBCASE("corrupt: a damaged byte") {
        std::string bad = good;
        bad[nodes + 8 * 1000 + 3] ^= 0x10;
        writeAll(path, bad);
        rebuiltBecause("corrupt", "checksum");
    }
    SUBCASE("corrupt: a NaN node") {
        patchNode(77, std::nan(""));
        rebuiltBecause("corrupt", "node 77 is nan");
    }
    SUBCASE("corrupt: a node off by 1e-9 where a spot check looks") {
        // A fresh process checks the quadrature at a few spot nodes.
        int spot = int(reference->z.size()) / 3;
        LambdaTable copy = *reference;
        copy.z[spot] += 1e-9;
        facet::LambdaTableFileResult r =
            facet::decodeLambdaTable(facet::encodeLambdaTable(copy), "t.bin", &ndf, &shape);
        CHECK(r.status == facet::TableFileStatus::Corrupt);
        CHECK(r.message.find("the quadrature gives") != std::string::npos);
    }
    SUBCASE("corrupt: a node off by 1e-9 anywhere, in a process that holds the table") {
        // The cache compares every node with the table the process built.
        int node = int(reference->z.size()) / 3 + 1;
        patchNode(node, reference->z[node] + 1e-9);
        rebuiltBecause("corrupt", "the table this process holds has");
    }
    SUBCASE("stale: another table version") {
        std::string bad = good;
        std::string version = "version " + std::to_string(facet::kLambdaTableVersion) + "\n";
        bad.replace(bad.find(version), version.size(), "version 0\n");
        writeAll(path, bad);
        rebuiltBecause("stale", "version '0'");
    }
    SUBCASE("stale: another shape value's table under this name") {
        LambdaTable copy = *reference;
        copy.shape = other;
        writeAll(path, facet::encodeLambdaTable(copy));
        rebuiltBecause("stale", ("holds table " + otherKey).c_str());
    }
    SUBCASE("unreadable: not a table file") {
        writeAll(path, "this is not a Lambda table");
        rebuiltBecause("unreadable", "not a Facet Lambda table file");
    }
}

}  // namespace

TEST_SUITE("lambda cache") {

TEST_CASE("Lambda cache: a cold cache writes the file, a second loads it; bad files are rebuilt with the reason") {
    checkCacheRecovery(studentT(), kShape, "student_t_g2.5", {3.0}, "student_t_g3");
}

// A table in (a, alpha): its rows and grid in the header, the same recovery.
TEST_CASE("Lambda cache: a gtr table in (a, alpha) round-trips and recovers alike") {
    const facet::NdfEntry& gtr = facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "gtr"));
    auto table = facet::lambdaTable(gtr, {1.5});
    std::string bytes = facet::encodeLambdaTable(*table);
    // Rows from alpha = 1 (y = asinh(4 b) = 0 with s = max(4, 2 gamma) = 4)
    // down to kMinAlpha, at most 1/8 apart.
    CHECK(table->grid.rows == int(std::ceil(std::asinh(4 * (1 / (facet::kMinAlpha * facet::kMinAlpha) - 1)) * 8)) + 1);
    CHECK(bytes.find(fmt::format("\ncount 443\ny0 0\nystep {}\nrows {}\nrowscale 4\n", table->grid.yStep,
                                 table->grid.rows)) != std::string::npos);
    checkCacheRecovery(gtr, {1.5}, "gtr_g1.5", {2.0}, "gtr_g2");
}

// gaussian's table, with rows 1/16 apart, is one of the largest files (1.2
// MB, like gtr's beyond gamma = 5): it must load back, not be rebuilt.
TEST_CASE("Lambda cache: the largest tables load back from disk") {
    const facet::NdfEntry& gaussian = facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, "gaussian"));
    ScratchDir dir("lambda");
    std::string path;
    {
        TableCache c(dir.path.string());
        path = c.lambdaPathFor(gaussian, {});
        c.getLambda(gaussian, {});
        CHECK(lastEvent(c).writeError == "");
    }
    CHECK(fs::file_size(path) > (uint64_t(1) << 20));
    TableCache c(dir.path.string());
    auto t = c.getLambda(gaussian, {});
    INFO("event: ", lastEvent(c).action, " / ", lastEvent(c).reason);
    CHECK(lastEvent(c).action == "disk");
    CHECK(sameBits(t->z, facet::lambdaTable(gaussian, {})->z));
}

TEST_CASE("Lambda cache: memory only, and a group-writable directory refused with the warning") {
    {
        TableCache c("");
        CHECK(c.lambdaPathFor(studentT(), kShape) == "");
        auto t = c.getLambda(studentT(), kShape);
        CHECK(t == facet::lambdaTable(studentT(), kShape));
        CHECK(lastEvent(c).action == "built");
        CHECK(lastEvent(c).reason.rfind("memory-only cache", 0) == 0);
    }
    ScratchDir dir("lambda");
    REQUIRE(::chmod(dir.path.c_str(), 0775) == 0);
    std::vector<std::string> warnings;
    auto cache = std::make_shared<facet::CacheDirectory>(dir.path.string(),
                                                         [&](const std::string& m) { warnings.push_back(m); });
    TableCache c(cache, "tables");
    auto t = c.getLambda(studentT(), kShape);
    REQUIRE(t);
    REQUIRE(warnings.size() == 1);
    CHECK(warnings[0].find("is writable by group or others") != std::string::npos);
    CHECK(lastEvent(c).reason.rfind("refused: ", 0) == 0);
    CHECK(fs::is_empty(dir.path));
}

}  // TEST_SUITE
