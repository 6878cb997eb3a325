// KernelCacheFile: writing and reading the kernel cache file format.
#include "KernelCacheFile.h"

#include <llvm/ADT/StringRef.h>
#include <llvm/Support/xxhash.h>

#include <cstdint>
#include <cstring>

namespace facet {
namespace {

constexpr char kCacheMagic[8] = {'F', 'A', 'C', 'E', 'T', 'K', 'O', '2'};

// Reads the fields of a cache file from memory.
class CacheFileReader {
public:
    explicit CacheFileReader(std::string_view bytes) : rest_(bytes) {}
    bool raw(void* out, size_t n) {
        if (rest_.size() < n) return false;
        std::memcpy(out, rest_.data(), n);
        rest_.remove_prefix(n);
        return true;
    }
    bool field(std::string& out) {
        uint64_t len = 0;
        if (!raw(&len, 8) || len > rest_.size()) return false;
        out.assign(rest_.data(), size_t(len));
        rest_.remove_prefix(size_t(len));
        return true;
    }
    bool magic() {
        char m[8];
        return raw(m, 8) && std::memcmp(m, kCacheMagic, 8) == 0;
    }
    bool atEnd() const { return rest_.empty(); }

private:
    std::string_view rest_;
};

void appendRaw(std::string& out, const void* p, size_t n) { out.append(static_cast<const char*>(p), n); }
void appendField(std::string& out, const std::string& s) {
    uint64_t len = s.size();
    appendRaw(out, &len, 8);
    out += s;
}

}  // namespace

std::string kernelCacheFileBytes(const std::string& key, const CachedKernel& record) {
    std::string out(kCacheMagic, 8);
    uint64_t checksum = llvm::xxh3_64bits(llvm::StringRef(record.object));
    appendField(out, key);
    appendField(out, record.variant);
    appendRaw(out, &record.measuredError, 8);
    appendRaw(out, &checksum, 8);
    appendField(out, record.object);
    return out;
}

std::optional<CachedKernel> parseKernelCacheFile(std::string_view bytes, const std::string& key) {
    CacheFileReader in(bytes);
    std::string storedKey;
    CachedKernel k;
    uint64_t checksum = 0;
    if (!in.magic() || !in.field(storedKey) || storedKey != key) return std::nullopt;
    if (!in.field(k.variant)) return std::nullopt;
    if (!in.raw(&k.measuredError, 8) || !in.raw(&checksum, 8)) return std::nullopt;
    if (!in.field(k.object) || !in.atEnd()) return std::nullopt;
    if (llvm::xxh3_64bits(llvm::StringRef(k.object)) != checksum) return std::nullopt;
    return k;
}

std::optional<std::string> kernelCacheFileKey(std::string_view bytes) {
    CacheFileReader in(bytes);
    std::string key;
    if (!in.magic() || !in.field(key)) return std::nullopt;
    return key;
}

}  // namespace facet
