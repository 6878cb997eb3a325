// Checker: names, types and model rules of a parsed program.
//
// Resolves every name (inputs and lets must be defined before use), types
// every expression (float and rgb, with float promoting to rgb), evaluates
// input defaults and ranges (which must be constant), matches model
// arguments against the model's forms (positional or named), and enforces
// the material rules: `ndf` required, no duplicate statements, masking
// compatible with the NDF (Smith needs a closed-form Lambda; ward is a whole
// BRDF and needs masking = none), and those of lobes (SPEC 10): every model
// statement inside a lobe once a material has lobe blocks, each lobe with an
// ndf or only a diffuse term, a `bsdf` that uses every lobe and numbers as
// weights (BsdfCombination.h). Reports through the DiagnosticEngine.
#pragma once

#include "AST.h"
#include "Diagnostics.h"
#include "Material.h"

#include <optional>
#include <string>

namespace facet {

// Checks `program`. The result is meaningful only if diags has no errors.
CheckedProgram checkProgram(const Program& program, DiagnosticEngine& diags);

// Convenience: read, parse and check a file; diagnostics go to diags.
// A file that cannot be read is reported as an error at "path".
CheckedProgram loadProgramFile(const std::string& path, DiagnosticEngine& diags);
// The text of a material file (a regular file, or a pipe read to its end;
// never a directory or device; at most kMaxSourceBytes). nullopt with the
// reason in `error` ("cannot open file", "is a directory, not a file").
std::optional<std::string> readSourceFile(const std::string& path, std::string& error);
CheckedProgram loadProgramText(std::string_view text, const std::string& path, DiagnosticEngine& diags);

// Largest material file accepted (the compiler must not allocate without bound).
constexpr size_t kMaxSourceBytes = 4u << 20;

}  // namespace facet
