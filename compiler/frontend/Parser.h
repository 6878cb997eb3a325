// Parser: recursive-descent parser from tokens to the AST (Program).
//
// Syntax errors are reported through the DiagnosticEngine; after an error the
// parser skips to the end of the statement and goes on, so one file reports
// every independent mistake. Nesting depth is bounded so that no input can
// exhaust the stack.
#pragma once

#include "AST.h"
#include "Diagnostics.h"

#include <string_view>

namespace facet {

// Parses `source` (named `path` in diagnostics). Always returns a Program;
// it is meaningful only if diags has no errors.
Program parseProgram(std::string_view source, const std::string& path, DiagnosticEngine& diags);

}  // namespace facet
