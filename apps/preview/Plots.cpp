// Plots: the lobe plot (a compiled kernel's BRDF slice in the plane of
// incidence, polar) and the NDF plot (D(theta_m) of resolved NDFs, log or
// linear) of `facet render --plot lobe|ndf`. The numbers come from the
// kernel and the reference interpreter; this file lays the picture out and
// draws it on a PlotCanvas (ImageBufAlgo).
#include "Plots.h"

#include "Color.h"
#include "PlotCanvas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <numbers>

namespace facet::preview {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
// Samples of theta in [-90, 90] degrees: a quarter-degree step, fine enough
// for the narrow lobes of alpha ~ 0.05 and for locating a peak to 0.25 deg.
constexpr int kSamples = 721;
// One lobe per palette colour (more lobes in one polar plot are unreadable
// anyway); NDF curves beyond the palette repeat it dashed, then dotted.
constexpr size_t kMaxLobes = 8;
constexpr size_t kMaxNdfCurves = 24;

// Okabe & Ito (2008) colour-blind-safe palette, ordered so that the first
// colours are distinct in every kind of colour vision and readable on white
// (yellow last; black is kept for the axes).
constexpr Rgb kPalette[] = {
    {0.000f, 0.447f, 0.698f},  // blue
    {0.835f, 0.369f, 0.000f},  // vermillion
    {0.000f, 0.620f, 0.451f},  // bluish green
    {0.800f, 0.475f, 0.655f},  // reddish purple
    {0.902f, 0.624f, 0.000f},  // orange
    {0.337f, 0.706f, 0.914f},  // sky blue
    {0.000f, 0.000f, 0.000f},  // black
    {0.941f, 0.894f, 0.259f},  // yellow
};
constexpr Rgb kInk{0.08f, 0.08f, 0.08f};       // text, axes, the surface
constexpr Rgb kMuted{0.40f, 0.40f, 0.40f};     // secondary labels
constexpr Rgb kGrid{0.82f, 0.82f, 0.82f};      // major grid
constexpr Rgb kGridMinor{0.91f, 0.91f, 0.91f}; // minor grid

Rgb curveColor(size_t i) { return kPalette[i % std::size(kPalette)]; }

// Curve i's stroke: its palette colour, solid for the first round of the
// palette, then dashed, then dotted (scaled with the font size).
Stroke curveStroke(size_t i, double fontSize) {
    Stroke s{curveColor(i), 2.2};
    switch (i / std::size(kPalette)) {
        case 0: break;
        case 1: s.dash = 0.7 * fontSize, s.gap = 0.4 * fontSize; break;
        default: s.dash = 0.2 * fontSize, s.gap = 0.3 * fontSize; break;
    }
    return s;
}

double thetaAt(int k) { return -90.0 + 180.0 * k / (kSamples - 1); }
// The lobe plot over the whole circle (a lobe that scatters below the
// surface): theta_o in [-180, 180], twice the samples for the same step.
constexpr int kCircleSamples = 2 * kSamples - 1;
double circleThetaAt(int k) { return -180.0 + 360.0 * k / (kCircleSamples - 1); }

// The next, smaller font size for a layout that did not fit; below ~6
// pixels text is illegible and the plot is better drawn without.
void shrinkOrDropText(double& fontSize, bool& text) {
    constexpr double kSmallestLegible = 6;
    if (fontSize * 0.85 >= kSmallestLegible) fontSize *= 0.85;
    else text = false;
}

// "30°" where the font draws the degree sign, else "30 deg" (`number` is
// the formatted angle).
std::string degrees(const PlotCanvas& canvas, const std::string& number) {
    return number + (canvas.rendersDegreeSign() ? "\xC2\xB0" : " deg");
}

// ---- lobe plot --------------------------------------------------------

struct LobeCurve {
    double thetaI = 0;
    std::vector<double> theta;  // signed theta_o of each sample, degrees
    std::vector<double> value;  // luminance(f) |cos(theta_o)| per sample
    double peak = 0;
    int peakIndex = 0;
};

std::string checkLobeOptions(const LobePlotOptions& o, const std::string& path) {
    if (path.empty()) return "no output path for the lobe plot";
    if (std::string e = checkPlotSize(o.width, o.height); !e.empty()) return e;
    if (o.incidentDegrees.empty()) return "the lobe plot needs at least one incident angle";
    if (o.incidentDegrees.size() > kMaxLobes) return fmt::format("the lobe plot draws at most {} incident angles", kMaxLobes);
    const double top = o.wholeSphere ? 180 : 90;
    for (double t : o.incidentDegrees)
        if (!(t >= 0 && t < top) || (o.wholeSphere && t == 90))
            return fmt::format("incident angle theta_i = {:g} is outside [0, {:g}) degrees{}", t, top,
                               o.wholeSphere ? " or in the surface (90)" : "");
    return "";
}

// One curve: the kernel in the plane of incidence at default inputs.
LobeCurve evaluateLobe(const Kernel& kernel, double thetaI, bool wholeSphere, int64_t& invalid) {
    LobeCurve c;
    c.thetaI = thetaI;
    const int samples = wholeSphere ? kCircleSamples : kSamples;
    for (int k = 0; k < samples; ++k) c.theta.push_back(wholeSphere ? circleThetaAt(k) : thetaAt(k));
    std::vector<float> dir[6], rgb[3];
    for (auto& d : dir) d.resize(samples);
    for (auto& ch : rgb) ch.assign(samples, 0.0f);
    float sinI = float(std::sin(thetaI * kDeg)), cosI = float(std::cos(thetaI * kDeg));
    for (int k = 0; k < samples; ++k) {
        double to = c.theta[k] * kDeg;
        dir[0][k] = -sinI;
        dir[1][k] = 0;
        dir[2][k] = cosI;
        dir[3][k] = float(std::sin(to));
        dir[4][k] = 0;
        dir[5][k] = float(std::cos(to));
    }
    const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
    const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
    float* out[3] = {rgb[0].data(), rgb[1].data(), rgb[2].data()};
    invalid += kernel.evalBatch(samples, wi, wo, nullptr, out);

    c.value.resize(samples);
    for (int k = 0; k < samples; ++k) {
        double v = luminance(rgb[0][k], rgb[1][k], rgb[2][k]) * std::abs(std::cos(c.theta[k] * kDeg));
        // The kernel never returns NaN, Inf or negatives (SPEC 2); if it
        // did, the picture shows a gap rather than a scale ruined by it.
        c.value[k] = std::isfinite(v) && v > 0 ? v : 0;
        if (c.value[k] > c.peak) {
            c.peak = c.value[k];
            c.peakIndex = k;
        }
    }
    return c;
}

// What the radius means, under the legend.
constexpr const char* kLobeNote = "radius: luminance(f) |cos(theta_o)| / peak (f in 1/sr); dashed: incident direction";

std::string lobeLegendText(const PlotCanvas& canvas, const LobeCurve& c) {
    std::string head = "theta_i = " + degrees(canvas, fmt::format("{:g}", c.thetaI));
    if (c.peak <= 0) return head + ": zero";
    return head + fmt::format(": peak {:.3g} at theta_o = ", c.peak) + degrees(canvas, fmt::format("{:g}", c.theta[size_t(c.peakIndex)]));
}

// Returns whether the labels fitted (false: drawn without text).
// `whole`: the full circle (below the surface too), else the upper half.
bool drawLobePlot(PlotCanvas& canvas, const std::vector<LobeCurve>& curves, const std::string& title, bool whole) {
    const double W = canvas.width(), H = canvas.height();
    double fs = plotFontSize(canvas.width(), canvas.height());
    bool text = canvas.hasFont();
    // Laid out with the base font size; when the legend is wider than the
    // image or the disk too small, again with smaller text, and below a
    // legible size as a bare picture.
    double margin, titleH, angleLabelW, angleLabelH, radiusLabelH, legendRowH, noteH, R;
    double swatchW, entryW, colGap;
    size_t cols = 1, rows = 0;
    std::vector<std::string> legend;
    for (const LobeCurve& c : curves) legend.push_back(lobeLegendText(canvas, c));
    for (;;) {
        margin = text ? fs : 4;
        titleH = text && !title.empty() ? 2.4 * fs : 0;
        angleLabelW = text ? canvas.textWidth(degrees(canvas, "-90"), 0.9 * fs) + 0.6 * fs : 0;
        angleLabelH = text ? 1.5 * fs : 0;
        radiusLabelH = text ? 1.5 * fs : 0;
        noteH = text ? 1.6 * fs : 0;
        swatchW = 2.4 * fs, colGap = 2 * fs;
        entryW = 0;
        for (const std::string& s : legend) entryW = std::max(entryW, swatchW + 0.6 * fs + canvas.textWidth(s, fs));
        double fitting = std::max(0.0, (W - 2 * margin + colGap) / (entryW + colGap));
        cols = text ? std::clamp<size_t>(size_t(fitting), 1, curves.size()) : 1;
        rows = text ? (curves.size() + cols - 1) / cols : 0;
        legendRowH = 1.6 * fs;
        double belowDisk = (whole ? (angleLabelH + radiusLabelH) : radiusLabelH) + rows * legendRowH + noteH;
        R = std::min((W - 2 * margin - 2 * angleLabelW) / 2,
                     (H - 2 * margin - titleH - angleLabelH - belowDisk) / (whole ? 2 : 1));
        double widest = std::max(entryW, canvas.textWidth(kLobeNote, 0.8 * fs));
        if (!text || (R >= 4 * fs && widest <= W - 2 * margin)) break;
        shrinkOrDropText(fs, text);
    }
    R = std::max(R, 4.0);
    double belowDisk = (whole ? (angleLabelH + radiusLabelH) : radiusLabelH) + rows * legendRowH + noteH;
    double contentH = titleH + angleLabelH + (whole ? 2 : 1) * R + belowDisk;
    double top = margin + std::max(0.0, (H - 2 * margin - contentH) / 2);  // centre vertically
    Point centre{W / 2, top + titleH + angleLabelH + R};
    auto polar = [&](double thetaDeg, double r) {
        return Point{centre.x + R * r * std::sin(thetaDeg * kDeg), centre.y - R * r * std::cos(thetaDeg * kDeg)};
    };

    if (text && !title.empty()) canvas.text({W / 2, top}, title, 1.25 * fs, kInk, HAlign::Center, VAlign::Top);

    // Grid: radial lines every 15 degrees, circles at quarter steps of the peak.
    for (int a = whole ? -165 : -75; a <= (whole ? 180 : 75); a += 15)
        if (std::abs(a) != 90) canvas.line(centre, polar(a, 1), {a % 30 == 0 ? kGrid : kGridMinor, 1});
    for (int q = 1; q <= 4; ++q)
        canvas.arc(centre, R * q / 4, 0, whole ? 2 * kPi : kPi, {q == 4 ? kMuted : kGrid, q == 4 ? 1.2 : 1});
    // The surface, a little wider than the disk.
    double overhang = 0.25 * margin + 2;
    canvas.line({centre.x - R - overhang, centre.y}, {centre.x + R + overhang, centre.y}, {kInk, 2});

    if (text) {
        // theta_o labels every 30 degrees just outside the disk (signed: the
        // incident side is negative), the +-90 ones beside the surface ends.
        for (int a = whole ? -150 : -90; a <= (whole ? 180 : 90); a += 30) {
            std::string s = degrees(canvas, fmt::format("{}", a));
            if (std::abs(a) == 90) {
                Point p{centre.x + (a < 0 ? -1 : 1) * (R + overhang + 0.3 * fs), centre.y};
                canvas.text(p, s, 0.9 * fs, kMuted, a < 0 ? HAlign::Right : HAlign::Left, VAlign::Center);
                continue;
            }
            Point p = polar(a, 1 + 0.35 * fs / R);
            bool lower = std::abs(a) > 90;  // (the whole circle's lower half: labels below the disk)
            HAlign h = a % 180 == 0 ? HAlign::Center : (a < 0) ? HAlign::Right : HAlign::Left;
            canvas.text(p, s, 0.9 * fs, kMuted, h, lower ? VAlign::Top : VAlign::Bottom);
        }
        // Radius labels under the surface, on the reflected side.
        for (int q = 1; q <= 4; ++q) {
            static constexpr const char* kRadius[] = {"", "0.25", "0.5", "0.75", "1"};
            canvas.text({centre.x + R * q / 4, centre.y + 0.45 * fs}, kRadius[q], 0.8 * fs, kMuted, HAlign::Center,
                        VAlign::Top);
        }
    }

    // Incident directions first, so that the curves are drawn over them.
    for (size_t i = 0; i < curves.size(); ++i)
        canvas.line(centre, polar(-curves[i].thetaI, 1), {curveColor(i), 1.5, 0.6 * fs, 0.4 * fs});
    for (size_t i = 0; i < curves.size(); ++i) {
        const LobeCurve& c = curves[i];
        if (c.peak <= 0) continue;  // nothing reflected: no curve (the legend says "zero")
        std::vector<Point> pts(c.theta.size());
        for (size_t k = 0; k < pts.size(); ++k) pts[k] = polar(c.theta[k], c.value[k] / c.peak);
        canvas.polyline(pts, {curveColor(i), 2.2});
    }

    if (!text) return false;
    double legendTop = centre.y + (whole ? R + (angleLabelH + radiusLabelH) : radiusLabelH);
    double legendW = cols * entryW + (cols - 1) * colGap;
    double left = (W - legendW) / 2;
    for (size_t i = 0; i < curves.size(); ++i) {
        size_t col = i / rows, row = i % rows;  // fill columns first: angles read downwards
        double x = left + col * (entryW + colGap), y = legendTop + (row + 0.5) * legendRowH;
        canvas.line({x, y}, {x + swatchW, y}, {curveColor(i), 2.2});
        canvas.text({x + swatchW + 0.6 * fs, y}, legend[i], fs, kInk, HAlign::Left, VAlign::Center);
    }
    canvas.text({W / 2, legendTop + rows * legendRowH + 0.3 * fs},
                kLobeNote, 0.8 * fs, kMuted,
                HAlign::Center, VAlign::Top);
    return true;
}

// ---- NDF plot ---------------------------------------------------------

std::string checkNdfInputs(const std::vector<NdfCurve>& curves, const NdfPlotOptions& o, const std::string& path) {
    if (path.empty()) return "no output path for the NDF plot";
    if (std::string e = checkPlotSize(o.width, o.height); !e.empty()) return e;
    if (curves.empty()) return "the NDF plot needs at least one curve";
    if (curves.size() > kMaxNdfCurves) return fmt::format("the NDF plot draws at most {} curves", kMaxNdfCurves);
    for (const NdfCurve& c : curves) {
        if (c.ndf.ndf->wholeLobe)
            return fmt::format("{} is a whole BRDF lobe without a microfacet distribution D(m) (plot it with --plot lobe)",
                               c.ndf.ndf->name);
        if (!c.ndf.valid) return "NDF curve '" + c.label + "' has a non-finite parameter";
    }
    return "";
}

// "1e-3", "0.01", "0.1", "1", "10", "100", "1e3": plain where short.
std::string decadeLabel(int k) {
    if (k >= -2 && k <= 2) return fmt::format("{:g}", std::pow(10.0, k));
    return fmt::format("1e{}", k);
}

// A 1-2-5 step that cuts [0, top] into about five intervals.
double niceStep(double top) {
    double raw = top / 5, p = std::pow(10.0, std::floor(std::log10(raw)));
    double m = raw / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

struct YAxis {
    bool log = true;
    double bottom = 0, top = 1;  // value range (log: powers of ten)
    double step = 0;             // linear tick step
    // Fraction of the axis height, 0 at the bottom; log values <= 0 map to -inf.
    double frac(double v) const {
        if (log) return v > 0 ? (std::log10(v) - std::log10(bottom)) / (std::log10(top) - std::log10(bottom))
                              : -std::numeric_limits<double>::infinity();
        return (v - bottom) / (top - bottom);
    }
};

YAxis chooseYAxis(double maxValue, bool log) {
    YAxis y;
    y.log = log;
    if (log) {
        // From the decade above the peak down five decades: alpha = 0.05
        // GGX peaks near 130 while the rough lobes' tails reach 1e-2 or so.
        int topExp = int(std::floor(std::log10(maxValue))) + 1;
        y.top = std::pow(10.0, topExp);
        y.bottom = std::pow(10.0, topExp - 5);
    } else {
        y.step = niceStep(maxValue);
        y.bottom = 0;
        y.top = std::ceil(maxValue * 1.02 / y.step) * y.step;
    }
    return y;
}

// Curves over theta in [-90, 90] degrees with a legend; the captions say
// what the axes are. Returns whether the labels fitted (false: drawn
// without text).
bool drawCurvePlot(PlotCanvas& canvas, const std::vector<std::string>& labels,
                   const std::vector<std::vector<double>>& values, const YAxis& y, const std::string& title,
                   const std::string& yCaption, const std::string& xCaption) {
    const double W = canvas.width(), H = canvas.height();
    double fs = plotFontSize(canvas.width(), canvas.height());
    bool text = canvas.hasFont();

    std::vector<std::pair<double, std::string>> yTicks;  // value, label
    if (y.log) {
        for (int k = int(std::lround(std::log10(y.bottom))); k <= int(std::lround(std::log10(y.top))); ++k)
            yTicks.emplace_back(std::pow(10.0, k), decadeLabel(k));
    } else {
        for (int i = 0; i * y.step <= y.top * (1 + 1e-9); ++i) yTicks.emplace_back(i * y.step, fmt::format("{:g}", i * y.step));
    }

    double x0, x1, y0, y1, swatchW, legendW, legendRowH;
    for (;;) {
        double margin = text ? fs : 4;
        swatchW = 2.4 * fs, legendRowH = 1.6 * fs;
        double yLabelW = 0;
        if (text)
            for (const auto& t : yTicks) yLabelW = std::max(yLabelW, canvas.textWidth(t.second, 0.9 * fs));
        legendW = 0;
        if (text)
            for (const std::string& label : labels)
                legendW = std::max(legendW, swatchW + 0.6 * fs + canvas.textWidth(label, fs));
        x0 = margin + (text ? yLabelW + 0.8 * fs : 0);
        x1 = W - margin - (text ? legendW + 1.5 * fs : 0);
        y0 = margin + (text ? (title.empty() ? 0 : 2.0 * fs) + 1.6 * fs : 0);  // title, y caption
        y1 = H - margin - (text ? 3.6 * fs : 0);                               // x labels, x caption
        bool legendFits = legendW <= 0.4 * W && labels.size() * legendRowH <= H - margin - y0;
        if (!text || (x1 - x0 >= 8 * fs && y1 - y0 >= 5 * fs && legendFits)) break;
        shrinkOrDropText(fs, text);
    }
    auto X = [&](double thetaDeg) { return x0 + (thetaDeg + 90) / 180 * (x1 - x0); };
    auto Y = [&](double v) { return y1 - y.frac(v) * (y1 - y0); };

    // Grid and ticks.
    for (int a = -90; a <= 90; a += 15) {
        if (a > -90 && a < 90) canvas.line({X(a), y0}, {X(a), y1}, {a % 30 == 0 ? kGrid : kGridMinor, 1});
        canvas.line({X(a), y1}, {X(a), y1 + (a % 30 == 0 ? 0.4 : 0.25) * fs}, {kInk, 1});
    }
    for (size_t i = 0; i < yTicks.size(); ++i) {
        double v = yTicks[i].first;
        if (i > 0 && i + 1 < yTicks.size()) canvas.line({x0, Y(v)}, {x1, Y(v)}, {kGrid, 1});
        canvas.line({x0 - 0.4 * fs, Y(v)}, {x0, Y(v)}, {kInk, 1});
        if (y.log && i + 1 < yTicks.size())
            for (int m = 2; m <= 9; ++m) canvas.line({x0 - 0.25 * fs, Y(v * m)}, {x0, Y(v * m)}, {kInk, 1});
    }

    // Curves, clipped at the bottom of the axis: a run of samples above it
    // is drawn down to the bottom edge where it leaves the axis.
    for (size_t i = 0; i < labels.size(); ++i) {
        const std::vector<double>& v = values[i];
        std::vector<Point> run;
        auto flush = [&] {
            canvas.polyline(run, curveStroke(i, fs));
            run.clear();
        };
        auto inside = [&](double d) { return std::isfinite(d) && y.frac(d) >= 0; };
        for (int k = 0; k < kSamples; ++k) {
            double d = v[size_t(k)];
            if (inside(d)) {
                if (run.empty() && k > 0 && std::isfinite(v[size_t(k - 1)])) run.push_back({X(thetaAt(k - 1)), y1});
                run.push_back({X(thetaAt(k)), Y(d)});
            } else if (!run.empty()) {
                if (std::isfinite(d)) run.push_back({X(thetaAt(k)), y1});
                flush();
            }
        }
        flush();
    }
    canvas.box({x0, y0}, {x1, y1}, kInk, false, 1);  // the frame, over the curves' ends

    if (!text) return false;
    if (!title.empty()) canvas.text({W / 2, fs}, title, 1.25 * fs, kInk, HAlign::Center, VAlign::Top);
    canvas.text({x0, y0 - 0.5 * fs}, y.log ? yCaption + ", log scale" : yCaption, 0.9 * fs, kMuted, HAlign::Left,
                VAlign::Bottom);
    for (const auto& [v, label] : yTicks)
        canvas.text({x0 - 0.6 * fs, Y(v)}, label, 0.9 * fs, kInk, HAlign::Right, VAlign::Center);
    for (int a = -90; a <= 90; a += 30)
        canvas.text({X(a), y1 + 0.6 * fs}, fmt::format("{}", a), 0.9 * fs, kInk, HAlign::Center, VAlign::Top);
    canvas.text({(x0 + x1) / 2, y1 + 2.2 * fs},
                xCaption + " (" + std::string(canvas.rendersDegreeSign() ? "\xC2\xB0" : "degrees") + ") in the x-z plane",
                0.9 * fs, kMuted, HAlign::Center, VAlign::Top);
    double lx = x1 + 1.5 * fs;
    for (size_t i = 0; i < labels.size(); ++i) {
        double ly = y0 + (i + 0.5) * legendRowH;
        canvas.line({lx, ly}, {lx + swatchW, ly}, curveStroke(i, fs));
        canvas.text({lx + swatchW + 0.6 * fs, ly}, labels[i], fs, kInk, HAlign::Left, VAlign::Center);
    }
    return true;
}

}  // namespace

LobePlotResult writeLobePlot(const Kernel& kernel, const LobePlotOptions& options, const std::string& path) {
    LobePlotResult result;
    result.error = checkLobeOptions(options, path);
    if (!result.error.empty()) return result;
    try {
        std::vector<LobeCurve> curves;
        for (double ti : options.incidentDegrees) {
            curves.push_back(evaluateLobe(kernel, ti, options.wholeSphere, result.invalidLanes));
            result.peakValue.push_back(curves.back().peak);
            result.peakThetaDeg.push_back(curves.back().theta[size_t(curves.back().peakIndex)]);
        }
        std::string font = plotFontOrDefault(options.fontPath);
        PlotCanvas canvas(options.width, options.height, font);
        result.warning = noTextWarning(canvas, font);
        noteNoRoomForText(canvas, drawLobePlot(canvas, curves, options.title, options.wholeSphere), result.warning);
        result.error = canvas.write(path);
    } catch (const std::exception& e) {
        // Out of memory for a huge canvas, or an OIIO failure: a message, not a crash.
        result.error = std::string("cannot draw the lobe plot: ") + e.what();
    }
    return result;
}

ResolvedMaterial<double> ndfAtAlpha(const NdfEntry& ndf, double alpha, std::vector<double> shape) {
    for (size_t i = shape.size(); i < ndf.tableShapeParams.size(); ++i)
        shape.push_back(ndf.canonical[ndf.tableShapeParams[i]].typical);
    bool finite = std::isfinite(alpha);
    for (size_t i = 0; i < shape.size(); ++i) {
        finite &= std::isfinite(shape[i]);
        // The same domain clamps as Interpreter::resolve applies to arguments.
        const ModelParam& p = ndf.canonical[ndf.tableShapeParams.at(i)];
        shape[i] = std::clamp(shape[i], p.lo, p.hi);
    }
    ResolvedMaterial<double> r = lobeAtAlpha(ndf, maskingEntry(*findModel(ModelSlot::Masking, "none")),
                                             finite ? alpha : 1.0, shape);
    r.valid = finite;
    return r;
}

std::string writeNdfPlot(const std::vector<NdfCurve>& curves, const NdfPlotOptions& options, const std::string& path,
                         std::string* warning) {
    if (std::string e = checkNdfInputs(curves, options, path); !e.empty()) return e;
    CurvePlot plot;
    plot.yCaption = "D(theta_m) in 1/sr", plot.xCaption = "theta_m";
    for (const NdfCurve& c : curves) {
        plot.labels.push_back(c.label);
        plot.values.emplace_back(kSamples);
        for (int k = 0; k < kSamples; ++k) {
            double t = thetaAt(k) * kDeg;
            plot.values.back()[size_t(k)] = c.ndf.D({std::sin(t), 0.0, std::cos(t)});
        }
    }
    std::string e = writeCurvePlot(plot, options, path, warning);
    return e == kNothingToPlot ? "every NDF curve is zero (or not finite): nothing to plot" : e;
}

int curvePlotSamples() { return kSamples; }
double curvePlotTheta(int k) { return thetaAt(k); }

std::string writeCurvePlot(const CurvePlot& plot, const NdfPlotOptions& options, const std::string& path,
                           std::string* warning) {
    if (path.empty()) return "no output path for the plot";
    if (std::string e = checkPlotSize(options.width, options.height); !e.empty()) return e;
    if (plot.labels.empty() || plot.labels.size() != plot.values.size()) return "the plot needs one label per curve";
    if (plot.labels.size() > kMaxNdfCurves) return fmt::format("a plot draws at most {} curves", kMaxNdfCurves);
    try {
        double maxValue = 0;
        for (const std::vector<double>& v : plot.values) {
            if (v.size() != size_t(kSamples)) return "a curve has the wrong number of samples";
            for (double d : v)
                if (std::isfinite(d)) maxValue = std::max(maxValue, d);
        }
        if (!(maxValue > 0)) return kNothingToPlot;
        YAxis y = chooseYAxis(maxValue, options.logScale);
        std::string font = plotFontOrDefault(options.fontPath);
        PlotCanvas canvas(options.width, options.height, font);
        std::string note = noTextWarning(canvas, font);
        noteNoRoomForText(canvas,
                          drawCurvePlot(canvas, plot.labels, plot.values, y, options.title, plot.yCaption, plot.xCaption),
                          note);
        if (!note.empty()) {
            if (warning) *warning = note;
            else std::fprintf(stderr, "warning: %s\n", note.c_str());
        }
        return canvas.write(path);
    } catch (const std::exception& e) {
        return std::string("cannot draw the plot: ") + e.what();
    }
}

}  // namespace facet::preview
