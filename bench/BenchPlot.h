// BenchPlot: the speed-vs-error scatter plot of `facet bench` (PNG).
//
// One point per row of the report: x = ns/eval, y = max relative error on
// the regular sample (filled marker; errors below the floor are drawn on
// it), with the p99.9 relative error as a hollow marker joined by a thin
// line. Both axes are logarithmic. Colour = material, marker shape =
// backend; each point is labelled with its backend and math mode (points
// that coincide share one label). Axes, ticks and text are drawn into a
// pixel buffer with the built-in bitmap font and written through
// OpenImageIO, so the picture needs no plotting library.
#pragma once

#include "BenchRunner.h"

#include <string>

namespace facet::bench {

constexpr int kPlotWidth = 1600, kPlotHeight = 1000;
constexpr double kPlotErrorFloor = 1e-9;

// Writes the plot to `path` (any format OpenImageIO writes; the bench uses
// PNG). Returns "" or an error message.
std::string writeScatterPlot(const BenchReport& report, const std::string& path);

}  // namespace facet::bench
