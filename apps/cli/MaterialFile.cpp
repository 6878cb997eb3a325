// MaterialFile: see MaterialFile.h.
#include "MaterialFile.h"

#include "Checker.h"
#include "Diagnostics.h"

#include <cstdio>
#include <fmt/format.h>

namespace facet {

NamedMaterial loadNamedMaterial(const std::string& file, const std::string& name) {
    NamedMaterial out;
    DiagnosticEngine diags;
    out.program = loadProgramFile(file, diags);
    if (diags.hasErrors()) {
        std::fputs(diags.str().c_str(), stderr);
        out.fileErrors = true;
        return out;
    }
    out.material = out.program.find(name);
    if (!out.material) {
        std::string names;
        for (const CheckedMaterial& m : out.program.materials) names += (names.empty() ? "" : ", ") + m.name;
        out.missing = fmt::format("no material named '{}' in {} ({})", name, file,
                                  names.empty() ? "it has none" : "materials: " + names);
    }
    return out;
}

}  // namespace facet
