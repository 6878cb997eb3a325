// TableCache: Kulla-Conty E tables (KullaConty.h) on disk as EXR files
// (through OpenEXR, ExrCodec.h), tabulated Smith Lambdas (LambdaTable.h) on disk as
// small binary files, and an in-memory cache of both owned by the caller.
//
// Library facet_tables (links OpenEXR); the front end stays free of it.
//
// File format (one table per file, kc_<key>.exr, e.g. kc_ggx_smith_height_correlated.exr):
//   width = mu_count, height = alpha_count (row i = alpha node i, column j = mu node j),
//   4 float32 channels, ZIP compression:
//     E      = 1 - Ec                 (for viewers)
//     Ec     = 1 - E(mu, alpha)       (what Facet reads; exact in float near E = 1)
//     Eavg   = 1 - EcAvg              (constant along each row)
//     EcAvg  = 1 - E_avg(alpha)
//   metadata (string/int attributes): facet:table = "kulla_conty_E", facet:version,
//   facet:key, facet:ndf, facet:masking, facet:gamma, facet:schlick_k, facet:mu_count,
//   facet:alpha_count, facet:alpha_min, facet:alpha_max, facet:mu_axis, facet:alpha_axis,
//   facet:interpolation, facet:quadrature, facet:build_ms.
//
// Reading checks, in order: the file opens and is a 4-channel float image
// (else "unreadable"); the metadata names the expected key, version, grid
// and quadrature (else "stale"); the pixels are finite, within [0, 1],
// E + Ec = 1, EcAvg constant along rows and equal to the exact integral of
// the interpolated Ec row (else "corrupt"). A cache miss of any kind rebuilds
// the table and rewrites the file (atomically: a temporary file renamed over
// it, so a concurrent reader never sees half a file). The cache's files are
// read and written through a CacheDirectory (CacheFiles.h): only files the
// current user owns and nobody else can write are loaded.
//
// Lambda table files (one per NDF and shape, lambda_<name>.bin, e.g.
// lambda_student_t_g1.8.bin, the shape printed shortest round-trip exact):
// a text header of "field value" lines, an empty line, then the kSize nodes
// z as IEEE binary64 little-endian (exact: a loaded table is bit-identical
// to the built one). The first line is "facet lambda table"; the fields are
// kind (smith_lambda), version (kLambdaTableVersion), key, ndf, shape
// (comma-separated, %.17g), x0, step, count, floor, axis, encoding,
// build_ms and checksum (FNV-1a 64 of the node bytes). Reading checks, in
// order: the first line and the header's end (else "unreadable"); kind,
// version, ndf, key and shape as expected, the grid and encoding this build
// uses (else "stale"); the node bytes' count and checksum, every node finite
// and at least the floor, and four nodes recomputed by quadrature (else
// "corrupt"). A miss of any kind takes the table from the process's memory
// layer (lambdaTable(), which builds it once per process) and rewrites the
// file atomically; a hit is adopted into that layer (LambdaTable.h).
#pragma once

#include "CacheFiles.h"
#include "KullaConty.h"
#include "LambdaTable.h"

#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace facet {

// defaultCacheRoot() + "/tables"; "" if there is no cache root (an empty
// FACET_CACHE_DIR included).
std::string defaultTableCacheDir();

// Largest table file read (a 4096 x 4096 grid of 4 floats is 256 MB).
constexpr uint64_t kMaxTableFileBytes = uint64_t(300) << 20;

// Writes `table` to `path` (any directory must exist), every write checked.
// Returns "" or an error message naming the file.
std::string writeEnergyTableExr(const EnergyTable& table, const std::string& path);
// The EXR file of `table` in memory. Returns "" or an error message.
std::string encodeEnergyTableExr(const EnergyTable& table, std::string& bytes);

// Writes `table` to `path` atomically (a temporary file in the same
// directory, renamed over `path`; the directory is created). "" or an error.
std::string replaceEnergyTableExr(const EnergyTable& table, const std::string& path);

enum class TableFileStatus { Ok, Missing, Unreadable, Stale, Corrupt };
const char* tableFileStatusName(TableFileStatus s);

struct TableFileResult {
    TableFileStatus status = TableFileStatus::Missing;
    std::string message;                 // why it is not Ok
    std::shared_ptr<EnergyTable> table;  // set when Ok
};

// Reads a table file. With `expected`, a table for another key, version,
// grid or quadrature is Stale; without, any well-formed table is accepted.
TableFileResult readEnergyTableExr(const std::string& path, const EnergyTableKey* expected = nullptr,
                                   const EnergyQuadrature& quadrature = {});
// The same from the bytes of a file; `path` names it in messages.
TableFileResult decodeEnergyTableExr(const std::string& bytes, const std::string& path,
                                     const EnergyTableKey* expected = nullptr, const EnergyQuadrature& quadrature = {});

