// BenchFormat: terminal table, Markdown and JSON of a bench report (see BenchFormat.h).
#include "BenchFormat.h"
#include "ReferenceComparison.h"

#include <array>
#include <cmath>
#include <fmt/format.h>

namespace facet::bench {

namespace {

std::string num(double v, const char* spec) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return fmt::format(fmt::runtime(spec), v);
}
std::string opt(const std::optional<double>& v, const char* spec) { return v ? num(*v, spec) : "-"; }
std::string rel(double v) { return v == 0 ? "0" : num(v, "{:.2e}"); }
std::string ulp(double v) { return num(v, "{:.4g}"); }

struct Column {
    const char* title;
    int width;
    bool left;
};

std::vector<std::string> cells(const BenchRow& r) {
    return {r.backend,
            r.mode,
            r.variant,
            num(r.nsPerEval, "{:.2f}"),
            num(r.evalsPerSecond / 1e6, "{:.1f}"),
            opt(r.coldMs, "{:.2f}"),
            opt(r.tierUpMs, "{:.2f}"),
            opt(r.coldOptimizedMs, "{:.2f}"),
            opt(r.memoryHitMs, "{:.3f}"),
            opt(r.diskHitMs, "{:.3f}"),
            opt(r.aotRatio, "{:.2f}"),
            opt(r.bareRatio, "{:.2f}"),
            rel(r.regular.maxRel),
            rel(r.regular.p999Rel),
            ulp(r.regular.maxUlp),
            r.hard.values ? rel(r.hard.maxRel) : "-",
            r.hard.values ? rel(r.hard.p999Rel) : "-",
            r.hard.values ? ulp(r.hard.maxUlp) : "-"};
}

const std::vector<Column>& columns() {
    static const std::vector<Column> c = {
        {"backend", 7, true},       {"mode", 12, true},         {"variant", 12, true},      {"ns/eval", 9, false},
        {"Meval/s", 8, false},      {"cold ms", 8, false},      {"tier-up ms", 10, false},  {"cold-opt ms", 11, false},
        {"mem-hit ms", 10, false},  {"disk-hit ms", 11, false},
        {"JIT/AOT", 7, false},      {"JIT/bare", 8, false},
        {"max rel", 9, false},      {"p99.9 rel", 9, false},    {"max ulp", 9, false},
        {"hard max", 9, false},     {"hard p99.9", 10, false},  {"hard ulp", 9, false},
    };
    return c;
}

std::vector<std::string> samplerCells(const SamplerRow& r) {
    return {r.backend,
            r.mode,
            r.tier,
            std::to_string(r.width),
            num(r.nsPerSample, "{:.2f}"),
            num(1e3 / r.nsPerSample, "{:.1f}"),
            num(r.nsPerPdf, "{:.2f}"),
            r.tier == "jit" ? opt(r.firstUseMs, "{:.1f}") : "-",
            opt(r.aotRatio, "{:.2f}")};
}

const std::vector<Column>& samplerColumns() {
    static const std::vector<Column> c = {
        {"backend", 7, true},       {"mode", 12, true},     {"sampler", 9, true},  {"width", 5, false},
        {"ns/sample", 9, false},    {"Msample/s", 9, false}, {"ns/pdf", 8, false},  {"first-use ms", 12, false},
        {"JIT/AOT", 7, false},
    };
    return c;
}

// The columns of `rows` as aligned text lines, the header first.
template <typename Row, typename Cells>
std::string textTable(const std::vector<Column>& columns, const std::vector<Row>& rows, Cells&& cellsOf) {
    auto line = [&](const std::vector<std::string>& v) {
        std::string out;
        for (size_t i = 0; i < v.size(); ++i)
            out += fmt::format(fmt::runtime(columns[i].left ? "{:<{}} " : "{:>{}} "), v[i], columns[i].width);
        return out + "\n";
    };
    std::vector<std::string> titles;
    for (const Column& c : columns) titles.push_back(c.title);
    std::string out = line(titles);
    for (const Row& r : rows) out += line(cellsOf(r));
    return out;
}

template <typename Row, typename Cells>
std::string markdownTable(const std::vector<Column>& columns, const std::vector<Row>& rows, Cells&& cellsOf) {
    std::string md = "|";
    for (const Column& c : columns) md += fmt::format(" {} |", c.title);
    md += "\n|";
    for (const Column& c : columns) md += c.left ? "---|" : "--:|";
    md += "\n";
    for (const Row& r : rows) {
        md += "|";
        for (const std::string& v : cellsOf(r)) md += fmt::format(" {} |", v);
        md += "\n";
    }
    return md;
}

std::vector<std::string> batchSizeCells(const BatchSizeRow& r) {
    std::vector<std::string> c{r.label};
    for (double ns : r.nsPerEval) c.push_back(std::isnan(ns) ? "-" : num(ns, "{:.2f}"));
    return c;
}

// The batch-size table's columns, the first titled `what`.
std::vector<Column> batchSizeColumns(const char* what) {
    static const std::vector<std::string> titles = [] {
        std::vector<std::string> t;
        for (size_t n : kBatchSizes) t.push_back(fmt::format("n={}", n));
        return t;
    }();
    std::vector<Column> cols{{what, 32, true}};
    for (const std::string& t : titles) cols.push_back({t.c_str(), 8, false});
    return cols;
}
constexpr const char* kBatchNsTitle = "ns/eval by batch size";
constexpr const char* kBatchRatioTitle = "ratio to aot bare, same n";

// The batch-size rows over the bare loop's ns/eval at the same batch size
// (SPEC 6: the hand-written loop pays the same per-call costs on short
// batches), when the material has an AOT bare twin; else none.
std::vector<BatchSizeRow> batchRatioRows(const std::vector<BatchSizeRow>& rows) {
    const BatchSizeRow* bare = nullptr;
    for (const BatchSizeRow& r : rows)
        if (r.label == "aot bare") bare = &r;
    std::vector<BatchSizeRow> out;
    if (!bare) return out;
    for (const BatchSizeRow& r : rows) {
        if (&r == bare) continue;
        BatchSizeRow q{r.label, {}};
        for (size_t i = 0; i < r.nsPerEval.size(); ++i) q.nsPerEval.push_back(r.nsPerEval[i] / bare->nsPerEval[i]);
        out.push_back(std::move(q));
    }
    return out;
}

std::string header(const BenchReport& report, const MaterialBench& m) {
    const BenchSettings& s = report.settings;
    std::string aot = m.aotModel.empty() ? (m.aotNote.empty() ? "none" : m.aotNote) : m.aotModel;
    return fmt::format("{} ({})  aot: {}\n"
                       "  timing (thread CPU time): median of {} warm runs on {} lanes (interp: {} lanes); SIMD width {}; "
                       "error vs the double interpreter on {} regular and {} hard-case lanes; parse+check {:.2f} ms",
                       m.material, m.file, aot, s.runs, m.regularLanes, std::min(s.interpLanes, m.regularLanes),
                       report.hostWidth, m.regularLanes, m.hardLanes, m.parseCheckMs);
}

// " / loaded from cache in X ms", or why not.
std::string cacheLoadText(const TableTiming& t) {
    if (t.cachedLoadMs) return fmt::format(" / loaded from cache in {:.3f} ms", *t.cachedLoadMs);
    return fmt::format(" / not loaded from cache: {}", t.note);
}

}  // namespace

