// facet build: a material compiled ahead of time into a self-contained
// object (or assembly, IR, bitcode) and the C header that declares it.
//
//   facet build FILE.mat [--material NAME] [--backend scalar|simd] [--math exact|fast|tolerance=X]
//               [--width 4|8|16] [--set NAME=VALUE]... [--target TRIPLE] [--cpu NAME]
//               [--features +a,-b] [--prefix SYMBOL_PREFIX] [--emit obj|asm|llvm-ir|bitcode]
//               -o OUT [--header OUT.h]
//
// The kernel and its sampler are built by Compiler::compileAot, the JIT's
// pipeline for another target machine (runtime/Aot.h). A material whose NDF
// has no compiled sampler gets an object without sampler symbols, a header
// saying PREFIX_HAS_SAMPLER 0, and a note on stderr. Outputs are written to temporary
// files in their own directory and renamed into place once both are
// complete, so a failed build leaves no partial file. An output goes only
// to a new path or over a regular file, never over the material file or
// the other output (OutputFile.h: outputProblem). Exit codes: 0 ok,
// 2 usage (bad options, an unknown target, CPU or feature, an output that
// cannot be written, as for `facet eval --out`, or may not be), 65 a
// material file error (including a material the file does not have).
#include "Checker.h"
#include "Commands.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"
#include "Specialize.h"

#include <llvm/ADT/StringExtras.h>
#include <llvm/Config/llvm-config.h>
#include <llvm/Support/SHA256.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <fmt/format.h>
#include <string>
#include <unistd.h>
#include <vector>

