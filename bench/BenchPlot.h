// BenchPlot: the speed-vs-error scatter plot of `facet bench` (PNG).
//
// One point per row of the report: x = ns/eval, y = max relative error on
// the regular sample (filled marker; errors below the floor are drawn on
// it), with the p99.9 relative error as a hollow marker joined by a thin
// line. Both axes are logarithmic. Colour = material, marker shape =
// backend; each point is labelled with its backend and math mode (points
// that coincide share one label). Drawn on the PlotCanvas of the `facet
// render` plots (apps/preview/PlotCanvas.h): without a TrueType font the
// plot is drawn without text.
#pragma once

#include "BenchRunner.h"

#include <string>

namespace facet::bench {

constexpr int kPlotWidth = 1600, kPlotHeight = 1000;
constexpr double kPlotErrorFloor = 1e-9;

// Writes the plot to `path` (any format OpenImageIO writes; the bench uses
// PNG). Returns "" or an error message; `warning`, when given, receives ""
// or why the plot has no text.
std::string writeScatterPlot(const BenchReport& report, const std::string& path, std::string* warning = nullptr);

}  // namespace facet::bench
