// OutputFile: checked writes of command outputs, and the paths they may go to (OutputFile.h).
#include "OutputFile.h"

#include "CacheFiles.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

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

namespace {

const char* nodeKind(mode_t mode) {
    if (S_ISLNK(mode)) return "a symbolic link";
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISCHR(mode)) return "a character device";
    return "a special file";
}

// A path that names no file yet, in the one form two spellings of it share:
// absolute, with the part of it that exists resolved (symlinked directories,
// "..") and the rest lexically normal ("./x.o" and "x.o").
std::string normalizedPath(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    if (ec) return fs::path(path).lexically_normal().string();
    fs::path resolved = fs::weakly_canonical(absolute, ec);
    return (ec ? absolute.lexically_normal() : resolved).string();
}

}  // namespace

std::string outputProblem(const std::string& command, const std::string& out, const std::vector<OtherPath>& others) {
    struct stat outStat {};
    // lstat: the output itself, not what a symlink there points to.
    if (::lstat(out.c_str(), &outStat) == 0 && !S_ISREG(outStat.st_mode))
        return fmt::format("{} is {}, not a regular file; {} writes its outputs only to new paths or regular files", out,
                           nodeKind(outStat.st_mode), command);
    return sameFileProblem(command, out, others);
}

std::string sameFileProblem(const std::string& command, const std::string& out, const std::vector<OtherPath>& others) {
    struct stat outStat {};
    const bool outExists = ::stat(out.c_str(), &outStat) == 0;
    for (const OtherPath& other : others) {
        if (other.path.empty()) continue;
        bool same = false;
        if (outExists) {
            struct stat otherStat {};
            same = ::stat(other.path.c_str(), &otherStat) == 0 && otherStat.st_dev == outStat.st_dev &&
                   otherStat.st_ino == outStat.st_ino;
        } else {
            same = normalizedPath(out) == normalizedPath(other.path);
        }
        if (same)
            return fmt::format("{} is the same file as {} {}; {} does not write an output over {}", out, other.role,
                               other.path, command, other.role);
    }
    return "";
}

OutputStream::OutputStream(std::string path) : path_(std::move(path)) {
    if (path_.empty() || path_ == "-") {
        std::fflush(stdout);  // what the command printed before comes first
        fd_ = STDOUT_FILENO;
        return;
    }
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd_ < 0) fail(errno);
}

OutputStream::~OutputStream() {
    if (fd_ > STDOUT_FILENO) ::close(fd_);
}

bool OutputStream::fail(int err) {
    if (!failed_) {
        std::string name = fd_ == STDOUT_FILENO ? "standard output" : path_;
        std::fprintf(stderr, "facet: error: cannot write %s: %s\n", name.c_str(), std::strerror(err ? err : EIO));
    }
    failed_ = true;
    return false;
}

bool OutputStream::write(std::string_view text) {
    if (failed_) return false;
    while (!text.empty()) {
        ssize_t n = ::write(fd_, text.data(), text.size());
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return fail(n < 0 ? errno : EIO);
        text.remove_prefix(size_t(n));
    }
    return true;
}

bool OutputStream::finish() {
    if (failed_ || finished_) return !failed_;
    finished_ = true;
    if (fd_ > STDOUT_FILENO) {
        int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0) return fail(errno);
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
