// ward: Ward's anisotropic lobe as IR (the reference is Ward.cpp): a whole
// lobe with its own normalization, no D and no masking term.
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlphaX = 0, kAlphaY = 1;

class WardEmitter final : public NdfEmitter {
public:
    WardEmitter() {
        traits.wholeLobe = true;
        traits.dFromUnnormalizedHalf = true;
        traits.samplesNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.singleLobe().ndf, kAlphaX, kAlphaY);
    }

    // exp(-tan^2-weighted slope) / (4 pi ax ay sqrt(ci co)), precise type.
    Value* wholeLobe(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* e = lane.slopeExponent(n, geo.slopeH);
        Value *ciD = geo.wiD[2], *coD = geo.woD[2];
        // sqrt(ci) sqrt(co) in float: ci co underflows for float-subnormal cosines.
        Value* root = pm.isDouble() ? pm.sqrt(pm.mul(ciD, coD)) : pm.mul(pm.sqrt(ciD), pm.sqrt(coD));
        return pm.div(pm.div(lane.expTail(e), pm.mul(pm.c(4 * kPi), pm.mul(n.axD, n.ayD))), root);
    }

    // Walter 2005: half vectors from the Beckmann NDF of the lobe's
    // exponent, whose slope radius has the CDF 1 - exp(-r^2); their density
    // is exp(-e) / (pi ax ay mz^4) times mz.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        return lane.stretchedSlopeNormal(n, pm.neg(pm.log1p(pm.neg(u1))), u2);
    }
    Value* normalPdf(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& atM) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* z = atM.hD[2];
        Value* e = lane.slopeExponent(n, atM.hD);
        return pm.div(lane.expTail(e), pm.mul(pm.mul(pm.c(kPi), pm.mul(n.axD, n.ayD)), pm.mul(z, pm.mul(z, z))));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_WardEmitter() {
    static const WardEmitter& emitter = immortal<WardEmitter>();
    return {{ModelSlot::Ndf, "ward", &emitter}};
}

}  // namespace facet
