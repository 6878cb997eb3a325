// OutputFile: how `facet` commands write what they produce, every write and
// close checked, so that a full disk or a closed pipe is an error naming the
// file (exit 1), never a truncated file presented as success.
#pragma once

#include <string>

namespace facet {

// Writes `text` to `path` ("" or "-": standard output, flushed). On failure
// prints "facet: error: cannot write PATH: REASON" on stderr and returns false.
bool writeOutput(const std::string& path, const std::string& text);

// Flushes and checks standard output after a command printed to it with
// stdio; false (and the one-line error) when any of it was lost.
bool finishStandardOutput();

}  // namespace facet
