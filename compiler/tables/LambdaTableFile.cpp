// LambdaTableFile: the cache file of a tabulated Smith Lambda (format in
// TableCache.h): a text header naming the table and its grid, then the nodes
// as exact doubles, and the checks a file must pass to be used.
#include "TableCache.h"

#include "CacheFiles.h"
#include "TableFileRead.h"
#include "LambdaTable.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

namespace facet {

namespace {

constexpr const char* kMagic = "facet lambda table";
constexpr const char* kKind = "smith_lambda";
// The nodes' meaning per table axes (LambdaAxes).
const char* axisText(LambdaAxes axes) {
    return axes == LambdaAxes::Slope ? "z[i] = log(a Lambda(a)) at a = exp(x0 + i step), alpha = 1; "
                                       "z[count] = its limit at a = 0"
                                     : "z[j count + i] = log(a Lambda(a, alpha)) at a = exp(x0 + i step), "
                                       "alpha of row coordinate y0 + j ystep; z[rows count + j] = its limit at a = 0";
}
constexpr const char* kEncoding = "float64 little-endian";
constexpr size_t kMaxHeaderBytes = 4096;
// Nodes recomputed by quadrature when a file is read (a few ms): a file
// whose checksum is right but whose contents are not this build's table
// (e.g. from a build whose quadrature differed without a version bump).
// Nodes k of a table of n nodes in all.
std::vector<int> spotChecks(int n) { return {0, n / 3, 2 * n / 3, n - 1}; }
constexpr double kSpotTolerance = 1e-12;  // relative, in z: the same build reproduces it exactly

std::string exact(double x) { return fmt::format("{:.17g}", x); }

std::string shapeText(const std::vector<double>& shape) {
    std::string s;
    for (double v : shape) s += (s.empty() ? "" : ",") + exact(v);
    return s;
}

// FNV-1a, 64 bits, over the node bytes: detects damage, not tampering (the
// cache directory's trust rules do that, CacheFiles.h).
uint64_t checksum(std::string_view bytes) {
    uint64_t h = 0xcbf29ce484222325ull;
    for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ull;
    return h;
}

std::string encodeNodes(const std::vector<double>& z) {
    std::string out(z.size() * 8, '\0');
    for (size_t i = 0; i < z.size(); ++i) {
        uint64_t bits;
        std::memcpy(&bits, &z[i], 8);
        for (int b = 0; b < 8; ++b) out[i * 8 + b] = char((bits >> (8 * b)) & 0xff);
    }
    return out;
}

double decodeNode(std::string_view bytes, size_t i) {
    uint64_t bits = 0;
    for (int b = 0; b < 8; ++b) bits |= uint64_t(static_cast<unsigned char>(bytes[i * 8 + b])) << (8 * b);
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
}

}  // namespace

std::string lambdaTableFileName(const NdfEntry& ndf, const std::vector<double>& shape) {
    return "lambda_" + lambdaTableName(ndf, shape) + ".bin";
}

std::string encodeLambdaTable(const LambdaTable& t) {
    std::string nodes = encodeNodes(t.z);
    std::string header;
    auto line = [&](const char* key, const std::string& value) { header += fmt::format("{} {}\n", key, value); };
    header += std::string(kMagic) + "\n";
    line("kind", kKind);
    line("version", std::to_string(kLambdaTableVersion));
    line("key", t.name());
    line("ndf", t.ndf->name);
    line("shape", shapeText(t.shape));
    const LambdaGrid& g = t.grid;
    line("x0", exact(g.x0));
    line("step", exact(g.step));
    line("count", std::to_string(g.size));
    line("y0", exact(g.y0));
    line("ystep", exact(g.yStep));
    line("rows", std::to_string(g.rows));
    line("rowscale", exact(g.rowScale));
    line("floor", exact(LambdaTable::kLogFloor));
    line("axis", axisText(t.axes));
    line("encoding", kEncoding);
    line("build_ms", exact(t.buildMillis));
    line("checksum", fmt::format("{:016x}", checksum(nodes)));
    return header + "\n" + nodes;
}

LambdaTableFileResult decodeLambdaTable(const std::string& bytes, const std::string& path, const NdfEntry* ndf,
                                        const std::vector<double>* shape, const LambdaTable* trusted) {
    LambdaTableFileResult r;
    auto fail = [&](TableFileStatus s, std::string msg) {
        r.status = s;
        r.message = std::move(msg);
        r.table.reset();
        return r;
    };
    size_t end = bytes.find("\n\n");
    if (bytes.rfind(std::string(kMagic) + "\n", 0) != 0 || end == std::string::npos || end > kMaxHeaderBytes)
        return fail(TableFileStatus::Unreadable, fmt::format("{} is not a Facet Lambda table file", path));
    std::map<std::string, std::string> fields;
    for (size_t pos = std::strlen(kMagic) + 1; pos <= end;) {
        size_t eol = bytes.find('\n', pos);
        std::string line = bytes.substr(pos, eol - pos);
        size_t space = line.find(' ');
        if (space == std::string::npos)
            return fail(TableFileStatus::Corrupt, fmt::format("{}: bad header line '{}'", path, line));
        fields[line.substr(0, space)] = line.substr(space + 1);
        pos = eol + 1;
    }
    auto field = [&](const char* key) {
        auto it = fields.find(key);
        return it == fields.end() ? std::string() : it->second;
    };
    if (field("kind") != kKind) return fail(TableFileStatus::Stale, fmt::format("{} is not a Lambda table", path));
    if (field("version") != std::to_string(kLambdaTableVersion))
        return fail(TableFileStatus::Stale, fmt::format("{} has table version '{}', expected {}", path,
                                                        field("version"), kLambdaTableVersion));
    const ModelInfo* info = findModel(ModelSlot::Ndf, field("ndf"));
    if (!info || !ndfEntry(*info).tabulatedLambda)
        return fail(TableFileStatus::Stale, fmt::format("{}: no tabulated ndf '{}'", path, field("ndf")));
    auto t = std::make_shared<LambdaTable>();
    t->ndf = &ndfEntry(*info);
    std::string shapeField = field("shape");
    for (size_t pos = 0; pos < shapeField.size();) {
        size_t comma = std::min(shapeField.find(',', pos), shapeField.size());
        t->shape.push_back(std::strtod(shapeField.substr(pos, comma - pos).c_str(), nullptr));
        pos = comma + 1;
    }
    if (t->shape.size() != t->ndf->tableShapeParams.size() || shapeText(t->shape) != shapeField ||
        field("key") != t->name())
        return fail(TableFileStatus::Corrupt, fmt::format("{}: key '{}' does not match ndf {} with shape '{}'", path,
                                                          field("key"), t->ndf->name, shapeField));
    if (ndf && (t->ndf != ndf || !shape || t->shape != *shape))
        return fail(TableFileStatus::Stale, fmt::format("{} holds table {}, expected {}", path, t->name(),
                                                        lambdaTableName(*ndf, shape ? *shape : t->shape)));
    t->axes = lambdaAxes(*t->ndf);
    t->grid = lambdaGrid(*t->ndf, t->shape, t->axes);
    const LambdaGrid& g = t->grid;
    size_t count = size_t(g.nodeCount());
    if (field("x0") != exact(g.x0) || field("step") != exact(g.step) || field("count") != std::to_string(g.size) ||
        field("y0") != exact(g.y0) || field("ystep") != exact(g.yStep) || field("rows") != std::to_string(g.rows) ||
        field("rowscale") != exact(g.rowScale) ||
        field("floor") != exact(LambdaTable::kLogFloor) || field("axis") != axisText(t->axes) ||
        field("encoding") != kEncoding)
        return fail(TableFileStatus::Stale,
                    fmt::format("{} has another grid or encoding (x0 {}, step {}, count {}, rows {})", path,
                                field("x0"), field("step"), field("count"), field("rows")));
    std::string_view nodes = std::string_view(bytes).substr(end + 2);
    if (nodes.size() != count * 8)
        return fail(TableFileStatus::Corrupt,
                    fmt::format("{}: {} bytes of nodes, expected {}", path, nodes.size(), count * 8));
    if (field("checksum") != fmt::format("{:016x}", checksum(nodes)))
        return fail(TableFileStatus::Corrupt, fmt::format("{}: the nodes do not match their checksum", path));
    t->z.resize(count);
    for (size_t i = 0; i < count; ++i) {
        t->z[i] = decodeNode(nodes, i);
        if (!std::isfinite(t->z[i]) || t->z[i] < LambdaTable::kLogFloor)
            return fail(TableFileStatus::Corrupt, fmt::format("{}: node {} is {}", path, i, t->z[i]));
    }
    if (trusted && trusted->z.size() == count) {
        // The same key built or verified in this process: every node must be
        // its node, bit for bit (the build is deterministic).
        for (size_t i = 0; i < count; ++i)
            if (t->z[i] != trusted->z[i])
                return fail(TableFileStatus::Corrupt, fmt::format("{}: node {} is {}, the table this process holds has {}",
                                                                  path, i, t->z[i], trusted->z[i]));
    } else
        for (int i : spotChecks(int(count))) {
            double z = lambdaTableNode(*t->ndf, t->shape, t->grid, i);
            if (!(std::abs(t->z[i] - z) <= kSpotTolerance * std::max(1.0, std::abs(z))))
                return fail(TableFileStatus::Corrupt,
                            fmt::format("{}: node {} is {}, the quadrature gives {}", path, i, t->z[i], z));
        }
    t->buildMillis = std::strtod(field("build_ms").c_str(), nullptr);
    t->origin = "disk";
    r.status = TableFileStatus::Ok;
    r.table = std::move(t);
    return r;
}

LambdaTableFileResult readLambdaTableFile(const std::string& path, const NdfEntry& ndf,
                                          const std::vector<double>& shape) {
    return readTableFile<LambdaTableFileResult>(path, kMaxLambdaTableFileBytes, [&](const std::string& bytes) {
        return decodeLambdaTable(bytes, path, &ndf, &shape);
    });
}

}  // namespace facet
