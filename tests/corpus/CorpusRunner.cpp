// CorpusRunner: runs the material test corpus (tests/corpus/**/*.mat) against
// one evaluator backend, Crafting-Interpreters style: every test is a tiny
// material file whose expectations are written inline in comments.
//
//   facet_corpus_runner --backend interp [--facet PATH/TO/facet] DIR_OR_FILE...
//
// Directives (each on its own `//` comment line):
//   // expect: wi=(x,y,z) wo=(x,y,z) [NAME=V | NAME=(r,g,b)]... [tol=T] -> r g b
//        the BRDF at (wi, wo), with the named inputs set, equals r g b (or one
//        value for all three channels) within relative T (default 1e-9);
//        an expected 0 must be exactly 0.
//   // error: LINE:COL: message
//        checking the file prints exactly "<file>:LINE:COL: error: message";
//        the printed diagnostics must be exactly the file's `// error:` lines.
//        "$FILE" in the message stands for the file's path (messages such as
//        "first defined at $FILE:3:11" name it, and it depends on how the
//        runner was invoked).
//   // material: NAME
//        the following expect lines evaluate material NAME (default: the first).
// A file with `// error:` lines is an error file; otherwise it must check
// cleanly and is a value file. A file with no directive at all fails, so that
// a misspelled directive cannot silently turn a test into nothing.
//
// With --facet, every file is also run through the real `facet check` binary,
// whose output and exit code (65 for errors, 0 for clean files) must agree.
//
// The expected numbers come from scripts/reference_values.py, an independent
// Python implementation of the SPEC formulas (`--check` re-verifies them).
//
// Prints one line per failure ("FAIL file:line: ...", expected vs actual) and ends with
// exactly "N passed, M failed"; exits 1 on any failure, 2 on usage errors.
#include "Checker.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "ReferenceComparison.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace fs = std::filesystem;
using facet::CheckedInput;
using facet::CheckedMaterial;
using facet::CheckedProgram;
using facet::DiagnosticEngine;

