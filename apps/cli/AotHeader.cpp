// AotHeader: the C header that `facet build` writes beside an object (AotHeader.h).
#include "AotHeader.h"

#include <llvm/Config/llvm-config.h>

#include <cctype>
#include <fmt/format.h>
#include <map>

namespace facet {

std::string commentText(std::string_view text) {
    std::string out;
    for (size_t i = 0; i < text.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        const char next = i + 1 < text.size() ? text[i + 1] : '\0';
        if (c == '\n') out += "\\n";
        else if (c == '\r') out += "\\r";
        else if (c == '\t') out += "\\t";
        else if (c == '\\') out += "\\\\";
        else if (c < 0x20 || c >= 0x7f) out += fmt::format("\\x{:02x}", c);
        // "*/" would end the comment, "/*" inside one is a -Wcomment warning.
        else if ((c == '*' && next == '/') || (c == '/' && next == '*')) out += std::string(1, char(c)) + ' ';
        // "??/" is a trigraph for a backslash under -std=c99: no "??" at all.
        else if (c == '?' && !out.empty() && out.back() == '?') out += "\\x3f";
        else out += char(c);
    }
    return out;
}

namespace {

// The sampler's part of the header: PREFIX_HAS_SAMPLER, and where it is 1
// the four sampling functions (facet.h's conventions without the kernel).
std::string samplerDeclarations(const std::string& p, const AotKernel& aot) {
    const CheckedMaterial& m = aot.material;
    std::string h;
    if (!aot.hasSampler) {
        h += fmt::format("/* No importance sampler: Facet has no compiled sampler for\n   {}\n",
                         commentText(samplerlessWhat(m)));
        h += "   (`facet ir --plan` shows the sampling line), so this\n";
        h += fmt::format("   object has no {}_sample, {}_sample_batch,\n", p, p);
        h += fmt::format("   {}_pdf or {}_pdf_batch.\n", p, p);
        h += "   libfacet's facet_sample samples such materials through its reference\n";
        h += "   sampler. */\n";
        h += fmt::format("#define {}_HAS_SAMPLER 0\n\n", p);
        return h;
    }
    const std::string indent(p.size() + 22, ' ');
    h += "/* Importance sampling, as facet_sample / facet_pdf and their batch calls in\n";
    h += "   facet/facet.h. u: three uniform numbers in [0, 1) (u[0] picks the lobe,\n";
    h += "   u[1] and u[2] place the direction). Outputs: wi, the whole mixture's pdf of\n";
    h += "   wi per solid angle, weight = f (n.wi) / pdf per channel. n.wo <= 0: no\n";
    h += "   sample (all 0, a valid lane); a sample below the horizon is valid with\n";
    h += "   weight 0. An invalid lane (a non-finite or non-unit wo, u outside [0, 1),\n";
    h += "   a non-finite input, a result float cannot hold) gives wi = 0, pdf = 0,\n";
    h += fmt::format("   weight = 0. {}_sample returns 1 for an invalid lane (a NULL wo or u is\n", p);
    h += fmt::format("   one), else 0, and does not write a NULL output. {}_pdf returns 0 for an\n", p);
    h += "   invalid lane or a NULL wi or wo. */\n";
    h += fmt::format("#define {}_HAS_SAMPLER 1\n", p);
    h += fmt::format("int {}_sample(const float wo[3], const float u[3], const float* inputs, float wi[3],\n", p);
    h += std::string(p.size() + 12, ' ') + "float* pdf, float weight[3]);\n";
    h += fmt::format("float {}_pdf(const float wi[3], const float wo[3], const float* inputs);\n\n", p);
    h += "/* SoA: wo[0..2], u[0..2], wi[0..2], weight[0..2] each point to n floats, pdf\n";
    h += "   to n floats; inputs as in the eval batch. Return the number of invalid\n";
    h += "   lanes, 0 for n = 0 (whatever the pointers), -1 for n < 0 or a NULL\n";
    h += "   array (or a NULL entry of one). */\n";
    h += fmt::format("int64_t {}_sample_batch(int64_t n, const float* const wo[3], const float* const u[3],\n", p);
    h += indent + "const float* const* inputs, float* const wi[3], float* pdf,\n";
    h += indent + "float* const weight[3]);\n";
    h += fmt::format("int64_t {}_pdf_batch(int64_t n, const float* const wi[3], const float* const wo[3],\n", p);
    h += std::string(p.size() + 19, ' ') + "const float* const* inputs, float* pdf);\n\n";
    return h;
}

}  // namespace

std::string formatNumber(double v) { return fmt::format("{:.9g}", v); }

std::string slotMacro(const std::string& prefix, const std::string& slotName) {
    std::string macro = prefix + "_SLOT_";
    for (char c : slotName) macro += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
    return macro;
}

std::string slotMacroClash(const std::string& prefix, const CheckedMaterial& m) {
    std::map<std::string, std::pair<const CheckedInput*, int>> seen;  // macro -> input and slot
    for (const CheckedInput& in : m.inputs)
        for (int c = 0; c < in.slotCount(); ++c) {
            const int slot = in.firstSlot + c;
            auto [it, fresh] = seen.try_emplace(slotMacro(prefix, m.slotName(slot)), &in, slot);
            if (fresh) continue;
            const auto& [other, otherSlot] = it->second;
            return fmt::format("inputs '{}' (slot {}) and '{}' (slot {}) would both be the header's macro {}; rename "
                               "one, or bind one with --set",
                               other->name, m.slotName(otherSlot), in.name, m.slotName(slot), it->first);
        }
    return "";
}

std::string aotHeaderText(const AotHeaderSource& opt, const AotKernel& aot, const AotTarget& target) {
    // The prefix as given, in every macro and the include guard: prefixes
    // (and input names) that differ only in case give distinct macros.
    const std::string& p = opt.prefix;
    const CheckedMaterial& m = aot.material;
    std::string h;
    // Every text in the comment below that a user chose (file, material and
    // input names, options, target) goes through commentText.
    h += fmt::format("/* {}.h: the C interface of material '{}', compiled ahead of time by Facet.\n", p,
                     commentText(m.name));
    h += " *\n";
    h += fmt::format(" * Generated by `facet build` (Facet {}, LLVM {}); do not edit.\n", FACET_VERSION,
                     LLVM_VERSION_STRING);
    h += fmt::format(" *   material  {} from {}\n", commentText(m.name), commentText(opt.file));
    h += fmt::format(" *   hash      sha256 {} (the specialized material as Facet prints it)\n", opt.materialHash);
    h += fmt::format(" *   options   {}\n", commentText(opt.optionText));
    h += fmt::format(" *   variant   {}", aot.variant);
    if (aot.measuredError >= 0) h += fmt::format(" (max relative error {:.3g} measured on the build host)", aot.measuredError);
    h += "\n";
    h += fmt::format(" *   target    {}, cpu {}, {}\n", commentText(target.triple), commentText(target.cpu),
                     aot.width > 1 ? fmt::format("SIMD width {}", aot.width) : std::string("scalar kernel"));
    // Only the enabled features: the host's list also names every disabled one.
    std::string enabled;
    size_t start = 0;
    while (start < target.features.size()) {
        size_t comma = target.features.find(',', start);
        std::string f =
            commentText(target.features.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
        start = comma == std::string::npos ? target.features.size() : comma + 1;
        if (f.empty() || f[0] != '+') continue;
        size_t lineStart = enabled.rfind('\n');
        size_t lineLength = enabled.size() - (lineStart == std::string::npos ? 0 : lineStart + 1);
        if (!enabled.empty()) enabled += lineLength + f.size() > 80 ? ",\n *             " : ",";
        enabled += f;
    }
    h += fmt::format(" *   features  {}\n", enabled.empty() ? "(the CPU's own)" : enabled);
    h += " *\n";
    h += " * Self-contained: link the object built with this header and nothing else\n";
    h += " * (no libfacet, no LLVM, no table files; at most libm). The functions are\n";
    h += " * thread-safe and have the conventions of facet_eval / facet_eval_batch\n";
    h += fmt::format(" * (and, where {}_HAS_SAMPLER is 1, facet_sample / facet_pdf) in\n", p);
    h += " * facet/facet.h: the BRDF f_r in 1/sr, rgb, without the cosine factor;\n";
    h += " * n = +z, wi (towards the light) and wo (towards the viewer) unit vectors\n";
    h += " * pointing away from the surface. A non-finite input or a direction whose\n";
    h += " * length is not 1 within 1e-3 gives 0 and counts as an invalid lane.\n";
    if (opt.assume == "unit") {
        h += " * Built with --assume unit: the caller promises finite unit directions\n";
        h += " * (within 1e-3) and finite inputs; on those the outputs are the\n";
        h += " * default build's, and the batch functions return 0.\n";
        h += " * Other inputs give undefined values (never a crash).\n";
    }
    h += " *\n";
    h += fmt::format(" * Input slots ({}_INPUT_COUNT floats; an rgb input takes three, r g b).\n", p);
    h += " * Values outside a range are clamped to it.\n";
    if (m.slotCount == 0) h += " *   (none: every input is bound)\n";
    else h += " *   slot  name                    default       range\n";
    for (const CheckedInput& in : m.inputs)
        for (int c = 0; c < in.slotCount(); ++c) {
            int slot = in.firstSlot + c;
            h += fmt::format(" *   {:<5} {:<23} {:<13} {}\n", slot, commentText(m.slotName(slot)),
                             formatNumber(in.defaultValue[c]),
                             in.hasRange ? fmt::format("{} .. {}", formatNumber(in.lo), formatNumber(in.hi)) : "none");
        }
    h += " */\n";
    h += fmt::format("#ifndef FACET_AOT_{}_H\n#define FACET_AOT_{}_H\n\n#include <stdint.h>\n\n", p, p);
    h += "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
    h += fmt::format("#define {}_INPUT_COUNT {}\n", p, m.slotCount);
    for (int s = 0; s < m.slotCount; ++s) h += fmt::format("#define {} {}\n", slotMacro(p, m.slotName(s)), s);
    h += "\n/* One direction pair. inputs: one value per slot, or NULL (all defaults).\n";
    h += "   A NULL wi, wo or rgb does nothing (rgb, if not NULL, is set to 0). */\n";
    h += fmt::format("void {}_eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]);\n\n", p);
    h += "/* SoA batch: wi[0..2], wo[0..2], rgb[0..2] each point to n floats; inputs is\n";
    h += "   NULL (all defaults) or inputs[s] points to n floats (or is NULL: that slot's\n";
    h += "   default). Returns the number of invalid lanes (their rgb is 0), 0 for n = 0\n";
    h += "   (whatever the pointers), -1 for n < 0 or a NULL wi, wo or rgb (or a NULL\n";
    h += "   entry of one). */\n";
    h += fmt::format("int64_t {}_eval_batch(int64_t n, const float* const wi[3], const float* const wo[3],\n", p);
    h += std::string(p.size() + 20, ' ') + "const float* const* inputs, float* const rgb[3]);\n\n";
    h += samplerDeclarations(p, aot);
    h += "#ifdef __cplusplus\n}\n#endif\n\n";
    h += fmt::format("#endif /* FACET_AOT_{}_H */\n", p);
    return h;
}

}  // namespace facet
