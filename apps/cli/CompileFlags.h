// CompileFlags: the flags that `facet eval` and `facet ir` share (the
// material, --backend, --math, --width, --assume, --set) and the compile
// options they make, so that both commands read them, and fail on them,
// alike. Errors are UsageErrors (Commands.h): exit 2 with the usage text.
#pragma once

#include "Kernel.h"

#include <map>
#include <string>
#include <vector>

namespace facet {

// Values bound with --set, by input name (float: one value, rgb: three).
using Bindings = std::map<std::string, std::vector<double>>;

// Adds one --set NAME=VALUE (or NAME=R,G,B) to `out`; a name given twice is
// an error.
void parseSet(const std::string& spec, Bindings& out);

// --set values against the material's inputs: the same usage errors (exit 2)
// in every command.
void checkBindings(const CheckedMaterial& material, const Bindings& bindings);

// The flags of `facet eval`; `facet ir` reads the same ones but --in and
// --out, and sets the backend from --simd.
struct EvalOptions {
    std::string file, material, backend = "interp", in, out, math = "exact", width, assume;
    Bindings bindings;
};

// Builds the compile-option string of the C++/C API from CLI flags.
CompileOptions compileOptionsFor(const EvalOptions& opt);

}  // namespace facet
