// Diagnostics: rendering of user diagnostics and the internal-error reporter.
#include "Diagnostics.h"

#include <algorithm>
#include <fmt/format.h>

namespace facet {

std::string SourceLoc::str() const {
    const std::string& name = file ? *file : std::string("<input>");
    if (!valid()) return name;
    return fmt::format("{}:{}:{}", name, line, col);
}

std::string Diagnostic::str() const { return fmt::format("{}: error: {}", loc.str(), message); }

void DiagnosticEngine::error(const SourceLoc& loc, std::string message) {
    if (full()) return;
    diagnostics_.push_back({loc, std::move(message)});
    if (full())
        diagnostics_.push_back({loc, fmt::format("too many errors ({}), stopping", kMaxErrors)});
}

std::string DiagnosticEngine::str() const {
    // In source order: syntax errors are found before checker errors, but a
    // reader wants them top to bottom.
    std::vector<Diagnostic> sorted = diagnostics_;
    std::stable_sort(sorted.begin(), sorted.end(), [](const Diagnostic& a, const Diagnostic& b) {
        if (a.loc.file != b.loc.file) return false;
        return std::pair(a.loc.line, a.loc.col) < std::pair(b.loc.line, b.loc.col);
    });
    std::string out;
    for (const Diagnostic& d : sorted) {
        out += d.str();
        out += '\n';
    }
    return out;
}

}  // namespace facet
