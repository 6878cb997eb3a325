// CombinationPlan: the lowering plan of a material that combines lobes
// (SPEC 10; LoweringPlan::lobes): one plan per lobe, made by planLowering()
// of the lobe alone, and each layer's g table, baked here once from the
// constant parameters it depends on (compiledBackendsRefuse() turns away a
// layer whose tables would vary per lane).
#include "LoweringPlan.h"

#include "Diagnostics.h"
#include "Interpreter.h"
#include "LayerAlbedo.h"
#include "LobeCombination.h"

#include <sstream>

namespace facet {

LoweringPlan planCombination(const CheckedMaterial& material, const MathVariant& variant, bool trustInputs,
                             const std::vector<std::shared_ptr<const EnergyTable>>& lobeEnergyTables,
                             bool samplerTables) {
    internal_assert(compiledBackendsRefuse(material).empty())
        << "planning material '" << material.name << "', which the compiled backends refuse";
    LoweringPlan plan;
    plan.variant = variant;
    plan.trustInputs = trustInputs;
    plan.reads = material.readByModels();
    // Each lobe as its own kernel would plan it. The batch entry has two
    // bodies when some lobe has a guarded batch body: first every lobe in
    // its batch body, then, for the lanes any of them distrusts, the whole
    // combination in the lobes' plain bodies (a lane needs every lobe).
    bool guarded = false;
    for (size_t l = 0; l < material.lobes.size(); ++l) {
        auto lobe = std::make_shared<LobeLowering>();
        lobe->material = lobeView(material, int(l));
        lobe->plan = planLowering(lobe->material, variant, trustInputs);
        plan.compensatesEnergy = plan.compensatesEnergy || lobe->plan.compensatesEnergy;
        guarded = guarded || lobe->plan.batchBodies != BatchBodies::Plain;
        plan.lobes.push_back(std::move(lobe));
    }
    plan.scalarBody = plan.lobes[0]->plan.scalarBody;
    plan.batchBodies = !guarded ? BatchBodies::Plain : variant.precise ? BatchBodies::FloatFirst : BatchBodies::GuardedFast;
    plan.batchBody = plan.lobes[0]->plan.batchBody;
    if (guarded) plan.fallbackBody = plan.scalarBody;
    // The mixture sampler (CombinationSampling.cpp), in each lobe's plain body.
    plan.sampling.compiled = hasCompiledSampler(material);
    plan.sampling.body = plan.sampling.batchBody = plan.scalarBody;

    plan.layerG.resize(material.bsdf.size());
    plan.nodeAlbedo.resize(material.bsdf.size());
    // The layers' tables depend on constant parameters only: any slot
    // values resolve them alike, the defaults included. The sampler's
    // estimates are taken at the defaults.
    Interpreter<double> interp(material, lobeEnergyTables);
    ResolvedBsdf<double> resolved = interp.resolveAll(nullptr);
    for (size_t i = 0; i < material.bsdf.size(); ++i) {
        const BsdfNode& n = material.bsdf[i];
        if (n.kind == BsdfKind::Layer) plan.layerG[i] = layerG(material, resolved, int(i));
        if (!samplerTables || !plan.sampling.compiled || !resolved.valid) continue;
        if (n.kind == BsdfKind::Lobe) plan.nodeAlbedo[i] = albedoTable(material, resolved, int(i));
        if (n.kind == BsdfKind::Layer) plan.nodeAlbedo[i] = albedoTable(material, resolved, n.a);
    }
    return plan;
}

void printCombinationPlan(std::ostringstream& os, const CheckedMaterial& material, const LoweringPlan& plan) {
    os << "material " << material.name << "\n";
    os << "combination: " << printBsdf(material, material.bsdfRoot()) << "\n";
    os << "variant: " << plan.variant.name() << "\n";
    os << "batch-bodies: " << batchBodiesName(plan.batchBodies)
       << (plan.fallbackBody ? " (each lobe's batch body, then the plain bodies for the lanes any distrusts)" : "")
       << "\n";
    os << "trust-inputs: " << (plan.trustInputs ? "yes" : "no") << "\n";
    auto count = [](const std::vector<bool>& v) { return std::count(v.begin(), v.end(), true); };
    os << "reads: inputs " << count(plan.reads.inputs) << " of " << plan.reads.inputs.size() << ", lets "
       << count(plan.reads.lets) << " of " << plan.reads.lets.size() << "\n";
    for (size_t i = 0; i < material.bsdf.size(); ++i) {
        const MuTable* g = plan.layerG[i].get();
        if (!g) continue;
        os << "layer " << printBsdf(material, material.bsdf[i]) << ": g table " << MuTable::kNodes
           << " nodes, g(mu=1) = " << g->v.back()[0] << " " << g->v.back()[1] << " " << g->v.back()[2]
           << ", g(mu=0) = " << g->v.front()[0] << " " << g->v.front()[1] << " " << g->v.front()[2] << "\n";
    }
    os << "sampling: " << (plan.sampling.compiled ? "compiled mixture over the lobes" : "reference mixture (a lobe has no compiled sampler)") << "\n";
    for (size_t l = 0; l < plan.lobes.size(); ++l) {
        os << "\nlobe " << material.lobes[l].name << ":\n";
        std::istringstream lobeText(printPlan(plan.lobes[l]->material, plan.lobes[l]->plan));
        for (std::string line; std::getline(lobeText, line);)
            if (line.rfind("material ", 0) != 0) os << "  " << line << "\n";
    }
}

}  // namespace facet
