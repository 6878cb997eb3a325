// BenchOutputTests: the `facet bench` report is complete and well formed.
//
// One quick bench of the GGX/Schlick reference model (AOT twin included) is
// shared by the tests: its JSON must parse (a small strict JSON parser below)
// and carry every field with the right type for every row, and the scatter
// plot must be written with the documented size. A quick bench of
// materials/gold.mat (energy = kulla_conty) must report its Kulla-Conty
// table (cold build, cached load) in the JSON, Markdown and terminal output,
// and bench/models/student_t_plastic.mat its Smith Lambda table.
#include "BenchFormat.h"
#include "BenchPlot.h"
#include "BenchRunner.h"
#include "Checker.h"
#include "KullaConty.h"
#include "LambdaTable.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>

#include <cmath>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <variant>

using namespace facet;

namespace {

// ---- a strict JSON parser (RFC 8259 subset: no \u escapes beyond ASCII) ----
struct JsonValue;
using JsonObject = std::map<std::string, JsonValue>;
using JsonArray = std::vector<JsonValue>;
struct JsonValue {
    std::variant<std::nullptr_t, bool, double, std::string, std::shared_ptr<JsonArray>, std::shared_ptr<JsonObject>> v;
    bool isNull() const { return std::holds_alternative<std::nullptr_t>(v); }
    bool isNumber() const { return std::holds_alternative<double>(v); }
    bool isString() const { return std::holds_alternative<std::string>(v); }
    bool isBool() const { return std::holds_alternative<bool>(v); }
    bool isArray() const { return std::holds_alternative<std::shared_ptr<JsonArray>>(v); }
    bool isObject() const { return std::holds_alternative<std::shared_ptr<JsonObject>>(v); }
    double num() const { return std::get<double>(v); }
    const std::string& str() const { return std::get<std::string>(v); }
    const JsonArray& arr() const { return *std::get<std::shared_ptr<JsonArray>>(v); }
    const JsonObject& obj() const { return *std::get<std::shared_ptr<JsonObject>>(v); }
};

class JsonParser {
public:
    explicit JsonParser(const std::string& s) : s_(s) {}
    JsonValue parseDocument() {
        JsonValue v = value();
        ws();
        if (p_ != s_.size()) fail("trailing characters");
        return v;
    }

private:
    [[noreturn]] void fail(const std::string& why) {
        throw std::runtime_error("JSON: " + why + " at offset " + std::to_string(p_));
    }
    void ws() {
        while (p_ < s_.size() && (s_[p_] == ' ' || s_[p_] == '\n' || s_[p_] == '\t' || s_[p_] == '\r')) ++p_;
    }
    bool eat(char c) {
        ws();
        if (p_ < s_.size() && s_[p_] == c) return ++p_, true;
        return false;
    }
    void expect(char c) {
        if (!eat(c)) fail(std::string("expected '") + c + "'");
    }
    bool literal(const char* word) {
        size_t n = std::strlen(word);
        if (s_.compare(p_, n, word) == 0) return p_ += n, true;
        return false;
    }
    std::string string() {
        expect('"');
        std::string out;
        while (p_ < s_.size() && s_[p_] != '"') {
            char c = s_[p_++];
            if (static_cast<unsigned char>(c) < 0x20) fail("control character in string");
            if (c == '\\') {
                if (p_ >= s_.size()) fail("bad escape");
                char e = s_[p_++];
                switch (e) {
                    case '"': case '\\': case '/': out += e; break;
                    case 'n': out += '\n'; break;
                    case 't': out += '\t'; break;
                    case 'r': out += '\r'; break;
                    case 'b': out += '\b'; break;
                    case 'f': out += '\f'; break;
                    case 'u': {
                        if (p_ + 4 > s_.size()) fail("bad \\u escape");
                        out += char(std::stoi(s_.substr(p_, 4), nullptr, 16));
                        p_ += 4;
                        break;
                    }
                    default: fail("bad escape");
                }
            } else {
                out += c;
            }
        }
        expect('"');
        return out;
    }
    double number() {
        size_t start = p_;
        if (s_[p_] == '-') ++p_;
        if (p_ >= s_.size() || !std::isdigit(static_cast<unsigned char>(s_[p_]))) fail("bad number");
        while (p_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[p_])) || std::strchr(".eE+-", s_[p_]))) ++p_;
        size_t used = 0;
        double v = std::stod(s_.substr(start, p_ - start), &used);
        if (used != p_ - start) fail("bad number");
        return v;
    }
    JsonValue value() {
        ws();
        if (p_ >= s_.size()) fail("unexpected end");
        char c = s_[p_];
        if (c == '{') {
            ++p_;
            auto o = std::make_shared<JsonObject>();
            if (!eat('}')) {
                do {
                    ws();
                    std::string k = string();
                    expect(':');
                    if (o->count(k)) fail("duplicate key " + k);
                    (*o)[k] = value();
                } while (eat(','));
                expect('}');
            }
            return {o};
        }
        if (c == '[') {
            ++p_;
            auto a = std::make_shared<JsonArray>();
            if (!eat(']')) {
                do a->push_back(value());
                while (eat(','));
                expect(']');
            }
            return {a};
        }
        if (c == '"') return {string()};
        if (literal("true")) return {true};
        if (literal("false")) return {false};
        if (literal("null")) return {nullptr};
        return {number()};
    }
    const std::string& s_;
    size_t p_ = 0;
};

