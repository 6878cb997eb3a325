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
#include "AotHeader.h"
#include "Checker.h"
#include "Commands.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"
#include "Specialize.h"

#include <llvm/ADT/StringExtras.h>
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

// An output that must not be written (OutputFile.h: outputProblem), or a
// header whose macros would clash (AotHeader.h: slotMacroClash).
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

// A file written next to its destination and renamed over it only by
// commit(), so that nothing partial is ever seen under the final name.
class PendingFile {
public:
    PendingFile(std::string path) : path_(std::move(path)) {}
    ~PendingFile() {
        if (!tmp_.empty()) ::unlink(tmp_.c_str());
    }
    // Writes the whole content to the temporary file; "" or an error message
    // ("cannot write PATH: REASON", as writeOutput's).
    std::string write(const std::string& content) {
        std::string templ = path_ + ".tmpXXXXXX";
        int fd = ::mkstemp(templ.data());
        if (fd < 0) return fmt::format("cannot write {}: {}", path_, std::strerror(errno));
        tmp_ = templ;
        size_t done = 0;
        while (done < content.size()) {
            ssize_t n = ::write(fd, content.data() + done, content.size() - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                int err = errno;
                ::close(fd);
                return fmt::format("cannot write {}: {}", path_, std::strerror(err));
            }
            done += size_t(n);
        }
        // mkstemp creates 0600; an output is an ordinary build product.
        mode_t mask = ::umask(0);
        ::umask(mask);
        bool modeSet = ::fchmod(fd, 0666 & ~mask) == 0;
        int err = errno;
        if (::close(fd) != 0 || !modeSet)
            return fmt::format("cannot write {}: {}", path_, std::strerror(modeSet ? errno : err));
        return "";
    }
    std::string commit() {
        if (::rename(tmp_.c_str(), path_.c_str()) != 0)
            return fmt::format("cannot write {}: {}", path_, std::strerror(errno));
        tmp_.clear();
        return "";
    }

private:
    std::string path_, tmp_;
};


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
    if (std::string why = compiledBackendsRefuse(*material); !why.empty()) {
        DiagnosticEngine refused;
        refused.error(material->loc, why);
        std::fputs(refused.str().c_str(), stderr);
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
    if (!opt.header.empty())
        if (std::string clash = slotMacroClash(opt.prefix, aot->material); !clash.empty())
            throw BuildOutputError{clash};
    if (!aot->hasSampler)
        std::fprintf(stderr,
                     "facet: note: material %s has no compiled sampler (%s): the object has "
                     "%s_eval and %s_eval_batch only, and the header says %s_HAS_SAMPLER 0\n",
                     aot->material.name.c_str(), samplerlessWhat(aot->material).c_str(),
                     opt.prefix.c_str(), opt.prefix.c_str(), opt.prefix.c_str());
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
        error = header->write(
            aotHeaderText({opt.prefix, opt.file, opt.assume, optionText, llvm::toHex(digest, true)}, *aot, target));
    }
    // Again just before the renames: the paths may have changed during the compilation.
    if (error.empty()) checkOutputPaths(opt);
    if (error.empty()) error = object.commit();
    if (error.empty() && header) error = header->commit();
    if (!error.empty()) {
        std::fprintf(stderr, "facet: error: %s\n", error.c_str());
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
