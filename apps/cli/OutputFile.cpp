// OutputFile: checked writes of command outputs (OutputFile.h).
#include "OutputFile.h"

#include "CacheFiles.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace facet {

namespace {
void reportStandardOutput(int err) {
    std::fprintf(stderr, "facet: error: cannot write standard output: %s\n", std::strerror(err ? err : EIO));
}
}  // namespace

bool writeOutput(const std::string& path, const std::string& text) {
    if (path.empty() || path == "-") {
        errno = 0;
        if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0) {
            reportStandardOutput(errno);
            return false;
        }
        return true;
    }
    std::string err = writeFileChecked(path, text);
    if (!err.empty()) {
        std::fprintf(stderr, "facet: error: %s\n", err.c_str());
        return false;
    }
    return true;
}

bool finishStandardOutput() {
    errno = 0;
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        reportStandardOutput(errno);
        return false;
    }
    return true;
}

}  // namespace facet