std::string energyTableLine(const MaterialBench& m) {
    if (!m.energyTable) return "";
    const EnergyTableBench& e = *m.energyTable;
    std::string s = fmt::format("Kulla-Conty tables: {} ({}), built in {:.1f} ms (cold, {} x {} grid; wall time, {} "
                                "thread{})",
                                e.pair(), e.key, e.buildMs, e.muCount, e.alphaCount, e.threads, e.threads == 1 ? "" : "s");
    return s + cacheLoadText(e);
}

std::string walkLine(const MaterialBench& m) {
    if (!m.walk) return "";
    const WalkBench& w = *m.walk;
    return fmt::format("Kulla-Conty against the random walk (theta_o {:g}, default inputs, docs/models.md): albedo "
                       "single scattering {:.4f}, with Kulla-Conty {:.4f}, walk {:.4f} +- {:.4f}; shape error "
                       "single {:.3f}, with Kulla-Conty {:.3f} (walk noise {:.3f})",
                       w.thetaO, w.single, w.compensated, w.walk, w.walkError, w.singleShape, w.compensatedShape,
                       w.noise);
}

std::string lambdaTableLine(const MaterialBench& m) {
    if (!m.lambdaTable) return "";
    const LambdaTableBench& e = *m.lambdaTable;
    std::string s = fmt::format("Smith Lambda table: {}, built in {:.1f} ms (cold, {} nodes; {})", e.key, e.buildMs,
                                e.nodes, e.threads == 1 ? "one thread" : fmt::format("{} threads", e.threads));
    return s + cacheLoadText(e);
}

