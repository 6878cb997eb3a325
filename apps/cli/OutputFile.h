// OutputFile: how `facet` commands write what they produce, every write and
// close checked, so that a full disk or a closed pipe is an error naming the
// file (exit 1), never a truncated file presented as success; and which
// paths a command may write its outputs to at all.
#pragma once

#include <string>
#include <vector>
#include <string_view>

namespace facet {

// Writes `text` to `path` ("" or "-": standard output, flushed). On failure
// prints "facet: error: cannot write PATH: REASON" on stderr and returns false.
bool writeOutput(const std::string& path, const std::string& text);

// Flushes and checks standard output after a command printed to it with
// stdio; false (and the one-line error) when any of it was lost.
bool finishStandardOutput();

// A path the command reads or writes besides the output being checked,
// with what it is to the user ("the material file", "the header").
struct OtherPath {
    std::string path, role;
};

// Why `command` must not write an output to `out`, as one line without the
// "facet: error: " prefix, or "" when it may. Outputs that are replaced by
// renaming a complete file over them may only go to a new path or over an
// existing regular file: a rename over a symlink, FIFO, socket or device
// would replace that node by a regular file (as root, /dev/null itself), and
// one over a directory fails late. `out` must also be none of `others`:
// existing files are compared by device and inode (hard links, `./x` and
// `x`, symlinked directories), paths that do not exist yet by their
// normalized absolute form with the existing part of them resolved.
std::string outputProblem(const std::string& command, const std::string& out, const std::vector<OtherPath>& others);
// Only the second half: `out` is none of `others`. For outputs written in
// place (`facet sample --out`, `facet eval --out`), which may go to a FIFO or
// a device such as /dev/null, but never over the files the command reads.
std::string sameFileProblem(const std::string& command, const std::string& out, const std::vector<OtherPath>& others);

// An output written in pieces, for results too large to hold in memory
// (`facet sample -n 100000000`): "" or "-" is standard output, anything
// else the file, created or truncated when the stream opens. Each write is
// checked; the first failure prints the one-line error and makes every
// later call return false.
class OutputStream {
public:
    explicit OutputStream(std::string path);
    ~OutputStream();
    OutputStream(const OutputStream&) = delete;
    OutputStream& operator=(const OutputStream&) = delete;

    bool write(std::string_view text);
    // Flushes and closes; false when anything was lost.
    bool finish();

private:
    bool fail(int err);
    std::string path_;
    int fd_ = -1;
    bool failed_ = false, finished_ = false;
};

}  // namespace facet