// A quick bench of one file (path relative to the source tree).
bench::BenchReport quickBench(const std::string& file) {
    bench::BenchReport r;
    r.settings = bench::BenchSettings::quickSettings();
    r.settings.lanes = 2048;
    r.settings.runs = 3;
    r.settings.compileRuns = 1;
    bench::describeHost(r);
    DiagnosticEngine diags;
    bool ok = bench::benchFile(std::string(FACET_SOURCE_DIR) + "/" + file, r.settings, r, diags, nullptr);
    if (!ok) throw std::runtime_error(diags.str());
    return r;
}

// The report of one quick bench, computed once for all tests here.
const bench::BenchReport& quickReport() {
    static const bench::BenchReport report = quickBench("bench/models/ggx_schlick.mat");
    return report;
}

// The same for a material with energy = kulla_conty (GGX, height-correlated Smith).
const bench::BenchReport& kullaContyReport() {
    static const bench::BenchReport report = quickBench("materials/gold.mat");
    return report;
}

// What printTable writes for `report`.
std::string terminalReport(const bench::BenchReport& report) {
    char* buf = nullptr;
    size_t size = 0;
    std::FILE* out = open_memstream(&buf, &size);
    REQUIRE(out);
    bench::printTable(report, out);
    std::fclose(out);
    std::string text(buf, size);
    std::free(buf);
    return text;
}

// The JSON of a one-material report, parsed: that material's object.
JsonObject materialJson(const bench::BenchReport& report) {
    std::string text = bench::json(report);
    JsonValue doc = JsonParser(text).parseDocument();
    const JsonArray& materials = doc.obj().at("materials").arr();
    REQUIRE(materials.size() == 1);
    return materials[0].obj();
}

enum class Kind { Number, String, Bool, Object, Array, NumberOrNull, StringOrNull, ObjectOrNull };

void checkField(const JsonObject& o, const std::string& key, Kind kind) {
    CAPTURE(key);
    auto it = o.find(key);
    REQUIRE_MESSAGE(it != o.end(), "missing field " << key);
    const JsonValue& v = it->second;
    switch (kind) {
        case Kind::Number: CHECK(v.isNumber()); break;
        case Kind::String: CHECK(v.isString()); break;
        case Kind::Bool: CHECK(v.isBool()); break;
        case Kind::Object: CHECK(v.isObject()); break;
        case Kind::Array: CHECK(v.isArray()); break;
        case Kind::NumberOrNull: CHECK((v.isNumber() || v.isNull())); break;
        case Kind::StringOrNull: CHECK((v.isString() || v.isNull())); break;
        case Kind::ObjectOrNull: CHECK((v.isObject() || v.isNull())); break;
    }
}

