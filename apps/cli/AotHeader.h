// AotHeader: the plain C99 header of an ahead-of-time object (`facet build
// --header`): what was built and how, the input slots, and the entry
// points with the conventions of facet/facet.h.
#pragma once

#include "Aot.h"
#include "Kernel.h"

#include <string>
#include <string_view>

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

// The header's macro for an input slot: PREFIX_SLOT_ and the slot's name
// with '.' as '_' ("albedo.g" -> PREFIX_SLOT_albedo_g), case kept.
std::string slotMacro(const std::string& prefix, const std::string& slotName);

// Where two slots of `m` would have one macro (an rgb input tint's slot
// tint.r and a float input tint_r), one line naming both inputs and the
// macro; else "". The header cannot be written then.
std::string slotMacroClash(const std::string& prefix, const CheckedMaterial& m);

// `text` as it may appear inside a C comment of the header: "*/" (and
// "/*") never, "??" (trigraphs) never, and no byte that would break the
// line or is not printable ASCII: newline, tab and CR as \n \t \r, other
// control and non-ASCII bytes as \xNN, a backslash as \\. Whatever a
// path, name or option holds, the comment cannot be ended or a line broken.
std::string commentText(std::string_view text);

// A number as the header and the options text print it (%.9g).
std::string formatNumber(double v);

}  // namespace facet
