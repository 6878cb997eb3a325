// KernelCache: the memory and disk caches of compiled objects and their
// keys (KernelCache.h).
#include "KernelCache.h"

#include "CacheFiles.h"
#include "CodegenIdentity.h"
#include "KullaConty.h"
#include "Specialize.h"

#include <fmt/format.h>
#include <llvm/ADT/StringExtras.h>
#include <llvm/Config/llvm-config.h>
#include <llvm/Support/SHA256.h>

namespace facet {

namespace {

// Largest kernel cache file read; objects are tens of kilobytes.
constexpr uint64_t kMaxCacheFileBytes = uint64_t(256) << 20;

std::string sha256Hex(const std::string& text) {
    return llvm::toHex(llvm::SHA256::hash(llvm::arrayRefFromStringRef(text)), true);
}

}  // namespace

KernelCacheKey::KernelCacheKey(const CheckedMaterial& specialized, const CompileOptions& options, int width,
                               const FacetJit& jit,
                               const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables) {
    std::string tableId;
    for (const auto& table : lobeEnergyTables)
        tableId += table ? fmt::format("{}/v{}/{};", table->key.name(), kEnergyTableVersion, table->quadrature.describe())
                         : ";";
    if (lobeEnergyTables.size() == 1) tableId.pop_back();  // one lobe: the key it always had
    text_ = fmt::format("{}|{}|w{}|{}|{}|{}|{}|{}|{}", printMaterial(specialized), options.canonical(), width,
                        LLVM_VERSION_STRING, jit.cpuName(), jit.cpuFeatures(), codegenIdentity(specialized),
                        FacetJit::kPipelineId, tableId);
    eval_ = sha256Hex(text_);
}

std::string KernelCacheKey::sampler(const std::string& variantName) const {
    return sha256Hex(text_ + "|sampler|" + variantName);
}

std::string kernelCacheFileName(const std::string& key) { return key + ".fko"; }

std::optional<CachedKernel> lookUpCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key,
                                         const std::string& cachePath, CompileOptions::Cache cache,
                                         std::string& origin) {
    if (cache == CompileOptions::Cache::Off) return std::nullopt;
    {
        std::lock_guard<std::mutex> lock(memory.mutex);
        auto it = memory.objects.find(key);
        if (it != memory.objects.end()) {
            origin = "memory cache";
            return it->second;
        }
    }
    if (cache != CompileOptions::Cache::On || cachePath.empty()) return std::nullopt;
    std::optional<std::string> bytes = disk.read(cachePath, kMaxCacheFileBytes);
    std::optional<CachedKernel> record = bytes ? parseKernelCacheFile(*bytes, key) : std::nullopt;
    if (record) {
        origin = "disk cache";
        std::lock_guard<std::mutex> lock(memory.mutex);
        memory.objects.emplace(key, *record);
    }
    return record;
}

void storeInCaches(MemoryCache& memory, CacheDirectory& disk, const std::string& key, const std::string& cachePath,
                   CompileOptions::Cache cache, const CachedKernel& record) {
    if (cache == CompileOptions::Cache::On && !cachePath.empty()) disk.write(cachePath, kernelCacheFileBytes(key, record));
    if (cache != CompileOptions::Cache::Off) {
        std::lock_guard<std::mutex> lock(memory.mutex);
        memory.objects.emplace(key, record);
    }
}

}  // namespace facet
