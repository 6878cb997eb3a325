// CacheFiles: trusted reads and atomic writes of cache files (CacheFiles.h).
#include "CacheFiles.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

namespace facet {

namespace {

// Closes a file descriptor on scope exit.
struct Fd {
    int fd = -1;
    explicit Fd(int f) : fd(f) {}
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
    int release() {
        int f = fd;
        fd = -1;
        return f;
    }
};

std::string errnoText(int err) { return std::strerror(err); }

const char* fileKind(mode_t mode) {
    if (S_ISLNK(mode)) return "a symlink";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISREG(mode)) return "a regular file";
    return "of an unknown kind";
}

enum class ReadOutcome { Ok, Missing, Refused, Failed };

// Reads dirFd/name: not through a symlink, not blocking on a FIFO, regular
// files only, at most maxBytes; with `checkOwner`, only a file the current
// user owns and nobody else can write. `display` names the file in messages.
ReadOutcome readAt(int dirFd, const std::string& name, const std::string& display, uint64_t maxBytes,
                   bool checkOwner, std::string& bytes, std::string& why) {
    struct stat before;
    if (::fstatat(dirFd, name.c_str(), &before, AT_SYMLINK_NOFOLLOW) != 0) {
        why = fmt::format("{}: {}", display, errnoText(errno));
        return errno == ENOENT ? ReadOutcome::Missing : ReadOutcome::Failed;
    }
    if (!S_ISREG(before.st_mode)) {
        why = fmt::format("{} is {}, not a regular file", display, fileKind(before.st_mode));
        return ReadOutcome::Refused;
    }
    if (checkOwner) {
        why = untrustedBecause(before, display);
        if (!why.empty()) return ReadOutcome::Refused;
    }
    Fd fd(::openat(dirFd, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC));
    if (fd.fd < 0) {
        why = fmt::format("{}: {}", display, errnoText(errno));
        return errno == ENOENT ? ReadOutcome::Missing : errno == ELOOP ? ReadOutcome::Refused : ReadOutcome::Failed;
    }
    // The name may have been replaced between the two looks: judge the file opened.
    struct stat st;
    if (::fstat(fd.fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_dev != before.st_dev || st.st_ino != before.st_ino) {
        why = fmt::format("{} changed while it was opened", display);
        return ReadOutcome::Refused;
    }
    if (checkOwner) {
        why = untrustedBecause(st, display);
        if (!why.empty()) return ReadOutcome::Refused;
    }
    if (uint64_t(st.st_size) > maxBytes) {
        why = fmt::format("{} is {} bytes, more than the {} allowed", display, uint64_t(st.st_size), maxBytes);
        return ReadOutcome::Failed;
    }
    bytes.assign(size_t(st.st_size), '\0');
    size_t done = 0;
    while (done < bytes.size()) {
        ssize_t got = ::read(fd.fd, bytes.data() + done, bytes.size() - done);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            why = fmt::format("{}: {}", display, errnoText(errno));
            return ReadOutcome::Failed;
        }
        if (got == 0) break;
        done += size_t(got);
    }
    bytes.resize(done);  // a file that shrank meanwhile reads short, and its checks reject it
    return ReadOutcome::Ok;
}

// Writes all of `bytes` to fd; "" or the error.
std::string writeAll(int fd, std::string_view bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
        ssize_t put = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (put < 0 && errno == EINTR) continue;
        if (put <= 0) return errnoText(put < 0 ? errno : EIO);
        done += size_t(put);
    }
    return "";
}

