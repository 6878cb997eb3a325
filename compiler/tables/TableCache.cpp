// TableCache: EXR I/O of the Kulla-Conty tables (through ExrCodec) and the
// cache object (both kinds of table; the Lambda file format is in
// LambdaTableFile.cpp).
#include "TableCache.h"

#include "CacheFiles.h"
#include "ExrCodec.h"
#include "TableFileRead.h"
#include "Material.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <fmt/format.h>

namespace facet {

namespace {

constexpr const char* kTableKind = "kulla_conty_E";
// The largest grid side a table file may have; ExrReader refuses a larger
// data window before OpenEXR sizes anything by it.
constexpr int kMaxGridSide = 4096;
constexpr const char* kMuAxis = "u = sqrt(mu) * (mu_count - 1)";
constexpr const char* kAlphaAxis =
    "v = (sqrt(alpha) - sqrt(alpha_min)) / (sqrt(alpha_max) - sqrt(alpha_min)) * (alpha_count - 1)";
constexpr const char* kInterpolation =
    "bilinear in (u, v) for Ec, linear in v for EcAvg; EcAvg(row) = 2 Int Ec_interp(mu) mu dmu exactly";

std::string exact(double x) { return fmt::format("{:.17g}", x); }

double millisSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// The table of `key` from `tables`, produced once: concurrent requests for
// one key wait for a single produce() (the mutex is not held while it runs).
template <typename Key, typename Table, typename Produce>
std::shared_ptr<const Table> getOnce(std::mutex& mutex,
                                     std::map<Key, std::shared_future<std::shared_ptr<const Table>>>& tables,
                                     const Key& key, Produce&& produce) {
    std::promise<std::shared_ptr<const Table>> promise;
    std::shared_future<std::shared_ptr<const Table>> future;
    bool mine = false;
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = tables.find(key);
        if (it != tables.end()) {
            future = it->second;
        } else {
            future = promise.get_future().share();
            tables.emplace(key, future);
            mine = true;
        }
    }
    if (!mine) return future.get();  // another thread loads or builds it
    try {
        promise.set_value(produce());
    } catch (...) {
        promise.set_exception(std::current_exception());
        std::lock_guard<std::mutex> lock(mutex);
        tables.erase(key);  // a later request tries again
    }
    return future.get();
}

}  // namespace

std::string defaultTableCacheDir() {
    std::string root = defaultCacheRoot();
    return root.empty() ? "" : root + "/tables";
}

std::string replaceEnergyTableExr(const EnergyTable& table, const std::string& path) {
    // Readers in other threads or processes see the old file or the new
    // one, never half (CacheFiles.h).
    std::string bytes, err = encodeEnergyTableExr(table, bytes);
    if (!err.empty()) return fmt::format("cannot write {}: {}", path, err);
    std::filesystem::path dir = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty()) std::filesystem::create_directories(dir, ec);
    return writeFileAtomically(path, bytes);
}

const char* tableFileStatusName(TableFileStatus s) {
    switch (s) {
        case TableFileStatus::Ok: return "ok";
        case TableFileStatus::Missing: return "missing";
        case TableFileStatus::Unreadable: return "unreadable";
        case TableFileStatus::Stale: return "stale";
        case TableFileStatus::Corrupt: return "corrupt";
    }
    return "?";
}

std::string writeEnergyTableExr(const EnergyTable& table, const std::string& path) {
    std::string bytes, err = encodeEnergyTableExr(table, bytes);
    if (!err.empty()) return fmt::format("cannot write {}: {}", path, err);
    return writeFileChecked(path, bytes);
}

