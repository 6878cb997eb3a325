// KernelCache: where compiled objects are kept between compiles (internal
// to the runtime): a Compiler's memory cache, its disk cache (CacheFiles.h
// decides whether a file may be read at all, KernelCacheFile.h what is in
// it), and the keys both are filed under.
//
// Eval objects and samplers' share both caches, under keys of their own.
// What each cache= option allows: on, memory and disk; memory, memory only;
// off, neither (every compile compiles).
#pragma once

#include "Kernel.h"
#include "KernelCacheFile.h"

#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace facet {

class CacheDirectory;

// A Compiler's in-memory cache of compiled objects, eval kernels' and
// samplers'. Shared with the kernels it built: a kernel gets its sampler on
// first use, which may come after the Compiler is gone.
struct MemoryCache {
    std::mutex mutex;
    std::map<std::string, CachedKernel> objects;  // key -> record
};

// The keys of one kernel's objects: the one definition of what a cached
// object must match. The eval object's key is the SHA-256 (hex) of what the
// kernel computes (the specialized material, printed), how (the canonical
// options, tolerance included, and the SIMD width) and with what (LLVM, the
// CPU and its features, the code generator (CodegenIdentity.h), the
// optimization pipeline, and each lobe's energy table's version and quadrature), so
// that a cache shared by several LLVMs or CPUs never hands one the other's
// code. A sampler's key adds the variant its eval code was compiled with
// (a tolerance search's choice).
class KernelCacheKey {
public:
    KernelCacheKey(const CheckedMaterial& specialized, const CompileOptions& options, int width, const FacetJit& jit,
                   const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables);
    const std::string& eval() const { return eval_; }
    std::string sampler(const std::string& variantName) const;

private:
    std::string text_;  // what the eval key hashes
    std::string eval_;
};

// A key's cache file, relative to the cache root.
std::string kernelCacheFileName(const std::string& key);

// The record cached under `key`: from memory (cache=on or memory), else
// from the disk file `cachePath` (cache=on; "" = no disk cache), which is
// then kept in memory too. `origin` says which ("memory cache", "disk
// cache"). A file that does not parse as this key's record (truncated,
// corrupted, another key) is a miss: the caller compiles and overwrites it.
std::optional<CachedKernel> lookUpCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key,
                                         const std::string& cachePath, CompileOptions::Cache cache,
                                         std::string& origin);

// Stores `record` in memory (cache=on or memory) and in the disk file
// `cachePath` (cache=on; "" = memory only). A cache that cannot be
// written is only slower.
void storeInCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key, const std::string& cachePath,
                   CompileOptions::Cache cache, const CachedKernel& record);

}  // namespace facet