std::string summaryLine(const MaterialBench& m) {
    const BenchRow* simd = m.find("simd", "exact");
    const BenchRow* scalar = m.find("scalar", "exact");
    const BenchRow* aot = m.find("aot", "hand-written");
    if (!simd) return "";
    std::string s = fmt::format("simd exact {:.2f} ns/eval ({:.0f} M/s)", simd->nsPerEval, simd->evalsPerSecond / 1e6);
    if (scalar) s += fmt::format("; simd/scalar speed-up {:.1f}x", scalar->nsPerEval / simd->nsPerEval);
    if (aot) s += fmt::format("; aot {:.2f} ns/eval, JIT/AOT {:.2f}", aot->nsPerEval, simd->nsPerEval / aot->nsPerEval);
    if (const BenchRow* bare = m.find("aot", "bare"))
        s += fmt::format("; bare {:.2f} ns/eval, JIT/bare {:.2f}", bare->nsPerEval, simd->nsPerEval / bare->nsPerEval);
    s += fmt::format("; compile cold {} ms (+ tier-up {} ms; optimized alone {} ms), memory hit {} ms, disk hit {} ms",
                     opt(simd->coldMs, "{:.2f}"), opt(simd->tierUpMs, "{:.2f}"), opt(simd->coldOptimizedMs, "{:.2f}"),
                     opt(simd->memoryHitMs, "{:.3f}"), opt(simd->diskHitMs, "{:.3f}"));
    return s;
}

// "lobes alone (SIMD exact): coat 10.1 + base 20.2 = 30.3 ns/eval; the combination 44.7 ns/eval, 1.48x their sum"
std::string lobesAloneLine(const MaterialBench& m) {
    if (!m.lobesAlone) return "";
    const LobesAlone& a = *m.lobesAlone;
    std::string parts;
    for (const auto& [name, ns] : a.lobes) parts += fmt::format("{}{} {:.2f}", parts.empty() ? "" : " + ", name, ns);
    return fmt::format("lobes alone (SIMD exact, same sample, interleaved runs): {} = {:.2f} ns/eval; the "
                       "combination {:.2f} ns/eval, {:.2f}x their sum",
                       parts, a.sum(), a.combination, a.sum() > 0 ? a.combination / a.sum() : 0.0);
}

std::string samplerSummaryLine(const MaterialBench& m) {
    auto find = [&](const char* backend, const char* mode) -> const SamplerRow* {
        for (const SamplerRow& r : m.samplerRows)
            if (r.backend == backend && r.mode == mode) return &r;
        return nullptr;
    };
    const SamplerRow* simd = find("simd", "exact");
    if (!simd) return "";
    std::string s = fmt::format("simd exact {:.2f} ns/sample, {:.2f} ns/pdf ({} sampler)", simd->nsPerSample,
                                simd->nsPerPdf, simd->tier);
    if (const SamplerRow* fast = find("simd", "fast")) s += fmt::format("; simd fast {:.2f} ns/sample", fast->nsPerSample);
    if (const SamplerRow* scalar = find("scalar", "exact"))
        s += fmt::format("; simd/scalar speed-up {:.1f}x", scalar->nsPerSample / simd->nsPerSample);
    if (const SamplerRow* aot = find("aot", "hand-written"))
        s += fmt::format("; aot {:.2f} ns/sample, JIT/AOT {:.2f}", aot->nsPerSample, simd->nsPerSample / aot->nsPerSample);
    return s;
}

