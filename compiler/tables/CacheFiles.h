// CacheFiles: the one place where Facet's disk caches (compiled kernel
// objects, Kulla-Conty tables) touch the file system, the trust model both
// follow, and the checked whole-file writer of output files.
//
// A cache holds native code that Facet will run, so a file is used only if
// nobody but the current user could have written it:
//   - the cache root and every directory below it that Facet uses are owned
//     by the current user and not writable by group or others; Facet creates
//     missing ones with mode 0700 (whatever the umask);
//   - a cache file is opened without following symlinks and must be a
//     regular file (a FIFO, device or symlink is refused without blocking),
//     owned by the current user, not writable by group or others, and no
//     larger than the caller's bound;
//   - files are written through a fresh temporary file created with
//     O_CREAT | O_EXCL | O_NOFOLLOW (mode 0600) in the same directory and
//     renamed over the entry, so readers see the old file or the new one and
//     a planted name or symlink is never written through.
// Anything else is refused: the CacheDirectory reports one warning (its
// first refusal) and from then on behaves as if there were no disk cache.
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <sys/stat.h>

namespace facet {

// The cache root: $FACET_CACHE_DIR if set (empty: no disk cache), else
// $XDG_CACHE_HOME/facet (an absolute path; a relative one is ignored, as
// the XDG base directory specification says), else $HOME/.cache/facet; ""
// when there is none.
std::string defaultCacheRoot();

// Why a file or directory with status `st` cannot be trusted to hold what
// Facet runs, or "": it must be owned by the current user (or, with
// `rootMayOwn`, by root, as installed programs are) and not writable by
// group or others.
std::string untrustedBecause(const struct stat& st, const std::string& path, bool rootMayOwn = false);

// Reads a whole regular file without following a final symlink and without
// blocking on a FIFO; refuses one larger than maxBytes. Returns the bytes, or
// nullopt with the reason in `why` (`missing` set when there is no file).
std::optional<std::string> readRegularFile(const std::string& path, uint64_t maxBytes, std::string& why,
                                           bool* missing = nullptr);

// Writes `bytes` to `path` (created or truncated, as an output file the user
// named), every write and the close checked. Returns "" or an error naming
// the file, e.g. "cannot write /dev/full: No space left on device".
std::string writeFileChecked(const std::string& path, std::string_view bytes);

// Writes `bytes` to `path` atomically: an exclusive temporary file (mode
// 0600) in the same directory, every write and the close checked, renamed
// over `path`. Returns "" or an error naming the file.
std::string writeFileAtomically(const std::string& path, std::string_view bytes);

class CacheDirectory {
public:
    using WarningSink = std::function<void(const std::string&)>;
    // root "" = no disk cache. The default sink prints
    // "facet: warning: ..." on stderr.
    explicit CacheDirectory(std::string root, WarningSink warn = {});

    const std::string& root() const { return root_; }
    // False when there is no root or a refusal disabled the cache.
    bool usable() const;

    // relPath is "NAME" or "SUBDIR/NAME" below the root. nullopt when the
    // file is missing, unusable (corrupt is the caller's business) or refused.
    std::optional<std::string> read(const std::string& relPath, uint64_t maxBytes);
    // Creates missing directories (0700) and writes the file atomically
    // (0600). Returns "" or why not (a refusal also warns once).
    std::string write(const std::string& relPath, std::string_view bytes);

    // The warning given, if any (for tests and tools).
    std::string warning() const;
    // Reports something about a file of the cache through the warning sink
    // without refusing the cache (a table that had to be rebuilt).
    void notice(const std::string& message) const;

private:
    // Opens root/sub as a trusted directory (creating it when `create`);
    // returns its fd or -1 with `why` set (`missing` when absent).
    int openTrustedDir(const std::string& sub, bool create, std::string& why, bool& missing);
    void refuse(const std::string& why);

    std::string root_;
    WarningSink warn_;
    mutable std::mutex mutex_;
    bool refused_ = false;
    std::string warning_;
};

}  // namespace facet
