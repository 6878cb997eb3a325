// CompileFlags: parsing and checking the flags eval and ir share
// (CompileFlags.h).
#include "CompileFlags.h"

#include "Checker.h"
#include "Commands.h"
#include "CsvTable.h"

#include <cmath>
#include <fmt/format.h>

namespace facet {

void parseSet(const std::string& spec, Bindings& out) {
    size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0)
        throw UsageError{fmt::format("--set expects NAME=VALUE, got '{}'", spec)};
    std::string name = spec.substr(0, eq), rest = spec.substr(eq + 1);
    std::vector<double> values;
    for (const std::string& field : splitFields(rest)) {
        std::optional<double> v = parseNumber(field);
        if (!v || !std::isfinite(*v))
            throw UsageError{fmt::format("--set {}: '{}' is not a finite number", name, field)};
        values.push_back(*v);
    }
    if (values.size() != 1 && values.size() != 3)
        throw UsageError{fmt::format("--set {}: expected one value or three (r,g,b), got {}", name, values.size())};
    if (!out.emplace(name, values).second) throw UsageError{fmt::format("--set {}: given twice", name)};
}

void checkBindings(const CheckedMaterial& material, const Bindings& bindings) {
    for (const auto& [name, values] : bindings) {
        const CheckedInput* in = material.findInput(name);
        if (!in) throw UsageError{fmt::format("--set: material '{}' has no input '{}'", material.name, name)};
        if (in->type == ValueType::Float && values.size() != 1)
            throw UsageError{fmt::format("--set {}: input '{}' is float; give one value", name, name)};
    }
}

// Through the option string of the C++/C API, so that the CLI accepts what
// the API accepts, with its messages.
CompileOptions compileOptionsFor(const EvalOptions& opt) {
    std::string spec = fmt::format("backend={};math={}", opt.backend, opt.math);
    if (!opt.width.empty()) spec += ";width=" + opt.width;
    if (!opt.assume.empty()) spec += ";assume=" + opt.assume;
    CompileOptions options;
    std::string error = CompileOptions::parse(spec, options);
    if (!error.empty()) throw UsageError{error};
    return options;
}

}  // namespace facet
