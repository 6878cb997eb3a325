// Plots: the diagnostic plots of `facet render --plot lobe|ndf`, and the
// curve plot they share with `--plot walk` (WalkPlot.h).
//
// The lobe plot is the BRDF slice in the plane of incidence, evaluated by a
// compiled kernel (any backend), drawn as a polar plot: one curve per
// incident angle. The NDF plot draws D(theta_m) curves computed by the
// reference interpreter's term functions (ResolvedMaterial::D), either one
// NDF at several roughnesses or several NDFs at matched roughness. Both are
// drawn with OpenImageIO's ImageBufAlgo (lines, boxes, TrueType text through
// PlotCanvas) and written in any format OpenImageIO writes (PNG, EXR, ...).
#pragma once

#include "Interpreter.h"
#include "Kernel.h"

#include <cstdint>
#include <string>
#include <vector>

namespace facet::preview {

struct LobePlotOptions {
    std::vector<double> incidentDegrees{0, 30, 60, 80};  // theta_i of each curve, in [0, 90)
    // The whole circle of theta_o (a lobe that scatters below the surface):
    // theta_i in [0, 180) too (past 90: light arriving from inside).
    bool wholeSphere = false;
    int width = 960, height = 600;
    std::string title;  // drawn at the top; empty: none
    // TrueType font for the labels: "" finds one (findPlotFont in
    // PlotCanvas.h: $FACET_FONT, else DejaVu Sans). Without a usable font the
    // plot is drawn without text and `warning` says so.
    std::string fontPath;
};

struct LobePlotResult {
    std::string error;                 // "" on success
    std::vector<double> peakValue;     // per curve: max over theta_o of luminance(f) cos(theta_o)
    std::vector<double> peakThetaDeg;  // per curve: the signed theta_o of that maximum
    int64_t invalidLanes = 0;          // kernel lanes reported invalid (should be 0)
    std::string warning;               // "" or e.g. why the plot has no text (not an error)
};

// Evaluates `kernel` (default inputs) with wi = (-sin ti, 0, cos ti) and
// wo = (sin to, 0, cos to) for signed to in [-90, 90] degrees ([-180, 180]
// with wholeSphere) and draws luminance(f) |cos(to)| in polar form, each curve normalized to its own peak
// (the legend gives the peak), with the incident directions as dashed rays.
LobePlotResult writeLobePlot(const Kernel& kernel, const LobePlotOptions& options, const std::string& path);

// One D(theta_m) curve: a resolved NDF (only the NDF fields are used).
struct NdfCurve {
    std::string label;
    ResolvedMaterial<double> ndf;
};

// The NDF `ndf` at equivalent roughness alpha (isotropic; the entry's
// argsAtAlpha: blinn_phong takes the matched exponent 2 / alpha^2 - 2 of
// Walter et al. 2007), with the given values of its shape parameters (gtr's
// gamma), each defaulting to the parameter's typical value. Invalid when
// alpha or a shape value is not finite.
ResolvedMaterial<double> ndfAtAlpha(const NdfEntry& ndf, double alpha, std::vector<double> shape = {});

struct NdfPlotOptions {
    int width = 960, height = 600;
    std::string title;
    bool logScale = true;  // D spans decades between alpha = 0.1 and 1
    std::string fontPath;  // as LobePlotOptions::fontPath
};

// Draws D(theta_m) for theta_m in [-90, 90] degrees (m in the x-z plane),
// one curve per entry. Returns "" or an error message (ward has no D(m): an
// error). A non-fatal problem (no font: no text) goes to *warning, or to
// stderr when warning is null.
std::string writeNdfPlot(const std::vector<NdfCurve>& curves, const NdfPlotOptions& options, const std::string& path,
                         std::string* warning = nullptr);

// Curves over theta in [-90, 90] degrees, curvePlotSamples() values each at
// curvePlotTheta(k), drawn like the NDF plot (the options' scale, title and
// font; "log scale" appended to the y caption). Returns "" or an error;
// kNothingToPlot when every value is zero or not finite.
struct CurvePlot {
    std::vector<std::string> labels;
    std::vector<std::vector<double>> values;
    std::string yCaption, xCaption;  // e.g. "D(theta_m) in 1/sr", "theta_m"
};
inline constexpr const char* kNothingToPlot = "every curve is zero (or not finite): nothing to plot";
int curvePlotSamples();
double curvePlotTheta(int k);
std::string writeCurvePlot(const CurvePlot& plot, const NdfPlotOptions& options, const std::string& path,
                           std::string* warning = nullptr);

}  // namespace facet::preview
