// FuzzMutants: randomized mutation test of the Facet front end and the
// reference interpreter, built against an ASan+UBSan copy of the front end.
//
// Why: SPEC 1 promises that the compiler "never crashes, hangs or allocates
// without bound on any input" and that every mistake is reported as
// `file:line:col: error: message`; SPEC 2 promises that the BRDF is never
// NaN, infinite or negative. Hand-written tests only cover the mistakes
// somebody thought of. This program damages real materials mechanically
// (token edits, byte edits, splices, pathological repetitions), runs each
// mutant through loadProgramText, and checks those promises on every one;
// the sanitizers turn silent memory errors and undefined behaviour into
// aborts, so "no report" really means "no bug seen".
//
// Modes:
//   facet_fuzz_mutants [--seed N] [--count N] [--only INDEX] [--corpus DIR]...
//                      [--no-default-corpus] [--dump DIR] [--verbose]
//       the mutation run (ctest: fuzz_mutants_asan). Every mutant is derived
//       from (seed, index) and the seed files alone, so `--only INDEX` replays
//       one mutant as long as materials/ and tests/corpus/ are unchanged.
//   facet_fuzz_mutants --file PATH...
//       the same checks on given files (replaying a saved crash input).
//   facet_fuzz_mutants --stress [--dump DIR]
//       large hand-built adversarial inputs (deep expression chains, huge
//       statement and argument counts, megabyte identifiers), each in a forked
//       child with a time limit (ctest: fuzz_stress_asan). These probe the
//       "never hangs / never exhausts the stack" promise at sizes that random
//       mutation of small seeds never reaches.
//
// Exit status: 0 when every check passed, 1 otherwise. A sanitizer report
// aborts the process; the mutant being processed is then written to
// DUMP/fuzz_crash_mutant.mat first (see onSanitizerDeath).
#include "Builtins.h"
#include "Checker.h"
#include "Diagnostics.h"
#include "Interpreter.h"
#include "Lexer.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__) && __has_include(<sanitizer/common_interface_defs.h>)
#include <sanitizer/common_interface_defs.h>
#define FACET_HAVE_SANITIZER_CALLBACK 1
#endif

#ifndef FACET_SOURCE_DIR
#define FACET_SOURCE_DIR "."
#endif

namespace fs = std::filesystem;
using namespace facet;

namespace {

// The path every mutant is compiled under; diagnostics must name it.
const std::string kMutantName = "mutant.mat";

// ---- deterministic randomness ----------------------------------------------
// std::uniform_int_distribution is implementation-defined, so a seed would
// not replay the same mutants across standard libraries; splitmix64 does.
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t s) : state(s) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    size_t below(size_t n) { return n ? size_t(next() % n) : 0; }  // [0, n)
    size_t range(size_t lo, size_t hi) { return lo + below(hi - lo + 1); }  // [lo, hi]
    bool chance(int percent) { return below(100) < size_t(percent); }
    template <typename T>
    const T& pick(const std::vector<T>& v) { return v[below(v.size())]; }
};

// ---- seeds -------------------------------------------------------------------
// Embedded so that the test is meaningful even when materials/ and
// tests/corpus/ are empty. Together they use every model of every slot, every
// builtin function, named and positional arguments, rgb inputs, ranges,
// comments, lets that use lets, and several materials in one file.
const char* const kEmbeddedSeeds[] = {
    R"(// gold: the SPEC example
material gold {
    input roughness = 0.35 in 0 .. 1;          // per-evaluation input
    input tint = rgb(1, 1, 1);
    let alpha = roughness * roughness;
    ndf     = ggx(alpha);
    masking = smith_height_correlated;
    fresnel = conductor(eta = rgb(0.143, 0.374, 1.442), k = rgb(3.983, 2.385, 1.603));
    energy  = none;
    diffuse = none;
}
)",
    R"(/* anisotropic Beckmann glass over a Lambert base */
material glass_aniso {
    input ax = 0.2 in 1e-3 .. 1;
    input ay = .05 in 0.001 .. 1;
    input base = rgb(0.2, 0.3, 0.4) in 0 .. 1;
    ndf = beckmann(alpha_x = ax, alpha_y = ay);
    masking = smith_separable;
    fresnel = dielectric(eta = 1.5);
    diffuse = lambert(albedo = base * 0.5);
}
)",
    R"(material phong {
    input r = 0.4 in 0.05 .. 1;
    input f0 = rgb(0.04, 0.04, 0.04);
    let e = phong_exponent(r);
    let e2 = min(e, beckmann_to_phong(0.3)) + 0 * e;
    ndf = blinn_phong(exponent = e2);
    masking = schlick_smith(k = r * sqrt(2 / 3.14159265));
    fresnel = schlick(f0);
}
material second {
    ndf = trowbridge_reitz(0.5, 0.25);
    masking = smith_direction_correlated;
    fresnel = schlick(eta = rgb(1.5, 1.45, 1.4));
}
)",
    R"(material clearcoat {
    input gloss = 0.8 in 0 .. 1;
    let a = mix(0.1, 0.001, gloss);
    let g = clamp(1 + 0 * a, 1, 2);
    ndf = gtr(a, g);
    masking = cook_torrance;
    fresnel = schlick(f0 = 0.04);
    diffuse = lambert(rgb(0.05, 0.12, 0.35));
}
)",
    R"(material satin {
    input s = 0.3 in 0.01 .. 1.5;
    ndf = gaussian(alpha = s);
    masking = kelemen;
    fresnel = none;
    diffuse = lambert(0.1);
}
material brushed {
    ndf = ward(0.1, 0.3);
    masking = none;
    fresnel = conductor(rgb(0.2, 0.9, 1.1), rgb(3.9, 2.4, 2.2));
}
)",
    R"(material exprs {
    input a = -(-2)^2 + 2^3^2 / 64 - 1 - -1 in -100 .. 100;
    input c = rgb(exp(0), log(2.718281828), abs(-0.5)) in 0 .. 2;
    let p = pow(2, -3) * 8 / 4 / 2;
    let q = max(p, 0.01) + min(a, 0) * 0;
    let w = c * q + rgb(0, 0, 0);
    ndf = ggx(alpha_y = q, alpha_x = q * 2);
    masking = smith_height_direction_correlated;
    fresnel = schlick(f0 = w);
    energy = none;
    diffuse = lambert(albedo = w / 4);
}
)",
    R"(material neumann_beck {
    input m = 0.25;
    let m2 = m * m;
    ndf = beckmann(m2);
    masking = neumann;
    fresnel = dielectric(rgb(1.33, 1.34, 1.35));
}
material implicit_ggx { ndf = ggx(1e-4); masking = implicit; }
)",
    R"(material broken_on_purpose {
    input r = 2 in 0 .. 1;
    let x = y;
    ndf = ggx(r, r, r);
    masking = smith_height_correlated;
    ndf = beckmann(r);
    fresnel = conductor(eta = 1);
    energy = kulla_conty;
}
)",
};

struct Seed {
    std::string name;
    std::string text;
};