std::string encodeEnergyTableExr(const EnergyTable& t, std::string& bytes) {
    std::string bad = t.validate();
    if (!bad.empty()) return "refusing to write an invalid table: " + bad;
    ExrImage image;
    image.width = t.muCount;
    image.height = t.alphaCount;
    image.channels = {"E", "Ec", "Eavg", "EcAvg"};
    image.strings["facet:table"] = kTableKind;
    image.ints["facet:version"] = kEnergyTableVersion;
    image.strings["facet:key"] = t.key.name();
    image.strings["facet:ndf"] = t.key.ndf->name;
    image.strings["facet:masking"] = t.key.masking->name;
    std::string shape;
    for (double v : t.key.shape) shape += (shape.empty() ? "" : ",") + exact(v);
    image.strings["facet:shape"] = shape;
    image.strings["facet:interface_eta"] = exact(t.key.interfaceEta);
    image.ints["facet:mu_count"] = t.muCount;
    image.ints["facet:alpha_count"] = t.alphaCount;
    image.strings["facet:alpha_min"] = exact(t.alphaMin);
    image.strings["facet:alpha_max"] = exact(t.alphaMax);
    image.strings["facet:mu_axis"] = kMuAxis;
    image.strings["facet:alpha_axis"] = kAlphaAxis;
    image.strings["facet:interpolation"] = kInterpolation;
    image.strings["facet:quadrature"] = t.quadrature.describe();
    image.strings["facet:build_ms"] = exact(t.buildMillis);
    std::vector<float>& pixels = image.pixels;
    pixels.resize(size_t(t.muCount) * t.alphaCount * 4);
    for (int i = 0; i < t.alphaCount; ++i)
        for (int j = 0; j < t.muCount; ++j) {
            float* p = &pixels[(size_t(i) * t.muCount + j) * 4];
            float ec = t.ec[size_t(i) * t.muCount + j], avg = t.ecAvg[i];
            p[0] = 1 - ec;
            p[1] = ec;
            p[2] = 1 - avg;
            p[3] = avg;
        }
    // Encoded in memory: the file itself is written by the caller, with
    // every write checked (and, for the cache, atomically).
    return encodeExr(image, bytes);
}

TableFileResult readEnergyTableExr(const std::string& path, const EnergyTableKey* expected,
                                   const EnergyQuadrature& quadrature) {
    return readTableFile<TableFileResult>(path, kMaxTableFileBytes, [&](const std::string& bytes) {
        return decodeEnergyTableExr(bytes, path, expected, quadrature);
    });
}

