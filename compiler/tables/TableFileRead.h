// TableFileRead: the read step shared by the table cache files' readers
// (Kulla-Conty EXR, Smith Lambda): get the file's bytes under the cache's
// trust rules (CacheFiles.h), or say why there are none, before the
// reader's own decoding classifies what it finds.
#pragma once

#include "CacheFiles.h"
#include "TableCache.h"

#include <optional>
#include <string>

namespace facet {

// `decode(bytes)` of the file at `path`, or a Result (TableFileResult or
// LambdaTableFileResult) that is Missing ("no file PATH") or Unreadable (the
// reason: not a regular file, not the user's, larger than maxBytes, ...).
template <typename Result, typename Decode>
Result readTableFile(const std::string& path, uint64_t maxBytes, Decode decode) {
    std::string why;
    bool missing = false;
    std::optional<std::string> bytes = readRegularFile(path, maxBytes, why, &missing);
    if (bytes) return decode(*bytes);
    Result r;
    r.status = missing ? TableFileStatus::Missing : TableFileStatus::Unreadable;
    r.message = missing ? "no file " + path : why;
    return r;
}

}  // namespace facet