void addSeedFiles(const fs::path& dir, std::vector<Seed>& seeds) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return;
    std::vector<fs::path> paths;
    for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
        if (it->is_regular_file(ec) && it->path().extension() == ".mat") paths.push_back(it->path());
    }
    std::sort(paths.begin(), paths.end());  // the same mutants for the same corpus
    for (const fs::path& p : paths) {
        std::ifstream in(p, std::ios::binary);
        std::stringstream ss;
        ss << in.rdbuf();
        std::string text = ss.str();
        // Huge files belong in --stress; as seeds they would only slow every mutant.
        if (text.size() > (64u << 10)) continue;
        seeds.push_back({p.string(), std::move(text)});
    }
}

// ---- token spans -----------------------------------------------------------
// facet::lex gives line:col; mutations need byte ranges.
struct Span {
    size_t begin, end;
    TokenKind kind;
};

std::vector<Span> tokenSpans(const std::string& text) {
    std::vector<size_t> lineStart{0};
    for (size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') lineStart.push_back(i + 1);
    std::vector<Span> spans;
    for (const Token& t : lex(text, std::make_shared<const std::string>("seed"))) {
        if (t.kind == TokenKind::End || t.loc.line < 1 || size_t(t.loc.line) > lineStart.size()) continue;
        size_t begin = lineStart[t.loc.line - 1] + size_t(t.loc.col - 1);
        // An Error token's text is its message, not its spelling: take one byte.
        size_t len = t.kind == TokenKind::Error ? 1 : t.text.size();
        if (begin >= text.size()) continue;
        spans.push_back({begin, std::min(text.size(), begin + len), t.kind});
    }
    return spans;
}

// ---- the vocabulary insertions draw from ---------------------------------
std::vector<std::string> buildVocabulary() {
    std::vector<std::string> v = {
        "material", "input", "let", "in", "ndf", "masking", "fresnel", "energy", "diffuse",
        "{", "}", "(", ")", ",", ";", "=", "..", "+", "-", "*", "/", "^", ".",
        "0", "1", "0.5", ".5", "5.", "1e-3", "2", "1e308", "1e-320", "4.9e-324", "1e999", "0.0001",
        "1e6", "2e8", "-1", "0..1", "1.5..2", "2e", "1e+", "3x", "0.0.0",
        "alpha", "roughness", "tint", "x", "y", "r", "g", "b", "tint.r",
        "@", "#", "\"", "$", "`", "\\", "'", "\xff", std::string(1, '\0'), "\t", "\r\n", "/*", "*/", "//",
    };
    for (const BuiltinFunction& f : builtinFunctions()) v.push_back(f.name);
    for (const ModelInfo* m : catalog()) {
        v.push_back(m->name);
        for (const char* a : m->aliases) v.push_back(a);
        for (const ModelForm& f : m->forms)
            for (const auto& p : f.params) v.push_back(p.name);
    }
    return v;
}

std::vector<std::string> identifierVocabulary(const std::vector<std::string>& vocab) {
    std::vector<std::string> out;
    for (const std::string& s : vocab)
        if (!s.empty() && (std::isalpha((unsigned char)s[0]) || s[0] == '_') &&
            std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum((unsigned char)c) || c == '_'; }))
            out.push_back(s);
    return out;
}

const std::vector<std::string> kExtremeNumbers = {
    "0", "0.0", "00000", "1e308", "1.7976931348623157e308", "1e309", "1e-308", "2.2250738585072014e-308",
    "4.9e-324", "1e-324", "1e-400", "1e999", "123456789012345678901234567890", "0.000000000000000000001",
    "1e+0", "1E5", "9e18", "18446744073709551617", "2147483648", "1e-7", "1e-4", "0.9999999999999999",
    "1.0000000000000002", "3.4028235e38", "1e38",
};

// ---- mutators ----------------------------------------------------------------
struct Context {
    const std::vector<Seed>& seeds;
    const std::vector<std::string>& vocab;
    const std::vector<std::string>& idents;
};

using Mutator = void (*)(std::string&, Rng&, const Context&);

size_t randomPos(const std::string& s, Rng& rng) { return rng.below(s.size() + 1); }

std::string longRun(Rng& rng, const std::string& unit, size_t lo, size_t hi) {
    size_t n = rng.range(lo, hi);
    std::string out;
    out.reserve(unit.size() * n);
    for (size_t i = 0; i < n; ++i) out += unit;
    return out;
}

