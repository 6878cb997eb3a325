// facet bench FILE... [--out DIR] [--json] [--quick] [--lanes N] [--runs N] [--compile-runs N]
//
// Speed against error (SPEC section 6). The measurements live in bench/
// (library facet_bench); this file only parses the command line and routes
// the report: the terminal table on stdout (or the JSON with --json), and
// bench.md, bench.json and bench.png in DIR (default ./bench-out).
#include "BenchFormat.h"
#include "BenchPlot.h"
#include "BenchRunner.h"
#include "Commands.h"
#include "MaterialFile.h"
#include "OutputFile.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <optional>
#include <unistd.h>

namespace facet {

namespace {

const char* kBenchUsage =
    "usage: facet bench FILE... [--out DIR] [--json] [--quick] [--lanes N] [--runs N] [--compile-runs N]\n"
    "  --out DIR   write bench.md, bench.json and bench.png there (default ./bench-out)\n"
    "  --json      print the JSON report on stdout instead of the table\n"
    "  --quick     small batches and few runs (a smoke test; numbers are noisy)\n"
    "  --lanes N   lanes per timed batch and in the regular error sample (default 65536)\n"
    "  --runs N    timed runs per row, median reported (default 15)\n"
    "  --compile-runs N  timed cold compiles and cache hits per row, median reported (default 7)\n";

int usage(const std::string& message) {
    std::fprintf(stderr, "facet bench: %s\n%s", message.c_str(), kBenchUsage);
    return kExitUsage;
}

}  // namespace

int cmdBench(const std::vector<std::string>& args) {
    std::vector<std::string> files;
    std::string outDir = "bench-out";
    bool asJson = false, quick = false;
    std::optional<size_t> lanes;
    std::optional<int> runs, compileRuns;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string* { return i + 1 < args.size() ? &args[++i] : nullptr; };
        auto count = [&](long lo, long hi) -> std::optional<long> {
            const std::string* v = value();
            if (!v) return std::nullopt;
            char* end = nullptr;
            long n = std::strtol(v->c_str(), &end, 10);
            if (end == v->c_str() || *end || n < lo || n > hi) return std::nullopt;
            return n;
        };
        if (a == "--out") {
            const std::string* v = value();
            if (!v) return usage("--out needs a directory");
            outDir = *v;
        } else if (a == "--json") {
            asJson = true;
        } else if (a == "--quick") {
            quick = true;
        } else if (a == "--lanes") {
            auto n = count(16, 1 << 26);
            if (!n) return usage("--lanes needs a count in 16 .. 67108864");
            lanes = size_t(*n);
        } else if (a == "--runs") {
            auto n = count(1, 10000);
            if (!n) return usage("--runs needs a count in 1 .. 10000");
            runs = int(*n);
        } else if (a == "--compile-runs") {
            auto n = count(1, 1000);
            if (!n) return usage("--compile-runs needs a count in 1 .. 1000");
            compileRuns = int(*n);
        } else if (!a.empty() && a[0] == '-') {
            return usage(fmt::format("unknown option '{}'", a));
        } else {
            files.push_back(a);
        }
    }
    if (files.empty()) return usage("no material files given");

    bench::BenchReport report;
    report.settings = quick ? bench::BenchSettings::quickSettings() : bench::BenchSettings{};
    if (lanes) report.settings.lanes = *lanes;
    if (runs) report.settings.runs = *runs;
    if (compileRuns) report.settings.compileRuns = *compileRuns;
    bench::describeHost(report);
    // One line of progress per file on stderr (a long run in a log shows
    // how far along it is); the per-row figures go to a terminal only.
    std::FILE* rows = isatty(fileno(stderr)) ? stderr : nullptr;
    bool materialErrors = false;
    for (size_t i = 0; i < files.size(); ++i) {
        const std::string& file = files[i];
        DiagnosticEngine diags;
        const auto start = std::chrono::steady_clock::now();
        const size_t before = report.materials.size();
        if (!bench::benchFile(file, report.settings, report, diags, rows)) {
            std::fputs(diags.str().c_str(), stderr);
            materialErrors = true;
            continue;
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr, "facet bench: [%zu/%zu] %s: eval, sampling and compile time of %zu material(s), %.1f s\n",
                     i + 1, files.size(), file.c_str(), report.materials.size() - before, seconds);
    }

    if (report.materials.empty()) return materialErrors ? kExitMaterialError : kExitOk;

    if (asJson) std::fputs(bench::json(report).c_str(), stdout);
    else bench::printTable(report, stdout);

    std::error_code ec;
    std::filesystem::create_directories(outDir, ec);
    std::filesystem::path dir(outDir);
    if (ec) {
        std::fprintf(stderr, "facet bench: error: cannot create '%s': %s\n", outDir.c_str(), ec.message().c_str());
        return kExitFailed;
    }
    if (!writeOutput((dir / "bench.md").string(), bench::markdown(report)) ||
        !writeOutput((dir / "bench.json").string(), bench::json(report)))
        return kExitFailed;
    std::string plotWarning;
    std::string plotError = bench::writeScatterPlot(report, (dir / "bench.png").string(), &plotWarning);
    if (!plotError.empty()) {
        std::fprintf(stderr, "facet bench: %s\n", plotError.c_str());
        return kExitFailed;
    }
    if (!plotWarning.empty()) std::fprintf(stderr, "facet bench: warning: %s\n", plotWarning.c_str());
    if (!asJson) std::printf("\nwrote %s/bench.md, bench.json, bench.png\n", outDir.c_str());
    return materialErrors ? kExitMaterialError : kExitOk;
}

}  // namespace facet