void checkErrorBlock(const JsonObject& e) {
    for (const char* k : {"values", "skipped", "nonfinite", "negative", "invalid_lanes", "reference_invalid_lanes",
                          "max_rel", "p999_rel", "max_ulp"})
        checkField(e, k, Kind::Number);
    checkField(e, "worst", Kind::ObjectOrNull);
    if (e.at("worst").isObject()) {
        const JsonObject& w = e.at("worst").obj();
        for (const char* k : {"lane", "got", "want", "rel"}) checkField(w, k, Kind::Number);
        checkField(w, "channel", Kind::String);
        checkField(w, "wi", Kind::Array);
        checkField(w, "wo", Kind::Array);
        checkField(w, "inputs", Kind::Object);
        CHECK(w.at("wi").arr().size() == 3);
        CHECK(w.at("wo").arr().size() == 3);
    }
    CHECK(e.at("p999_rel").num() <= e.at("max_rel").num());
}

}  // namespace

TEST_SUITE("output") {

TEST_CASE("the JSON parser of this test rejects malformed documents") {
    for (const char* bad : {"{", "{\"a\":}", "[1,]", "{\"a\":1,\"a\":2}", "nan", "{\"a\":1} x", "\"\x01\""})
        CHECK_THROWS(JsonParser(bad).parseDocument());
    CHECK(JsonParser("{\"a\":[1,-2.5e3,null,true,\"x\\n\"]}").parseDocument().isObject());
}

TEST_CASE("bench --json output parses and has every field") {
    const bench::BenchReport& report = quickReport();
    std::string text = bench::json(report);
    JsonValue doc;
    REQUIRE_NOTHROW(doc = JsonParser(text).parseDocument());
    REQUIRE(doc.isObject());
    const JsonObject& top = doc.obj();
    checkField(top, "facet_bench_format", Kind::Number);
    checkField(top, "host", Kind::Object);
    checkField(top, "settings", Kind::Object);
    checkField(top, "materials", Kind::Array);
    const JsonObject& host = top.at("host").obj();
    checkField(host, "cpu", Kind::String);
    checkField(host, "features", Kind::String);
    checkField(host, "vector_width", Kind::Number);
    const JsonObject& settings = top.at("settings").obj();
    for (const char* k : {"lanes", "interp_lanes", "runs", "warmup", "compile_runs", "disk_runs", "seed", "abs_floor"})
        checkField(settings, k, Kind::Number);
    checkField(settings, "quick", Kind::Bool);
    checkField(settings, "hard_sample", Kind::String);

    const JsonArray& materials = top.at("materials").arr();
    REQUIRE(materials.size() == 1);
    const JsonObject& m = materials[0].obj();
    for (const char* k : {"file", "material", "aot_note", "kulla_conty_pair", "summary"}) checkField(m, k, Kind::String);
    checkField(m, "aot", Kind::StringOrNull);
    for (const char* k : {"parse_check_ms", "regular_lanes", "hard_lanes"}) checkField(m, k, Kind::Number);
    checkField(m, "kulla_conty_ms", Kind::NumberOrNull);
    checkField(m, "energy_table", Kind::ObjectOrNull);
    checkField(m, "lambda_table", Kind::ObjectOrNull);
    checkField(m, "rows", Kind::Array);
    CHECK(m.at("material").str() == "ggx_schlick");
    CHECK(m.at("aot").str() == "ggx_schlick");
    CHECK(m.at("energy_table").isNull());  // energy = none
    CHECK(m.at("kulla_conty_ms").isNull());
    CHECK(m.at("lambda_table").isNull());  // ggx: a closed-form Lambda
    checkField(m, "walk_comparison", Kind::ObjectOrNull);
    CHECK(m.at("walk_comparison").isNull());  // energy = none

    // Every backend x mode, and the AOT row.
    std::set<std::pair<std::string, std::string>> seen;
    for (const JsonValue& rv : m.at("rows").arr()) {
        const JsonObject& r = rv.obj();
        for (const char* k : {"backend", "mode", "options", "variant"}) checkField(r, k, Kind::String);
        for (const char* k : {"width", "lanes", "runs", "ns_per_eval", "ns_per_eval_min", "evals_per_second"})
            checkField(r, k, Kind::Number);
        for (const char* k : {"measured_error", "compile_cold_ms", "compile_tier_up_ms", "compile_cold_optimized_ms",
                              "compile_memory_hit_ms", "compile_disk_hit_ms", "jit_over_aot", "jit_over_bare"})
            checkField(r, k, Kind::NumberOrNull);
        std::string backend = r.at("backend").str(), mode = r.at("mode").str();
        checkField(r, "error_regular", Kind::Object);
        checkErrorBlock(r.at("error_regular").obj());
        // The bare row's host promises valid input: no hard-case error.
        checkField(r, "error_hard", mode == "bare" ? Kind::ObjectOrNull : Kind::Object);
        if (mode == "bare") CHECK(r.at("error_hard").isNull());
        else checkErrorBlock(r.at("error_hard").obj());
        CAPTURE(backend);
        CAPTURE(mode);
        seen.insert({backend, mode});
        CHECK(r.at("ns_per_eval").num() > 0);
        CHECK(r.at("evals_per_second").num() > 0);
        if (backend == "scalar" || backend == "simd") {
            CHECK(r.at("compile_cold_ms").isNumber());
            // Tiered by default: the optimized code comes from the tier-up.
            CHECK(r.at("compile_tier_up_ms").num() > 0);
            CHECK(r.at("compile_cold_optimized_ms").num() > 0);
            CHECK(r.at("compile_memory_hit_ms").isNumber());
            CHECK(r.at("compile_disk_hit_ms").isNumber());
            CHECK(r.at("jit_over_aot").isNumber());
            CHECK(r.at("jit_over_bare").isNumber());
        }
        // The bare loop computes the same BRDF in float.
        if (mode == "bare") CHECK(r.at("error_regular").obj().at("max_rel").num() < 1e-4);
        // The reference is compared with itself to float rounding.
        if (backend == "interp") CHECK(r.at("error_regular").obj().at("max_rel").num() < 1e-6);
    }
    for (const char* b : {"interp", "scalar", "simd"})
        for (const char* mode : {"exact", "fast", "tol 1e-3", "tol 1e-5"}) CHECK(seen.count({b, mode}));
    CHECK(seen.count({"aot", "hand-written"}));
    CHECK(seen.count({"aot", "bare"}));
    CHECK(seen.size() == 14);

    // ns/eval by batch size: simd exact and fast (also under assume=unit), the two AOT functions,
    // and the scalar entry at n = 1 only.
    checkField(m, "batch_sizes", Kind::Array);
    std::set<std::string> evaluators;
    for (const JsonValue& rv : m.at("batch_sizes").arr()) {
        const JsonObject& r = rv.obj();
        checkField(r, "evaluator", Kind::String);
        checkField(r, "ns_per_eval", Kind::Object);
        std::string evaluator = r.at("evaluator").str();
        CAPTURE(evaluator);
        evaluators.insert(evaluator);
        const JsonObject& ns = r.at("ns_per_eval").obj();
        bool oneLaneOnly = evaluator.rfind("scalar", 0) == 0;
        for (size_t n : bench::kBatchSizes) {
            std::string key = std::to_string(n);
            checkField(ns, key.c_str(), Kind::NumberOrNull);
            if (oneLaneOnly && n > 1) CHECK(ns.at(key).isNull());
            else CHECK(ns.at(key).num() > 0);
        }
    }
    CHECK(evaluators == std::set<std::string>{"simd exact", "simd fast", "simd exact, assume=unit",
                                              "simd fast, assume=unit", "aot hand-written", "aot bare",
                                              "scalar exact, one call per lane"});
    // Each row but the bare one also as its ratio to the bare loop at the same n.
    const JsonObject* bareNs = nullptr;
    for (const JsonValue& rv : m.at("batch_sizes").arr())
        if (rv.obj().at("evaluator").str() == "aot bare") bareNs = &rv.obj().at("ns_per_eval").obj();
    REQUIRE(bareNs);
    for (const JsonValue& rv : m.at("batch_sizes").arr()) {
        const JsonObject& r = rv.obj();
        std::string evaluator = r.at("evaluator").str();
        CAPTURE(evaluator);
        if (evaluator == "aot bare") {
            CHECK(r.count("ratio_to_bare") == 0);
            continue;
        }
        checkField(r, "ratio_to_bare", Kind::Object);
        for (size_t n : bench::kBatchSizes) {
            std::string key = std::to_string(n);
            const JsonValue& ns = r.at("ns_per_eval").obj().at(key);
            const JsonValue& ratio = r.at("ratio_to_bare").obj().at(key);
            if (ns.isNull()) CHECK(ratio.isNull());
            else CHECK(ratio.num() == doctest::Approx(ns.num() / bareNs->at(key).num()).epsilon(1e-7));  // 9 digits each
        }
    }
    CHECK(bench::markdown(report).find("| ratio to aot bare, same n ") != std::string::npos);

    // The sampler rows: interp, scalar and simd (exact, fast), and the
    // hand-written GGX visible-normal sampler of the AOT twin.
    checkField(m, "sampling_summary", Kind::String);
    checkField(m, "sampler_rows", Kind::Array);
    std::set<std::pair<std::string, std::string>> sampled;
    for (const JsonValue& rv : m.at("sampler_rows").arr()) {
        const JsonObject& r = rv.obj();
        for (const char* k : {"backend", "mode", "sampler"}) checkField(r, k, Kind::String);
        for (const char* k : {"width", "lanes", "ns_per_sample", "ns_per_pdf"}) checkField(r, k, Kind::Number);
        for (const char* k : {"first_use_ms", "jit_over_aot"}) checkField(r, k, Kind::NumberOrNull);
        std::string backend = r.at("backend").str(), mode = r.at("mode").str();
        CAPTURE(backend);
        CAPTURE(mode);
        sampled.insert({backend, mode});
        CHECK(r.at("ns_per_sample").num() > 0);
        CHECK(r.at("ns_per_pdf").num() > 0);
        // GGX under Smith masking has a compiled sampler.
        std::string expected = backend == "interp" ? "reference" : backend == "aot" ? "aot" : "jit";
        CHECK(r.at("sampler").str() == expected);
        if (backend == "scalar" || backend == "simd") {
            CHECK(r.at("jit_over_aot").isNumber());
            CHECK(r.at("first_use_ms").num() > 0);
        }
    }
    for (const char* b : {"scalar", "simd"})
        for (const char* mode : {"exact", "fast"}) CHECK(sampled.count({b, mode}));
    CHECK(sampled.count({"interp", "exact"}));
    CHECK(sampled.count({"aot", "hand-written"}));
    CHECK(sampled.size() == 6);
}

TEST_CASE("a kulla_conty material reports its table: cold build and cached load") {
    const bench::BenchReport& report = kullaContyReport();
    REQUIRE(report.materials.size() == 1);
    const JsonObject m = materialJson(report);
    CHECK(m.at("material").str() == "gold");
    checkField(m, "energy_table", Kind::Object);
    const JsonObject& e = m.at("energy_table").obj();
    for (const char* k : {"pair", "ndf", "masking", "key", "cache_file", "note"}) checkField(e, k, Kind::String);
    for (const char* k : {"build_ms", "build_threads", "cached_load_ms", "cached_load_runs"})
        checkField(e, k, Kind::Number);
    checkField(e, "grid", Kind::Array);
    CHECK(e.at("pair").str() == "ggx x smith_height_correlated");
    CHECK(e.at("ndf").str() == "ggx");
    CHECK(e.at("masking").str() == "smith_height_correlated");
    CHECK(e.at("key").str() == "ggx_smith_height_correlated");
    CHECK(e.at("build_ms").num() > 0);
    CHECK(e.at("build_threads").num() >= 1);
    CHECK(e.at("cached_load_ms").num() > 0);
    CHECK(e.at("cached_load_runs").num() >= 1);
    CHECK(e.at("note").str() == "");
    // A cache hit is a small file read; the quadrature is not.
    CHECK(e.at("cached_load_ms").num() < e.at("build_ms").num());
    REQUIRE(e.at("grid").arr().size() == 2);
    CHECK(e.at("grid").arr()[0].num() == EnergyTable::kMuCount);
    CHECK(e.at("grid").arr()[1].num() == EnergyTable::kAlphaCount);
    CHECK(std::filesystem::exists(e.at("cache_file").str()));
    CHECK(e.at("cache_file").str().find("kc_ggx_smith_height_correlated.exr") != std::string::npos);
    // The older fields agree.
    CHECK(m.at("kulla_conty_ms").num() == e.at("build_ms").num());
    CHECK(m.at("kulla_conty_pair").str() == "ggx_smith_height_correlated");

    // Kulla-Conty against the random walk: the compensated albedo nearer the
    // walk's than single scattering's (gold at roughness 0.35 loses a few
    // percent to masking at 60 degrees), and its shape no further off.
    checkField(m, "walk_comparison", Kind::Object);
    const JsonObject& w = m.at("walk_comparison").obj();
    for (const char* k : {"theta_o", "albedo_single", "albedo_kulla_conty", "albedo_walk", "albedo_walk_std_error",
                          "shape_error_single", "shape_error_kulla_conty", "shape_noise"})
        checkField(w, k, Kind::Number);
    CHECK(w.at("albedo_single").num() < w.at("albedo_kulla_conty").num());
    CHECK(std::abs(w.at("albedo_kulla_conty").num() - w.at("albedo_walk").num()) <
          0.5 * (w.at("albedo_walk").num() - w.at("albedo_single").num()));
    CHECK(w.at("shape_error_kulla_conty").num() <= w.at("shape_error_single").num());
    CHECK(bench::walkLine(report.materials[0]).find("Kulla-Conty against the random walk (theta_o 60") == 0);

    // Terminal and Markdown show it in the material's section, before the rows.
    std::string line = bench::energyTableLine(report.materials[0]);
    CHECK(line.find("Kulla-Conty tables: ggx x smith_height_correlated (ggx_smith_height_correlated), built in ") == 0);
    CHECK(line.find(" ms (cold, 64 x 64 grid") != std::string::npos);
    CHECK(line.find(" / loaded from cache in ") != std::string::npos);
    std::string md = bench::markdown(report);
    size_t at = md.find(line);
    CHECK(at != std::string::npos);
    CHECK(at > md.find("## gold"));
    CHECK(at < md.find("| backend |"));
    std::string text = terminalReport(report);
    at = text.find("  " + line + "\n");
    CHECK(at != std::string::npos);
    CHECK(at < text.find("backend "));
    // No such line for a material without energy compensation.
    CHECK(bench::energyTableLine(quickReport().materials.at(0)).empty());
}

TEST_CASE("the Kulla-Conty table bench without a cache directory reports why there is no cached load") {
    DiagnosticEngine diags;
    CheckedProgram program = loadProgramFile(std::string(FACET_SOURCE_DIR) + "/materials/gold.mat", diags);
    REQUIRE(!diags.hasErrors());
    std::optional<bench::EnergyTableBench> e = bench::benchEnergyTable(program.materials.at(0), 1, std::string());
    REQUIRE(e);
    CHECK(e->buildMs > 0);
    CHECK(!e->cachedLoadMs);
    CHECK(e->note.find("no table cache directory") != std::string::npos);
}

// The Lambda table of bench/models/student_t_plastic.mat (student_t, gamma
// 3, under a Smith masking): built cold, written to and loaded from a cache
// directory of its own, and reported in the JSON, Markdown and terminal
// output (a report of that material alone, without its timing rows: about
// a second, the quadrature's time).
TEST_CASE("a material with a tabulated Smith Lambda reports its table: cold build and cached load") {
    DiagnosticEngine diags;
    const std::string file = std::string(FACET_SOURCE_DIR) + "/bench/models/student_t_plastic.mat";
    CheckedProgram program = loadProgramFile(file, diags);
    REQUIRE_MESSAGE(!diags.hasErrors(), diags.str());
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "facet-bench-lambda-test";
    std::filesystem::remove_all(dir);
    bench::BenchReport report;
    bench::MaterialBench mb;
    mb.file = file;
    mb.material = program.materials.at(0).name;
    mb.lambdaTable = bench::benchLambdaTable(program.materials.at(0), 3, dir.string());
    REQUIRE(mb.lambdaTable);
    report.materials.push_back(mb);
    const JsonObject m = materialJson(report);
    checkField(m, "lambda_table", Kind::Object);
    const JsonObject& e = m.at("lambda_table").obj();
    for (const char* k : {"key", "cache_file", "note"}) checkField(e, k, Kind::String);
    for (const char* k : {"nodes", "build_ms", "cached_load_ms", "cached_load_runs"}) checkField(e, k, Kind::Number);
    CHECK(e.at("key").str() == "student_t_g3");
    CHECK(e.at("nodes").num() == LambdaTable::kSize + 1);  // the nodes and the grazing node
    CHECK(e.at("build_ms").num() > 0);
    CHECK(e.at("cached_load_ms").num() > 0);
    CHECK(e.at("cached_load_runs").num() == 3);
    CHECK(e.at("note").str() == "");
    // A load reads 33 KB and recomputes four nodes; the build computes 4129.
    CHECK(e.at("cached_load_ms").num() < e.at("build_ms").num());
    CHECK(e.at("cache_file").str() == (dir / "lambda_student_t_g3.bin").string());
    CHECK(std::filesystem::exists(e.at("cache_file").str()));
    MESSAGE(bench::lambdaTableLine(report.materials[0]));

    std::string line = bench::lambdaTableLine(report.materials[0]);
    CHECK(line.find("Smith Lambda table: student_t_g3, built in ") == 0);
    CHECK(line.find(" ms (cold, 4129 nodes; one thread) / loaded from cache in ") != std::string::npos);
    CHECK(bench::markdown(report).find(line + ".") != std::string::npos);
    std::string text = terminalReport(report);
    CHECK(text.find("  " + line + "\n") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("the Markdown and terminal reports name every row") {
    const bench::BenchReport& report = quickReport();
    std::string md = bench::markdown(report);
    CHECK(md.find("## ggx_schlick") != std::string::npos);
    CHECK(md.find("| simd | tol 1e-3 |") != std::string::npos);
    CHECK(md.find("| aot | hand-written |") != std::string::npos);
    CHECK(md.find("JIT/AOT") != std::string::npos);
    CHECK(!bench::summaryLine(report.materials.at(0)).empty());
    CHECK(md.find("| simd | fast | jit |") != std::string::npos);  // a sampler row
    CHECK(md.find("| aot | hand-written | aot |") != std::string::npos);
    CHECK(bench::samplerSummaryLine(report.materials.at(0)).find("JIT/AOT") != std::string::npos);
}

TEST_CASE("the scatter plot is written as a PNG of the expected size") {
    const bench::BenchReport& report = quickReport();
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "facet-bench-plot-test";
    std::filesystem::create_directories(dir);
    std::string path = (dir / "bench.png").string();
    std::filesystem::remove(path);
    REQUIRE(bench::writeScatterPlot(report, path) == "");
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    CHECK(std::string(in->format_name()) == "png");
    CHECK(spec.width == bench::kPlotWidth);
    CHECK(spec.height == bench::kPlotHeight);
    CHECK(spec.nchannels == 3);
    // Not blank: the plot has dark (axis, text) and coloured (marker) pixels.
    std::vector<uint8_t> px(size_t(spec.width) * spec.height * 3);
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
    size_t dark = 0, coloured = 0;
    for (size_t i = 0; i < px.size(); i += 3) {
        int r = px[i], g = px[i + 1], b = px[i + 2];
        dark += r < 60 && g < 60 && b < 60;
        coloured += std::max({r, g, b}) - std::min({r, g, b}) > 80;
    }
    CHECK(dark > 1000);
    CHECK(coloured > 100);
    in->close();
    std::filesystem::remove_all(dir);
}

}  // TEST_SUITE