// Writes dirFd/name atomically through an exclusive temporary file.
std::string writeAt(int dirFd, const std::string& name, const std::string& display, std::string_view bytes) {
    static std::atomic<uint64_t> counter{0};
    thread_local std::mt19937_64 rng{std::random_device{}() ^ (uint64_t(::getpid()) << 32)};
    std::string tmp;
    int raw = -1;
    for (int attempt = 0; attempt < 100 && raw < 0; ++attempt) {
        tmp = fmt::format(".{}.{:016x}{:x}.tmp", name, rng(), counter++);
        raw = ::openat(dirFd, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
        if (raw < 0 && errno != EEXIST) return fmt::format("cannot create a temporary file for {}: {}", display, errnoText(errno));
    }
    if (raw < 0) return fmt::format("cannot create a temporary file for {}: names taken", display);
    Fd fd(raw);
    auto fail = [&](const std::string& what, int err) {
        ::unlinkat(dirFd, tmp.c_str(), 0);
        return fmt::format("cannot write {}: {}: {}", display, what, errnoText(err));
    };
    if (::fchmod(fd.fd, 0600) != 0) return fail("chmod", errno);  // whatever the umask
    if (std::string err = writeAll(fd.fd, bytes); !err.empty()) {
        ::unlinkat(dirFd, tmp.c_str(), 0);
        return fmt::format("cannot write {}: {}", display, err);
    }
    if (::close(fd.release()) != 0) return fail("close", errno);
    if (::renameat(dirFd, tmp.c_str(), dirFd, name.c_str()) != 0) return fail("rename", errno);
    return "";
}

void splitPath(const std::string& path, std::string& dir, std::string& name) {
    size_t slash = path.rfind('/');
    dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
    name = slash == std::string::npos ? path : path.substr(slash + 1);
}

// mkdir -p with mode 0700 for every directory created (chmod'ed, so the
// umask cannot widen or narrow it).
bool makeDirs(const std::string& path, std::string& why) {
    if (path.empty()) return true;
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) return true;
    size_t slash = path.find_last_of('/');
    if (slash != std::string::npos && slash > 0 && !makeDirs(path.substr(0, slash), why)) return false;
    if (::mkdir(path.c_str(), 0700) != 0 && errno != EEXIST) {
        why = fmt::format("cannot create {}: {}", path, errnoText(errno));
        return false;
    }
    ::chmod(path.c_str(), 0700);
    return true;
}

}  // namespace

std::string untrustedBecause(const struct stat& st, const std::string& path, bool rootMayOwn) {
    if (st.st_uid != ::geteuid() && !(rootMayOwn && st.st_uid == 0))
        return fmt::format("{} is owned by uid {}, not by {}the current user (uid {})", path, st.st_uid,
                           rootMayOwn ? "root or " : "", ::geteuid());
    if (st.st_mode & (S_IWGRP | S_IWOTH))
        return fmt::format("{} is writable by group or others (mode {:04o})", path, st.st_mode & 07777);
    return "";
}

std::string defaultCacheRoot() {
    if (const char* dir = std::getenv("FACET_CACHE_DIR")) return dir;  // "" disables
    // The XDG base directory specification: a relative path there is
    // invalid and ignored (it would name a different directory in every
    // working directory).
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && xdg[0] == '/') return std::string(xdg) + "/facet";
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/facet";
    return "";
}

std::optional<std::string> readRegularFile(const std::string& path, uint64_t maxBytes, std::string& why,
                                           bool* missing) {
    std::string bytes;
    ReadOutcome r = readAt(AT_FDCWD, path, path, maxBytes, false, bytes, why);
    if (missing) *missing = r == ReadOutcome::Missing;
    if (r != ReadOutcome::Ok) return std::nullopt;
    return bytes;
}

std::string writeFileChecked(const std::string& path, std::string_view bytes) {
    Fd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666));
    if (fd.fd < 0) return fmt::format("cannot write {}: {}", path, errnoText(errno));
    std::string err = writeAll(fd.fd, bytes);
    if (err.empty() && ::close(fd.release()) != 0) err = errnoText(errno);
    return err.empty() ? "" : fmt::format("cannot write {}: {}", path, err);
}

std::string writeFileAtomically(const std::string& path, std::string_view bytes) {
    std::string dir, name;
    splitPath(path, dir, name);
    Fd dirFd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (dirFd.fd < 0) return fmt::format("cannot write {}: {}: {}", path, dir, errnoText(errno));
    return writeAt(dirFd.fd, name, path, bytes);
}

CacheDirectory::CacheDirectory(std::string root, WarningSink warn) : root_(std::move(root)), warn_(std::move(warn)) {
    if (!warn_) warn_ = [](const std::string& m) { std::fprintf(stderr, "facet: warning: %s\n", m.c_str()); };
}

