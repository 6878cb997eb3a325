// Diagnostics: the one path through which every user-facing error flows, and
// the internal-error mechanism that is kept apart from it.
//
// User errors (a mistake in a material file, a bad command-line value) are
// collected by a DiagnosticEngine and printed as "file:line:col: error: msg".
// Internal errors (a broken invariant inside Facet) throw InternalError via
// internal_assert; they are bugs, never the user's fault, and say so.
// There is no global state: each compilation owns its DiagnosticEngine.
#pragma once

#include "SourceLoc.h"

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace facet {

struct Diagnostic {
    SourceLoc loc;
    std::string message;
    std::string str() const;  // "file:line:col: error: message"
};

class DiagnosticEngine {
public:
    // Stop collecting after this many errors: one real mistake often causes
    // a cascade, and an adversarial file must not make us allocate without bound.
    static constexpr size_t kMaxErrors = 50;

    void error(const SourceLoc& loc, std::string message);
    bool hasErrors() const { return !diagnostics_.empty(); }
    bool full() const { return diagnostics_.size() >= kMaxErrors; }
    const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }
    std::string str() const;  // all diagnostics, one per line
    void clear() { diagnostics_.clear(); }

private:
    std::vector<Diagnostic> diagnostics_;
};

// Thrown for broken internal invariants (bugs in Facet).
class InternalError : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

// Thrown by API entry points that report user errors as exceptions (the C++
// library API); carries the rendered diagnostics.
class CompileError : public std::runtime_error {
public:
    explicit CompileError(const DiagnosticEngine& diags)
        : std::runtime_error(diags.str()), diagnostics(diags.diagnostics()) {}
    std::vector<Diagnostic> diagnostics;
};

namespace detail {
// Collects a message with operator<< and throws InternalError when destroyed.
// Header-only, so that the libraries below the front end (compiler/numeric)
// report their invariants the same way without linking it.
class InternalErrorReporter {
public:
    InternalErrorReporter(const char* file, int line, const char* cond) {
        msg_ << "internal error (a bug in Facet, please report it) at " << file << ":" << line;
        if (cond) msg_ << ": condition failed: " << cond;
        msg_ << ": ";
    }
    [[noreturn]] ~InternalErrorReporter() noexcept(false) { throw InternalError(msg_.str()); }
    template <typename T>
    InternalErrorReporter& operator<<(const T& v) {
        msg_ << v;
        return *this;
    }

private:
    std::ostringstream msg_;
};
}  // namespace detail

}  // namespace facet

// internal_assert(cond) << "context";  -- for invariants, not for user input.
#define internal_assert(cond) \
    if (cond) {               \
    } else                    \
        ::facet::detail::InternalErrorReporter(__FILE__, __LINE__, #cond)
#define internal_error ::facet::detail::InternalErrorReporter(__FILE__, __LINE__, nullptr)
