// PdfPlot: the picture of `facet render --plot pdf`: where a sampler's
// directions fell beside where its pdf says they should fall.
//
// Both panels cover the whole sphere of wi on one grid of equal-area cells,
// cos(theta) from 1 (top, the normal) to -1 (bottom) against phi from 0 to
// 2 pi (left to right): the left panel the histogram of the samples, the
// right one the expected count of each cell (N times the pdf integrated over
// it). They share one colour scale, so a sampler that matches its pdf gives
// two pictures that differ only by noise; the chi-square tests of the
// sampling suite compare the same two arrays (ChiSquare.h).
#pragma once

#include <string>
#include <vector>

namespace facet::preview {

// Counts on a cos(theta) x phi grid, row-major from cos(theta) = 1, phi = 0.
struct SampleHistogram {
    int rows = 0, columns = 0;
    std::vector<double> observed;  // samples per cell
    std::vector<double> expected;  // N times the pdf's integral over the cell
};

struct PdfPlotOptions {
    int width = 1200, height = 450;  // the panels fill 3:8
    std::string title;     // drawn at the top; empty: none
    std::string subtitle;  // a second line (e.g. the chi-square result)
    std::string fontPath;  // as LobePlotOptions::fontPath (Plots.h)
};

// Draws the two panels. Returns "" or an error message; a non-fatal problem
// (no font: no text) goes to *warning, or to stderr when warning is null.
std::string writePdfPlot(const SampleHistogram& histogram, const PdfPlotOptions& options, const std::string& path,
                         std::string* warning = nullptr);

}  // namespace facet::preview