void printTable(const BenchReport& report, std::FILE* out) {
    for (const MaterialBench& m : report.materials) {
        std::fprintf(out, "\n%s\n", header(report, m).c_str());
        if (m.energyTable) std::fprintf(out, "  %s\n", energyTableLine(m).c_str());
        if (m.lambdaTable) std::fprintf(out, "  %s\n", lambdaTableLine(m).c_str());
        if (m.walk) std::fprintf(out, "  %s\n", walkLine(m).c_str());
        std::fprintf(out, "%s", textTable(columns(), m.rows, cells).c_str());
        std::fprintf(out, "worst inputs (regular | hard):\n");
        for (const BenchRow& r : m.rows) {
            std::fprintf(out, "  %-19s %s\n", r.label().c_str(), r.regular.worst.str().c_str());
            std::fprintf(out, "  %-19s %s\n", "", r.hard.worst.str().c_str());
        }
        std::fprintf(out, "summary: %s\n", summaryLine(m).c_str());
        if (m.lobesAlone) std::fprintf(out, "%s\n", lobesAloneLine(m).c_str());
        if (!m.batchSizes.empty())
            std::fprintf(out, "%s", textTable(batchSizeColumns(kBatchNsTitle), m.batchSizes, batchSizeCells).c_str());
        if (std::vector<BatchSizeRow> ratios = batchRatioRows(m.batchSizes); !ratios.empty())
            std::fprintf(out, "%s", textTable(batchSizeColumns(kBatchRatioTitle), ratios, batchSizeCells).c_str());
        if (!m.samplerRows.empty()) {
            std::fprintf(out, "sampling (sample and pdf batches):\n%s",
                         textTable(samplerColumns(), m.samplerRows, samplerCells).c_str());
            std::fprintf(out, "sampling summary: %s\n", samplerSummaryLine(m).c_str());
        }
    }
}