bool CacheDirectory::usable() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !root_.empty() && !refused_;
}

void CacheDirectory::notice(const std::string& message) const { warn_(message); }

std::string CacheDirectory::warning() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return warning_;
}

void CacheDirectory::refuse(const std::string& why) {
    std::string message;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (refused_) return;
        refused_ = true;
        warning_ = message = fmt::format("not using the cache in {}: {}; running without a disk cache", root_, why);
    }
    warn_(message);
}

int CacheDirectory::openTrustedDir(const std::string& sub, bool create, std::string& why, bool& missing) {
    missing = false;
    if (create && !makeDirs(root_, why)) return -1;
    // The root may be reached through a symlink the user made; what counts
    // is the directory it names.
    Fd root(::open(root_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (root.fd < 0) {
        missing = errno == ENOENT;
        struct stat st;
        why = errno == ENOTDIR && ::stat(root_.c_str(), &st) == 0
                  ? fmt::format("{} is {}, not a directory", root_, fileKind(st.st_mode))
                  : fmt::format("cannot open {}: {}", root_, errnoText(errno));
        return -1;
    }
    struct stat st;
    if (::fstat(root.fd, &st) != 0 || !(why = untrustedBecause(st, root_)).empty()) {
        if (why.empty()) why = fmt::format("cannot stat {}", root_);
        return -1;
    }
    if (sub.empty()) return root.release();
    std::string display = root_ + "/" + sub;
    if (create && ::mkdirat(root.fd, sub.c_str(), 0700) == 0) {
        Fd made(::openat(root.fd, sub.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
        if (made.fd >= 0) ::fchmod(made.fd, 0700);
    }
    Fd dir(::openat(root.fd, sub.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
    if (dir.fd < 0) {
        missing = errno == ENOENT;
        struct stat lst;
        if (errno == ENOTDIR || errno == ELOOP)
            why = ::fstatat(root.fd, sub.c_str(), &lst, AT_SYMLINK_NOFOLLOW) == 0
                      ? fmt::format("{} is {}, not a directory", display, fileKind(lst.st_mode))
                      : fmt::format("{} is not a directory", display);
        else
            why = fmt::format("cannot open {}: {}", display, errnoText(errno));
        return -1;
    }
    if (::fstat(dir.fd, &st) != 0 || !(why = untrustedBecause(st, display)).empty()) {
        if (why.empty()) why = fmt::format("cannot stat {}", display);
        return -1;
    }
    return dir.release();
}

std::optional<std::string> CacheDirectory::read(const std::string& relPath, uint64_t maxBytes) {
    if (!usable()) return std::nullopt;
    std::string sub, name;
    splitPath(relPath, sub, name);
    if (sub == ".") sub.clear();
    std::string why;
    bool missing = false;
    Fd dir(openTrustedDir(sub, false, why, missing));
    if (dir.fd < 0) {
        if (!missing) refuse(why);
        return std::nullopt;
    }
    std::string bytes;
    switch (readAt(dir.fd, name, root_ + "/" + relPath, maxBytes, true, bytes, why)) {
        case ReadOutcome::Ok: return bytes;
        case ReadOutcome::Refused: refuse(why); return std::nullopt;
        case ReadOutcome::Missing:
        case ReadOutcome::Failed: return std::nullopt;  // rebuilt and rewritten by the caller
    }
    return std::nullopt;
}

std::string CacheDirectory::write(const std::string& relPath, std::string_view bytes) {
    if (!usable()) return root_.empty() ? "no cache directory" : "the cache directory was refused";
    std::string sub, name;
    splitPath(relPath, sub, name);
    if (sub == ".") sub.clear();
    std::string why;
    bool missing = false;
    Fd dir(openTrustedDir(sub, true, why, missing));
    if (dir.fd < 0) {
        // A directory that cannot be created (read-only file system, no
        // permission) is only a slower run; a distrusted one is refused.
        if (!missing && why.rfind("cannot ", 0) != 0) refuse(why);
        return why;
    }
    return writeAt(dir.fd, name, root_ + "/" + relPath, bytes);
}

}  // namespace facet
