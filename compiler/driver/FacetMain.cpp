// facet: the command-line driver (SPEC section 5).
//
//   facet check FILE...
//   facet eval FILE [--material NAME] [--backend interp] [--set NAME=VALUE]...
//              --in IN.csv [--out OUT.csv]
//
// Exit codes: 0 ok, 1 a check failed (e.g. invalid rows), 2 usage,
// 65 a material file error.
#include "Checker.h"
#include "CsvTable.h"
#include "Interpreter.h"

#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <map>
#include <string>
#include <vector>

namespace facet {
namespace {

constexpr int kExitOk = 0, kExitCheckFailed = 1, kExitUsage = 2, kExitMaterialError = 65;

const char* kUsage =
    "usage: facet <command> [options]\n"
    "  check FILE...                       check material files, print diagnostics\n"
    "  eval FILE --in IN.csv [--out OUT.csv] [--material NAME] [--backend interp]\n"
    "       [--set NAME=VALUE]...          evaluate the BRDF for each CSV row\n"
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
    size_t start = 0;
    for (;;) {
        size_t comma = rest.find(',', start);
        std::string field = rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        std::optional<double> v = parseNumber(field);
        if (!v || !std::isfinite(*v))
            throw UsageError{fmt::format("--set {}: '{}' is not a finite number", name, field)};
        values.push_back(*v);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (values.size() != 1 && values.size() != 3)
        throw UsageError{fmt::format("--set {}: expected one value or three (r,g,b), got {}", name, values.size())};
    out[name] = values;
}

struct EvalOptions {
    std::string file, material, backend = "interp", in, out;
    Bindings bindings;
};

int cmdEval(const std::vector<std::string>& args) {
    EvalOptions opt;
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
        else if (!a.empty() && a[0] == '-') throw UsageError{fmt::format("eval: unknown option '{}'", a)};
        else if (opt.file.empty()) opt.file = a;
        else throw UsageError{fmt::format("eval: more than one material file ('{}' and '{}')", opt.file, a)};
    }
    if (opt.file.empty()) throw UsageError{"eval: no material file given"};
    if (opt.in.empty()) throw UsageError{"eval: --in IN.csv is required"};
    if (opt.backend != "interp")
        throw UsageError{fmt::format("eval: unknown backend '{}' (expected interp)", opt.backend)};

    DiagnosticEngine diags;
    CheckedProgram program = loadProgramFile(opt.file, diags);
    if (diags.hasErrors()) {
        std::fputs(diags.str().c_str(), stderr);
        return kExitMaterialError;
    }
    const CheckedMaterial* material = program.find(opt.material);
    if (!material) throw UsageError{fmt::format("eval: no material named '{}' in {}", opt.material, opt.file)};

    // Slot values: defaults, overridden by --set, overridden per row by columns.
    std::vector<double> slots = material->defaultSlots();
    for (const auto& [name, values] : opt.bindings) {
        const CheckedInput* in = material->findInput(name);
        if (!in) throw UsageError{fmt::format("--set: material '{}' has no input '{}'", material->name, name)};
        if (in->type == ValueType::Float && values.size() != 1)
            throw UsageError{fmt::format("--set {}: input '{}' is float; give one value", name, name)};
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
        inputColumns.push_back({int(c), targets});
    }

    FILE* out = stdout;
    if (!opt.out.empty()) {
        out = std::fopen(opt.out.c_str(), "w");
        if (!out) {
            std::fprintf(stderr, "%s: error: cannot open for writing\n", opt.out.c_str());
            return kExitUsage;
        }
    }
    std::fprintf(out, "r,g,b\n");
    Interpreter<double> interp(*material);
    int bad = 0;
    for (size_t r = 0; r < table->rows.size(); ++r) {
        const CsvRow& row = table->rows[r];
        std::string problem = row.error;
        double rgb[3] = {0, 0, 0};
        if (problem.empty()) {
            double wi[3], wo[3];
            for (int d = 0; d < 3; ++d) {
                wi[d] = row.values[dirIndex[d]];
                wo[d] = row.values[dirIndex[d + 3]];
            }
            std::vector<double> rowSlots = slots;
            for (const auto& [col, targets] : inputColumns)
                for (int s : targets) rowSlots[s] = row.values[col];
            // Say precisely why a lane is invalid before evaluating it.
            for (int d = 0; d < 6 && problem.empty(); ++d)
                if (!std::isfinite(row.values[dirIndex[d]]))
                    problem = fmt::format("column '{}' is {}", dirColumns[d],
                                          std::isnan(row.values[dirIndex[d]]) ? "NaN" : "infinite");
            for (const auto& [col, targets] : inputColumns)
                if (problem.empty() && !std::isfinite(row.values[col]))
                    problem = fmt::format("column '{}' is {}", table->columns[col],
                                          std::isnan(row.values[col]) ? "NaN" : "infinite");
            for (int d = 0; d < 2 && problem.empty(); ++d) {
                const double* w = d ? wo : wi;
                double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
                if (!(std::fabs(len - 1) <= kUnitTolerance))
                    problem = fmt::format("{} is not a unit vector (length {:.9g})", d ? "wo" : "wi", len);
            }
            if (problem.empty()) {
                EvalResult<double> res = interp.eval(wi, wo, rowSlots.data());
                if (!res.valid) problem = "a model parameter is not finite for this row's inputs";
                else for (int c = 0; c < 3; ++c) rgb[c] = res.rgb[c];
            }
        }
        if (!problem.empty()) {
            ++bad;
            std::fprintf(stderr, "%s:%d: error: row %zu: %s; its output is 0,0,0\n", opt.in.c_str(), row.line, r + 1,
                         problem.c_str());
        }
        std::fprintf(out, "%.17g,%.17g,%.17g\n", rgb[0], rgb[1], rgb[2]);
    }
    if (out != stdout) std::fclose(out);
    if (bad) {
        std::fprintf(stderr, "%d of %zu rows invalid\n", bad, table->rows.size());
        return kExitCheckFailed;
    }
    return kExitOk;
}

}  // namespace
}  // namespace facet

int main(int argc, char** argv) {
    using namespace facet;
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
        std::fputs(kUsage, args.empty() ? stderr : stdout);
        return args.empty() ? kExitUsage : kExitOk;
    }
    std::string command = args[0];
    args.erase(args.begin());
    try {
        if (command == "check") return cmdCheck(args);
        if (command == "eval") return cmdEval(args);
        throw UsageError{fmt::format("unknown command '{}'", command)};
    } catch (const UsageError& e) {
        std::fprintf(stderr, "facet: %s\n%s", e.message.c_str(), kUsage);
        return kExitUsage;
    } catch (const InternalError& e) {
        std::fprintf(stderr, "facet: %s\n", e.what());
        return 70;
    }
}