std::string markdown(const BenchReport& report) {
    std::string md = "# facet bench\n\n";
    const BenchSettings& s = report.settings;
    md += fmt::format("Host: {} (SIMD width {}). Median of {} warm runs ({} warm-up) of one batch of {} lanes "
                      "(scalar entry and interpreter: median over chunks of 4096 / 256 lanes); the interpreter is "
                      "timed on {} lanes. Compile times are medians of {} cold compiles (cache=off), {} memory-cache "
                      "hits and {} disk-cache hits (fresh compiler). Cold compiles are tiered (the default): "
                      "`cold ms` is the time until the compile returns a kernel with quickly emitted code, "
                      "`tier-up ms` the time the tier-up thread then takes for the optimized code (timed kernels "
                      "run it), `cold-opt ms` a compile with codegen=optimized. All times are CPU time of the "
                      "thread doing the work.{}\n\n",
                      report.cpu, report.hostWidth, s.runs, s.warmup, s.lanes, s.interpLanes, s.compileRuns,
                      s.compileRuns, s.diskRuns, s.quick ? " **Quick mode**: small batches, few runs." : "");
    md += fmt::format("Error is relative to the double-precision interpreter on the same float inputs "
                      "(differences below {:g} count as 0). Hard-case sample: {}.\n",
                      kAbsoluteErrorFloor, report.hardSample);
    for (const MaterialBench& m : report.materials) {
        md += fmt::format("\n## {}\n\n`{}`, AOT twin: {}", m.material, m.file,
                          m.aotModel.empty() ? (m.aotNote.empty() ? "none" : m.aotNote) : "`" + m.aotModel + "`");
        md += fmt::format(". Regular sample {} lanes, hard-case sample {} lanes.\n\n", m.regularLanes, m.hardLanes);
        if (m.energyTable) md += energyTableLine(m) + ".\n\n";
        if (m.lambdaTable) md += lambdaTableLine(m) + ".\n\n";
        if (m.walk) md += walkLine(m) + ".\n\n";
        md += markdownTable(columns(), m.rows, cells);
        md += fmt::format("\n**Summary:** {}\n", summaryLine(m));
        if (m.lobesAlone) md += fmt::format("\n**Lobes:** {}\n", lobesAloneLine(m));
        md += "\nWorst inputs:\n\n";
        for (const BenchRow& r : m.rows)
            md += fmt::format("- {}: regular `{}`; hard `{}`\n", r.label(), r.regular.worst.str(), r.hard.worst.str());
        if (!m.batchSizes.empty()) {
            md += "\nBatch sizes: the regular sample evaluated in consecutive batches of n lanes, one call each "
                  "(`Kernel::evalBatch` for the SIMD rows, the AOT functions through a function pointer); the "
                  "scalar entry once per lane. ns/eval, median of the runs.\n\n";
            md += markdownTable(batchSizeColumns(kBatchNsTitle), m.batchSizes, batchSizeCells);
            if (std::vector<BatchSizeRow> ratios = batchRatioRows(m.batchSizes); !ratios.empty()) {
                md += "\nThe same rows over the bare loop's ns/eval at the same batch size:\n\n";
                md += markdownTable(batchSizeColumns(kBatchRatioTitle), ratios, batchSizeCells);
            }
        }
        if (!m.samplerRows.empty()) {
            md += "\nSampling: `Kernel::sampleBatch` and `Kernel::pdfBatch` (the AOT row: the hand-written sampler) on "
                  "the regular sample's directions with uniform u; `sampler` says which code sampled (the kernel's "
                  "compiled sampler, or the interpreter's reference sampler), `first-use ms` the first sampling "
                  "call of a fresh kernel, which compiles its sampler.\n\n";
            md += markdownTable(samplerColumns(), m.samplerRows, samplerCells);
            md += fmt::format("\n**Sampling summary:** {}\n", samplerSummaryLine(m));
        }
    }
    return md;
}