TableFileResult decodeEnergyTableExr(const std::string& bytes, const std::string& path,
                                     const EnergyTableKey* expected, const EnergyQuadrature& quadrature) {
    TableFileResult r;
    auto fail = [&](TableFileStatus s, std::string msg) {
        r.status = s;
        r.message = std::move(msg);
        r.table.reset();
        return r;
    };
    ExrReader in(bytes);
    std::string why = in.open(kMaxGridSide);
    if (!why.empty()) return fail(TableFileStatus::Unreadable, fmt::format("cannot open {}: {}", path, why));
    if (in.stringAttribute("facet:table") != kTableKind)
        return fail(TableFileStatus::Stale, fmt::format("{} is not a Kulla-Conty table", path));
    int version = in.intAttribute("facet:version", -1);
    if (version != kEnergyTableVersion)
        return fail(TableFileStatus::Stale, fmt::format("{} has table version {}, expected {}", path, version,
                                                        kEnergyTableVersion));
    auto t = std::make_shared<EnergyTable>();
    t->muCount = in.intAttribute("facet:mu_count", -1);
    t->alphaCount = in.intAttribute("facet:alpha_count", -1);
    t->alphaMin = std::strtod(in.stringAttribute("facet:alpha_min").c_str(), nullptr);
    t->alphaMax = std::strtod(in.stringAttribute("facet:alpha_max").c_str(), nullptr);
    std::string ndf(in.stringAttribute("facet:ndf")), masking(in.stringAttribute("facet:masking"));
    const ModelInfo* ndfInfo = findModel(ModelSlot::Ndf, ndf);
    const ModelInfo* maskInfo = findModel(ModelSlot::Masking, masking);
    if (!ndfInfo || !maskInfo)
        return fail(TableFileStatus::Stale, fmt::format("{}: unknown ndf '{}' or masking '{}'", path, ndf, masking));
    t->key.ndf = &ndfEntry(*ndfInfo);
    t->key.masking = &maskingEntry(*maskInfo);
    std::string shape(in.stringAttribute("facet:shape"));
    for (size_t pos = 0; pos < shape.size();) {
        size_t end = std::min(shape.find(',', pos), shape.size());
        t->key.shape.push_back(std::strtod(shape.substr(pos, end - pos).c_str(), nullptr));
        pos = end + 1;
    }
    t->key.interfaceEta = std::strtod(in.stringAttribute("facet:interface_eta").c_str(), nullptr);
    t->quadrature = quadrature;
    std::string quad(in.stringAttribute("facet:quadrature"));
    if (expected) {
        if (!(t->key == *expected))
            return fail(TableFileStatus::Stale, fmt::format("{} holds table {}, expected {}", path, t->key.name(),
                                                            expected->name()));
        TableGrid grid = defaultTableGrid(*expected);
        if (t->muCount != grid.mu || t->alphaCount != grid.alpha || t->alphaMin != EnergyTable::kAlphaMin ||
            t->alphaMax != EnergyTable::kAlphaMax)
            return fail(TableFileStatus::Stale,
                        fmt::format("{} has a {} x {} grid over alpha [{}, {}], expected {} x {} over [{}, {}]", path,
                                    t->muCount, t->alphaCount, t->alphaMin, t->alphaMax, grid.mu, grid.alpha,
                                    EnergyTable::kAlphaMin, EnergyTable::kAlphaMax));
        if (quad != quadrature.describe())
            return fail(TableFileStatus::Stale, fmt::format("{} was integrated with other quadrature settings ({})",
                                                            path, quad));
        if (in.stringAttribute("facet:mu_axis") != kMuAxis ||
            in.stringAttribute("facet:alpha_axis") != kAlphaAxis)
            return fail(TableFileStatus::Stale, fmt::format("{} uses another axis mapping", path));
    }
    if (in.width() != t->muCount || in.height() != t->alphaCount || in.channels().size() != 4 || in.originX() != 0 ||
        in.originY() != 0)
        return fail(TableFileStatus::Corrupt,
                    fmt::format("{}: image is {} x {} with {} channels, metadata says {} x {} with 4", path,
                                in.width(), in.height(), in.channels().size(), t->muCount, t->alphaCount));
    if (t->muCount < 2 || t->alphaCount < 2 || t->muCount > kMaxGridSide || t->alphaCount > kMaxGridSide)
        return fail(TableFileStatus::Corrupt, fmt::format("{}: bad grid {} x {}", path, t->muCount, t->alphaCount));
    // Read by name: EXR stores channels sorted by name.
    std::vector<float> pixels;
    why = in.readPixels({"E", "Ec", "Eavg", "EcAvg"}, pixels);
    if (why.rfind("no channel", 0) == 0) return fail(TableFileStatus::Corrupt, fmt::format("{}: {}", path, why));
    if (!why.empty()) return fail(TableFileStatus::Unreadable, fmt::format("{}: cannot read pixels: {}", path, why));
    t->ec.resize(size_t(t->muCount) * t->alphaCount);
    std::vector<float> stored(t->alphaCount);
    for (int i = 0; i < t->alphaCount; ++i)
        for (int j = 0; j < t->muCount; ++j) {
            const float* p = &pixels[(size_t(i) * t->muCount + j) * 4];
            for (int c = 0; c < 4; ++c)
                if (!std::isfinite(p[c]) || p[c] < 0 || p[c] > 1)
                    return fail(TableFileStatus::Corrupt,
                                fmt::format("{}: pixel ({}, {}) channel {} is {}", path, j, i, c, p[c]));
            if (std::abs(p[0] + p[1] - 1) > 1e-6 || std::abs(p[2] + p[3] - 1) > 1e-6)
                return fail(TableFileStatus::Corrupt, fmt::format("{}: pixel ({}, {}) has E + Ec != 1", path, j, i));
            if (j == 0) stored[i] = p[3];
            else if (p[3] != stored[i])
                return fail(TableFileStatus::Corrupt, fmt::format("{}: EcAvg varies along row {}", path, i));
            t->ec[size_t(i) * t->muCount + j] = p[1];
        }
    t->computeAverages();
    for (int i = 0; i < t->alphaCount; ++i)
        if (std::abs(double(t->ecAvg[i]) - stored[i]) > 1e-6 * std::max(1.0, double(stored[i])))
            return fail(TableFileStatus::Corrupt,
                        fmt::format("{}: EcAvg of row {} is {}, the integral of its Ec is {}", path, i, stored[i],
                                    t->ecAvg[i]));
    std::string bad = t->validate();
    if (!bad.empty()) return fail(TableFileStatus::Corrupt, path + ": " + bad);
    t->origin = "disk";
    r.status = TableFileStatus::Ok;
    r.table = std::move(t);
    return r;
}

// ---- cache ----------------------------------------------------------------

TableCache::TableCache(std::string dir, EnergyQuadrature quadrature)
    : TableCache(std::make_shared<CacheDirectory>(std::move(dir)), "", std::move(quadrature)) {}

TableCache::TableCache(std::shared_ptr<CacheDirectory> cache, std::string sub, EnergyQuadrature quadrature)
    : cache_(std::move(cache)),
      sub_(sub.empty() ? "" : sub + "/"),
      dir_(cache_->root().empty() ? "" : sub.empty() ? cache_->root() : cache_->root() + "/" + sub),
      quadrature_(std::move(quadrature)) {}

