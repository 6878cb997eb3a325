// AotHeader: the plain C99 header of an ahead-of-time object (`facet build
// --header`): what was built and how, the input slots, and the entry
// points with the conventions of facet/facet.h.
#pragma once

#include "Aot.h"
#include "Kernel.h"

#include <string>

namespace facet {

// What the header records besides the kernel and the target.
struct AotHeaderSource {
    std::string prefix;        // the C symbol prefix of the entry points
    std::string file;          // the material file as given on the command line
    std::string assume;        // --assume ("" or "unit")
    std::string optionText;    // the options as facet_compile_file would take them
    std::string materialHash;  // SHA-256 of the specialized material, hex
};

std::string aotHeaderText(const AotHeaderSource& source, const AotKernel& aot, const AotTarget& target);

// A number as the header and the options text print it (%.9g).
std::string formatNumber(double v);

}  // namespace facet
