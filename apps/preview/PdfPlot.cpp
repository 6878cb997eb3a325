// PdfPlot: the sample histogram beside the integrated pdf (see PdfPlot.h).
#include "PdfPlot.h"

#include "PlotCanvas.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>

namespace facet::preview {

namespace {

// A perceptually ordered ramp (dark blue, teal, green, yellow): equal steps in
// count read as roughly equal steps in lightness, also in grey print.
Rgb ramp(double t) {
    static constexpr Rgb kStops[] = {{0.267f, 0.005f, 0.329f}, {0.229f, 0.322f, 0.546f}, {0.128f, 0.567f, 0.551f},
                                     {0.369f, 0.789f, 0.383f}, {0.993f, 0.906f, 0.144f}};
    constexpr int kLast = int(std::size(kStops)) - 1;
    t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * kLast;
    int i = std::min(int(t), kLast - 1);
    float f = float(t - i);
    const Rgb &a = kStops[i], &b = kStops[i + 1];
    return {a.r + (b.r - a.r) * f, a.g + (b.g - a.g) * f, a.b + (b.b - a.b) * f};
}

std::string checkHistogram(const SampleHistogram& h, const PdfPlotOptions& o, const std::string& path) {
    if (path.empty()) return "no output path for the pdf plot";
    if (std::string e = checkPlotSize(o.width, o.height); !e.empty()) return e;
    if (h.rows < 1 || h.columns < 1 || h.rows > 1024 || h.columns > 2048)
        return fmt::format("pdf plot grid {} x {} is outside 1 .. 1024 rows and 1 .. 2048 columns", h.rows, h.columns);
    size_t cells = size_t(h.rows) * size_t(h.columns);
    if (h.observed.size() != cells || h.expected.size() != cells)
        return fmt::format("pdf plot: {} observed and {} expected counts for a {} x {} grid", h.observed.size(),
                           h.expected.size(), h.rows, h.columns);
    for (const auto* v : {&h.observed, &h.expected})
        for (double x : *v)
            if (!std::isfinite(x) || x < 0) return "pdf plot: a count is negative or not finite";
    return "";
}

struct Panel {
    double x0, y0, width, height;
};

// One panel: a box per cell, coloured by count / scale.
void drawCells(PlotCanvas& canvas, const Panel& p, const SampleHistogram& h, const std::vector<double>& counts,
               double scale) {
    double cw = p.width / h.columns, ch = p.height / h.rows;
    for (int r = 0; r < h.rows; ++r)
        for (int c = 0; c < h.columns; ++c) {
            double x = p.x0 + c * cw, y = p.y0 + r * ch;
            canvas.box({x, y}, {x + cw, y + ch}, ramp(counts[size_t(r) * h.columns + c] / scale), true);
        }
    canvas.box({p.x0, p.y0}, {p.x0 + p.width, p.y0 + p.height}, {0.3f, 0.3f, 0.3f}, false);
}

// Axis labels of a panel: cos(theta) on the left, phi below.
void drawAxes(PlotCanvas& canvas, const Panel& p, double font, bool yLabels) {
    Rgb ink{0.15f, 0.15f, 0.15f};
    const char* cosTicks[] = {"1", "0", "-1"};
    for (int k = 0; k < 3; ++k) {
        double y = p.y0 + p.height * k / 2;
        canvas.line({p.x0 - 4, y}, {p.x0, y}, {ink, 1});
        if (yLabels) canvas.text({p.x0 - 7, y}, cosTicks[k], font, ink, HAlign::Right, VAlign::Center);
    }
    const char* phiTicks[] = {"0", "90", "180", "270", "360"};
    for (int k = 0; k < 5; ++k) {
        double x = p.x0 + p.width * k / 4;
        canvas.line({x, p.y0 + p.height}, {x, p.y0 + p.height + 4}, {ink, 1});
        std::string label = phiTicks[k];
        if (canvas.rendersDegreeSign()) label += "\xC2\xB0";
        canvas.text({x, p.y0 + p.height + 7}, label, font, ink, HAlign::Center, VAlign::Top);
    }
    canvas.text({p.x0 + p.width / 2, p.y0 + p.height + 9 + 1.3 * font}, "phi (azimuth of wi)", font, ink,
                HAlign::Center, VAlign::Top);
    if (yLabels)
        canvas.text({4, p.y0 - 0.6 * font}, "cos theta", font, ink, HAlign::Left, VAlign::Bottom);
}

// The shared colour scale under the panels, labelled 0 and `scale`.
void drawColourBar(PlotCanvas& canvas, double x0, double y, double width, double font, double scale) {
    constexpr int kSteps = 128;
    double h = std::max(6.0, 0.8 * font);
    for (int i = 0; i < kSteps; ++i) {
        double a = x0 + width * i / kSteps, b = x0 + width * (i + 1) / kSteps;
        canvas.box({a, y}, {b, y + h}, ramp((i + 0.5) / kSteps), true);
    }
    Rgb ink{0.15f, 0.15f, 0.15f};
    canvas.box({x0, y}, {x0 + width, y + h}, {0.3f, 0.3f, 0.3f}, false);
    canvas.text({x0 - 6, y + h / 2}, "0", font, ink, HAlign::Right, VAlign::Center);
    canvas.text({x0 + width + 6, y + h / 2}, fmt::format("{:.4g} samples per cell", scale), font, ink, HAlign::Left,
                VAlign::Center);
}

}  // namespace

std::string writePdfPlot(const SampleHistogram& histogram, const PdfPlotOptions& options, const std::string& path,
                         std::string* warning) {
    if (std::string e = checkHistogram(histogram, options, path); !e.empty()) return e;
    try {
        double scale = 0, observedTotal = 0;
        for (double v : histogram.observed) scale = std::max(scale, v), observedTotal += v;
        for (double v : histogram.expected) scale = std::max(scale, v);
        if (!(scale > 0)) return "the pdf plot has no samples and no expected counts: nothing to draw";

        std::string font = plotFontOrDefault(options.fontPath);
        PlotCanvas canvas(options.width, options.height, font);
        std::string note = noTextWarning(canvas, font);
        double size = plotFontSize(options.width, options.height);
        bool text = canvas.hasFont();
        Rgb ink{0.1f, 0.1f, 0.1f};
        // Layout, top to bottom: title lines, panel headers, the two panels
        // (2:1, the aspect of 2 pi by 2), phi labels, the colour bar.
        double top = (options.title.empty() ? 0 : 1.8 * size) + (options.subtitle.empty() ? 0 : 1.5 * size) +
                     1.8 * size + 8;
        double left = 4.5 * size, right = 1.5 * size, gap = 2.5 * size;
        double bottom = 6.5 * size;
        double panelWidth = (options.width - left - right - gap) / 2;
        double panelHeight = std::min(panelWidth / 2, options.height - top - bottom);
        if (panelWidth < 32 || panelHeight < 16) {
            // Too small for the labelled layout: the two panels alone.
            text = false;
            top = 2, left = 2, right = 2, gap = 4, bottom = 2;
            panelWidth = (options.width - left - right - gap) / 2;
            panelHeight = std::min(panelWidth / 2, options.height - top - bottom);
        }
        Panel observed{left, top, panelWidth, panelHeight};
        Panel expected{left + panelWidth + gap, top, panelWidth, panelHeight};
        drawCells(canvas, observed, histogram, histogram.observed, scale);
        drawCells(canvas, expected, histogram, histogram.expected, scale);
        if (text) {
            double y = 1.4 * size;
            if (!options.title.empty())
                canvas.text({options.width / 2.0, y}, options.title, 1.2 * size, ink, HAlign::Center), y += 1.5 * size;
            if (!options.subtitle.empty()) canvas.text({options.width / 2.0, y}, options.subtitle, size, ink, HAlign::Center);
            canvas.text({observed.x0 + panelWidth / 2, top - 0.5 * size},
                        fmt::format("histogram of {:.0f} samples", observedTotal), size, ink, HAlign::Center);
            canvas.text({expected.x0 + panelWidth / 2, top - 0.5 * size}, "pdf integrated over each cell, times N",
                        size, ink, HAlign::Center);
            drawAxes(canvas, observed, 0.9 * size, true);
            drawAxes(canvas, expected, 0.9 * size, false);
            drawColourBar(canvas, left + panelWidth / 2, top + panelHeight + 3.6 * size, panelWidth, 0.9 * size,
                          scale);
        }
        noteNoRoomForText(canvas, text, note);
        if (!note.empty()) {
            if (warning) *warning = note;
            else std::fprintf(stderr, "warning: %s\n", note.c_str());
        }
        return canvas.write(path);
    } catch (const std::exception& e) {
        return std::string("cannot draw the pdf plot: ") + e.what();
    }
}

}  // namespace facet::preview
