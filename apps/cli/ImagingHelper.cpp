// ImagingHelper: `facet render` and `facet bench` hand over to facet-imaging
// (ImagingHelper.h).
#include "ImagingHelper.h"

#include "CacheFiles.h"

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

extern char** environ;

namespace facet {

namespace {

constexpr const char* kHelperName = "facet-imaging";

// The directory of this executable, "" (with `why`) when unknown.
std::string ownDirectory(std::string& why) {
    char buf[PATH_MAX];
    ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) {
        why = std::string("cannot read /proc/self/exe: ") + std::strerror(errno);
        return "";
    }
    std::string self(buf, size_t(n));
    size_t slash = self.rfind('/');
    return slash == std::string::npos ? "." : self.substr(0, slash ? slash : 1);
}

int fail(const std::string& why) {
    std::fprintf(stderr,
                 "facet: error: `facet render` and `facet bench` run in %s (the command line linked with "
                 "OpenImageIO), which cannot be used: %s\n",
                 kHelperName, why.c_str());
    return 1;
}

}  // namespace

int runImagingHelper(char** argv) {
    std::string why;
    std::string dir = ownDirectory(why);
    if (dir.empty()) return fail(why);
    std::string path = dir + "/" + kHelperName;
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0) return fail(dir + ": " + std::strerror(errno));
    if (!(why = untrustedBecause(st, dir, true)).empty()) return fail(why);
    // O_NOFOLLOW: the helper itself, not whatever a symlink in its place names.
    int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) return fail(path + ": " + std::strerror(errno));
    if (::fstat(fd, &st) != 0) why = path + ": " + std::strerror(errno);
    else if (!S_ISREG(st.st_mode)) why = path + " is not a regular file";
    else if (!(st.st_mode & S_IXUSR)) why = path + " is not executable";
    else why = untrustedBecause(st, path, true);
    if (!why.empty()) {
        ::close(fd);
        return fail(why);
    }
    std::string name = kHelperName;
    argv[0] = name.data();
    ::fexecve(fd, argv, environ);
    why = path + ": " + std::strerror(errno);
    ::close(fd);
    return fail(why);
}

}  // namespace facet
