// SamplingSetup: see SamplingSetup.h.
#include "SamplingSetup.h"

#include "CacheFiles.h"
#include "LambdaTable.h"
#include "MaterialFile.h"
#include "TableCache.h"

#include <cerrno>
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
    return "";
}

std::string viewSideProblem(const std::string& option, const std::string& text, const std::array<double, 3>& view,
                            const CheckedMaterial& material) {
    const bool eitherSide = scattersBelowSurface(material);
    if (eitherSide && view[2] == 0)
        return fmt::format("{} {} lies in the surface (z = 0): material '{}' scatters on both sides of it, and wo "
                           "must be on one of them",
                           option, text, material.name);
    if (!eitherSide && !(view[2] > 0))
        return fmt::format("{} {} points into the surface (z <= 0); wo points away from it, towards the viewer "
                           "(n = +z)",
                           option, text);
    return "";
}

std::string parseSeed(const std::string& option, const std::string& text, uint64_t& seed) {
    const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
    errno = 0;
    char* end = nullptr;
    unsigned long long s = digits ? std::strtoull(text.c_str(), &end, 10) : 0;
    if (!digits || errno == ERANGE || *end)
        return fmt::format("{} expects a whole number from 0 to 2^64 - 1 = 18446744073709551615, got '{}'", option,
                           text);
    seed = s;
    return "";
}

std::unique_ptr<Interpreter<double>> referenceInterpreter(const CheckedMaterial& material) {
    // A combination's lobes build their tables in memory (Interpreter).
    if (material.combinesLobes()) return std::make_unique<Interpreter<double>>(material);
    std::shared_ptr<const EnergyTable> table;
    const bool lambda = usesTabulatedLambda(material);
    if (material.singleLobe().compensatesEnergy() || lambda) {
        // The kernels' arrangement (Compiler): tables/ below the cache root,
        // one trust decision and one warning for the root.
        TableCache tables(std::make_shared<CacheDirectory>(defaultCacheRoot()), "tables");
        if (material.singleLobe().compensatesEnergy()) table = tables.getFor(material);
        // The table stays resident in the process, where the interpreter's
        // Lambda finds it (LambdaTable.h).
        if (lambda) tables.lambdaFor(material);
    }
    return std::make_unique<Interpreter<double>>(material, table);
}

}  // namespace facet