namespace {

using Rgb = std::array<double, 3>;
using Vec = std::array<double, 3>;

// ===========================================================================
// Backend dispatch: the ONE place that knows the evaluators. A JIT backend
// ("scalar", "simd") is added by naming it in kBackends, giving its tolerance
// floor, and adding its branch to evaluate(); nothing else in this file
// depends on which backend runs.
// ===========================================================================

const std::vector<std::string> kBackends = {"interp", "scalar", "simd", "simd4", "simd8", "simd16"};

// The smallest relative tolerance an expectation is checked with on this
// backend. The interpreter is the double-precision reference, so the file's
// tolerance (default 1e-9) applies as written; the float JIT kernels are held
// to the bound of the differential tests, 1e-5 relative.
double toleranceFloor(const std::string& backend) {
    if (backend == "interp") return 0;
    return 1e-5;
}

// Float kernels cannot represent values below kAbsoluteErrorFloor to relative
// accuracy (nor above FLT_MAX at all): those compare in absolute terms, and a
// value beyond float range must come back as an invalid lane.
constexpr double kFloatMax = 3.4028234663852886e38;

// Compiled kernels, one per (material, backend), built on first use.
facet::Compiler& jitCompiler() {
    static facet::Compiler compiler;
    return compiler;
}

// The BRDF of `material` at (wi, wo) with the given input slot values, or
// nullopt when the backend reports the lane invalid.
std::optional<Rgb> evaluate(const std::string& backend, const CheckedMaterial& material, const Vec& wi,
                            const Vec& wo, const std::vector<double>& slots) {
    if (backend == "interp") {
        facet::Interpreter<double> interp(material);
        facet::EvalResult<double> r = interp.eval(wi.data(), wo.data(), slots.data());
        if (!r.valid) return std::nullopt;
        return r.rgb;
    }
    // LLVM JIT kernels, float in and out.
    // A material the compiled backends take only with constant layer
    // parameters is compiled per line, every input bound to the line's
    // value (`--set`), as a user would.
    const bool bindAll = !facet::compiledBackendsRefuse(material).empty();
    std::string bound;
    if (bindAll)
        for (double v : slots) bound += fmt::format("{},", v);
    // Keyed by file and material name: checked materials of different files
    // may reuse the same address once a file's program is gone.
    static std::map<std::string, std::unique_ptr<facet::Kernel>> kernels;
    std::unique_ptr<facet::Kernel>& kernel =
        kernels[fmt::format("{}\n{}\n{}\n{}", material.loc.str(), material.name, backend, bound)];
    if (!kernel) {
        facet::CompileOptions options;
        std::string spec = backend == "scalar" ? "backend=scalar" : "backend=simd";
        if (backend.size() > 4 && backend.rfind("simd", 0) == 0) spec += ";width=" + backend.substr(4);
        std::string err = facet::CompileOptions::parse(spec + ";cache=memory", options);
        if (!err.empty()) throw std::runtime_error(err);
        if (bindAll)
            for (const facet::CheckedInput& in : material.inputs)
                options.bindings[in.name] = std::vector<double>(slots.begin() + in.firstSlot,
                                                                slots.begin() + in.firstSlot + in.slotCount());
        DiagnosticEngine diags;
        kernel = jitCompiler().compileMaterial(material, options, diags);
        if (!kernel) throw std::runtime_error("kernel compilation failed: " + diags.str());
    }
    float a[3], b[3], out[3];
    std::vector<float> in(slots.begin(), slots.end());
    if (bindAll) in.clear();
    for (int i = 0; i < 3; ++i) {
        a[i] = float(wi[i]);
        b[i] = float(wo[i]);
    }
    const float* wiP[3] = {&a[0], &a[1], &a[2]};
    const float* woP[3] = {&b[0], &b[1], &b[2]};
    std::vector<const float*> inP;
    for (float& v : in) inP.push_back(&v);
    float* outP[3] = {&out[0], &out[1], &out[2]};
    if (kernel->evalBatch(1, wiP, woP, inP.empty() ? nullptr : inP.data(), outP) != 0) return std::nullopt;
    return Rgb{out[0], out[1], out[2]};
}

// ===========================================================================
// Directives
// ===========================================================================

struct InputValue {
    std::string name;
    std::vector<double> values;  // 1 (float, or broadcast to rgb) or 3
};

struct Expect {
    int line = 0;
    std::string material;  // empty: the first
    Vec wi{}, wo{};
    std::vector<InputValue> inputs;
    double tol = 1e-9;
    Rgb want{};
};

struct ExpectedError {
    int line = 0;     // where the directive is
    std::string text;  // "LINE:COL: message"
};

struct CorpusFile {
    std::string path;
    std::vector<Expect> expects;
    std::vector<ExpectedError> errors;
    std::vector<std::pair<int, std::string>> malformed;  // directive lines that did not parse
};

std::string trim(std::string_view s) {
    size_t b = s.find_first_not_of(" \t\r"), e = s.find_last_not_of(" \t\r");
    return b == std::string_view::npos ? std::string() : std::string(s.substr(b, e - b + 1));
}

std::optional<double> parseDouble(const std::string& text) {
    std::string t = trim(text);
    if (t.empty()) return std::nullopt;
    char* end = nullptr;
    double v = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

// "(x, y, z)" -> three numbers.
std::optional<std::vector<double>> parseTuple(const std::string& text) {
    if (text.size() < 2 || text.front() != '(' || text.back() != ')') return std::nullopt;
    std::vector<double> out;
    std::stringstream in(text.substr(1, text.size() - 2));
    std::string field;
    while (std::getline(in, field, ',')) {
        auto v = parseDouble(field);
        if (!v) return std::nullopt;
        out.push_back(*v);
    }
    if (out.size() != 3) return std::nullopt;
    return out;
}

// Parses the text after "expect:"; returns an error message or "".
std::string parseExpect(const std::string& body, Expect& e) {
    size_t arrow = body.find("->");
    if (arrow == std::string::npos) return "missing '->'";
    std::string args = body.substr(0, arrow), result = body.substr(arrow + 2);
    bool haveWi = false, haveWo = false;
    size_t pos = 0;
    while (true) {
        while (pos < args.size() && std::isspace((unsigned char)args[pos])) ++pos;
        if (pos >= args.size()) break;
        size_t eq = args.find('=', pos);
        if (eq == std::string::npos) return fmt::format("expected NAME=VALUE at '{}'", args.substr(pos));
        std::string key = trim(args.substr(pos, eq - pos));
        pos = eq + 1;
        while (pos < args.size() && std::isspace((unsigned char)args[pos])) ++pos;
        size_t end;
        if (pos < args.size() && args[pos] == '(') {
            end = args.find(')', pos);
            if (end == std::string::npos) return fmt::format("unclosed '(' in the value of {}", key);
            ++end;
        } else {
            end = pos;
            while (end < args.size() && !std::isspace((unsigned char)args[end])) ++end;
        }
        std::string raw = args.substr(pos, end - pos);
        pos = end;
        std::vector<double> values;
        if (!raw.empty() && raw[0] == '(') {
            auto t = parseTuple(raw);
            if (!t) return fmt::format("'{}' is not (x,y,z)", raw);
            values = *t;
        } else if (auto v = parseDouble(raw)) {
            values = {*v};
        } else {
            return fmt::format("'{}' is not a number", raw);
        }
        if (key == "wi" || key == "wo") {
            if (values.size() != 3) return fmt::format("{} needs (x,y,z)", key);
            (key == "wi" ? e.wi : e.wo) = {values[0], values[1], values[2]};
            (key == "wi" ? haveWi : haveWo) = true;
        } else if (key == "tol") {
            if (values.size() != 1 || values[0] <= 0) return "tol needs one positive number";
            e.tol = values[0];
        } else {
            e.inputs.push_back({key, values});
        }
    }
    if (!haveWi || !haveWo) return "wi=(x,y,z) and wo=(x,y,z) are required";
    std::vector<double> want;
    std::stringstream in(result);
    std::string field;
    while (in >> field) {
        auto v = parseDouble(field);
        if (!v) return fmt::format("expected value '{}' is not a number", field);
        want.push_back(*v);
    }
    if (want.size() == 1) want.assign(3, want[0]);
    if (want.size() != 3) return "expected one value or three (r g b) after '->'";
    e.want = {want[0], want[1], want[2]};
    return "";
}

CorpusFile readCorpusFile(const std::string& path) {
    CorpusFile f;
    f.path = path;
    std::ifstream in(path, std::ios::binary);
    std::string line, material;
    for (int no = 1; std::getline(in, line); ++no) {
        std::string t = trim(line);
        if (t.rfind("//", 0) != 0) continue;
        std::string c = trim(std::string_view(t).substr(2));
        // The word before ':' names the directive; anything that merely looks
        // like one ("// expect wi=...", "//expects:") is reported, not ignored.
        std::string word = c.substr(0, c.find_first_of(": \t"));
        bool hasColon = c.size() > word.size() && c[word.size()] == ':';
        std::string body = hasColon ? trim(std::string_view(c).substr(word.size() + 1)) : "";
        if (word == "expect" || word == "error" || word == "material") {
            if (!hasColon) {
                f.malformed.push_back({no, fmt::format("'{}' directive needs a ':'", word)});
            } else if (word == "material") {
                material = body;
            } else if (word == "error") {
                f.errors.push_back({no, body});
            } else {
                Expect e;
                e.line = no;
                e.material = material;
                std::string problem = parseExpect(body, e);
                if (problem.empty()) f.expects.push_back(std::move(e));
                else f.malformed.push_back({no, "malformed expect line: " + problem});
            }
        } else if (word == "expects" || word == "errors" || word == "expected") {
            f.malformed.push_back({no, fmt::format("unknown directive '{}'", word)});
        }
    }
    return f;
}

// ===========================================================================
// Running
// ===========================================================================

struct Tally {
    int passed = 0, failed = 0;
    // Expect lines a compiled backend does not run: materials it refuses
    // (compiledBackendsRefuse: a compensated thin sheet whose index is an
    // input; a layer whose tables read one); printed in the summary.
    int referenceOnly = 0;
    void pass() { ++passed; }
    template <typename... Args>
    void fail(fmt::format_string<Args...> f, Args&&... args) {
        ++failed;
        std::printf("FAIL %s\n", fmt::format(f, std::forward<Args>(args)...).c_str());
    }
};

std::string fmtRgb(const Rgb& v) { return fmt::format("{:.17g} {:.17g} {:.17g}", v[0], v[1], v[2]); }

bool close(double actual, double want, double tol) {
    if (want == 0) return actual == 0;  // below the horizon etc.: exactly zero
    return std::fabs(actual - want) <= tol * std::fabs(want);
}

// Runs `cmd` through the shell; returns its combined output lines and exit status.
std::pair<std::vector<std::string>, int> runCommand(const std::string& cmd) {
    std::vector<std::string> lines;
    FILE* p = popen((cmd + " 2>&1").c_str(), "r");
    if (!p) return {lines, -1};
    std::string cur;
    for (int ch; (ch = std::fgetc(p)) != EOF;) {
        if (ch == '\n') {
            lines.push_back(cur);
            cur.clear();
        } else {
            cur += char(ch);
        }
    }
    if (!cur.empty()) lines.push_back(cur);
    int status = pclose(p);
    return {lines, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

// The diagnostics the file's `// error:` lines promise, as printed lines.
std::vector<std::string> expectedDiagnostics(const CorpusFile& f) {
    std::vector<std::string> out;
    for (const ExpectedError& e : f.errors) {
        // "LINE:COL: message" -> "<file>:LINE:COL: error: message"
        size_t c1 = e.text.find(':');
        size_t c2 = c1 == std::string::npos ? c1 : e.text.find(':', c1 + 1);
        if (c2 == std::string::npos) {
            out.push_back(fmt::format("<malformed error directive: {}>", e.text));
            continue;
        }
        std::string message = trim(e.text.substr(c2 + 1));
        for (size_t at = 0; (at = message.find("$FILE", at)) != std::string::npos; at += f.path.size())
            message.replace(at, 5, f.path);
        out.push_back(fmt::format("{}:{}: error: {}", f.path, e.text.substr(0, c2), message));
    }
    return out;
}

void runErrorFile(const CorpusFile& f, Tally& tally) {
    DiagnosticEngine diags;
    facet::loadProgramFile(f.path, diags);
    std::vector<std::string> printed;
    for (const facet::Diagnostic& d : diags.diagnostics()) printed.push_back(d.str());
    std::vector<std::string> expected = expectedDiagnostics(f);
    // Multiset comparison: each expected line consumes one printed line.
    std::vector<bool> used(printed.size(), false);
    for (size_t i = 0; i < expected.size(); ++i) {
        bool found = false;
        for (size_t j = 0; j < printed.size() && !found; ++j)
            if (!used[j] && printed[j] == expected[i]) used[j] = found = true;
        if (found) tally.pass();
        else tally.fail("{}:{}: expected diagnostic not printed: {}", f.path, f.errors[i].line, expected[i]);
    }
    for (size_t j = 0; j < printed.size(); ++j)
        if (!used[j]) tally.fail("{}: unexpected diagnostic: {}", f.path, printed[j]);
}

void runValueFile(const CorpusFile& f, const std::string& backend, Tally& tally) {
    DiagnosticEngine diags;
    CheckedProgram program = facet::loadProgramFile(f.path, diags);
    if (diags.hasErrors()) {
        const std::string first = diags.diagnostics().front().str();
        for (const Expect& e : f.expects)
            tally.fail("{}:{}: cannot evaluate, the file has {} diagnostic(s), first: {}", f.path, e.line,
                       diags.diagnostics().size(), first);
        return;
    }
    for (const Expect& e : f.expects) {
        const CheckedMaterial* m = program.find(e.material);
        if (!m) {
            tally.fail("{}:{}: no material named '{}'", f.path, e.line, e.material);
            continue;
        }
        std::vector<double> slots = m->defaultSlots();
        std::string problem;
        for (const InputValue& iv : e.inputs) {
            const CheckedInput* in = m->findInput(iv.name);
            if (!in) {
                problem = fmt::format("material '{}' has no input '{}'", m->name, iv.name);
                break;
            }
            if (in->type == facet::ValueType::Float && iv.values.size() != 1) {
                problem = fmt::format("input '{}' is float; give one value", iv.name);
                break;
            }
            for (int c = 0; c < in->slotCount(); ++c)
                slots[in->firstSlot + c] = iv.values[iv.values.size() == 1 ? 0 : c];
        }
        if (!problem.empty()) {
            tally.fail("{}:{}: {}", f.path, e.line, problem);
            continue;
        }
        if (backend != "interp" && !facet::compiledBackendsRefuse(*m).empty()) {
            ++tally.referenceOnly;
            continue;
        }
        double tol = std::max(e.tol, toleranceFloor(backend));
        std::optional<Rgb> got = evaluate(backend, *m, e.wi, e.wo, slots);
        bool floatBackend = backend != "interp";
        bool beyondFloat = std::max({e.want[0], e.want[1], e.want[2]}) > kFloatMax;
        if (floatBackend && beyondFloat) {
            // Not representable: the lane must be reported invalid (rgb 0).
            if (!got) tally.pass();
            else tally.fail("{}:{}: expected an invalid lane (value beyond float), got {} ({})", f.path, e.line,
                            fmtRgb(*got), backend);
            continue;
        }
        if (!got) {
            tally.fail("{}:{}: expected {}, got an invalid lane ({})", f.path, e.line, fmtRgb(e.want), backend);
            continue;
        }
        bool ok = true;
        for (int c = 0; c < 3; ++c)
            ok &= close((*got)[c], e.want[c], tol) ||
                  (floatBackend && e.want[c] != 0 && std::fabs((*got)[c] - e.want[c]) <= facet::kAbsoluteErrorFloor);
        if (ok) tally.pass();
        else
            tally.fail("{}:{}: expected {}, got {} (tol {:g}, {})", f.path, e.line, fmtRgb(e.want), fmtRgb(*got), tol,
                       backend);
    }
}

// The real `facet check` must print the same diagnostics, with exit code 65
// for a file with errors and 0 (and no output) for a clean one.
void runFacetCheck(const CorpusFile& f, const std::string& facetBinary, Tally& tally) {
    auto [lines, status] = runCommand(shellQuote(facetBinary) + " check " + shellQuote(f.path));
    std::vector<std::string> expected = expectedDiagnostics(f);
    std::vector<std::string> a = lines, b = expected;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    int wantStatus = f.errors.empty() ? 0 : 65;
    if (a == b && status == wantStatus) {
        tally.pass();
        return;
    }
    std::string got;
    for (const std::string& l : lines) got += (got.empty() ? "" : " | ") + l;
    tally.fail("{}: `facet check` exited {} (expected {}) and printed: {}", f.path, status, wantStatus,
               got.empty() ? "nothing" : got);
}

int usage(const char* msg) {
    std::fprintf(stderr,
                 "facet_corpus_runner: %s\n"
                 "usage: facet_corpus_runner --backend NAME [--facet PATH] DIR_OR_FILE...\n",
                 msg);
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    std::string backend, facetBinary;
    std::vector<std::string> roots;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if ((a == "--backend" || a == "--facet") && i + 1 < argc) (a == "--backend" ? backend : facetBinary) = argv[++i];
        else if (!a.empty() && a[0] == '-') return usage(("unknown option " + a).c_str());
        else roots.push_back(a);
    }
    if (backend.empty()) return usage("--backend is required");
    if (std::find(kBackends.begin(), kBackends.end(), backend) == kBackends.end())
        return usage(("unknown backend '" + backend + "'").c_str());
    if (roots.empty()) return usage("no corpus directory or file given");

    // Directories contribute their *.mat files, recursively and sorted so the
    // output is stable; files named explicitly are run whatever their name.
    std::vector<std::string> files;
    for (const std::string& root : roots) {
        std::error_code ec;
        if (fs::is_directory(root, ec)) {
            std::vector<std::string> found;
            for (const auto& entry : fs::recursive_directory_iterator(root))
                if (entry.is_regular_file() && entry.path().extension() == ".mat") found.push_back(entry.path().string());
            std::sort(found.begin(), found.end());
            files.insert(files.end(), found.begin(), found.end());
        } else if (fs::is_regular_file(root, ec)) {
            files.push_back(root);
        } else {
            return usage(("no such file or directory: " + root).c_str());
        }
    }

    Tally tally;
    for (const std::string& path : files) {
        CorpusFile f = readCorpusFile(path);
        for (const auto& [line, msg] : f.malformed) tally.fail("{}:{}: {}", path, line, msg);
        if (f.expects.empty() && f.errors.empty()) {
            if (f.malformed.empty()) tally.fail("{}: no '// expect:' or '// error:' lines", path);
            continue;
        }
        if (!f.errors.empty() && !f.expects.empty()) {
            tally.fail("{}: has both '// error:' and '// expect:' lines; split it", path);
            continue;
        }
        if (f.errors.empty()) runValueFile(f, backend, tally);
        else runErrorFile(f, tally);
        if (!facetBinary.empty()) runFacetCheck(f, facetBinary, tally);
    }
    if (tally.referenceOnly > 0)
        std::printf("%d expect lines not run on %s: the compiled backends refuse their materials (only the "
                    "reference evaluates them so far)\n",
                    tally.referenceOnly, backend.c_str());
    std::printf("%d passed, %d failed\n", tally.passed, tally.failed);

    return tally.failed ? 1 : 0;
}
