// ScatterRules: the rules of whole-sphere lobes (see ScatterRules.h).
#include "ScatterRules.h"

#include "models/ModelCatalog.h"

#include <fmt/format.h>
#include <vector>

namespace facet {

std::optional<ScatterRuleBroken> applyLobeOption(const LobeOptionStmt& stmt, CheckedLobe& lobe) {
    if (stmt.option == "scatter") {
        for (Scatter s : {Scatter::Reflect, Scatter::Transmit, Scatter::Both})
            if (stmt.value == scatterName(s)) {
                lobe.scatter = s;
                lobe.scatterLoc = stmt.loc;
                return std::nullopt;
            }
        return ScatterRuleBroken{stmt.valueLoc, fmt::format("scatter '{}' is not reflect, transmit or both", stmt.value)};
    }
    if (stmt.value != "true" && stmt.value != "false")
        return ScatterRuleBroken{stmt.valueLoc, fmt::format("thin '{}' is not true or false", stmt.value)};
    lobe.thin = stmt.value == "true";
    lobe.thinLoc = stmt.loc;
    return std::nullopt;
}

namespace {

// "scatter = both" or "thin = true": what makes the lobe whole-sphere.
std::string wholeSphereWhat(const CheckedLobe& lobe) {
    return lobe.scatter != Scatter::Reflect ? fmt::format("scatter = {}", scatterName(lobe.scatter)) : "thin = true";
}

SourceLoc wholeSphereLoc(const CheckedLobe& lobe) { return lobe.scatter != Scatter::Reflect ? lobe.scatterLoc : lobe.thinLoc; }

}  // namespace

std::optional<ScatterRuleBroken> wholeSphereLobeUnsupported(const CheckedLobe& lobe) {
    if (!lobe.wholeSphere()) return std::nullopt;
    const std::string what = wholeSphereWhat(lobe);
    const SourceLoc at = wholeSphereLoc(lobe);
    if (!lobe.hasNdf())
        return ScatterRuleBroken{at, fmt::format("'{}' in lobe '{}', which has no ndf: a lobe scatters below the "
                                                 "surface through a rough dielectric interface (an ndf with 'fresnel "
                                                 "= dielectric(eta)')",
                                                 what, lobe.name)};
    const FresnelEntry& fresnel = fresnelEntry(*lobe.fresnel.model);
    if (fresnel.refractiveIndexParam < 0)
        return ScatterRuleBroken{lobe.fresnel.model->name == std::string("none") ? at : lobe.fresnel.loc,
                                 fmt::format("'{}' needs 'fresnel = dielectric(eta)': light passes through an "
                                             "interface with an index of refraction, which fresnel '{}' does not have",
                                             what, lobe.fresnel.model->name)};
    const ExprPtr& eta = lobe.fresnel.args.at(size_t(fresnel.refractiveIndexParam));
    if (!lobe.thin && eta && eta->type == ValueType::Rgb)
        return ScatterRuleBroken{eta->loc, fmt::format("'{}' needs one index of refraction (a float eta): with an rgb "
                                                       "eta the channels would refract into three directions, and a "
                                                       "sample has one; a thin sheet (thin = true) takes rgb",
                                                       what)};
    const MaskingEntry& masking = maskingEntry(*lobe.masking.model);
    if (!masking.transmission) {
        const bool none = lobe.masking.model->name == std::string("none");
        // The maskings with a transmission form, from the catalog: "a, b, c or d".
        std::vector<std::string> forms;
        for (const ModelInfo* m : catalogSlot(ModelSlot::Masking))
            if (maskingEntry(*m).transmission) forms.push_back(m->name);
        std::string list;
        for (size_t k = 0; k < forms.size(); ++k)
            list += (k == 0 ? "" : k + 1 == forms.size() ? " or " : ", ") + forms[k];
        return ScatterRuleBroken{none ? at : lobe.masking.loc,
                                 fmt::format("'{}' needs a Smith masking ({}): its transmission form follows from "
                                             "the NDF's Lambda; {}",
                                             what, list,
                                             none ? "the lobe has no masking statement"
                                                  : fmt::format("'{}' has none", lobe.masking.model->name))};
    }
    // (energy = random_walk is refused with any dielectric Fresnel term by
    // the random walk's own rule; kulla_conty compensates from both sides.)
    if (diffuseEntry(*lobe.diffuse.model).present)
        return ScatterRuleBroken{lobe.diffuse.loc, fmt::format("a diffuse term on a lobe with '{}': the diffuse base "
                                                               "reflects above the surface only; put it in a lobe of "
                                                               "its own",
                                                               what)};
    return std::nullopt;
}

std::optional<ScatterRuleBroken> wholeSphereCombinationUnsupported(const CheckedMaterial& material) {
    if (!material.combinesLobes()) return std::nullopt;
    for (const CheckedLobe& lobe : material.lobes)
        if (lobe.wholeSphere())
            return ScatterRuleBroken{wholeSphereLoc(lobe),
                                     fmt::format("lobe '{}' has '{}' and material '{}' combines lobes: the layer "
                                                 "model and the combination's sampler take lobes above the surface "
                                                 "only, so a lobe that scatters below it must be the material's only "
                                                 "lobe (bsdf = {};)",
                                                 lobe.name, wholeSphereWhat(lobe), material.name, lobe.name)};
    return std::nullopt;
}

}  // namespace facet
