// facet: the command-line driver (SPEC section 5).
//
//   facet check FILE...
//   facet ir FILE [--material NAME] [--simd] [--stages | --plan] [--set NAME=VALUE]...
//   facet eval | lut | bench | verify | render | build | sample ...  (in their own files, Commands.h)
//
// main() dispatches to the command and turns what it throws into an exit
// code: a UsageError prints the usage text. Built twice: `facet` hands
// `render` and `bench` to `facet-imaging`, built with FACET_WITH_IMAGING and
// OpenImageIO (ImagingHelper.h).
//
// Exit codes: 0 ok, 1 a check failed (e.g. invalid rows), 2 usage,
// 65 a material file error.
#include "Checker.h"
#include "Commands.h"
#include "CompileFlags.h"
#include "ImagingHelper.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"

#include <cstdio>
#include <fmt/format.h>
#include <string>
#include <vector>

namespace facet {
namespace {

const char* kUsage =
    "usage: facet <command> [options]\n"
    "  check FILE...                       check material files, print diagnostics\n"
    "  eval FILE --in IN.csv [--out OUT.csv] [--material NAME] [--backend interp|scalar|simd]\n"
    "       [--math exact|fast] [--width 4|8|16] [--assume unit] [--set NAME=VALUE]...\n"
    "                                      evaluate the BRDF for each CSV row\n"
    "  ir FILE [--material NAME] [--simd] [--stages|--plan] [--math exact|fast] [--width N] [--assume unit]\n"
    "       [--set NAME=VALUE]...\n"
    "                                      print the optimized LLVM IR (--stages: every stage;\n"
    "                                      --plan: only the lowering plan)\n"
    "  lut FILE [--material NAME] -o TABLES.exr   write the Kulla-Conty E/E_avg tables (EXR)\n"
    "  bench FILE... [--out DIR] [--json] [--quick]   speed against error (bench.md/.json/.png)\n"
    "  verify FILE... [--material NAME] [--verbose]   hard cases, backends and physics (SPEC 7)\n"
    "  render FILE -o OUT.png|.exr [--plot lobe|ndf|pdf] [--size N] [--light T,P] ...\n"
    "                                      lit-sphere preview, lobe, NDF or sample-histogram plot\n"
    "                                      ('facet render' for all options)\n"
    "  build FILE -o OUT.o [--header OUT.h] [--material NAME] [--backend scalar|simd]\n"
    "       [--math exact|fast|tolerance=X] [--width N] [--assume unit] [--set NAME=VALUE]... [--target TRIPLE]\n"
    "       [--cpu CPU] [--features +a,-b] [--prefix SYMBOL] [--emit obj|asm|llvm-ir|bitcode]\n"
    "                                      a self-contained object + C header, for the host or another target\n"
    "  sample FILE --wo X,Y,Z [-n N] [--out OUT.csv] [--seed S] [--material NAME]\n"
    "       [--backend interp|scalar|simd] [--math exact|fast]\n"
    "                                      importance-sample wi (the kernel's sampler; interp: the\n"
    "                                      reference sampler): wi, pdf, weight per row\n"
    "exit codes: 0 ok, 1 a check failed, 2 usage, 65 a material file error\n";

int cmdCheck(const std::vector<std::string>& args) {
    if (args.empty()) throw UsageError{"check: no files given"};
    bool failed = false;
    for (const std::string& path : args) {
        if (!path.empty() && path[0] == '-') throw UsageError{fmt::format("check: unknown option '{}'", path)};
        DiagnosticEngine diags;
        loadProgramFile(path, diags);
        if (diags.hasErrors()) {
            std::fputs(diags.str().c_str(), stderr);
            failed = true;
        }
    }
    return failed ? kExitMaterialError : kExitOk;
}

int cmdIr(const std::vector<std::string>& args) {
    EvalOptions opt;
    bool simd = false;
    Compiler::IrOutput output = Compiler::IrOutput::Optimized;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) throw UsageError{fmt::format("ir: {} needs a value", a)};
            return args[++i];
        };
        if (a == "--material") opt.material = value();
        else if (a == "--simd") simd = true;
        else if (a == "--stages" || a == "--plan") {
            Compiler::IrOutput wanted = a == "--plan" ? Compiler::IrOutput::Plan : Compiler::IrOutput::Stages;
            if (output != Compiler::IrOutput::Optimized && output != wanted)
                throw UsageError{"ir: --stages and --plan exclude each other"};
            output = wanted;
        }
        else if (a == "--set") parseSet(value(), opt.bindings);
        else if (a == "--math") opt.math = value();
        else if (a == "--width") opt.width = value();
        else if (a == "--assume") opt.assume = value();
        else if (!a.empty() && a[0] == '-') throw UsageError{fmt::format("ir: unknown option '{}'", a)};
        else if (opt.file.empty()) opt.file = a;
        else throw UsageError{"ir: more than one material file"};
    }
    if (opt.file.empty()) throw UsageError{"ir: no material file given"};
    opt.backend = simd ? "simd" : "scalar";
    CompileOptions options = compileOptionsFor(opt);
    options.bindings = opt.bindings;
    NamedMaterial named = loadNamedMaterial(opt.file, opt.material);
    if (named.fileErrors) return kExitMaterialError;
    if (!named.material) throw UsageError{"ir: " + named.missing};
    checkBindings(*named.material, opt.bindings);
    DiagnosticEngine diags;
    Compiler compiler;
    std::string ir = compiler.irText(opt.file, opt.material, options, simd, output, diags);
    if (diags.hasErrors()) {
        std::fputs(diags.str().c_str(), stderr);
        return kExitMaterialError;
    }
    return writeOutput("", ir) ? kExitOk : kExitFailed;
}

}  // namespace
}  // namespace facet

int main(int argc, char** argv) {
    using namespace facet;
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
        if (args.empty()) {
            std::fputs(kUsage, stderr);
            return kExitUsage;
        }
        return writeOutput("", kUsage) ? kExitOk : kExitFailed;
    }
    std::string command = args[0];
    args.erase(args.begin());
#ifndef FACET_WITH_IMAGING
    // The picture commands live in facet-imaging (ImagingHelper.h).
    if (command == "render" || command == "bench") return runImagingHelper(argv);
#endif
    try {
        int status = 0;
        if (command == "check") status = cmdCheck(args);
        else if (command == "eval") status = cmdEval(args);
        else if (command == "ir") status = cmdIr(args);
        else if (command == "verify") status = cmdVerify(args);
        else if (command == "lut") status = cmdLut(args);
#ifdef FACET_WITH_IMAGING
        else if (command == "bench") status = cmdBench(args);
        else if (command == "render") status = cmdRender(args);
#endif
        else if (command == "build") status = cmdBuild(args);
        else if (command == "sample") status = cmdSample(args);
        else throw UsageError{fmt::format("unknown command '{}'", command)};
        // Whatever a command printed must have reached its destination.
        if (status == kExitOk && !finishStandardOutput()) status = kExitFailed;
        return status;
    } catch (const UsageError& e) {
        std::fprintf(stderr, "facet: %s\n%s", e.message.c_str(), kUsage);
        return kExitUsage;
    } catch (const std::runtime_error& e) {
        std::fprintf(stderr, "facet: error: %s\n", e.what());
        return kExitFailed;
    } catch (const InternalError& e) {
        std::fprintf(stderr, "facet: %s\n", e.what());
        return 70;
    }
}