// Token-level edits keep most of the file well-formed, so the damage reaches
// the parser's recovery and the checker instead of stopping in the lexer.
void tokDelete(std::string& s, Rng& rng, const Context&) {
    auto spans = tokenSpans(s);
    if (spans.empty()) return;
    size_t first = rng.below(spans.size()), last = std::min(spans.size() - 1, first + (rng.chance(70) ? 0 : rng.below(6)));
    s.erase(spans[first].begin, spans[last].end - spans[first].begin);
}
void tokInsert(std::string& s, Rng& rng, const Context& cx) {
    auto spans = tokenSpans(s);
    std::string tok = rng.pick(cx.vocab);
    size_t at = spans.empty() ? randomPos(s, rng) : (rng.chance(50) ? spans[rng.below(spans.size())].begin
                                                                      : spans[rng.below(spans.size())].end);
    s.insert(at, rng.chance(50) ? " " + tok + " " : tok);
}
void tokDuplicate(std::string& s, Rng& rng, const Context&) {
    auto spans = tokenSpans(s);
    if (spans.empty()) return;
    size_t first = rng.below(spans.size()), last = std::min(spans.size() - 1, first + rng.below(4));
    std::string run = s.substr(spans[first].begin, spans[last].end - spans[first].begin);
    s.insert(spans[last].end, " " + run);
}
void tokSwap(std::string& s, Rng& rng, const Context&) {
    auto spans = tokenSpans(s);
    if (spans.size() < 2) return;
    size_t a = rng.below(spans.size()), b = rng.below(spans.size());
    if (a == b) return;
    if (a > b) std::swap(a, b);
    std::string ta = s.substr(spans[a].begin, spans[a].end - spans[a].begin);
    std::string tb = s.substr(spans[b].begin, spans[b].end - spans[b].begin);
    s.replace(spans[b].begin, tb.size(), ta);  // the later one first keeps offsets valid
    s.replace(spans[a].begin, ta.size(), tb);
}
void tokReplace(std::string& s, Rng& rng, const Context& cx) {
    auto spans = tokenSpans(s);
    if (spans.empty()) return;
    const Span& sp = spans[rng.below(spans.size())];
    s.replace(sp.begin, sp.end - sp.begin, rng.pick(cx.vocab));
}
// An identifier replaced by another known name: wrong model in a slot, a
// function used as a model, an argument name of another model, and so on.
void tokReplaceIdent(std::string& s, Rng& rng, const Context& cx) {
    auto spans = tokenSpans(s);
    std::vector<Span> ids;
    for (const Span& sp : spans)
        if (sp.kind == TokenKind::Identifier) ids.push_back(sp);
    if (ids.empty()) return;
    const Span& sp = ids[rng.below(ids.size())];
    s.replace(sp.begin, sp.end - sp.begin, rng.pick(cx.idents));
}
void tokReplaceNumber(std::string& s, Rng& rng, const Context&) {
    auto spans = tokenSpans(s);
    std::vector<Span> nums;
    for (const Span& sp : spans)
        if (sp.kind == TokenKind::Number) nums.push_back(sp);
    if (nums.empty()) return;
    const Span& sp = nums[rng.below(nums.size())];
    std::string n = rng.pick(kExtremeNumbers);
    if (rng.chance(25)) n = "-" + n;  // unary minus on an extreme value
    s.replace(sp.begin, sp.end - sp.begin, n);
}
// Statement-level edits: duplicate, drop or move a whole `...;` statement,
// which is what reaches duplicate-definition and use-before-definition rules.
void stmtEdit(std::string& s, Rng& rng, const Context&) {
    std::vector<size_t> semis;
    for (size_t i = 0; i < s.size(); ++i)
        if (s[i] == ';') semis.push_back(i);
    if (semis.size() < 2) return;
    size_t k = rng.below(semis.size() - 1);
    size_t begin = semis[k] + 1, end = semis[k + 1] + 1;
    std::string stmt = s.substr(begin, end - begin);
    switch (rng.below(3)) {
        case 0: s.insert(end, stmt); break;  // duplicate
        case 1: s.erase(begin, end - begin); break;  // drop
        default: {  // move to the position after another statement
            s.erase(begin, end - begin);
            std::vector<size_t> after;
            for (size_t i = 0; i < s.size(); ++i)
                if (s[i] == ';' || s[i] == '{') after.push_back(i + 1);
            if (after.empty()) return;
            s.insert(rng.pick(after), stmt);
        }
    }
}
const char kInterestingByteChars[] = "\0\xff\x80\x7f\x01\n\r\t /*()\"0123456789.e^E+-;{}=,'\\_";
const std::string kInterestingBytes(kInterestingByteChars, sizeof(kInterestingByteChars) - 1);
void byteDelete(std::string& s, Rng& rng, const Context&) {
    if (s.empty()) return;
    size_t at = rng.below(s.size());
    s.erase(at, rng.chance(80) ? 1 : rng.range(1, 16));
}
void byteInsert(std::string& s, Rng& rng, const Context&) {
    size_t n = rng.chance(85) ? 1 : rng.range(2, 8);
    size_t at = randomPos(s, rng);
    for (size_t i = 0; i < n; ++i)
        s.insert(s.begin() + std::ptrdiff_t(at), rng.chance(75) ? kInterestingBytes[rng.below(kInterestingBytes.size())]
                                                                 : char(rng.below(256)));
}
void byteFlip(std::string& s, Rng& rng, const Context&) {
    if (s.empty()) return;
    s[rng.below(s.size())] ^= char(1u << rng.below(8));
}
void byteReplace(std::string& s, Rng& rng, const Context&) {
    if (s.empty()) return;
    s[rng.below(s.size())] = rng.chance(75) ? kInterestingBytes[rng.below(kInterestingBytes.size())] : char(rng.below(256));
}
void truncateText(std::string& s, Rng& rng, const Context&) { s.resize(rng.below(s.size() + 1)); }
void spliceFiles(std::string& s, Rng& rng, const Context& cx) {
    const std::string& other = rng.pick(cx.seeds).text;
    if (rng.chance(50)) {  // at token boundaries
        auto a = tokenSpans(s), b = tokenSpans(other);
        size_t cutA = a.empty() ? 0 : a[rng.below(a.size())].begin;
        size_t cutB = b.empty() ? 0 : b[rng.below(b.size())].begin;
        s = s.substr(0, cutA) + other.substr(cutB);
    } else {  // anywhere, e.g. inside a comment or a number
        s = s.substr(0, randomPos(s, rng)) + other.substr(rng.below(other.size() + 1));
    }
}
void spliceTokens(std::string& s, Rng& rng, const Context& cx) {
    const std::string& other = rng.pick(cx.seeds).text;
    auto b = tokenSpans(other);
    if (b.empty()) return;
    size_t first = rng.below(b.size()), last = std::min(b.size() - 1, first + rng.below(12));
    s.insert(randomPos(s, rng), " " + other.substr(b[first].begin, b[last].end - b[first].begin) + " ");
}
// Nesting far past the parser's limit: must be a diagnostic, not a stack overflow.
void repeatOpeners(std::string& s, Rng& rng, const Context&) {
    static const std::vector<std::string> units = {"(", "(", "-", "sqrt(", "-(", "2^", "rgb(", ")", "{", "min(1,"};
    std::string run = longRun(rng, rng.pick(units), 200, 5000);
    s.insert(randomPos(s, rng), run);
}
void hugeNumber(std::string& s, Rng& rng, const Context&) {
    std::string n;
    switch (rng.below(5)) {
        case 0: n = longRun(rng, "9", 300, 5000); break;
        case 1: n = "0." + longRun(rng, "0", 300, 5000) + "1"; break;
        case 2: n = "1e" + longRun(rng, "9", 5, 400); break;
        case 3: n = "1e-" + longRun(rng, "9", 5, 400); break;
        default: n = longRun(rng, "1", 50, 400) + "." + longRun(rng, "7", 50, 400) + "e-300"; break;
    }
    auto spans = tokenSpans(s);
    std::vector<Span> nums;
    for (const Span& sp : spans)
        if (sp.kind == TokenKind::Number) nums.push_back(sp);
    if (!nums.empty() && rng.chance(70)) {
        const Span& sp = nums[rng.below(nums.size())];
        s.replace(sp.begin, sp.end - sp.begin, n);
    } else {
        s.insert(randomPos(s, rng), n);
    }
}
// Long names end up in "did you mean" suggestions and in messages. Kept to
// a few thousand bytes here: the quadratic cost of two huge names is a
// --stress case, not something to pay on every mutant.
void longIdentifier(std::string& s, Rng& rng, const Context&) {
    std::string id = "x" + longRun(rng, rng.chance(50) ? "a" : "_9", 500, 4000);
    auto spans = tokenSpans(s);
    std::vector<Span> ids;
    for (const Span& sp : spans)
        if (sp.kind == TokenKind::Identifier) ids.push_back(sp);
    if (!ids.empty() && rng.chance(70)) {
        const Span& sp = ids[rng.below(ids.size())];
        s.replace(sp.begin, sp.end - sp.begin, id);
    } else {
        s.insert(randomPos(s, rng), " " + id + " ");
    }
}
void commentEdit(std::string& s, Rng& rng, const Context&) {
    static const std::vector<std::string> bits = {"/*", "*/", "//", "/* unterminated", "/**/", "/*/", "//\n", "\n"};
    s.insert(randomPos(s, rng), rng.pick(bits));
}
void whitespaceEdit(std::string& s, Rng& rng, const Context&) {
    switch (rng.below(3)) {
        case 0: s.erase(std::remove_if(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\n'; }), s.end()); break;
        case 1: {  // CRLF line ends
            std::string out;
            for (char c : s) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
            s = out;
            break;
        }
        default: s.insert(randomPos(s, rng), longRun(rng, rng.chance(50) ? "\n" : "\t ", 1, 3000)); break;
    }
}

struct NamedMutator {
    const char* name;
    Mutator fn;
    int weight;
};
const std::vector<NamedMutator> kMutators = {
    {"tok-delete", tokDelete, 10},       {"tok-insert", tokInsert, 10},
    {"tok-duplicate", tokDuplicate, 6},  {"tok-swap", tokSwap, 6},
    {"tok-replace", tokReplace, 8},      {"tok-ident", tokReplaceIdent, 10},
    {"tok-number", tokReplaceNumber, 8}, {"stmt-edit", stmtEdit, 8},
    {"byte-delete", byteDelete, 5},      {"byte-insert", byteInsert, 6},
    {"byte-flip", byteFlip, 4},          {"byte-replace", byteReplace, 4},
    {"truncate", truncateText, 3},       {"splice-files", spliceFiles, 4},
    {"splice-tokens", spliceTokens, 4},  {"repeat-openers", repeatOpeners, 2},
    {"huge-number", hugeNumber, 2},      {"long-ident", longIdentifier, 2},
    {"comment", commentEdit, 3},         {"whitespace", whitespaceEdit, 2},
};

const NamedMutator& pickMutator(Rng& rng) {
    int total = 0;
    for (const auto& m : kMutators) total += m.weight;
    int r = int(rng.below(size_t(total)));
    for (const auto& m : kMutators) {
        if (r < m.weight) return m;
        r -= m.weight;
    }
    return kMutators.front();
}

struct Mutant {
    std::string text;
    std::string recipe;  // seed name and mutators, for the failure report
};

Mutant makeMutant(uint64_t seed, uint64_t index, const Context& cx) {
    Rng rng(seed * 0x100000001b3ull ^ (index + 1) * 0x9e3779b97f4a7c15ull);
    rng.next();
    const Seed& base = cx.seeds[rng.below(cx.seeds.size())];
    Mutant m{base.text, base.name};
    // Mostly one edit (close to a real typo), sometimes a pile-up.
    size_t edits = rng.chance(60) ? 1 : rng.range(2, 5);
    for (size_t i = 0; i < edits; ++i) {
        const NamedMutator& mut = pickMutator(rng);
        mut.fn(m.text, rng, cx);
        m.recipe += std::string(" + ") + mut.name;
    }
    return m;
}

// ---- checks ------------------------------------------------------------------
struct Failures {
    int count = 0;
    std::vector<std::string> notes;
    void add(std::string msg) {
        ++count;
        if (notes.size() < 40) notes.push_back(std::move(msg));
    }
};

// Line lengths of `text` (lines end at '\n' or a lone '\r', as the lexer
// counts them), for checking that a diagnostic points inside the file.
std::vector<size_t> lineLengths(const std::string& text) {
    std::vector<size_t> out{0};
    for (size_t i = 0; i < text.size(); ++i) {
        char c = text[i];
        if (c == '\n' || (c == '\r' && (i + 1 == text.size() || text[i + 1] != '\n'))) out.push_back(0);
        else ++out.back();
    }
    return out;
}

// SPEC 1: every diagnostic is "file:line:col: error: message" (or, for a
// whole-file problem, "file: error: message"); the location lies in the
// file; the message is one line of printable text (a diagnostic must never
// echo raw bytes of a binary file into the user's terminal).
std::string diagnosticProblem(const Diagnostic& d, const std::vector<size_t>& lines) {
    std::string s = d.str();
    std::string rest;
    if (s.rfind(kMutantName, 0) != 0) return "does not start with the file name";
    rest = s.substr(kMutantName.size());
    if (rest.rfind(": error: ", 0) == 0) {
        if (d.loc.valid()) return "has a valid location but prints none";
        rest = rest.substr(9);
    } else {
        size_t i = 0;
        auto number = [&](long& out) {
            if (i >= rest.size() || rest[i] != ':') return false;
            size_t start = ++i;
            while (i < rest.size() && std::isdigit((unsigned char)rest[i])) ++i;
            if (i == start || i - start > 9) return false;
            out = std::stol(rest.substr(start, i - start));
            return true;
        };
        long line = 0, col = 0;
        if (!number(line) || !number(col)) return "has no ':line:col' after the file name";
        if (rest.compare(i, 9, ": error: ") != 0) return "has no ': error: ' after the location";
        if (line < 1 || col < 1) return "location is not 1-based";
        if (size_t(line) > lines.size()) return "line is past the end of the file";
        // One past the last byte of a line is where "end of file" and
        // "missing ';'" errors legitimately point.
        if (size_t(col) > lines[size_t(line) - 1] + 1) return "column is past the end of its line";
        if (line != d.loc.line || col != d.loc.col) return "printed location differs from loc";
        rest = rest.substr(i + 9);
    }
    if (rest.empty()) return "empty message";
    if (rest != d.message) return "printed message differs from the message";
    for (char c : rest)
        if ((unsigned char)c < 0x20 || (unsigned char)c > 0x7e) return "message has a non-printable byte";
    return {};
}

// Direction pairs: normal, off-specular, mirror, grazing to 1e-7, exactly
// on the horizon, below it, opposite, slightly non-unit (accepted), clearly
// non-unit / zero / NaN / Inf (rejected), denormal components.
struct DirPair {
    std::array<double, 3> wi, wo;
    enum Expect { Any, Zero, Invalid } expect;
    const char* what;
};
std::vector<DirPair> directionPairs() {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const double s60 = std::sqrt(3.0) / 2;
    auto grazing = [](double z) { return std::sqrt(1 - z * z); };
    return {
        {{0, 0, 1}, {0, 0, 1}, DirPair::Any, "normal"},
        {{0.6, 0, 0.8}, {-0.48, 0.6, 0.64}, DirPair::Any, "off-specular"},
        {{s60, 0, 0.5}, {-s60, 0, 0.5}, DirPair::Any, "mirror 60deg"},
        {{grazing(1e-7), 0, 1e-7}, {0, 0, 1}, DirPair::Any, "wi grazing 1e-7"},
        {{grazing(1e-4), 0, 1e-4}, {-grazing(1e-4), 0, 1e-4}, DirPair::Any, "both grazing, mirror"},
        {{grazing(1e-2), 0, 1e-2}, {grazing(1e-2), 0, 1e-2}, DirPair::Any, "both grazing, retro"},
        {{0, grazing(1e-7), 1e-7}, {grazing(1e-7), 0, 1e-7}, DirPair::Any, "grazing, 90deg azimuth"},
        {{1, 0, 0}, {0, 0, 1}, DirPair::Zero, "wi on the horizon"},
        {{0.6, 0, -0.8}, {0, 0, 1}, DirPair::Zero, "wi below the horizon"},
        {{0, 0, 1}, {0, 0.6, -0.8}, DirPair::Zero, "wo below the horizon"},
        {{0.6, 0, 0.8}, {-0.6, 0, -0.8}, DirPair::Zero, "wi = -wo"},
        {{1, 0, 0}, {-1, 0, 0}, DirPair::Zero, "wi + wo = 0 on the horizon"},
        {{0, 0, 1.0005}, {0, 0, 0.9995}, DirPair::Any, "non-unit within 1e-3"},
        {{1e-310, -1e-310, 1}, {0, 0, 1}, DirPair::Any, "denormal components"},
        {{0, 0, 1.1}, {0, 0, 1}, DirPair::Invalid, "wi length 1.1"},
        {{0, 0, 0}, {0, 0, 1}, DirPair::Invalid, "wi zero"},
        {{nan, 0, 1}, {0, 0, 1}, DirPair::Invalid, "wi NaN"},
        {{0, 0, 1}, {0, inf, 1}, DirPair::Invalid, "wo Inf"},
    };
}

struct EvalStats {
    long evals = 0, valid = 0, invalid = 0;
    long energyReplaced = 0;  // materials evaluated with energy = none (see runOne)
    long maskingReplaced = 0;  // Smith over a tabulated Lambda evaluated with masking = none
};

void checkMaterialEval(const CheckedMaterial& m, Rng& rng, Failures& fail, const std::string& where, EvalStats& st) {
    static const std::vector<DirPair> pairs = directionPairs();
    Interpreter<double> interp(m);
    bool wholeSphere = false;
    for (const CheckedLobe& lobe : m.lobes) wholeSphere |= lobe.wholeSphere();
    // Slot sets: defaults (null), defaults (explicit), and perturbed values
    // that clamping must tame; then NaN and Inf in one slot (must be invalid).
    std::vector<std::vector<double>> sets;
    sets.push_back(m.defaultSlots());
    static const double odd[] = {0, -0.0, -1, 1e-300, 1e300, 0.5, 2, 4.9e-324, 1e-4, 1e6, -1e300};
    std::vector<double> perturbed = m.defaultSlots();
    for (double& v : perturbed)
        if (rng.chance(60)) v = odd[rng.below(std::size(odd))];
    sets.push_back(perturbed);
    // Only a slot the material reads can invalidate a lane: an input no
    // model argument depends on is never loaded (SPEC 2), so NaN there is
    // ignored by design.
    std::vector<int> readSlots;
    const std::vector<bool> read = m.readByModels().slots;
    for (size_t s = 0; s < read.size(); ++s)
        if (read[s]) readSlots.push_back(int(s));
    for (int variant = 0; variant < (readSlots.empty() ? 0 : 2); ++variant) {
        std::vector<double> bad = m.defaultSlots();
        bad[size_t(readSlots[rng.below(readSlots.size())])] = variant ? std::numeric_limits<double>::infinity()
                                            : std::numeric_limits<double>::quiet_NaN();
        sets.push_back(bad);
    }
    for (size_t si = 0; si <= sets.size(); ++si) {
        const double* slots = si == 0 ? nullptr : sets[si - 1].data();
        bool badSlots = si >= 3;
        for (const DirPair& p : pairs) {
            EvalResult<double> r = interp.eval(p.wi.data(), p.wo.data(), slots);
            ++st.evals;
            (r.valid ? st.valid : st.invalid)++;
            auto report = [&](const char* what) {
                fail.add(fmt::format("{}: material '{}', slot set {}, directions '{}': {} (valid={}, rgb={}, {}, {})",
                                     where, m.name, si, p.what, what, r.valid, r.rgb[0], r.rgb[1], r.rgb[2]));
            };
            if (r.valid) {
                for (double v : r.rgb)
                    if (!std::isfinite(v) || v < 0) report("a valid result is not finite and >= 0");
                // A lobe that scatters below the surface (SPEC 11) is not 0
                // for a direction below it; on the horizon it is.
                bool belowCounts = !(wholeSphere && (p.wi[2] < 0 || p.wo[2] < 0));
                if (p.expect == DirPair::Zero && belowCounts && (r.rgb[0] != 0 || r.rgb[1] != 0 || r.rgb[2] != 0))
                    report("non-zero below/on the horizon (SPEC 2: f = 0)");
                if (p.expect == DirPair::Invalid) report("a non-finite or non-unit direction was accepted");
                if (badSlots) report("a NaN/Inf input was accepted (SPEC 2: invalid lane)");
            } else if (r.rgb[0] != 0 || r.rgb[1] != 0 || r.rgb[2] != 0) {
                report("an invalid result is not 0");
            }
            // Reciprocity f(wi, wo) = f(wo, wi) holds for every model in
            // exact arithmetic; rounding differs only in the last bits. The
            // dielectric's total-internal-reflection cut-off is a step, so a
            // rounding difference in wi.h against wo.h may legitimately
            // jump across it: skip that one.
            bool step = false;
            for (const CheckedLobe& lobe : m.lobes) step |= fresnelEntry(*lobe.fresnel.model).reciprocityStep;
            if (r.valid && p.expect == DirPair::Any && !step) {
                EvalResult<double> q = interp.eval(p.wo.data(), p.wi.data(), slots);
                for (int c = 0; c < 3 && q.valid; ++c) {
                    double a = r.rgb[c], b = q.rgb[c];
                    if (std::fabs(a - b) > 1e-9 * std::max(std::fabs(a), std::fabs(b)) + 1e-300) {
                        report(fmt::format("not reciprocal: f(wo, wi)[{}] = {}", c, b).c_str());
                        break;
                    }
                }
            }
        }
    }
}

struct Outcome {
    bool checked = false;
    size_t diagnostics = 0;
    std::string firstMessage;
};

struct RunOptions {
    bool determinism = false;  // compile twice, compare diagnostics
    bool lexCheck = true;      // lex separately and check token invariants
    bool fullEval = true;      // every direction pair and slot set, else one evaluation
};

// Compiles one text and checks every promise; returns what happened.
Outcome runOne(const std::string& text, Rng& rng, Failures& fail, const std::string& where, EvalStats& st,
               const RunOptions& opt) {
    Outcome out;
    std::vector<size_t> lines = lineLengths(text);
    // Lexer invariants: ends with End, locations 1-based and in order.
    if (opt.lexCheck) {
        std::vector<Token> toks = lex(text, std::make_shared<const std::string>(kMutantName));
        if (toks.empty() || toks.back().kind != TokenKind::End) fail.add(where + ": lex() does not end with End");
        for (size_t i = 0; i < toks.size(); ++i) {
            const SourceLoc& l = toks[i].loc;
            if (l.line < 1 || l.col < 1) {
                fail.add(where + ": token with a location that is not 1-based");
                break;
            }
            if (i && std::pair(l.line, l.col) < std::pair(toks[i - 1].loc.line, toks[i - 1].loc.col)) {
                fail.add(where + ": token locations go backwards");
                break;
            }
        }
        if (toks.size() > text.size() + 2) fail.add(where + ": more tokens than bytes");
    }
    DiagnosticEngine diags;
    CheckedProgram prog;
    try {
        prog = loadProgramText(text, kMutantName, diags);
    } catch (const CompileError&) {
        // Allowed by the API contract; its diagnostics are checked below.
    } catch (const InternalError& e) {
        fail.add(where + ": InternalError: " + e.what());
        return out;
    } catch (const std::exception& e) {
        fail.add(where + ": unexpected exception: " + e.what());
        return out;
    }
    out.diagnostics = diags.diagnostics().size();
    if (diags.hasErrors()) {
        if (!prog.materials.empty()) fail.add(where + ": diagnostics, yet loadProgramText returned materials");
        if (diags.diagnostics().size() > DiagnosticEngine::kMaxErrors + 1)
            fail.add(where + ": more diagnostics than the error limit");
        for (const Diagnostic& d : diags.diagnostics()) {
            std::string problem = diagnosticProblem(d, lines);
            if (!problem.empty()) fail.add(where + ": diagnostic " + problem + ": " + d.str().substr(0, 300));
        }
        out.firstMessage = diags.diagnostics().front().message;
    } else {
        out.checked = true;
        if (prog.materials.empty()) fail.add(where + ": no diagnostics and no materials");
        for (const CheckedMaterial& m : prog.materials) {
            for (const CheckedLobe& lobe : m.lobes)
                if ((!lobe.ndf.model && lobe.implicit) || !lobe.masking.model ||
                    !lobe.fresnel.model || !lobe.energy.model || !lobe.diffuse.model) {
                    fail.add(where + ": checked material '" + m.name + "' has an unset model slot");
                    return out;
                }
            int slots = 0;
            for (const CheckedInput& in : m.inputs) slots += in.slotCount();
            if (slots != m.slotCount) fail.add(where + ": slotCount does not add up");
            for (int s = 0; s < m.slotCount; ++s)
                if (m.slotName(s).empty()) fail.add(where + ": slot without a name");
        }
        // Cap the work per mutant: a splice can produce dozens of materials.
        for (size_t i = 0; i < prog.materials.size() && i < (opt.fullEval ? 4u : 1u); ++i) {
            // energy = kulla_conty makes the interpreter integrate its albedo
            // table on first use: ~0.5 s in a release build, about a minute
            // under ASan, per mutant. Evaluate every other term with energy
            // = none instead; the Kulla-Conty term has its own physics tests.
            CheckedMaterial m = prog.materials[i];
            for (CheckedLobe& lobe : m.lobes)
                if (lobe.compensatesEnergy()) {
                    lobe.energy.model = findModel(ModelSlot::Energy, "none");
                    ++st.energyReplaced;
                }
            // Likewise a Smith masking over a tabulated Lambda builds the
            // NDF's table on first use, and a mutated shape value is a new
            // table: seconds in a release build, most of a minute under
            // ASan. Evaluate with masking = none; the tables have their own
            // tests (tests/energy LambdaTableTests, the hard cases).
            for (CheckedLobe& lobe : m.lobes)
                if (lobe.hasNdf() && lobe.masking.model->smith && ndfEntry(*lobe.ndf.model).tabulatedLambda) {
                    lobe.masking.model = findModel(ModelSlot::Masking, "none");
                    ++st.maskingReplaced;
                }
            try {
                if (!opt.fullEval) {  // stress inputs: one evaluation proves the interpreter copes
                    const double n[3] = {0, 0, 1};
                    EvalResult<double> r = Interpreter<double>(m).eval(n, n, nullptr);
                    ++st.evals;
                    for (double v : r.rgb)
                        if (!std::isfinite(v) || v < 0) fail.add(where + ": a result is not finite and >= 0");
                    continue;
                }
                checkMaterialEval(m, rng, fail, where, st);
            } catch (const std::exception& e) {
                fail.add(where + ": exception while evaluating: " + e.what());
            }
        }
    }
    // The compiler is a function of its input: the same text gives the same
    // diagnostics (no hidden state between two compilations).
    if (opt.determinism) {
        DiagnosticEngine again;
        try {
            loadProgramText(text, kMutantName, again);
        } catch (...) {
        }
        if (again.str() != diags.str()) fail.add(where + ": a second compilation gave different diagnostics");
    }
    return out;
}

// ---- crash reporting ---------------------------------------------------------
// A sanitizer report ends the process; before it does, save what it was
// working on so that the crash can be replayed with --only or `facet check`.
std::string gDumpDir = ".";
const std::string* gCurrentText = nullptr;
std::string gCurrentWhere;

#ifdef FACET_HAVE_SANITIZER_CALLBACK
void onSanitizerDeath() {
    if (!gCurrentText) return;
    std::string path = gDumpDir + "/fuzz_crash_mutant.mat";
    if (FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(gCurrentText->data(), 1, gCurrentText->size(), f);
        std::fclose(f);
    }
    std::fprintf(stderr, "\n*** crash while processing %s; input saved to %s\n", gCurrentWhere.c_str(), path.c_str());
}
#endif

void dumpFailure(const std::string& text, const std::string& name) {
    std::string path = gDumpDir + "/" + name;
    if (FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(text.data(), 1, text.size(), f);
        std::fclose(f);
    }
}

// A short "kind" of a message for the statistics: quoted parts and numbers
// blanked out, e.g. "expected ';' after the ndf statement, found 'x'" ->
// "expected '_' after the ndf statement, found '_'".
std::string messageKind(const std::string& msg) {
    std::string k;
    bool quoted = false;
    for (char c : msg) {
        if (c == '\'') {
            if (!quoted) k += "'_'";
            quoted = !quoted;
        } else if (!quoted && !(std::isdigit((unsigned char)c) && !k.empty() && k.back() == '#')) {
            k += std::isdigit((unsigned char)c) ? '#' : c;
        }
        if (k.size() >= 70) break;
    }
    return k;
}

// ---- the mutation run ---------------------------------------------------------
int runMutants(uint64_t seed, long count, long only, const std::vector<std::string>& corpusDirs, bool verbose) {
    std::vector<Seed> seeds;
    for (size_t i = 0; i < std::size(kEmbeddedSeeds); ++i)
        seeds.push_back({fmt::format("<embedded seed {}>", i), kEmbeddedSeeds[i]});
    size_t embedded = seeds.size();
    for (const std::string& d : corpusDirs) addSeedFiles(d, seeds);
    std::vector<std::string> vocab = buildVocabulary(), idents = identifierVocabulary(vocab);
    Context cx{seeds, vocab, idents};
    std::printf("facet_fuzz_mutants: seed %llu, %zu seed files (%zu embedded, %zu from disk), %ld mutants\n",
                (unsigned long long)seed, seeds.size(), embedded, seeds.size() - embedded, only >= 0 ? 1L : count);

    Failures fail;
    EvalStats st;
    // Every unmutated seed first: a seed that crashes is the simplest reproducer.
    for (const Seed& s : seeds) {
        Rng rng(seed);
        gCurrentText = &s.text;
        gCurrentWhere = s.name;
        runOne(s.text, rng, fail, s.name, st, RunOptions{});
    }

    long checkedOk = 0, withDiags = 0, totalDiags = 0;
    std::map<std::string, long> kinds;
    std::map<std::string, std::pair<long, long>> perMutator;  // ok, diagnostics
    double slowest = 0;
    long slowestIndex = -1;
    size_t totalBytes = 0;
    auto start = std::chrono::steady_clock::now();
    long first = only >= 0 ? only : 0, last = only >= 0 ? only + 1 : count;
    for (long i = first; i < last; ++i) {
        Mutant m = makeMutant(seed, uint64_t(i), cx);
        totalBytes += m.text.size();
        std::string where = fmt::format("mutant {} ({})", i, m.recipe);
        gCurrentText = &m.text;
        gCurrentWhere = where;
        Rng evalRng(seed ^ (uint64_t(i) << 20) ^ 0x5eed);
        int before = fail.count;
        auto t0 = std::chrono::steady_clock::now();
        RunOptions opt;
        opt.determinism = i % 16 == 0;
        Outcome o = runOne(m.text, evalRng, fail, where, st, opt);
        double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (dt > slowest) {
            slowest = dt;
            slowestIndex = i;
        }
        // SPEC 1 "never hangs": nothing built from a small seed may take seconds.
        if (dt > 5.0) fail.add(fmt::format("{}: took {:.2f} s", where, dt));
        if (fail.count != before) dumpFailure(m.text, fmt::format("fuzz_failure_{}.mat", i));
        std::string firstMut = m.recipe.substr(m.recipe.find(" + ") + 3);
        firstMut = firstMut.substr(0, firstMut.find(" + "));
        if (o.checked) {
            ++checkedOk;
            ++perMutator[firstMut].first;
        } else {
            ++withDiags;
            totalDiags += long(o.diagnostics);
            ++kinds[messageKind(o.firstMessage)];
            ++perMutator[firstMut].second;
        }
        if (verbose) std::printf("%s: %s\n", where.c_str(), o.checked ? "ok" : o.firstMessage.c_str());
    }
    gCurrentText = nullptr;
    double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    long n = last - first;

    std::printf("\nmutants: %ld (%.1f KiB of source in all)\n", n, totalBytes / 1024.0);
    std::printf("  checked ok, evaluated:  %ld (%.1f%%)\n", checkedOk, n ? 100.0 * checkedOk / n : 0.0);
    std::printf("  rejected with diagnostics: %ld (%.1f%%), %ld diagnostics in all\n", withDiags,
                n ? 100.0 * withDiags / n : 0.0, totalDiags);
    std::printf("  interpreter evaluations: %ld (%ld valid, %ld reported invalid)\n", st.evals, st.valid, st.invalid);
    std::printf("  materials with energy = kulla_conty evaluated with energy = none: %ld\n", st.energyReplaced);
    std::printf("  materials with a Smith masking over a tabulated Lambda evaluated with masking = none: %ld\n",
                st.maskingReplaced);
    std::printf("  time: %.2f s in all, %.1f us per mutant on average, slowest %.1f ms (mutant %ld)\n", total,
                n ? 1e6 * total / n : 0.0, 1e3 * slowest, slowestIndex);
    std::printf("\nper first mutator (checked ok / diagnostics):\n");
    for (const auto& [name, c] : perMutator) std::printf("  %-16s %6ld / %6ld\n", name.c_str(), c.first, c.second);
    std::vector<std::pair<long, std::string>> sorted;
    for (const auto& [k, c] : kinds) sorted.push_back({c, k});
    std::sort(sorted.rbegin(), sorted.rend());
    std::printf("\nmost frequent first diagnostics:\n");
    for (size_t i = 0; i < sorted.size() && i < 15; ++i)
        std::printf("  %6ld  %s\n", sorted[i].first, sorted[i].second.c_str());

    if (fail.count) {
        std::printf("\nFAILED: %d check(s) failed (failing mutants written to %s/fuzz_failure_*.mat):\n", fail.count,
                    gDumpDir.c_str());
        for (const std::string& note : fail.notes) std::printf("  %s\n", note.c_str());
        return 1;
    }
    std::printf("\nOK: no crash, no sanitizer report, every diagnostic well-formed, every BRDF value finite and >= 0\n");
    return 0;
}

// ---- stress cases ---------------------------------------------------------------
// Each case is a generator and an expectation; each runs in a forked child so
// that a stack overflow or a hang in one is reported and the others still run.
struct StressCase {
    const char* name;
    const char* why;
    std::string (*make)();
    int seconds;  // CPU time limit in the ASan build
};

std::string repeat(const std::string& unit, size_t n) {
    std::string out;
    out.reserve(unit.size() * n);
    for (size_t i = 0; i < n; ++i) out += unit;
    return out;
}

// Sizes are chosen so that a front end that is linear in its input and does
// not recurse per operand finishes each case in a few seconds even in this
// ASan build on a loaded two-core machine, while the quadratic or recursive
// behaviour each case targets takes minutes or overflows the stack.
const std::vector<StressCase> kStressCases = {
    // -- recursion over left-associative operator chains. The parser bounds
    //    nesting, but 'a+b+c...' is built by a loop, so the tree is as deep
    //    as the chain is long, and every tree walk recurses once per operand.
    {"left-assoc chain 1+1+...+1, 200k terms (400 KB), in a let",
     "checker: MaterialChecker::typeOf/computeType recurse once per operand",
     [] { return "material m { let a = 1" + repeat("+1", 200000) + "; ndf = ggx(min(a, 0.5)); }\n"; }, 20},
    {"left-assoc chain 1-1-...-1, 3000 terms (6 KB), evaluated",
     "a small file: the checker's frame is ~4.6 KB in the ASan build, so its recursion fails early there",
     [] { return "material m { let a = 1" + repeat("-1", 3000) + "; ndf = ggx(min(0.5, 0.5 + a * a)); }\n"; }, 20},
    {"left-assoc chain 1*1*...*1, 20k terms (40 KB), evaluated",
     "interpreter: in a release build `facet check` accepts 15k terms, but evaluateExpr overflows in `facet eval`",
     [] { return "material m { let a = 1" + repeat("*1", 20000) + "; ndf = ggx(0.5 * a); }\n"; }, 20},
    {"left-assoc chain of 500k terms in a material with a syntax error",
     "the material is dropped unchecked: only the parser and the tree's recursive destructor run",
     [] { return "material m { let a = 1" + repeat("+1", 500000) + "; ndf = ggx(0.5); @ }\n"; }, 20},
    // -- super-linear time.
    {"300k duplicate 'let a=1;' statements (2.4 MB)",
     "checker: every duplicate is remembered (also past the 50-error cap) and looked up linearly per statement",
     [] { return "material m { " + repeat("let a=1;", 300000) + " ndf = ggx(0.5); }\n"; }, 5},
    {"ggx with 300k positional arguments (600 KB)",
     "checker: 'positional after named' scans every earlier argument for every argument",
     [] { return "material m { ndf = ggx(" + repeat("1,", 300000) + "1); }\n"; }, 5},
    {"5000 statements 'let zN = b;' with b undefined (60 KB)",
     "checker: each undefined name builds a 'did you mean' over all names, even after the 50-error cap",
     [] {
         std::string s = "material m { ";
         for (int i = 0; i < 5000; ++i) s += fmt::format("let z{}=b;", i);
         return s + " ndf = ggx(0.5); }\n";
     },
     5},
    {"a 1 MB let name and a 1 MB undefined name",
     "checker: 'did you mean' runs a full edit distance between the two names: 1e12 steps",
     [] {
         return "material m { let " + repeat("a", 1000000) + " = 1; let b = " + repeat("b", 1000000) +
                "; ndf = ggx(0.5); }\n";
     },
     5},
    // -- controls: pathological, and handled well.
    {"1M '(' (bounded nesting)", "must stop at the nesting limit with one diagnostic",
     [] { return "material m { let a = " + repeat("(", 1000000) + "1; ndf = ggx(0.5); }\n"; }, 20},
    {"1M unary '-'", "unary minus recursion is bounded too",
     [] { return "material m { let a = " + repeat("-", 1000000) + "1; ndf = ggx(0.5); }\n"; }, 20},
    {"2^2^...^2, 500k levels", "'^' is right-associative and recursive, and bounded",
     [] { return "material m { let a = " + repeat("2^", 500000) + "2; ndf = ggx(0.5); }\n"; }, 20},
    {"sqrt(sqrt(...)) 500k deep", "call nesting goes through expression() and is bounded",
     [] { return "material m { let a = " + repeat("sqrt(", 500000) + "1" + repeat(")", 500000) + "; ndf = ggx(0.5); }\n"; }, 20},
    {"sqrt with 1M arguments", "a function's arity is checked once, not per pair of arguments",
     [] { return "material m { let a = sqrt(" + repeat("1,", 1000000) + "1); ndf = ggx(0.5); }\n"; }, 20},
    {"4 MB of '@' (4M error tokens)",
     "the lexer makes a token (and a message string) per bad byte before the parser stops at 50 errors",
     [] { return repeat("@", (4u << 20) - 16); }, 30},
    {"file of 4 MB + 1 byte", "must be one 'file is too large' diagnostic without a location",
     [] { return repeat(" ", (4u << 20) + 1); }, 20},
    {"a 3 MB number literal", "strtod on a huge mantissa",
     [] { return "material m { ndf = ggx(0." + repeat("1", 3000000) + "); }\n"; }, 20},
    {"100k materials with the same name", "duplicate-material reporting over many materials",
     [] { return repeat("material m { ndf = ggx(0.5); }\n", 100000); }, 30},
    {"unterminated comment over 4 MB", "one diagnostic, no quadratic rescanning",
     [] { return "material m { ndf = ggx(0.5); } /*" + repeat("*", (4u << 20) - 40); }, 20},
    {"1M lines then an error", "line numbers far from the start",
     [] { return "material m {" + repeat("\n", 1000000) + " ndf = ggx(0.5) }\n"; }, 20},
};

int runStress() {
    std::printf("facet_fuzz_mutants --stress: %zu cases, each in its own process\n\n", kStressCases.size());
    int failed = 0;
    for (const StressCase& c : kStressCases) {
        std::string text = c.make();
        std::fflush(stdout);
        auto t0 = std::chrono::steady_clock::now();
        pid_t pid = fork();
        if (pid == 0) {
            // The limit is CPU time (SIGXCPU), so that a loaded machine does
            // not turn a slow pass into a failure; the wall-clock alarm is
            // only a backstop for a child that blocks without using CPU.
            struct rlimit cpu {rlim_t(c.seconds), rlim_t(c.seconds + 2)};
            setrlimit(RLIMIT_CPU, &cpu);
            alarm(unsigned(c.seconds * 10));
            gCurrentText = &text;
            gCurrentWhere = c.name;
            Failures fail;
            EvalStats st;
            Rng rng(1);
            RunOptions opt;
            opt.lexCheck = false;  // time the compiler, not this harness
            opt.fullEval = false;
            Outcome o = runOne(text, rng, fail, c.name, st, opt);
            std::printf("    %s\n", o.checked ? "checked ok" : ("first diagnostic: " + o.firstMessage.substr(0, 100)).c_str());
            for (const std::string& n : fail.notes) std::printf("    check failed: %s\n", n.substr(0, 300).c_str());
            std::fflush(stdout);
            _exit(fail.count ? 3 : 0);
        }
        int status = 0;
        struct rusage ru {};
        wait4(pid, &status, 0, &ru);
        double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::string verdict;
        if (WIFEXITED(status) && WEXITSTATUS(status) == 0) verdict = "pass";
        else if (WIFSIGNALED(status) && (WTERMSIG(status) == SIGXCPU || WTERMSIG(status) == SIGKILL))
            verdict = fmt::format("FAIL: no result after {} s of CPU time (hang or super-linear time)", c.seconds);
        else if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM)
            verdict = fmt::format("FAIL: no result after {} s of wall time", c.seconds * 10);
        else if (WIFSIGNALED(status)) verdict = fmt::format("FAIL: killed by signal {} ({})", WTERMSIG(status), strsignal(WTERMSIG(status)));
        else if (WEXITSTATUS(status) == 3) verdict = "FAIL: a check failed (see above)";
        else verdict = fmt::format("FAIL: exit status {} (sanitizer report above: crash)", WEXITSTATUS(status));
        if (verdict != "pass") ++failed;
        double cpu = ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
        std::printf("[%s] %s\n    %.2f s CPU (%.2f s wall), max RSS %.0f MiB, input %.1f MiB -- %s\n\n",
                    verdict == "pass" ? "pass" : "FAIL", c.name, cpu, dt, ru.ru_maxrss / 1024.0, text.size() / 1048576.0,
                    verdict == "pass" ? c.why : verdict.c_str());
        if (verdict != "pass") {
            std::printf("    (why this case: %s)\n\n", c.why);
        }
    }
    std::printf("%d of %zu stress cases failed\n", failed, kStressCases.size());
    return failed ? 1 : 0;
}

// --file PATH: every check of the mutation run on one file, e.g. a
// fuzz_crash_mutant.mat written by an earlier run, or a new stress input.
int runFiles(const std::vector<std::string>& files) {
    int failed = 0;
    for (const std::string& path : files) {
        std::ifstream in(path, std::ios::binary);
        if (!in) {
            std::fprintf(stderr, "%s: cannot open\n", path.c_str());
            return 2;
        }
        std::stringstream ss;
        ss << in.rdbuf();
        std::string text = ss.str();
        gCurrentText = &text;
        gCurrentWhere = path;
        Failures fail;
        EvalStats st;
        Rng rng(1);
        auto t0 = std::chrono::steady_clock::now();
        RunOptions opt;
        opt.determinism = true;
        Outcome o = runOne(text, rng, fail, path, st, opt);
        double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%s: %s (%.3f s, %ld evaluations)\n", path.c_str(),
                    o.checked ? "checked ok" : ("first diagnostic: " + o.firstMessage.substr(0, 200)).c_str(), dt,
                    st.evals);
        for (const std::string& n : fail.notes) std::printf("  check failed: %s\n", n.c_str());
        failed += fail.count ? 1 : 0;
    }
    return failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
    uint64_t seed = 20240601;
    long count = 20000, only = -1;
    bool stress = false, defaultCorpus = true, verbose = false;
    std::vector<std::string> dirs, files;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "%s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--seed") seed = std::stoull(value());
        else if (a == "--count") count = std::stol(value());
        else if (a == "--only") only = std::stol(value());
        else if (a == "--corpus") dirs.push_back(value());
        else if (a == "--no-default-corpus") defaultCorpus = false;
        else if (a == "--dump") gDumpDir = value();
        else if (a == "--stress") stress = true;
        else if (a == "--verbose") verbose = true;
        else if (a == "--file") files.push_back(value());
        else if (!a.empty() && std::isdigit((unsigned char)a[0])) seed = std::stoull(a);  // bare seed
        else {
            std::fprintf(stderr,
                         "usage: %s [SEED] [--seed N] [--count N] [--only INDEX] [--corpus DIR]... "
                         "[--no-default-corpus] [--dump DIR] [--verbose] | --stress | --file PATH...\n",
                         argv[0]);
            return 2;
        }
    }
    if (defaultCorpus) {
        dirs.insert(dirs.begin(), std::string(FACET_SOURCE_DIR) + "/tests/corpus");
        dirs.insert(dirs.begin(), std::string(FACET_SOURCE_DIR) + "/materials");
    }
#ifdef FACET_HAVE_SANITIZER_CALLBACK
    __sanitizer_set_death_callback(onSanitizerDeath);
#endif
    if (!files.empty()) return runFiles(files);
    return stress ? runStress() : runMutants(seed, count, only, dirs, verbose);
}
