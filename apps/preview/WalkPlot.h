// WalkPlot: `facet render FILE --plot walk`, a lobe's slice in the plane of
// incidence three ways: the single-scattering lobe, the lobe with its energy
// compensation (when it has one), and its stochastic reference, the random
// walk on its microsurface (compiler/reference/MicrosurfaceWalk.h), so that
// what Kulla-Conty adds can be seen against what multiple scattering does.
#pragma once

#include "Interpreter.h"
#include "Plots.h"

#include <cstdint>
#include <string>

namespace facet::preview {

struct WalkPlotOptions {
    double incidentDegrees = 60;  // theta_i, in [0, 90)
    int64_t paths = 2000;         // walks per outgoing angle
    uint64_t seed = 1;
    NdfPlotOptions plot;          // size, title, font (linear scale)
};

struct WalkPlotResult {
    std::string error;    // "" on success
    std::string warning;  // e.g. no font: no text
    double walkPeak = 0, modelPeak = 0;  // max of luminance(f) cos(theta_o) of the walk and of the model
};

// f cos(theta_o) (luminance) with wi = (-sin ti, 0, cos ti) and wo = (sin
// to, 0, cos to) for signed to in [-90, 90] degrees. `lobe` must be
// supported by the walk (MicrosurfaceWalk::unsupported); its diffuse base is
// left out.
WalkPlotResult writeWalkPlot(const ResolvedMaterial<double>& lobe, const WalkPlotOptions& options, const std::string& path);

}  // namespace facet::preview
