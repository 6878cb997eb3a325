// WalkPlot: the single-scattering lobe, its energy compensation and the
// random walk, in the plane of incidence (see the header).
#include "WalkPlot.h"

#include "MicrosurfaceWalk.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace facet::preview {

namespace {

double luminance(const std::array<double, 3>& rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

}  // namespace

WalkPlotResult writeWalkPlot(const ResolvedMaterial<double>& lobe, const WalkPlotOptions& options, const std::string& path) {
    WalkPlotResult result;
    if (!(options.incidentDegrees >= 0 && options.incidentDegrees < 90)) {
        result.error = "the walk plot's theta_i must be in [0, 90) degrees";
        return result;
    }
    if (!(options.paths >= 1 && options.paths <= 10000000)) {
        result.error = "the walk plot takes 1 to 10000000 walks per angle";
        return result;
    }
    if (std::string why = MicrosurfaceWalk::unsupported(lobe); !why.empty()) {
        result.error = "no random walk for this lobe: " + why;
        return result;
    }
    ResolvedMaterial<double> model = lobe;
    model.diffuse = lobe.specularLobe().diffuse;  // the `none` base
    ResolvedMaterial<double> single = model.withoutEnergy();
    bool compensated = lobe.energy->compensates;
    MicrosurfaceWalk walk(lobe);

    const double deg = std::numbers::pi / 180, ti = options.incidentDegrees * deg;
    Vec3<double> wi{-std::sin(ti), 0, std::cos(ti)};
    CurvePlot plot;
    plot.labels = {"single scattering"};
    if (compensated) plot.labels.push_back("+ Kulla-Conty");
    plot.labels.push_back("random walk");
    plot.yCaption = "luminance(f) cos(theta_o) in 1/sr";
    plot.xCaption = "theta_o";
    int n = curvePlotSamples();
    plot.values.assign(plot.labels.size(), std::vector<double>(size_t(n)));
    for (int k = 0; k < n; ++k) {
        double to = curvePlotTheta(k) * deg;
        Vec3<double> wo{std::sin(to), 0, std::cos(to)};
        double c = std::max(0.0, wo.z);
        size_t curve = 0;
        plot.values[curve++][size_t(k)] = luminance(single.brdf(wi, wo)) * c;
        if (compensated) plot.values[curve++][size_t(k)] = luminance(model.brdf(wi, wo)) * c;
        // The walk from wo with next events toward wi: f(wi, wo) (reciprocal).
        double f = wo.z > 0 ? luminance(walk.brdf(wi, wo, options.paths, options.seed + uint64_t(k)).mean) * c : 0.0;
        plot.values[curve][size_t(k)] = f;
        result.walkPeak = std::max(result.walkPeak, f);
        result.modelPeak = std::max(result.modelPeak, plot.values[curve - 1][size_t(k)]);
    }
    NdfPlotOptions plotOptions = options.plot;
    plotOptions.logScale = false;
    result.error = writeCurvePlot(plot, plotOptions, path, &result.warning);
    return result;
}

}  // namespace facet::preview
