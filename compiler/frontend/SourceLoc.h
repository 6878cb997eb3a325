// SourceLoc: where a token, node or diagnostic comes from (file:line:col).
//
// Every token and AST node carries one. The file name is shared by all
// locations of one file, so a location is cheap to copy and outlives the
// parser that made it.
#pragma once

#include <memory>
#include <string>

namespace facet {

struct SourceLoc {
    std::shared_ptr<const std::string> file;  // path as the user gave it
    int line = 0;                             // 1-based; 0 means "no location"
    int col = 0;                              // 1-based, in bytes

    bool valid() const { return line > 0; }
    std::string str() const;  // "file:line:col"
};

}  // namespace facet
