// TermEmitters: the registry of model emitters (generated from
// compiler/models/*/*Emitter.cpp) and the hooks' defaults.
#include "TermEmitters.h"
#include "Immortal.h"

#include "Diagnostics.h"
#include "LaneEmitter.h"

#include <cstring>

namespace facet {

#define FACET_EMITTER_FILE(slot, stem) std::vector<TermEmitterEntry> facetEmitters_##slot##_##stem();
#include "EmitterRegistry.inc"
#undef FACET_EMITTER_FILE

const std::vector<TermEmitterEntry>& termEmitterRegistry() {
    static const std::vector<TermEmitterEntry>& registry = immortal<std::vector<TermEmitterEntry>>([] {
        std::vector<TermEmitterEntry> all;
#define FACET_EMITTER_FILE(slot, stem)                             \
    for (const TermEmitterEntry& e : facetEmitters_##slot##_##stem()) \
        all.push_back(e);
#include "EmitterRegistry.inc"
#undef FACET_EMITTER_FILE
        return all;
    }());
    return registry;
}

const TermEmitterEntry* findTermEmitterEntry(const ModelInfo& model) {
    for (const TermEmitterEntry& e : termEmitterRegistry())
        if (e.slot == model.slot && std::strcmp(e.modelName, model.name) == 0) return &e;
    return nullptr;
}

const void* findTermEmitter(const ModelInfo& model) {
    const TermEmitterEntry* e = findTermEmitterEntry(model);
    return e ? e->emitter : nullptr;
}

namespace {

template <typename Emitter>
const Emitter& emitterOf(const ModelUse& use) {
    internal_assert(use.model) << "a checked material without a model in one of its slots";
    const void* e = findTermEmitter(*use.model);
    internal_assert(e) << "model '" << use.model->name << "' has no emitter (compiler/models/*/*Emitter.cpp)";
    return *static_cast<const Emitter*>(e);
}

// The NDF slot of a diffuse lobe (one without an NDF, in a combination):
// no hook of it is reached, LaneEmitter::brdfPrecise emits no specular term
// and the plan plans none.
class AbsentNdfEmitter final : public NdfEmitter {
public:
    NdfParams params(LaneEmitter&) const override { return {}; }
};

const NdfEmitter& ndfEmitterOf(const ModelUse& use) {
    static const AbsentNdfEmitter& absent = immortal<AbsentNdfEmitter>();
    return use.model ? emitterOf<NdfEmitter>(use) : absent;
}

}  // namespace

MaterialEmitters termEmitters(const CheckedMaterial& material) {
    return {ndfEmitterOf(material.singleLobe().ndf), emitterOf<MaskingEmitter>(material.singleLobe().masking),
            emitterOf<FresnelEmitter>(material.singleLobe().fresnel), emitterOf<DiffuseEmitter>(material.singleLobe().diffuse),
            emitterOf<EnergyEmitter>(material.singleLobe().energy)};
}

// ---- defaults: a hook an emitter does not override must not be reached (the plan and the traits keep them apart) ----

llvm::Value* NdfEmitter::D(LaneEmitter&, const NdfParams&, const LaneGeometry&) const {
    internal_error << "D of a whole-lobe NDF";
}

llvm::Value* NdfEmitter::wholeLobe(LaneEmitter&, const NdfParams&, const LaneGeometry&) const {
    internal_error << "wholeLobe of a microfacet NDF";
}

void NdfEmitter::smithAlphas(LaneEmitter&, const NdfParams& n, llvm::Value*& ax, llvm::Value*& ay,
                             bool& isotropic) const {
    ax = n.ax;
    ay = n.ay;
    isotropic = n.isotropic;
}

llvm::Value* NdfEmitter::cosLambda(LaneEmitter&, const NdfParams&, const std::array<llvm::Value*, 3>&) const {
    internal_error << "Smith Lambda of an NDF without one (the checker refuses the pair)";
}

llvm::Value* NdfEmitter::smithRootSquared(LaneEmitter&, const NdfParams&, const std::array<llvm::Value*, 3>&,
                                          bool) const {
    internal_error << "Smith root form of an NDF without one (NdfLoweringTraits::smithRootSums)";
}

// The geometric mean of the alphas, as the reference's lookup (KullaContyEval.h).
llvm::Value* NdfEmitter::energyAlpha(LaneEmitter& lane, const NdfParams& n) const {
    MathEmitter& pm = lane.preciseMath();
    return n.isotropic ? n.axD : pm.sqrt(pm.mul(n.axD, n.ayD));
}

std::array<llvm::Value*, 3> NdfEmitter::sampleNormal(LaneEmitter&, const NdfParams&, llvm::Value*, llvm::Value*) const {
    internal_error << "NDF sampling of an NDF without a sampler in IR (NdfLoweringTraits::samplesNormals)";
}

llvm::Value* NdfEmitter::normalPdf(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& atM) const {
    MathEmitter& pm = lane.preciseMath();
    return pm.mul(D(lane, n, atM), atM.hD[2]);
}

std::array<llvm::Value*, 3> NdfEmitter::sampleVisibleNormal(LaneEmitter&, const NdfParams&,
                                                            const std::array<llvm::Value*, 3>&, llvm::Value*,
                                                            llvm::Value*) const {
    internal_error << "visible-normal sampling of an NDF without it in IR (NdfLoweringTraits::samplesVisibleNormals)";
}

llvm::Value* NdfEmitter::visibleCosLambda(LaneEmitter& lane, const NdfParams& n,
                                          const std::array<llvm::Value*, 3>& v) const {
    MathEmitter& fm = lane.floatMath();
    MathEmitter& pm = lane.preciseMath();
    std::array<llvm::Value*, 3> vLane;
    for (int i = 0; i < 3; ++i) vLane[i] = fm.convert(v[i], fm.type());
    return pm.convert(cosLambda(lane, n, vLane), pm.type());
}

llvm::Value* NdfEmitter::visibleSmithSum(LaneEmitter& lane, const NdfParams& n,
                                         const std::array<llvm::Value*, 3>& v) const {
    MathEmitter& pm = lane.preciseMath();
    return pm.add(v[2], visibleCosLambda(lane, n, v));
}

FresnelAverageArgs FresnelEmitter::averageArgs(LaneEmitter&) const { return {}; }

LVal FresnelEmitter::refractiveIndex(LaneEmitter&) const {
    internal_error << "refractive index of a Fresnel term without one (the checker allows only dielectric)";
}
llvm::Value* FresnelEmitter::reflectanceAcross(LaneEmitter&, llvm::Value*, llvm::Value*) const {
    internal_error << "reflectance across an interface of a non-dielectric Fresnel term";
}
llvm::Value* FresnelEmitter::transmittanceAcross(LaneEmitter&, llvm::Value*, llvm::Value*) const {
    internal_error << "transmittance across an interface of a non-dielectric Fresnel term";
}
llvm::Value* FresnelEmitter::pairTransmittance(LaneEmitter&, llvm::Value*, llvm::Value*, llvm::Value*) const {
    internal_error << "transmittance of a refracted pair of a non-dielectric Fresnel term";
}
llvm::Value* MaskingEmitter::transmittedOverCosines(LaneEmitter&, const NdfEmitter&, const NdfParams&,
                                                    const LaneGeometry&, llvm::Value*) const {
    internal_error << "transmission form of a non-Smith masking (the checker refuses the pair)";
}

LVal DiffuseEmitter::diffuse(LaneEmitter&) const { internal_error << "diffuse term of `none`"; }

std::array<llvm::Value*, 3> EnergyEmitter::compensation(LaneEmitter&, const NdfEmitter&, const NdfParams&,
                                                        const FresnelEmitter&, llvm::Value*, llvm::Value*) const {
    internal_error << "energy compensation of an entry that does not compensate";
}

CompensationAlbedo EnergyEmitter::samplingAlbedo(LaneEmitter&, const NdfEmitter&, const NdfParams&,
                                                 const FresnelEmitter&, llvm::Value*) const {
    internal_error << "compensation albedo of an entry that does not compensate";
}

}  // namespace facet