namespace {

// A minimal JSON writer: objects and arrays with comma bookkeeping.
class Json {
public:
    std::string out;
    void open(char c) {
        sep();
        out += c;
        first_ = true;
    }
    void close(char c) {
        out += c;
        first_ = false;
    }
    void key(const std::string& k) {
        sep();
        str(k);
        out += ':';
        first_ = true;  // the value follows without a comma
    }
    void value(double v) {
        sep();
        out += std::isfinite(v) ? fmt::format("{:.9g}", v) : "null";
    }
    void value(const std::optional<double>& v) {
        if (v) value(*v);
        else raw("null");
    }
    void value(const std::string& s) {
        sep();
        str(s);
    }
    void value(int64_t v) { raw(std::to_string(v)); }
    void value(bool v) { raw(v ? "true" : "false"); }
    void raw(const std::string& s) {
        sep();
        out += s;
    }
    template <typename T>
    void field(const std::string& k, const T& v) {
        key(k);
        value(v);
    }
    // "k": [numbers]
    template <typename Range>
    void numbers(const std::string& k, const Range& values) {
        key(k);
        open('[');
        for (auto x : values) value(double(x));
        close(']');
    }

private:
    void sep() {
        if (!first_) out += ',';
        first_ = false;
    }
    void str(const std::string& s) {
        out += '"';
        for (unsigned char c : s) {
            if (c == '"' || c == '\\') out += '\\', out += char(c);
            else if (c < 0x20) out += fmt::format("\\u{:04x}", c);
            else out += char(c);
        }
        out += '"';
    }
    bool first_ = true;
};

void writeError(Json& j, const ErrorStats& e) {
    j.open('{');
    j.field("values", int64_t(e.values));
    j.field("skipped", int64_t(e.skipped));
    j.field("nonfinite", int64_t(e.nonFinite));
    j.field("negative", int64_t(e.negative));
    j.field("invalid_lanes", e.invalidLanes);
    j.field("reference_invalid_lanes", e.referenceInvalid);
    j.field("max_rel", e.maxRel);
    j.field("p999_rel", e.p999Rel);
    j.field("max_ulp", e.maxUlp);
    j.key("worst");
    if (!e.worst.present) {
        j.raw("null");
    } else {
        const auto& w = e.worst;
        j.open('{');
        j.field("lane", int64_t(w.lane));
        j.field("channel", std::string(1, "rgb"[w.channel]));
        j.numbers("wi", w.wi);
        j.numbers("wo", w.wo);
        j.key("inputs");
        j.open('{');
        for (const auto& [name, v] : w.inputs) j.field(name, double(v));
        j.close('}');
        j.field("got", w.got);
        j.field("want", w.want);
        j.field("rel", w.rel);
        j.close('}');
    }
    j.close('}');
}

// [{"evaluator": label, "ns_per_eval": {"1": ns or null, ...}}, ...]
void writeBatchSizes(Json& j, const std::vector<BatchSizeRow>& rows) {
    std::vector<BatchSizeRow> ratios = batchRatioRows(rows);
    auto perSize = [&](const char* key, const std::vector<double>& values) {
        j.key(key);
        j.open('{');
        for (size_t i = 0; i < values.size(); ++i)
            j.field(std::to_string(kBatchSizes[i]), std::isnan(values[i]) ? std::nullopt : std::optional<double>(values[i]));
        j.close('}');
    };
    j.open('[');
    for (const BatchSizeRow& r : rows) {
        j.open('{');
        j.field("evaluator", r.label);
        perSize("ns_per_eval", r.nsPerEval);
        for (const BatchSizeRow& q : ratios)
            if (q.label == r.label) perSize("ratio_to_bare", q.nsPerEval);
        j.close('}');
    }
    j.close(']');
}

void writeTableTiming(Json& j, const TableTiming& t) {
    j.field("build_ms", t.buildMs);
    j.field("cached_load_ms", t.cachedLoadMs);
    j.field("cached_load_runs", int64_t(t.loadRuns));
    j.field("cache_file", t.cacheFile);
    j.field("note", t.note);
}

void writeEnergyTable(Json& j, const std::optional<EnergyTableBench>& table) {
    if (!table) {
        j.raw("null");
        return;
    }
    const EnergyTableBench& e = *table;
    j.open('{');
    j.field("pair", e.pair());
    j.field("ndf", e.ndf);
    j.field("masking", e.masking);
    j.field("key", e.key);
    j.field("build_threads", int64_t(e.threads));
    j.numbers("grid", std::array<int, 2>{e.muCount, e.alphaCount});  // mu nodes, alpha nodes
    writeTableTiming(j, e);
    j.close('}');
}

void writeLambdaTable(Json& j, const std::optional<LambdaTableBench>& table) {
    if (!table) {
        j.raw("null");
        return;
    }
    const LambdaTableBench& e = *table;
    j.open('{');
    j.field("key", e.key);
    j.field("nodes", int64_t(e.nodes));
    writeTableTiming(j, e);
    j.close('}');
}

}  // namespace

