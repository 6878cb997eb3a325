// ScatterRules: what a lobe that scatters over the whole sphere (SPEC 11:
// `scatter = transmit | both`, `thin = true`) needs of its models and of the
// combination it sits in. The checker reports each broken rule at the
// statement that breaks it, with the reason.
#pragma once

#include "Diagnostics.h"
#include "Material.h"

#include <optional>

namespace facet {

struct ScatterRuleBroken {
    SourceLoc loc;
    std::string message;
};

// The option statement `stmt` applied to `lobe` (scatter's and thin's
// words), or why it cannot be.
std::optional<ScatterRuleBroken> applyLobeOption(const LobeOptionStmt& stmt, CheckedLobe& lobe);

// A whole-sphere lobe's models: an NDF with a Smith Lambda, a Smith masking
// with a transmission form, the dielectric Fresnel term (one index of
// refraction unless the lobe is thin), no diffuse term.
std::optional<ScatterRuleBroken> wholeSphereLobeUnsupported(const CheckedLobe& lobe);

// A whole-sphere lobe in a combination: the combination's sampler and the
// layer model take lobes above the surface only.
std::optional<ScatterRuleBroken> wholeSphereCombinationUnsupported(const CheckedMaterial& material);

}  // namespace facet
