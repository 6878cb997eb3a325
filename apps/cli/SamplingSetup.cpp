// SamplingSetup: see SamplingSetup.h.
#include "SamplingSetup.h"

#include "TableCache.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>

namespace facet {

std::string parseViewDirection(const std::string& option, const std::string& text, std::array<double, 3>& view) {
    const char* p = text.c_str();
    for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        view[k] = std::strtod(p, &end);
        if (end == p || !std::isfinite(view[k]) || *end != (k < 2 ? ',' : '\0'))
            return fmt::format("{} expects X,Y,Z (three finite numbers), got '{}'", option, text);
        p = end + 1;
    }
    double len = std::sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
    if (!(std::abs(len - 1) <= kUnitTolerance))
        return fmt::format("{} {} has length {:.6g}; it must be a unit vector (within {:g})", option, text, len,
                           kUnitTolerance);
    if (!(view[2] > 0))
        return fmt::format("{} {} points into the surface (z <= 0); wo points away from it, towards the viewer "
                           "(n = +z)",
                           option, text);
    return "";
}

std::unique_ptr<Interpreter<double>> referenceSampler(const CheckedMaterial& material) {
    std::shared_ptr<const EnergyTable> table;
    if (material.compensatesEnergy()) {
        TableCache tables;
        table = tables.getFor(material);
        if (!tables.refusal().empty()) std::fprintf(stderr, "facet: warning: %s\n", tables.refusal().c_str());
    }
    return std::make_unique<Interpreter<double>>(material, table);
}

}  // namespace facet
