// facet eval FILE --in IN.csv [--out OUT.csv] [--material NAME] [--backend interp|scalar|simd]
//            [--math exact|fast] [--width 4|8|16] [--assume unit] [--set NAME=VALUE]...
//
// Evaluates the BRDF for each row of a CSV table and writes r,g,b per row.
// The header names the six direction columns wi_x .. wo_z and, optionally,
// input columns (an input's name, or NAME.r/.g/.b for one channel of an
// rgb input); inputs without a column take --set or their default. interp
// (the default) evaluates in double and prints %.17g; scalar and simd
// compile one kernel, with every input left unbound so that it serves every
// row, and print floats (%.9g). A row that is not valid (unparsable, a
// non-finite value, a direction that is not unit, an input beyond float for
// a kernel, or one the kernel rejects) is reported on stderr with its line
// and written as 0,0,0; then the exit code is 1.
#include "Commands.h"

#include "Checker.h"
#include "CompileFlags.h"
#include "CsvTable.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"
#include "SamplingSetup.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <optional>

namespace facet {

namespace {

const char* const kDirColumns[6] = {"wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z"};

EvalOptions parseEvalArgs(const std::vector<std::string>& args) {
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
    return opt;
}

// Where a table's columns go: the six direction columns, and for every
// other column the slots it sets.
struct ColumnLayout {
    int dir[6];
    std::vector<std::pair<int, std::vector<int>>> inputs;  // column index -> the slots it sets
};

// The layout of `table`'s header for `material`; nullopt, after saying why
// on stderr, for a header eval cannot use (a usage error).
std::optional<ColumnLayout> columnLayout(const CsvTable& table, const CheckedMaterial& material,
                                         const EvalOptions& opt) {
    ColumnLayout layout;
    for (int d = 0; d < 6; ++d) {
        layout.dir[d] = table.columnIndex(kDirColumns[d]);
        if (layout.dir[d] < 0) {
            std::fprintf(stderr, "%s:1: error: missing column '%s' (the header needs wi_x,wi_y,wi_z,wo_x,wo_y,wo_z)\n",
                         opt.in.c_str(), kDirColumns[d]);
            return std::nullopt;
        }
    }
    for (size_t c = 0; c < table.columns.size(); ++c) {
        const std::string& name = table.columns[c];
        bool isDir = false;
        for (int d = 0; d < 6; ++d) isDir |= layout.dir[d] == int(c);
        if (isDir) continue;
        std::string base = name, channel;
        if (size_t dot = name.rfind('.'); dot != std::string::npos) {
            base = name.substr(0, dot);
            channel = name.substr(dot + 1);
        }
        const CheckedInput* in = material.findInput(name);
        std::vector<int> targets;
        if (in) {
            for (int s = 0; s < in->slotCount(); ++s) targets.push_back(in->firstSlot + s);
        } else if ((in = material.findInput(base)) && in->type == ValueType::Rgb &&
                   (channel == "r" || channel == "g" || channel == "b")) {
            targets.push_back(in->firstSlot + (channel == "r" ? 0 : channel == "g" ? 1 : 2));
        } else {
            std::string known;
            for (const CheckedInput& i : material.inputs) known += (known.empty() ? "" : ", ") + i.name;
            std::fprintf(stderr, "%s:1: error: column '%s' is not an input of material '%s' (inputs: %s)\n",
                         opt.in.c_str(), name.c_str(), material.name.c_str(), known.empty() ? "none" : known.c_str());
            return std::nullopt;
        }
        if (opt.bindings.count(in->name)) {
            std::fprintf(stderr, "%s:1: error: column '%s' sets input '%s', which is bound with --set\n",
                         opt.in.c_str(), name.c_str(), in->name.c_str());
            return std::nullopt;
        }
        for (const auto& [other, otherTargets] : layout.inputs)
            for (int t : targets)
                if (std::find(otherTargets.begin(), otherTargets.end(), t) != otherTargets.end()) {
                    std::fprintf(stderr, "%s:1: error: columns '%s' and '%s' both set '%s'\n", opt.in.c_str(),
                                 table.columns[other].c_str(), name.c_str(), material.slotName(t).c_str());
                    return std::nullopt;
                }
        layout.inputs.push_back({int(c), targets});
    }
    return layout;
}

// The output file, checked before any work: a file that cannot even be
// created is a usage error, found first. False after saying why.
bool outputWritable(const EvalOptions& opt) {
    if (opt.out.empty()) return true;
    if (std::string why = sameFileProblem("facet eval", opt.out,
                                          {{opt.file, "the material file"}, {opt.in, "the input CSV"}});
        !why.empty()) {
        std::fprintf(stderr, "facet: error: %s\n", why.c_str());
        return false;
    }
    FILE* probe = std::fopen(opt.out.c_str(), "w");
    if (!probe) {
        std::fprintf(stderr, "%s: error: cannot open for writing\n", opt.out.c_str());
        return false;
    }
    std::fclose(probe);
    return true;
}

// The rows as evaluated: each row's directions and slot values, and what is
// wrong with it ("" for a row to evaluate).
struct EvalRows {
    std::vector<std::string> problems;
    std::vector<std::array<double, 6>> dirs;
    std::vector<std::vector<double>> slots;
};

// Per-row validation with precise messages, and the slot values of every
// row: `slots` (defaults and --set) overridden by the row's columns.
EvalRows readRows(const CsvTable& table, const ColumnLayout& layout, const CheckedMaterial& material,
                  const std::vector<double>& slots, bool jitBackend) {
    size_t rows = table.rows.size();
    EvalRows out{std::vector<std::string>(rows), std::vector<std::array<double, 6>>(rows),
                 std::vector<std::vector<double>>(rows, slots)};
    for (size_t r = 0; r < rows; ++r) {
        const CsvRow& row = table.rows[r];
        std::string& problem = out.problems[r];
        std::array<double, 6>& dirs = out.dirs[r];
        problem = row.error;
        if (!problem.empty()) continue;
        for (int d = 0; d < 6; ++d) dirs[d] = row.values[layout.dir[d]];
        for (const auto& [col, targets] : layout.inputs)
            for (int s : targets) out.slots[r][s] = row.values[col];
        for (int d = 0; d < 6 && problem.empty(); ++d)
            if (!std::isfinite(dirs[d]))
                problem = fmt::format("column '{}' is {}", kDirColumns[d], std::isnan(dirs[d]) ? "NaN" : "infinite");
        for (const auto& [col, targets] : layout.inputs)
            if (problem.empty() && !std::isfinite(row.values[col]))
                problem = fmt::format("column '{}' is {}", table.columns[col],
                                      std::isnan(row.values[col]) ? "NaN" : "infinite");
        // Inputs are clamped to their declared ranges in double, before the
        // conversion to float (SPEC 4), so 1e39 for an input in 0 .. 1 is 1.
        for (const CheckedInput& in : material.inputs)
            for (int c = 0; c < in.slotCount(); ++c) {
                double& x = out.slots[r][in.firstSlot + c];
                if (in.hasRange) x = std::min(std::max(x, in.lo), in.hi);
                // A kernel takes float inputs; the interpreter, doubles.
                if (problem.empty() && jitBackend && std::isfinite(x) && std::fabs(x) > double(FLT_MAX))
                    problem = fmt::format("input '{}' = {:.9g} is beyond float range", material.slotName(in.firstSlot + c), x);
            }
        for (int d = 0; d < 2 && problem.empty(); ++d) {
            const double* w = &dirs[3 * d];
            double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            if (!(std::fabs(len - 1) <= kUnitTolerance))
                problem = fmt::format("{} is not a unit vector (length {:.9g})", d ? "wo" : "wi", len);
        }
    }
    return out;
}

// The interpreter's values of the valid rows; a row it rejects gets a problem.
void evaluateInterp(const CheckedMaterial& material, EvalRows& rows, std::vector<std::array<double, 3>>& results) {
    std::unique_ptr<Interpreter<double>> interp = referenceInterpreter(material);
    for (size_t r = 0; r < rows.problems.size(); ++r) {
        if (!rows.problems[r].empty()) continue;
        EvalResult<double> res = interp->eval(&rows.dirs[r][0], &rows.dirs[r][3], rows.slots[r].data());
        if (!res.valid) rows.problems[r] = "a model parameter is not finite for this row's inputs";
        else results[r] = {res.rgb[0], res.rgb[1], res.rgb[2]};
    }
}

// A JIT kernel's values of the valid rows, in one batch; a row it rejects
// gets a problem. False when the material does not compile (diagnostics on
// stderr).
bool evaluateKernel(const EvalOptions& opt, const CompileOptions& compileOptions, const CheckedMaterial& material,
                    EvalRows& rows, std::vector<std::array<double, 3>>& results) {
    // The input slots are all unbound (bindings are applied per row here,
    // so that one kernel serves every row).
    Compiler compiler;
    DiagnosticEngine kdiags;
    std::unique_ptr<Kernel> kernel = compiler.compileFile(opt.file, material.name, compileOptions, kdiags);
    if (!kernel) {
        std::fputs(kdiags.str().c_str(), stderr);
        return false;
    }
    std::vector<size_t> live;
    for (size_t r = 0; r < rows.problems.size(); ++r)
        if (rows.problems[r].empty()) live.push_back(r);
    int slotCount = kernel->inputCount();
    std::vector<float> soa((6 + slotCount + 3) * live.size());
    auto column = [&](int c) { return soa.data() + c * live.size(); };
    for (size_t j = 0; j < live.size(); ++j) {
        for (int d = 0; d < 6; ++d) column(d)[j] = float(rows.dirs[live[j]][d]);
        for (int s = 0; s < slotCount; ++s) column(6 + s)[j] = float(rows.slots[live[j]][s]);
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
            rows.problems[r] = fmt::format("the {} kernel rejected it: a model parameter is not finite in float, or "
                                           "the result is beyond float range",
                                           backendName(compileOptions.backend));
    }
    return true;
}

}  // namespace

int cmdEval(const std::vector<std::string>& args) {
    EvalOptions opt = parseEvalArgs(args);
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
    std::optional<ColumnLayout> layout = columnLayout(*table, *material, opt);
    if (!layout) return kExitUsage;

    // Output: built in memory and written at the end, every write checked.
    if (!outputWritable(opt)) return kExitUsage;
    std::string outText = "r,g,b\n";
    EvalRows rows = readRows(*table, *layout, *material, slots, jitBackend);
    std::vector<std::array<double, 3>> results(table->rows.size(), {0, 0, 0});
    if (compileOptions.backend == Backend::Interp) evaluateInterp(*material, rows, results);
    else if (!evaluateKernel(opt, compileOptions, *material, rows, results)) return kExitMaterialError;
    bool doublePrecision = compileOptions.backend == Backend::Interp;
    int bad = 0;
    for (size_t r = 0; r < table->rows.size(); ++r) {
        if (!rows.problems[r].empty()) {
            ++bad;
            results[r] = {0, 0, 0};
            std::fprintf(stderr, "%s:%d: error: row %zu: %s; its output is 0,0,0\n", opt.in.c_str(),
                         table->rows[r].line, r + 1, rows.problems[r].c_str());
        }
        if (doublePrecision)
            outText += fmt::format("{:.17g},{:.17g},{:.17g}\n", results[r][0], results[r][1], results[r][2]);
        else
            outText += fmt::format("{:.9g},{:.9g},{:.9g}\n", float(results[r][0]), float(results[r][1]),
                                   float(results[r][2]));
    }
    if (!writeOutput(opt.out, outText)) return kExitFailed;
    if (bad) {
        std::fprintf(stderr, "%d of %zu rows invalid\n", bad, table->rows.size());
        return kExitFailed;
    }
    return kExitOk;
}

}  // namespace facet