// Largest Lambda table file read (the nodes are 33 KB in a alone, 0.35-1.3
// MB in (a, alpha)).
constexpr uint64_t kMaxLambdaTableFileBytes = uint64_t(4) << 20;

// "lambda_student_t_g1.8.bin".
std::string lambdaTableFileName(const NdfEntry& ndf, const std::vector<double>& shape);
// The bytes of the Lambda table file of `table`.
std::string encodeLambdaTable(const LambdaTable& table);

struct LambdaTableFileResult {
    TableFileStatus status = TableFileStatus::Missing;
    std::string message;                 // why it is not Ok
    std::shared_ptr<LambdaTable> table;  // set when Ok, origin "disk"
};
// Reads the bytes of a Lambda table file; `path` names it in messages. With
// `ndf`, a table for another NDF or `shape` is Stale. The nodes are checked
// against the quadrature at a few spot nodes (~0.1 s each for the NDFs whose
// Lambda has no closed form) or, given `trusted` (the table of the same key
// this process already built or verified), against all of its nodes, exactly.
LambdaTableFileResult decodeLambdaTable(const std::string& bytes, const std::string& path,
                                        const NdfEntry* ndf = nullptr, const std::vector<double>* shape = nullptr,
                                        const LambdaTable* trusted = nullptr);

// Reads the Lambda table file at `path` (missing: Missing; refused or not
// a regular file: Unreadable), expecting the table of `ndf` with `shape`.
LambdaTableFileResult readLambdaTableFile(const std::string& path, const NdfEntry& ndf,
                                          const std::vector<double>& shape);

// Tables by key, shared by shared_ptr and immutable once built. Thread-safe:
// concurrent requests for one key wait for a single load/build (the mutex is
// not held while building). Owned by the caller (e.g. one per facet::Compiler);
// two caches on one directory are safe (files are replaced atomically).
class TableCache {
public:
    // dir: where the EXR files live; "" keeps tables in memory only.
    explicit TableCache(std::string dir = defaultTableCacheDir(), EnergyQuadrature quadrature = {});
    // The files live in `sub` below a cache directory shared with other
    // caches (one trust decision, one warning for all of them).
    TableCache(std::shared_ptr<CacheDirectory> cache, std::string sub, EnergyQuadrature quadrature = {});

    std::shared_ptr<const EnergyTable> get(const EnergyTableKey& key);
    // The table of a checked material with energy = kulla_conty.
    std::shared_ptr<const EnergyTable> getFor(const CheckedMaterial& material) { return get(energyTableKey(material)); }
    // The Lambda table of `ndf` with `shape` (see the top of this file), the
    // same object for every request to this cache.
    std::shared_ptr<const LambdaTable> getLambda(const NdfEntry& ndf, const std::vector<double>& shape);
    // The table of a checked material for which usesTabulatedLambda holds.
    std::shared_ptr<const LambdaTable> lambdaFor(const CheckedMaterial& material);

    // kc_<key>.exr in dir (empty when dir is empty).
    std::string pathFor(const EnergyTableKey& key) const;
    // lambda_<name>.bin in dir (empty when dir is empty).
    std::string lambdaPathFor(const NdfEntry& ndf, const std::vector<double>& shape) const;
    const std::string& dir() const { return dir_; }
    // The warning given when the directory or a file in it was refused, or "".
    std::string refusal() const { return cache_->warning(); }

    // What happened per request that reached the disk or built a table:
    // action is "disk" (loaded), "built" (no file), "rebuilt" (the file was
    // stale, unreadable or corrupt: reason says which), with the time taken
    // and any failure to write the file. key is the E table's key or the
    // Lambda file's stem ("lambda_student_t_g1.8"); a Lambda table the
    // process already held is not built again (reason says so).
    struct Event {
        std::string key, action, reason, writeError;
        double millis = 0;
    };
    std::vector<Event> events() const;

private:
    std::shared_ptr<const EnergyTable> produce(const EnergyTableKey& key);
    std::shared_ptr<const LambdaTable> produceLambda(const NdfEntry& ndf, const std::vector<double>& shape);
    // The action and reason of a request that found no usable file.
    void missed(Event& ev, bool haveBytes, TableFileStatus status, const std::string& message) const;

    std::shared_ptr<CacheDirectory> cache_;
    std::string sub_;  // "" or "SUBDIR/" below cache_'s root
    std::string dir_;  // cache_'s root + sub_, "" without a root
    EnergyQuadrature quadrature_;
    mutable std::mutex mutex_;
    std::map<EnergyTableKey, std::shared_future<std::shared_ptr<const EnergyTable>>> tables_;
    std::map<std::pair<const NdfEntry*, std::vector<double>>, std::shared_future<std::shared_ptr<const LambdaTable>>>
        lambdaTables_;
    std::vector<Event> events_;
};

}  // namespace facet