std::string json(const BenchReport& report) {
    Json j;
    const BenchSettings& s = report.settings;
    j.open('{');
    j.field("facet_bench_format", int64_t(1));
    j.key("host");
    j.open('{');
    j.field("cpu", report.cpu);
    j.field("features", report.cpuFeatures);
    j.field("vector_width", int64_t(report.hostWidth));
    j.close('}');
    j.key("settings");
    j.open('{');
    j.field("lanes", int64_t(s.lanes));
    j.field("interp_lanes", int64_t(s.interpLanes));
    j.field("runs", int64_t(s.runs));
    j.field("warmup", int64_t(s.warmup));
    j.field("compile_runs", int64_t(s.compileRuns));
    j.field("disk_runs", int64_t(s.diskRuns));
    j.field("quick", s.quick);
    j.field("seed", int64_t(s.seed));
    j.field("abs_floor", kAbsoluteErrorFloor);
    j.field("hard_sample", report.hardSample);
    j.close('}');
    j.key("materials");
    j.open('[');
    for (const MaterialBench& m : report.materials) {
        j.open('{');
        j.field("file", m.file);
        j.field("material", m.material);
        j.key("aot");
        if (m.aotModel.empty()) j.raw("null");
        else j.value(m.aotModel);
        j.field("aot_note", m.aotNote);
        j.field("parse_check_ms", m.parseCheckMs);
        // kulla_conty_ms / kulla_conty_pair: energy_table.build_ms / .key (kept for older readers).
        j.field("kulla_conty_ms", m.energyTable ? std::optional<double>(m.energyTable->buildMs) : std::nullopt);
        j.field("kulla_conty_pair", m.energyTable ? m.energyTable->key : std::string());
        j.key("energy_table");
        writeEnergyTable(j, m.energyTable);
        j.key("lambda_table");
        writeLambdaTable(j, m.lambdaTable);
        j.key("walk_comparison");
        if (!m.walk) {
            j.raw("null");
        } else {
            j.open('{');
            j.field("theta_o", m.walk->thetaO);
            j.field("albedo_single", m.walk->single);
            j.field("albedo_kulla_conty", m.walk->compensated);
            j.field("albedo_walk", m.walk->walk);
            j.field("albedo_walk_std_error", m.walk->walkError);
            j.field("shape_error_single", m.walk->singleShape);
            j.field("shape_error_kulla_conty", m.walk->compensatedShape);
            j.field("shape_noise", m.walk->noise);
            j.close('}');
        }
        j.field("regular_lanes", int64_t(m.regularLanes));
        j.field("hard_lanes", int64_t(m.hardLanes));
        j.field("summary", summaryLine(m));
        j.field("lobes_alone", lobesAloneLine(m));
        j.key("rows");
        j.open('[');
        for (const BenchRow& r : m.rows) {
            j.open('{');
            j.field("backend", r.backend);
            j.field("mode", r.mode);
            j.field("options", r.options);
            j.field("variant", r.variant);
            j.field("measured_error", r.measuredError >= 0 ? std::optional<double>(r.measuredError) : std::nullopt);
            j.field("width", int64_t(r.width));
            j.field("lanes", int64_t(r.lanes));
            j.field("runs", int64_t(r.runs));
            j.field("ns_per_eval", r.nsPerEval);
            j.field("ns_per_eval_min", r.nsPerEvalMin);
            j.field("evals_per_second", r.evalsPerSecond);
            j.field("compile_cold_ms", r.coldMs);
            j.field("compile_tier_up_ms", r.tierUpMs);
            j.field("compile_cold_optimized_ms", r.coldOptimizedMs);
            j.field("compile_memory_hit_ms", r.memoryHitMs);
            j.field("compile_disk_hit_ms", r.diskHitMs);
            j.field("jit_over_aot", r.aotRatio);
            j.field("jit_over_bare", r.bareRatio);
            j.key("error_regular");
            writeError(j, r.regular);
            j.key("error_hard");
            if (r.hard.values) writeError(j, r.hard);
            else j.raw("null");
            j.close('}');
        }
        j.close(']');
        j.key("batch_sizes");
        writeBatchSizes(j, m.batchSizes);
        j.field("sampling_summary", samplerSummaryLine(m));
        j.key("sampler_rows");
        j.open('[');
        for (const SamplerRow& r : m.samplerRows) {
            j.open('{');
            j.field("backend", r.backend);
            j.field("mode", r.mode);
            j.field("sampler", r.tier);
            j.field("width", int64_t(r.width));
            j.field("lanes", int64_t(r.lanes));
            j.field("ns_per_sample", r.nsPerSample);
            j.field("ns_per_pdf", r.nsPerPdf);
            j.field("first_use_ms", r.firstUseMs);
            j.field("jit_over_aot", r.aotRatio);
            j.close('}');
        }
        j.close(']');
        j.close('}');
    }
    j.close(']');
    j.close('}');
    return j.out + "\n";
}

}  // namespace facet::bench
