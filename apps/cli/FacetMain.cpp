// facet: the command-line driver (SPEC section 5).
//
//   facet check FILE...
//   facet eval FILE [--material NAME] [--backend interp|scalar|simd] [--math exact|fast]
//              [--width 4|8|16] [--set NAME=VALUE]... --in IN.csv [--out OUT.csv]
//   facet ir FILE [--material NAME] [--simd] [--stages | --plan] [--set NAME=VALUE]...
//   facet lut | bench | verify | render | build | sample ...  (in their own files, Commands.h)
//
// Exit codes: 0 ok, 1 a check failed (e.g. invalid rows), 2 usage,
// 65 a material file error.
#include "Checker.h"
#include "Commands.h"
#include "CsvTable.h"
#include "Interpreter.h"
#include "SamplingSetup.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <map>
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

struct UsageError {
    std::string message;
};

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

// Values bound with --set, by input name (float: one value, rgb: three).
using Bindings = std::map<std::string, std::vector<double>>;

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

// --set values against the material's inputs: the same usage errors (exit 2)
// in every command.
void checkBindings(const CheckedMaterial& material, const Bindings& bindings) {
    for (const auto& [name, values] : bindings) {
        const CheckedInput* in = material.findInput(name);
        if (!in) throw UsageError{fmt::format("--set: material '{}' has no input '{}'", material.name, name)};
        if (in->type == ValueType::Float && values.size() != 1)
            throw UsageError{fmt::format("--set {}: input '{}' is float; give one value", name, name)};
    }
}

struct EvalOptions {
    std::string file, material, backend = "interp", in, out, math = "exact", width, assume;
    Bindings bindings;
};

// Builds the compile-option string of the C++/C API from CLI flags.
CompileOptions compileOptionsFor(const EvalOptions& opt) {
    std::string spec = fmt::format("backend={};math={}", opt.backend, opt.math);
    if (!opt.width.empty()) spec += ";width=" + opt.width;
    if (!opt.assume.empty()) spec += ";assume=" + opt.assume;
    CompileOptions options;
    std::string error = CompileOptions::parse(spec, options);
    if (!error.empty()) throw UsageError{error};
    return options;
}