namespace facet {
namespace {

struct BuildUsageError {
    std::string message;
};

// An output that must not be written (OutputFile.h: outputProblem).
struct BuildOutputError {
    std::string message;
};

struct BuildOptions {
    std::string file, material, backend = "simd", math = "exact", width, prefix, out, header, emit = "obj", assume;
    std::vector<std::string> sets;  // NAME=VALUE
    AotTargetRequest target;
};

bool isCIdentifier(const std::string& s) {
    if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
    for (char c : s)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
    return true;
}

std::string upper(std::string s) {
    for (char& c : s) c = std::isalnum(static_cast<unsigned char>(c)) ? char(std::toupper(static_cast<unsigned char>(c))) : '_';
    return s;
}

// A file written next to its destination and renamed over it only by
// commit(), so that nothing partial is ever seen under the final name.
class PendingFile {
public:
    PendingFile(std::string path) : path_(std::move(path)) {}
    ~PendingFile() {
        if (!tmp_.empty()) ::unlink(tmp_.c_str());
    }
    // Writes the whole content to the temporary file; "" or an error message.
    std::string write(const std::string& content) {
        std::string templ = path_ + ".tmpXXXXXX";
        int fd = ::mkstemp(templ.data());
        if (fd < 0) return fmt::format("{}: error: cannot write: {}", path_, std::strerror(errno));
        tmp_ = templ;
        size_t done = 0;
        while (done < content.size()) {
            ssize_t n = ::write(fd, content.data() + done, content.size() - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                int err = errno;
                ::close(fd);
                return fmt::format("{}: error: cannot write: {}", path_, std::strerror(err));
            }
            done += size_t(n);
        }
        // mkstemp creates 0600; an output is an ordinary build product.
        mode_t mask = ::umask(0);
        ::umask(mask);
        bool modeSet = ::fchmod(fd, 0666 & ~mask) == 0;
        int err = errno;
        if (::close(fd) != 0 || !modeSet)
            return fmt::format("{}: error: cannot write: {}", path_, std::strerror(modeSet ? errno : err));
        return "";
    }
    std::string commit() {
        if (::rename(tmp_.c_str(), path_.c_str()) != 0)
            return fmt::format("{}: error: cannot write: {}", path_, std::strerror(errno));
        tmp_.clear();
        return "";
    }

private:
    std::string path_, tmp_;
};

std::string formatNumber(double v) { return fmt::format("{:.9g}", v); }

// The sampler's part of the header: PREFIX_HAS_SAMPLER, and where it is 1
// the four sampling functions (facet.h's conventions without the kernel).
std::string samplerDeclarations(const std::string& p, const std::string& macro, const AotKernel& aot) {
    const CheckedMaterial& m = aot.material;
    std::string h;
    if (!aot.hasSampler) {
        h += fmt::format("/* No importance sampler: Facet has no compiled sampler for ndf {} under\n", m.ndf.model->name);
        h += fmt::format("   masking {} (`facet ir --plan` shows sampling: specular=none), so this\n",
                         m.masking.model->name);
        h += fmt::format("   object has no {}_sample, {}_sample_batch,\n", p, p);
        h += fmt::format("   {}_pdf or {}_pdf_batch.\n", p, p);
        h += "   libfacet's facet_sample samples such materials through its reference\n";
        h += "   sampler. */\n";
        h += fmt::format("#define {}_HAS_SAMPLER 0\n\n", macro);
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
    h += fmt::format("#define {}_HAS_SAMPLER 1\n", macro);
    h += fmt::format("int {}_sample(const float wo[3], const float u[3], const float* inputs, float wi[3],\n", p);
    h += std::string(p.size() + 12, ' ') + "float* pdf, float weight[3]);\n";
    h += fmt::format("float {}_pdf(const float wi[3], const float wo[3], const float* inputs);\n\n", p);
    h += "/* SoA: wo[0..2], u[0..2], wi[0..2], weight[0..2] each point to n floats, pdf\n";
    h += "   to n floats; inputs as in the eval batch. Return the number of invalid\n";
    h += "   lanes, 0 for n = 0, -1 for n < 0 or a NULL array (or a NULL entry of\n";
    h += "   one). */\n";
    h += fmt::format("int64_t {}_sample_batch(int64_t n, const float* const wo[3], const float* const u[3],\n", p);
    h += indent + "const float* const* inputs, float* const wi[3], float* pdf,\n";
    h += indent + "float* const weight[3]);\n";
    h += fmt::format("int64_t {}_pdf_batch(int64_t n, const float* const wi[3], const float* const wo[3],\n", p);
    h += std::string(p.size() + 19, ' ') + "const float* const* inputs, float* pdf);\n\n";
    return h;
}

std::string headerText(const BuildOptions& opt, const AotKernel& aot, const AotTarget& target,
                       const std::string& optionText, const std::string& materialHash) {
    const std::string& p = opt.prefix;
    const std::string macro = upper(p);
    const CheckedMaterial& m = aot.material;
    std::string h;
    h += fmt::format("/* {}.h: the C interface of material '{}', compiled ahead of time by Facet.\n", p, m.name);
    h += " *\n";
    h += fmt::format(" * Generated by `facet build` (Facet {}, LLVM {}); do not edit.\n", FACET_VERSION,
                     LLVM_VERSION_STRING);
    h += fmt::format(" *   material  {} from {}\n", m.name, opt.file);
    h += fmt::format(" *   hash      sha256 {} (the specialized material as Facet prints it)\n", materialHash);
    h += fmt::format(" *   options   {}\n", optionText);
    h += fmt::format(" *   variant   {}", aot.variant);
    if (aot.measuredError >= 0) h += fmt::format(" (max relative error {:.3g} measured on the build host)", aot.measuredError);
    h += "\n";
    h += fmt::format(" *   target    {}, cpu {}, {}\n", target.triple, target.cpu,
                     aot.width > 1 ? fmt::format("SIMD width {}", aot.width) : std::string("scalar kernel"));
    // Only the enabled features: the host's list also names every disabled one.
    std::string enabled;
    size_t start = 0;
    while (start < target.features.size()) {
        size_t comma = target.features.find(',', start);
        std::string f = target.features.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
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
    h += fmt::format(" * (and, where {}_HAS_SAMPLER is 1, facet_sample / facet_pdf) in\n", macro);
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
    h += fmt::format(" * Input slots ({}_INPUT_COUNT floats; an rgb input takes three, r g b).\n", macro);
    h += " * Values outside a range are clamped to it.\n";
    if (m.slotCount == 0) h += " *   (none: every input is bound)\n";
    else h += " *   slot  name                    default       range\n";
    for (const CheckedInput& in : m.inputs)
        for (int c = 0; c < in.slotCount(); ++c) {
            int slot = in.firstSlot + c;
            h += fmt::format(" *   {:<5} {:<23} {:<13} {}\n", slot, m.slotName(slot), formatNumber(in.defaultValue[c]),
                             in.hasRange ? fmt::format("{} .. {}", formatNumber(in.lo), formatNumber(in.hi)) : "none");
        }
    h += " */\n";
    h += fmt::format("#ifndef FACET_AOT_{}_H\n#define FACET_AOT_{}_H\n\n#include <stdint.h>\n\n", macro, macro);
    h += "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
    h += fmt::format("#define {}_INPUT_COUNT {}\n", macro, m.slotCount);
    for (int s = 0; s < m.slotCount; ++s) h += fmt::format("#define {}_SLOT_{} {}\n", macro, upper(m.slotName(s)), s);
    h += "\n/* One direction pair. inputs: one value per slot, or NULL (all defaults).\n";
    h += "   A NULL wi, wo or rgb does nothing (rgb, if not NULL, is set to 0). */\n";
    h += fmt::format("void {}_eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]);\n\n", p);
    h += "/* SoA batch: wi[0..2], wo[0..2], rgb[0..2] each point to n floats; inputs is\n";
    h += "   NULL (all defaults) or inputs[s] points to n floats (or is NULL: that slot's\n";
    h += "   default). Returns the number of invalid lanes (their rgb is 0), 0 for n = 0,\n";
    h += "   -1 for n < 0 or a NULL wi, wo or rgb (or a NULL entry of one). */\n";
    h += fmt::format("int64_t {}_eval_batch(int64_t n, const float* const wi[3], const float* const wo[3],\n", p);
    h += std::string(p.size() + 20, ' ') + "const float* const* inputs, float* const rgb[3]);\n\n";
    h += samplerDeclarations(p, macro, aot);
    h += "#ifdef __cplusplus\n}\n#endif\n\n";
    h += fmt::format("#endif /* FACET_AOT_{}_H */\n", macro);
    return h;
}

BuildOptions parseBuildArgs(const std::vector<std::string>& args) {
    BuildOptions opt;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) throw BuildUsageError{fmt::format("build: {} needs a value", a)};
            return args[++i];
        };
        if (a == "--material") opt.material = value();
        else if (a == "--backend") opt.backend = value();
        else if (a == "--math") opt.math = value();
        else if (a == "--width") opt.width = value();
        else if (a == "--assume") opt.assume = value();
        else if (a == "--set") opt.sets.push_back(value());
        else if (a == "--target") opt.target.triple = value();
        else if (a == "--cpu") opt.target.cpu = value();
        else if (a == "--features") opt.target.features = value();
        else if (a == "--prefix") opt.prefix = value();
        else if (a == "-o") opt.out = value();
        else if (a == "--header") opt.header = value();
        else if (a == "--emit") opt.emit = value();
        else if (!a.empty() && a[0] == '-') throw BuildUsageError{fmt::format("build: unknown option '{}'", a)};
        else if (opt.file.empty()) opt.file = a;
        else throw BuildUsageError{fmt::format("build: more than one material file ('{}' and '{}')", opt.file, a)};
    }
    if (opt.file.empty()) throw BuildUsageError{"build: no material file given"};
    if (opt.out.empty()) throw BuildUsageError{"build: -o OUT is required"};
    if (opt.backend != "simd" && opt.backend != "scalar")
        throw BuildUsageError{fmt::format("build: backend '{}' is not scalar or simd", opt.backend)};
    if (opt.math != "exact" && opt.math != "fast" && opt.math.rfind("tolerance=", 0) != 0)
        throw BuildUsageError{fmt::format("build: math '{}' is not exact, fast or tolerance=X", opt.math)};
    if (!opt.prefix.empty() && !isCIdentifier(opt.prefix))
        throw BuildUsageError{fmt::format("build: prefix '{}' is not a C identifier", opt.prefix)};
    if (opt.emit != "obj" && opt.emit != "asm" && opt.emit != "llvm-ir" && opt.emit != "bitcode")
        throw BuildUsageError{fmt::format("build: --emit '{}' is not obj, asm, llvm-ir or bitcode", opt.emit)};
    return opt;
}

// Throws BuildOutputError when an output is not a new path or an existing
// regular file, or is the material file or the other output.
void checkOutputPaths(const BuildOptions& opt) {
    std::string problem = outputProblem("facet build", opt.out,
                                        {{opt.file, "the material file"}, {opt.header, "the header"}});
    if (problem.empty() && !opt.header.empty())
        problem = outputProblem("facet build", opt.header, {{opt.file, "the material file"}});
    if (!problem.empty()) throw BuildOutputError{problem};
}

int runBuild(const std::vector<std::string>& args) {
    BuildOptions opt = parseBuildArgs(args);
    checkOutputPaths(opt);
    // The option string of the C/C++ API, so that the kernel is the one
    // facet_compile_file builds with the same options.
    std::string spec = "backend=" + opt.backend;
    if (opt.math.rfind("tolerance=", 0) == 0) spec += ";" + opt.math;
    else spec += ";math=" + opt.math;
    if (!opt.width.empty()) spec += ";width=" + opt.width;
    if (!opt.assume.empty()) spec += ";assume=" + opt.assume;
    for (const std::string& s : opt.sets) {
        if (s.find('=') == std::string::npos || s[0] == '=')
            throw BuildUsageError{fmt::format("--set expects NAME=VALUE, got '{}'", s)};
        spec += ";set." + s;
    }
    CompileOptions options;
    if (std::string problem = CompileOptions::parse(spec, options); !problem.empty())
        throw BuildUsageError{"build: " + problem};

    std::string targetError;
    AotTarget target = createAotTarget(opt.target, targetError);
    if (!target.machine) {
        std::fprintf(stderr, "facet: error: %s\n", targetError.c_str());
        return kExitUsage;
    }

    NamedMaterial named = loadNamedMaterial(opt.file, opt.material);
    if (named.fileErrors) return kExitMaterialError;
    const CheckedMaterial* material = named.material;
    if (!material) {
        std::fprintf(stderr, "facet: error: %s\n", named.missing.c_str());
        return kExitMaterialError;
    }
    for (const auto& [name, values] : options.bindings)
        if (!material->findInput(name))
            throw BuildUsageError{fmt::format("--set: material '{}' has no input '{}'", material->name, name)};
    if (opt.prefix.empty()) {
        opt.prefix = material->name;
        if (!isCIdentifier(opt.prefix))
            throw BuildUsageError{fmt::format("build: material name '{}' is not a C identifier; give --prefix", opt.prefix)};
    }

    AotOutput kind = opt.emit == "asm"       ? AotOutput::Assembly
                     : opt.emit == "llvm-ir" ? AotOutput::LlvmIr
                     : opt.emit == "bitcode" ? AotOutput::Bitcode
                                             : AotOutput::Object;
    Compiler compiler;
    DiagnosticEngine diags;
    std::optional<AotKernel> aot =
        compiler.compileAot(*material, options, *target.machine, target.width, opt.prefix, kind, diags);
    if (!aot) {
        std::fputs(diags.str().c_str(), stderr);
        return kExitMaterialError;
    }
    if (!aot->hasSampler)
        std::fprintf(stderr,
                     "facet: note: material %s has no compiled sampler (ndf %s, masking %s): the object has "
                     "%s_eval and %s_eval_batch only, and the header says %s_HAS_SAMPLER 0\n",
                     aot->material.name.c_str(), aot->material.ndf.model->name, aot->material.masking.model->name,
                     opt.prefix.c_str(), opt.prefix.c_str(), upper(opt.prefix).c_str());
    auto digest = llvm::SHA256::hash(llvm::arrayRefFromStringRef(printMaterial(aot->material)));
    std::string optionText = fmt::format("backend={};{};width={}", opt.backend,
                                         options.tolerance ? opt.math : "math=" + opt.math, aot->width);
    for (const auto& [name, values] : options.bindings) {
        optionText += ";set." + name + "=";
        for (size_t i = 0; i < values.size(); ++i) optionText += (i ? "," : "") + formatNumber(values[i]);
    }

    PendingFile object(opt.out);
    std::optional<PendingFile> header;
    std::string error = object.write(aot->output);
    if (error.empty() && !opt.header.empty()) {
        header.emplace(opt.header);
        error = header->write(headerText(opt, *aot, target, optionText, llvm::toHex(digest, true)));
    }
    // Again just before the renames: the paths may have changed during the compilation.
    if (error.empty()) checkOutputPaths(opt);
    if (error.empty()) error = object.commit();
    if (error.empty() && header) error = header->commit();
    if (!error.empty()) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return kExitUsage;
    }
    return kExitOk;
}

}  // namespace

int cmdBuild(const std::vector<std::string>& args) {
    try {
        return runBuild(args);
    } catch (const BuildUsageError& e) {
        std::fprintf(stderr, "facet: %s\n", e.message.c_str());
        return kExitUsage;
    } catch (const BuildOutputError& e) {
        std::fprintf(stderr, "facet: error: %s\n", e.message.c_str());
        return kExitUsage;
    }
}

}  // namespace facet
