// BenchPlot: the log-log scatter plot of `facet bench` (see BenchPlot.h),
// drawn on the same PlotCanvas as the `facet render` plots.
#include "BenchPlot.h"

#include "PlotCanvas.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace facet::bench {

namespace {

using preview::HAlign;
using preview::PlotCanvas;
using preview::Rgb;
using preview::Stroke;
using preview::VAlign;
using PlotPoint = preview::Point;

constexpr Rgb rgb8(int r, int g, int b) { return {float(r) / 255, float(g) / 255, float(b) / 255}; }
const Rgb kWhite = rgb8(255, 255, 255), kBlack = rgb8(0, 0, 0), kGrid = rgb8(225, 225, 225),
          kMinorGrid = rgb8(242, 242, 242), kText = rgb8(40, 40, 40), kLeader = rgb8(150, 150, 150);
// Material colours (colour-blind friendly, Okabe & Ito 2008), cycled.
const Rgb kPalette[] = {rgb8(0, 114, 178), rgb8(213, 94, 0),  rgb8(0, 158, 115),   rgb8(204, 121, 167),
                        rgb8(230, 159, 0), rgb8(86, 180, 233), rgb8(120, 120, 120), rgb8(0, 0, 0)};
Rgb materialColor(size_t material) { return kPalette[material % std::size(kPalette)]; }

// Text sizes (nominal glyph height, output pixels).
constexpr double kFont = 17, kTitleFont = 26;

enum class Shape { Circle, Square, Triangle, Diamond };

Shape shapeOf(const std::string& backend) {
    if (backend == "simd") return Shape::Circle;
    if (backend == "scalar") return Shape::Square;
    if (backend == "interp") return Shape::Triangle;
    return Shape::Diamond;  // aot
}

// A marker of radius r centred on c: filled, or a 2-pixel outline.
void marker(PlotCanvas& canvas, PlotPoint c, double r, Shape shape, Rgb color, bool filled) {
    std::vector<PlotPoint> outline;
    switch (shape) {
        case Shape::Circle:
            for (int i = 0; i < 24; ++i)
                outline.push_back({c.x + r * std::cos(i * M_PI / 12), c.y + r * std::sin(i * M_PI / 12)});
            break;
        case Shape::Square: {
            double h = 0.85 * r;
            outline = {{c.x - h, c.y - h}, {c.x + h, c.y - h}, {c.x + h, c.y + h}, {c.x - h, c.y + h}};
            break;
        }
        case Shape::Triangle:  // pointing up, centred
            outline = {{c.x, c.y - r}, {c.x + 1.05 * r, c.y + 0.75 * r}, {c.x - 1.05 * r, c.y + 0.75 * r}};
            break;
        case Shape::Diamond: {
            double h = 1.15 * r;
            outline = {{c.x, c.y - h}, {c.x + h, c.y}, {c.x, c.y + h}, {c.x - h, c.y}};
            break;
        }
    }
    canvas.polygon(outline, color, filled, 2);
}

std::string shortMode(const std::string& mode) {
    if (mode == "tol 1e-3") return "t1e-3";
    if (mode == "tol 1e-5") return "t1e-5";
    if (mode == "hand-written") return "";
    return mode;
}

// "1e-9", "0.01", "1", "100", "1e5": decade tick labels.
std::string decadeLabel(int k) {
    if (k >= 0 && k <= 4) return fmt::format("{}", int(std::lround(std::pow(10.0, k))));
    if (k >= -2 && k < 0) return fmt::format("{:.{}f}", std::pow(10.0, k), -k);
    return fmt::format("1e{}", k);
}

struct Box {
    double x0, y0, x1, y1;
    bool overlaps(const Box& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
};

struct Point {
    size_t material;
    std::string backend, label;
    double ns, maxRel, p999;
    double x = 0, y = 0, yp = 0;
    bool clippedTop = false;
};

// Places each point group's label at the first free spot among candidates
// around the point, at growing distances (with a leader line once it is
// not adjacent), inside the plot area and clear of markers and other labels.
struct LabelGroup {
    double x, y;
    size_t material;
    std::string text;
};
void drawLabels(PlotCanvas& canvas, const std::vector<LabelGroup>& groups, std::vector<Box> occupied, Box area) {
    const double th = kFont;
    for (const LabelGroup& g : groups) {
        double tw = canvas.textWidth(g.text, kFont);
        std::vector<PlotPoint> candidates;  // top-left corners
        for (double d : {12, 30, 52, 80, 115})
            for (auto [ux, uy] : std::initializer_list<std::pair<int, int>>{
                     {1, 0}, {-1, 0}, {1, -1}, {1, 1}, {-1, -1}, {-1, 1}, {0, -1}, {0, 1}}) {
                double x = ux > 0 ? g.x + d : ux < 0 ? g.x - d - tw : g.x - tw / 2;
                double y = uy > 0 ? g.y + d - th / 2 : uy < 0 ? g.y - d - th / 2 : g.y - th / 2;
                if (uy != 0 && ux == 0) y = uy > 0 ? g.y + d : g.y - d - th;
                candidates.push_back({x, y});
            }
        Box chosen{};
        bool found = false;
        for (PlotPoint c : candidates) {
            Box b{c.x - 3, c.y - 3, c.x + tw + 3, c.y + th + 3};
            if (b.x0 < area.x0 + 2 || b.x1 > area.x1 - 2 || b.y0 < area.y0 + 2 || b.y1 > area.y1 - 2) continue;
            if (std::any_of(occupied.begin(), occupied.end(), [&](const Box& o) { return o.overlaps(b); })) continue;
            chosen = b;
            found = true;
            break;
        }
        if (!found) {  // crowded: right of the point, clamped into the plot
            double x = std::clamp(g.x + 12, area.x0 + 4, area.x1 - tw - 4);
            double y = std::clamp(g.y - th / 2, area.y0 + 4, area.y1 - th - 4);
            chosen = {x - 3, y - 3, x + tw + 3, y + th + 3};
        }
        double cx = std::clamp(g.x, chosen.x0, chosen.x1), cy = std::clamp(g.y, chosen.y0, chosen.y1);
        if (std::hypot(cx - g.x, cy - g.y) > 14) canvas.line({g.x, g.y}, {cx, cy}, {kLeader});
        canvas.box({chosen.x0, chosen.y0}, {chosen.x1, chosen.y1}, kWhite, true);
        canvas.text({chosen.x0 + 3, chosen.y0 + 3}, g.text, kFont, materialColor(g.material), HAlign::Left, VAlign::Top);
        occupied.push_back(chosen);
    }
}

// Legend right of the plot area: materials (colour), backends (shape), the
// two error markers, the label abbreviations. The material rows close up
// (down to the colour box's height) when many materials would run the legend
// off the canvas.
void drawLegend(PlotCanvas& canvas, const BenchReport& report, double lx, double ly) {
    const double row = 1.45 * kFont, gap = 0.9 * kFont;
    const double otherRows = 4 * (row + 2) + 9 * row + 4 * gap + 10;
    const double materials = double(std::max<size_t>(report.materials.size(), 1));
    const double materialRow = std::clamp((canvas.height() - ly - otherRows) / materials, 15.0, row);
    auto heading = [&](const std::string& s) {
        canvas.text({lx, ly}, s, kFont, kBlack, HAlign::Left, VAlign::Top);
        ly += row + 2;
    };
    auto entry = [&](const std::string& s) {
        canvas.text({lx + 26, ly}, s, kFont, kText, HAlign::Left, VAlign::Top);
        ly += row;
    };
    heading("materials");
    for (size_t mi = 0; mi < report.materials.size(); ++mi) {
        canvas.box({lx, ly}, {lx + 16, ly + 14}, materialColor(mi), true);
        std::string name = report.materials[mi].material;
        if (name.size() > 26) name = name.substr(0, 25) + "~";
        canvas.text({lx + 26, ly}, name, kFont, kText, HAlign::Left, VAlign::Top);
        ly += materialRow;
    }
    ly += gap;
    heading("backends");
    for (auto [b, what] : {std::pair{"simd", "simd (JIT)"}, {"scalar", "scalar (JIT)"},
                           {"interp", "interp (reference)"}, {"aot", "aot (hand-written)"}}) {
        marker(canvas, {lx + 8, ly + 7}, 7, shapeOf(b), kText, true);
        entry(what);
    }
    ly += gap;
    heading("y: regular sample");
    marker(canvas, {lx + 8, ly + 7}, 7, Shape::Circle, kText, true);
    entry("max rel. error");
    marker(canvas, {lx + 8, ly + 7}, 6, Shape::Circle, kText, false);
    entry("p99.9 rel. error");
    canvas.text({lx, ly}, fmt::format("errors < {:g} drawn", kPlotErrorFloor), kFont, kText, HAlign::Left, VAlign::Top);
    ly += row;
    canvas.text({lx, ly}, "on the floor; ^ = off scale", kFont, kText, HAlign::Left, VAlign::Top);
    ly += row + gap;
    heading("labels: backend mode");
    canvas.text({lx, ly}, "t1e-3 = tolerance=1e-3", kFont, kText, HAlign::Left, VAlign::Top);
    ly += row + gap;
    if (report.settings.quick) canvas.text({lx, ly}, "QUICK RUN (noisy)", kFont, rgb8(200, 0, 0), HAlign::Left, VAlign::Top);
}

}  // namespace

std::string writeScatterPlot(const BenchReport& report, const std::string& path, std::string* warning) {
    const double W = kPlotWidth, H = kPlotHeight;
    const double left = 130, right = W - 400, top = 90, bottom = H - 110;  // the plot area
    std::string font = preview::findPlotFont();
    PlotCanvas canvas(kPlotWidth, kPlotHeight, font);
    if (warning) *warning = preview::noTextWarning(canvas, font);

    // Points: one per row; rows of one material and backend that land on
    // the same spot share a label ("simd exact/fast").
    std::vector<Point> points;
    for (size_t mi = 0; mi < report.materials.size(); ++mi)
        for (const BenchRow& r : report.materials[mi].rows)
            if (r.nsPerEval > 0 && std::isfinite(r.nsPerEval))
                points.push_back({mi, r.backend, shortMode(r.mode), r.nsPerEval, r.regular.maxRel, r.regular.p999Rel});

    // Axis ranges in decades.
    double xlo = 0, xhi = 1, ylo = std::log10(kPlotErrorFloor), yhi = -2;
    if (!points.empty()) {
        double mn = INFINITY, mx = 0, emax = 0;
        for (const Point& p : points) {
            mn = std::min(mn, p.ns), mx = std::max(mx, p.ns);
            emax = std::max({emax, std::isfinite(p.maxRel) ? p.maxRel : 1e300, p.p999});
        }
        xlo = std::floor(std::log10(mn) - 0.05);
        xhi = std::ceil(std::log10(mx) + 0.05);
        yhi = std::clamp(std::ceil(std::log10(std::max(emax, kPlotErrorFloor)) + 0.05), ylo + 2, 3.0);
    }
    auto X = [&](double ns) { return left + (std::log10(ns) - xlo) / (xhi - xlo) * (right - left); };
    auto Y = [&](double e, bool* clipped = nullptr) {
        double l = std::log10(std::max(e, kPlotErrorFloor));
        if (!std::isfinite(e) || l > yhi) {
            if (clipped) *clipped = true;
            l = yhi;
        }
        return bottom - (l - ylo) / (yhi - ylo) * (bottom - top);
    };

    // Grid, ticks and tick labels.
    for (int k = int(xlo); k <= int(xhi); ++k) {
        for (int m = 2; m <= 9 && k < int(xhi); ++m) {
            double x = X(m * std::pow(10.0, k));
            canvas.line({x, top}, {x, bottom}, {kMinorGrid});
        }
        double x = X(std::pow(10.0, k));
        canvas.line({x, top}, {x, bottom}, {kGrid});
        canvas.line({x, bottom}, {x, bottom + 8}, {kBlack, 1.5});
        canvas.text({x, bottom + 14}, decadeLabel(k), kFont, kText, HAlign::Center, VAlign::Top);
    }
    for (int k = int(ylo); k <= int(yhi); ++k) {
        double y = Y(std::pow(10.0, k));
        canvas.line({left, y}, {right, y}, {kGrid});
        canvas.line({left - 8, y}, {left, y}, {kBlack, 1.5});
        std::string t = k == int(ylo) ? "<=" + decadeLabel(k) : decadeLabel(k);
        canvas.text({left - 14, y}, t, kFont, kText, HAlign::Right, VAlign::Center);
    }
    canvas.box({left, top}, {right, bottom}, kBlack, false, 1.5);

    // Titles; the y-axis title sits above the axis, where it reads left to right.
    canvas.text({(left + right) / 2, 12}, "facet bench: speed vs error", kTitleFont, kBlack, HAlign::Center, VAlign::Top);
    canvas.text({(left + right) / 2, bottom + 50}, "ns per evaluation (log scale; lower is faster)", kFont, kText,
                HAlign::Center, VAlign::Top);
    canvas.text({left - 14, top - 12}, "relative error vs double interpreter (log scale)", kFont, kText, HAlign::Left,
                VAlign::Bottom);

    // Points: positions, then groups of coinciding points.
    for (Point& p : points) {
        p.x = X(p.ns);
        p.y = Y(p.maxRel, &p.clippedTop);
        p.yp = Y(p.p999);
    }
    std::vector<LabelGroup> groups;
    for (const Point& p : points) {
        bool merged = false;
        for (LabelGroup& g : groups)
            if (g.material == p.material && std::abs(g.x - p.x) <= 10 && std::abs(g.y - p.y) <= 10 &&
                g.text.rfind(p.backend, 0) == 0) {
                if (!p.label.empty() && p.backend != "interp") g.text += "/" + p.label;
                merged = true;
                break;
            }
        // The interpreter has no math modes: its rows differ only by timing noise.
        bool plain = p.label.empty() || p.backend == "interp";
        if (!merged) groups.push_back({p.x, p.y, p.material, plain ? p.backend : p.backend + " " + p.label});
    }

    // p99.9 markers and their links first, so that the max markers sit on top.
    for (const Point& p : points)
        if (std::abs(p.yp - p.y) >= 1) {
            Rgb c = materialColor(p.material);
            canvas.line({p.x, p.y}, {p.x, p.yp}, {c, 1.5, 3, 3});
            marker(canvas, {p.x, p.yp}, 6, shapeOf(p.backend), c, false);
        }
    std::vector<Box> occupied;
    for (const Point& p : points) {
        Rgb c = materialColor(p.material);
        marker(canvas, {p.x, p.y}, 7, shapeOf(p.backend), c, true);
        if (p.clippedTop) canvas.text({p.x, p.y - 10}, "^", kFont, c, HAlign::Center, VAlign::Bottom);
        occupied.push_back({p.x - 8, p.y - 8, p.x + 8, p.y + 8});
    }
    drawLabels(canvas, groups, occupied, {left, top, right, bottom});
    drawLegend(canvas, report, right + 30, top);
    return canvas.write(path);
}

}  // namespace facet::bench