int cmdEval(const std::vector<std::string>& args) {
    EvalOptions opt;
    bool mathGiven = false, widthGiven = false, assumeGiven = false;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) throw UsageError{fmt::format("eval: {} needs a value", a)};
            return args[++i];
        };
        if (a == "--material") opt.material = value();
        else if (a == "--backend") opt.backend = value();
        else if (a == "--in") opt.in = value();
        else if (a == "--out") opt.out = value();
        else if (a == "--set") parseSet(value(), opt.bindings);
        else if (a == "--math") opt.math = value(), mathGiven = true;
        else if (a == "--width") opt.width = value(), widthGiven = true;
        else if (a == "--assume") opt.assume = value(), assumeGiven = true;
        else if (!a.empty() && a[0] == '-') throw UsageError{fmt::format("eval: unknown option '{}'", a)};
        else if (opt.file.empty()) opt.file = a;
        else throw UsageError{fmt::format("eval: more than one material file ('{}' and '{}')", opt.file, a)};
    }
    if (opt.file.empty()) throw UsageError{"eval: no material file given"};
    if (opt.in.empty()) throw UsageError{"eval: --in IN.csv is required"};
    if (opt.backend == "interp" && (mathGiven || widthGiven || assumeGiven))
        throw UsageError{fmt::format("eval: {} applies to the scalar and simd backends; the interp backend "
                                     "computes in double (add --backend scalar or simd)",
                                     mathGiven ? "--math" : widthGiven ? "--width" : "--assume")};
    CompileOptions compileOptions = compileOptionsFor(opt);
    const bool jitBackend = compileOptions.backend != Backend::Interp;

    NamedMaterial named = loadNamedMaterial(opt.file, opt.material);
    if (named.fileErrors) return kExitMaterialError;
    if (!named.material) throw UsageError{"eval: " + named.missing};
    const CheckedMaterial* material = named.material;

    // Slot values: defaults, overridden by --set, overridden per row by columns.
    std::vector<double> slots = material->defaultSlots();
    checkBindings(*material, opt.bindings);
    for (const auto& [name, values] : opt.bindings) {
        const CheckedInput* in = material->findInput(name);
        for (int c = 0; c < in->slotCount(); ++c) slots[in->firstSlot + c] = values[values.size() == 1 ? 0 : c];
    }

    std::string error;
    std::optional<CsvTable> table = readCsv(opt.in, error);
    if (!table) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return kExitUsage;
    }
    // Column layout: the six direction columns, and any input columns.
    static const char* dirColumns[6] = {"wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z"};
    int dirIndex[6];
    for (int d = 0; d < 6; ++d) {
        dirIndex[d] = table->columnIndex(dirColumns[d]);
        if (dirIndex[d] < 0) {
            std::fprintf(stderr, "%s:1: error: missing column '%s' (the header needs wi_x,wi_y,wi_z,wo_x,wo_y,wo_z)\n",
                         opt.in.c_str(), dirColumns[d]);
            return kExitUsage;
        }
    }
    // column index -> list of slots it sets
    std::vector<std::pair<int, std::vector<int>>> inputColumns;
    for (size_t c = 0; c < table->columns.size(); ++c) {
        const std::string& name = table->columns[c];
        bool isDir = false;
        for (int d = 0; d < 6; ++d) isDir |= dirIndex[d] == int(c);
        if (isDir) continue;
        std::string base = name, channel;
        if (size_t dot = name.rfind('.'); dot != std::string::npos) {
            base = name.substr(0, dot);
            channel = name.substr(dot + 1);
        }
        const CheckedInput* in = material->findInput(name);
        std::vector<int> targets;
        if (in) {
            for (int s = 0; s < in->slotCount(); ++s) targets.push_back(in->firstSlot + s);
        } else if ((in = material->findInput(base)) && in->type == ValueType::Rgb &&
                   (channel == "r" || channel == "g" || channel == "b")) {
            targets.push_back(in->firstSlot + (channel == "r" ? 0 : channel == "g" ? 1 : 2));
        } else {
            std::string known;
            for (const CheckedInput& i : material->inputs) known += (known.empty() ? "" : ", ") + i.name;
            std::fprintf(stderr, "%s:1: error: column '%s' is not an input of material '%s' (inputs: %s)\n",
                         opt.in.c_str(), name.c_str(), material->name.c_str(), known.empty() ? "none" : known.c_str());
            return kExitUsage;
        }
        if (opt.bindings.count(in->name)) {
            std::fprintf(stderr, "%s:1: error: column '%s' sets input '%s', which is bound with --set\n",
                         opt.in.c_str(), name.c_str(), in->name.c_str());
            return kExitUsage;
        }
        for (const auto& [other, otherTargets] : inputColumns)
            for (int t : targets)
                if (std::find(otherTargets.begin(), otherTargets.end(), t) != otherTargets.end()) {
                    std::fprintf(stderr, "%s:1: error: columns '%s' and '%s' both set '%s'\n", opt.in.c_str(),
                                 table->columns[other].c_str(), name.c_str(), material->slotName(t).c_str());
                    return kExitUsage;
                }
        inputColumns.push_back({int(c), targets});
    }

    // Output: built in memory and written at the end, every write checked;
    // a file that cannot even be created is a usage error, found first.
    if (!opt.out.empty()) {
        if (std::string why = sameFileProblem("facet eval", opt.out,
                                              {{opt.file, "the material file"}, {opt.in, "the input CSV"}});
            !why.empty()) {
            std::fprintf(stderr, "facet: error: %s\n", why.c_str());
            return kExitUsage;
        }
        FILE* probe = std::fopen(opt.out.c_str(), "w");
        if (!probe) {
            std::fprintf(stderr, "%s: error: cannot open for writing\n", opt.out.c_str());
            return kExitUsage;
        }
        std::fclose(probe);
    }
    std::string outText = "r,g,b\n";
    // First pass: per-row validation with precise messages, and the slot
    // values of every row.
    size_t rows = table->rows.size();
    std::vector<std::string> problems(rows);
    std::vector<std::array<double, 6>> dirs(rows);
    std::vector<std::vector<double>> rowSlots(rows, slots);
    for (size_t r = 0; r < rows; ++r) {
        const CsvRow& row = table->rows[r];
        std::string& problem = problems[r];
        problem = row.error;
        if (!problem.empty()) continue;
        for (int d = 0; d < 6; ++d) dirs[r][d] = row.values[dirIndex[d]];
        for (const auto& [col, targets] : inputColumns)
            for (int s : targets) rowSlots[r][s] = row.values[col];
        for (int d = 0; d < 6 && problem.empty(); ++d)
            if (!std::isfinite(dirs[r][d]))
                problem = fmt::format("column '{}' is {}", dirColumns[d], std::isnan(dirs[r][d]) ? "NaN" : "infinite");
        for (const auto& [col, targets] : inputColumns)
            if (problem.empty() && !std::isfinite(row.values[col]))
                problem = fmt::format("column '{}' is {}", table->columns[col],
                                      std::isnan(row.values[col]) ? "NaN" : "infinite");
        // Inputs are clamped to their declared ranges in double, before the
        // conversion to float (SPEC 4), so 1e39 for an input in 0 .. 1 is 1.
        for (const CheckedInput& in : material->inputs)
            for (int c = 0; c < in.slotCount(); ++c) {
                double& x = rowSlots[r][in.firstSlot + c];
                if (in.hasRange) x = std::min(std::max(x, in.lo), in.hi);
                // A kernel takes float inputs; the interpreter, doubles.
                if (problem.empty() && jitBackend && std::isfinite(x) && std::fabs(x) > double(FLT_MAX))
                    problem = fmt::format("input '{}' = {:.9g} is beyond float range", material->slotName(in.firstSlot + c), x);
            }
        for (int d = 0; d < 2 && problem.empty(); ++d) {
            const double* w = &dirs[r][3 * d];
            double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            if (!(std::fabs(len - 1) <= kUnitTolerance))
                problem = fmt::format("{} is not a unit vector (length {:.9g})", d ? "wo" : "wi", len);
        }
    }
    std::vector<std::array<double, 3>> results(rows, {0, 0, 0});
    if (compileOptions.backend == Backend::Interp) {
        std::unique_ptr<Interpreter<double>> interp = referenceInterpreter(*material);
        for (size_t r = 0; r < rows; ++r) {
            if (!problems[r].empty()) continue;
            EvalResult<double> res = interp->eval(&dirs[r][0], &dirs[r][3], rowSlots[r].data());
            if (!res.valid) problems[r] = "a model parameter is not finite for this row's inputs";
            else results[r] = {res.rgb[0], res.rgb[1], res.rgb[2]};
        }
    } else {
        // JIT backends: the input slots are all unbound (bindings are
        // applied per row here, so that one kernel serves every row).
        Compiler compiler;
        DiagnosticEngine kdiags;
        std::unique_ptr<Kernel> kernel = compiler.compileFile(opt.file, material->name, compileOptions, kdiags);
        if (!kernel) {
            std::fputs(kdiags.str().c_str(), stderr);
            return kExitMaterialError;
        }
        std::vector<size_t> live;
        for (size_t r = 0; r < rows; ++r)
            if (problems[r].empty()) live.push_back(r);
        int slotCount = kernel->inputCount();
        std::vector<float> soa((6 + slotCount + 3) * live.size());
        auto column = [&](int c) { return soa.data() + c * live.size(); };
        for (size_t j = 0; j < live.size(); ++j) {
            for (int d = 0; d < 6; ++d) column(d)[j] = float(dirs[live[j]][d]);
            for (int s = 0; s < slotCount; ++s) column(6 + s)[j] = float(rowSlots[live[j]][s]);
        }
        const float* wi[3] = {column(0), column(1), column(2)};
        const float* wo[3] = {column(3), column(4), column(5)};
        std::vector<const float*> inputs;
        for (int s = 0; s < slotCount; ++s) inputs.push_back(column(6 + s));
        float* rgb[3] = {column(6 + slotCount), column(7 + slotCount), column(8 + slotCount)};
        // Which rows are invalid comes from the kernel itself, lane by lane.
        std::vector<uint8_t> status(live.size(), 0);
        kernel->evalBatch(int64_t(live.size()), wi, wo, slotCount ? inputs.data() : nullptr, rgb, status.data());
        for (size_t j = 0; j < live.size(); ++j) {
            size_t r = live[j];
            for (int c = 0; c < 3; ++c) results[r][c] = rgb[c][j];
            if (status[j])
                problems[r] = fmt::format("the {} kernel rejected it: a model parameter is not finite in float, or "
                                          "the result is beyond float range",
                                          backendName(compileOptions.backend));
        }
    }
    bool doublePrecision = compileOptions.backend == Backend::Interp;
    int bad = 0;
    for (size_t r = 0; r < rows; ++r) {
        if (!problems[r].empty()) {
            ++bad;
            results[r] = {0, 0, 0};
            std::fprintf(stderr, "%s:%d: error: row %zu: %s; its output is 0,0,0\n", opt.in.c_str(),
                         table->rows[r].line, r + 1, problems[r].c_str());
        }
        if (doublePrecision)
            outText += fmt::format("{:.17g},{:.17g},{:.17g}\n", results[r][0], results[r][1], results[r][2]);
        else
            outText += fmt::format("{:.9g},{:.9g},{:.9g}\n", float(results[r][0]), float(results[r][1]),
                                   float(results[r][2]));
    }
    if (!writeOutput(opt.out, outText)) return kExitFailed;
    if (bad) {
        std::fprintf(stderr, "%d of %zu rows invalid\n", bad, rows);
        return kExitFailed;
    }
    return kExitOk;
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
    try {
        int status = 0;
        if (command == "check") status = cmdCheck(args);
        else if (command == "eval") status = cmdEval(args);
        else if (command == "ir") status = cmdIr(args);
        else if (command == "verify") status = cmdVerify(args);
        else if (command == "lut") status = cmdLut(args);
        else if (command == "bench") status = cmdBench(args);
        else if (command == "render") status = cmdRender(args);
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
