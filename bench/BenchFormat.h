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
// One line per material for the sampler rows: SIMD exact ns/sample and
// ns/pdf, SIMD fast, speed-up over scalar, JIT/AOT ("" without them).
std::string samplerSummaryLine(const MaterialBench& m);

// "Kulla-Conty tables: ggx x smith_height_correlated (key), built in X ms
// (cold, 64 x 64 grid; ...) / loaded from cache in Y ms" for a material with
// energy = kulla_conty, "" for the others.
std::string energyTableLine(const MaterialBench& m);
// "Smith Lambda table: student_t_g3, built in X ms (cold, 4129 nodes; one
// thread) / loaded from cache in Y ms" for a material whose Smith masking
// uses its NDF's Lambda table, "" for the others.
std::string lambdaTableLine(const MaterialBench& m);
// "Kulla-Conty against the random walk ...", or "" without one.
std::string walkLine(const MaterialBench& m);

}  // namespace facet::bench