std::string TableCache::pathFor(const EnergyTableKey& key) const {
    if (dir_.empty()) return "";
    return dir_ + "/kc_" + key.name() + ".exr";
}

std::vector<TableCache::Event> TableCache::events() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_;
}

std::shared_ptr<const EnergyTable> TableCache::get(const EnergyTableKey& key) {
    return getOnce(mutex_, tables_, key, [&] { return produce(key); });
}

std::shared_ptr<const LambdaTable> TableCache::getLambda(const NdfEntry& ndf, const std::vector<double>& shape) {
    return getOnce(mutex_, lambdaTables_, std::make_pair(&ndf, shape), [&] { return produceLambda(ndf, shape); });
}

std::shared_ptr<const LambdaTable> TableCache::lambdaFor(const CheckedMaterial& material) {
    return getLambda(ndfEntry(*material.singleLobe().ndf.model), tabulatedLambdaShape(material));
}

std::string TableCache::lambdaPathFor(const NdfEntry& ndf, const std::vector<double>& shape) const {
    return dir_.empty() ? "" : dir_ + "/" + lambdaTableFileName(ndf, shape);
}

void TableCache::missed(Event& ev, bool haveBytes, TableFileStatus status, const std::string& message) const {
    if (!cache_->usable() && dir_.empty()) {
        ev.action = "built";
        ev.reason = "memory-only cache";
    } else if (!cache_->usable() || !haveBytes) {
        ev.action = "built";
        ev.reason = cache_->usable() ? "missing" : "refused: " + cache_->warning();
    } else {
        ev.action = "rebuilt";
        ev.reason = std::string(tableFileStatusName(status)) + ": " + message;
        // A rebuild costs seconds each time the file fails again, so it is
        // never silent.
        cache_->notice(fmt::format("table {} cannot be used ({}); rebuilding it and rewriting the file", ev.key,
                                   ev.reason));
    }
}

std::shared_ptr<const EnergyTable> TableCache::produce(const EnergyTableKey& key) {
    auto start = std::chrono::steady_clock::now();
    Event ev;
    ev.key = key.name();
    std::string path = pathFor(key), relPath = sub_ + "kc_" + key.name() + ".exr";
    std::shared_ptr<EnergyTable> table;
    std::optional<std::string> bytes;
    TableFileResult r;
    if (cache_->usable()) bytes = cache_->read(relPath, kMaxTableFileBytes);
    if (bytes) r = decodeEnergyTableExr(*bytes, path, &key, quadrature_);
    if (r.status == TableFileStatus::Ok) {
        table = r.table;
        ev.action = "disk";
    } else {
        missed(ev, bytes.has_value(), r.status, r.message);
        table = buildEnergyTable(key, quadrature_);
        std::string encoded;
        if (cache_->usable()) {
            ev.writeError = encodeEnergyTableExr(*table, encoded);
            if (ev.writeError.empty()) ev.writeError = cache_->write(relPath, encoded);
        }
    }
    ev.millis = millisSince(start);
    std::lock_guard<std::mutex> lock(mutex_);
    events_.push_back(ev);
    return table;
}

std::shared_ptr<const LambdaTable> TableCache::produceLambda(const NdfEntry& ndf, const std::vector<double>& shape) {
    auto start = std::chrono::steady_clock::now();
    Event ev;
    std::string file = lambdaTableFileName(ndf, shape), relPath = sub_ + file;
    ev.key = file.substr(0, file.size() - 4);  // without ".bin"
    std::shared_ptr<const LambdaTable> table;
    std::optional<std::string> bytes;
    LambdaTableFileResult r;
    if (cache_->usable()) bytes = cache_->read(relPath, kMaxLambdaTableFileBytes);
    if (bytes) {
        const std::shared_ptr<const LambdaTable> resident = residentLambdaTable(ndf, shape);
        r = decodeLambdaTable(*bytes, lambdaPathFor(ndf, shape), &ndf, &shape, resident.get());
    }
    if (r.status == TableFileStatus::Ok) {
        table = adoptLambdaTable(r.table);
        ev.action = "disk";
    } else {
        missed(ev, bytes.has_value(), r.status, r.message);
        if (residentLambdaTable(ndf, shape)) ev.reason += " (the process already held the table)";
        table = lambdaTable(ndf, shape);
        if (cache_->usable()) ev.writeError = cache_->write(relPath, encodeLambdaTable(*table));
    }
    ev.millis = millisSince(start);
    std::lock_guard<std::mutex> lock(mutex_);
    events_.push_back(ev);
    return table;
}

}  // namespace facet
