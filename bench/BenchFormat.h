// BenchFormat: the `facet bench` report as a terminal table, Markdown and JSON.
//
// All three show the same rows (BenchRunner.h); the JSON is the complete
// record (every field, worst inputs included) and is what scripts and the
// tests read. Non-finite numbers are written as JSON null.
#pragma once

#include "BenchRunner.h"

#include <cstdio>
#include <string>

namespace facet::bench {

void printTable(const BenchReport& report, std::FILE* out);
std::string markdown(const BenchReport& report);
std::string json(const BenchReport& report);

// One line per material: SIMD exact vs AOT and vs scalar, compile times.
std::string summaryLine(const MaterialBench& m);

}  // namespace facet::bench
