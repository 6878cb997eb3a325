// The masking terms that are not Smith forms as IR (the reference is
// Empirical.cpp): each is the SPEC's G divided by (n.wi)(n.wo) and
// simplified, so that G and the cosines, which go to zero together at
// grazing, are never divided by each other.
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

namespace facet {
namespace {

using llvm::Value;

constexpr int kSchlickK = 0;

class NoMasking final : public MaskingEmitter {
    Value* overCosines(LaneEmitter& lane, const NdfEmitter&, const NdfParams&, const LaneGeometry& geo,
                       Value* D) const override {
        return lane.overProduct(D, geo.wiD[2], geo.woD[2]);
    }
};

class ImplicitMasking final : public MaskingEmitter {  // G = ci co
    Value* overCosines(LaneEmitter&, const NdfEmitter&, const NdfParams&, const LaneGeometry&, Value* D) const override {
        return D;
    }
};

class CookTorranceMasking final : public MaskingEmitter {
public:
    CookTorranceMasking() { traits.needsPreciseHalfAngle = true; }
    // min(1, 2 nh co / oh, 2 nh ci / oh) / (ci co)
    Value* overCosines(LaneEmitter& lane, const NdfEmitter&, const NdfParams&, const LaneGeometry& geo,
                       Value* D) const override {
        MathEmitter& pm = lane.preciseMath();
        Value *ci = geo.wiD[2], *co = geo.woD[2], *oh = geo.cosD, *nh = geo.hD[2];
        internal_assert(nh) << "cook_torrance needs the unit h, which the plan left out";
        Value* k = pm.mul(pm.div(D, oh), pm.mul(pm.c(2.0), nh));
        return pm.minnum(lane.overProduct(D, ci, co), pm.div(k, pm.maxnum(ci, co)));
    }
};

class KelemenMasking final : public MaskingEmitter {  // G = ci co / (wo.h)^2
public:
    KelemenMasking() { traits.needsPreciseHalfAngle = true; }
    Value* overCosines(LaneEmitter& lane, const NdfEmitter&, const NdfParams&, const LaneGeometry& geo,
                       Value* D) const override {
        return lane.overProduct(D, geo.cosD, geo.cosD);
    }
};

class NeumannMasking final : public MaskingEmitter {  // G = ci co / max(ci, co)
    Value* overCosines(LaneEmitter& lane, const NdfEmitter&, const NdfParams&, const LaneGeometry& geo,
                       Value* D) const override {
        MathEmitter& pm = lane.preciseMath();
        return pm.div(D, pm.maxnum(geo.wiD[2], geo.woD[2]));
    }
};

class SchlickSmithMasking final : public MaskingEmitter {  // G1(c) / c = 1 / (c (1 - k) + k)
    Value* overCosines(LaneEmitter& lane, const NdfEmitter&, const NdfParams&, const LaneGeometry& geo,
                       Value* D) const override {
        MathEmitter& pm = lane.preciseMath();
        Value *ci = geo.wiD[2], *co = geo.woD[2];
        Value* one = pm.c(1.0);
        Value* k = pm.convert(lane.scalarParam(lane.material.singleLobe().masking, kSchlickK), pm.type());
        Value* omk = pm.sub(one, k);
        return lane.overProduct(D, pm.fma(ci, omk, k), pm.fma(co, omk, k));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_masking_EmpiricalEmitter() {
    static const NoMasking& none = immortal<NoMasking>();
    static const ImplicitMasking& implicit = immortal<ImplicitMasking>();
    static const CookTorranceMasking& cookTorrance = immortal<CookTorranceMasking>();
    static const KelemenMasking& kelemen = immortal<KelemenMasking>();
    static const NeumannMasking& neumann = immortal<NeumannMasking>();
    static const SchlickSmithMasking& schlickSmith = immortal<SchlickSmithMasking>();
    return {{ModelSlot::Masking, "none", &none},
            {ModelSlot::Masking, "implicit", &implicit},
            {ModelSlot::Masking, "cook_torrance", &cookTorrance},
            {ModelSlot::Masking, "kelemen", &kelemen},
            {ModelSlot::Masking, "neumann", &neumann},
            {ModelSlot::Masking, "schlick_smith", &schlickSmith}};
}

}  // namespace facet
