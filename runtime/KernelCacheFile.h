// KernelCacheFile: the format of a kernel cache file (`<key>.fko`), the one
// place that writes and reads it. A file holds an 8-byte magic, the key and
// the math variant (each a 64-bit length and its bytes), the measured error
// (8 bytes), the object's checksum (xxh3, 8 bytes) and the object (length
// and bytes). The checksum only detects damage; whether a file may be read
// at all is CacheFiles.h's decision.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace facet {

// A compiled kernel as the caches keep it: object code, the math variant it
// was compiled with, and (for tolerance builds) its measured error.
struct CachedKernel {
    std::string object;
    std::string variant;
    double measuredError = -1;  // < 0: not measured
};

// The bytes of the cache file of `record` under `key`.
std::string kernelCacheFileBytes(const std::string& key, const CachedKernel& record);

// The record in `bytes` if they are a whole, undamaged cache file stored
// under `key`; nullopt otherwise (truncated, corrupted, another key or
// format), and the caller recompiles. Every length is checked against the
// bytes left before anything is allocated.
std::optional<CachedKernel> parseKernelCacheFile(std::string_view bytes, const std::string& key);

// The key a cache file says it was stored under (nullopt: not a cache file
// of this format); the rest of the file is not checked.
std::optional<std::string> kernelCacheFileKey(std::string_view bytes);

}  // namespace facet
