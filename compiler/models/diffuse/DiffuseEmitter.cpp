// none, lambert: the diffuse base as IR (the reference is Diffuse.cpp).
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

namespace facet {
namespace {

constexpr int kAlbedo = 0;

class NoDiffuseEmitter final : public DiffuseEmitter {};

class LambertEmitter final : public DiffuseEmitter {
public:
    bool present() const override { return true; }
    // albedo / pi per channel; the albedo is the user's expression, clamped
    // to >= 0 and unbounded above (so the output keeps its range check).
    LVal diffuse(LaneEmitter& lane) const override {
        MathEmitter& pm = lane.preciseMath();
        LVal albedo = lane.rgbParam(lane.material.singleLobe().diffuse, kAlbedo, false);
        return lane.map({albedo}, true, [&](auto& x) { return pm.mul(x[0], pm.c(1.0 / kPi)); });
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_diffuse_DiffuseEmitter() {
    static const NoDiffuseEmitter& none = immortal<NoDiffuseEmitter>();
    static const LambertEmitter& lambert = immortal<LambertEmitter>();
    return {{ModelSlot::Diffuse, "none", &none}, {ModelSlot::Diffuse, "lambert", &lambert}};
}

}  // namespace facet
