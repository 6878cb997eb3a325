// blinn_phong: the normalized Blinn-Phong NDF as IR (the reference is
// BlinnPhong.cpp), with the Beckmann-profile Smith Lambda at its
// equivalent alpha sqrt(2 / (e + 2)).
#include "BeckmannProfileEmitter.h"

namespace facet {
namespace {

using llvm::Value;

constexpr int kExponent = 0;
constexpr int kOwnExponent = 0;  // NdfParams::own: the clamped exponent, precise type

// sqrt(2 / (e + 2)) in the precise type.
Value* equivalentAlpha(LaneEmitter& lane, const NdfParams& n) {
    MathEmitter& pm = lane.preciseMath();
    return pm.sqrt(pm.div(pm.c(2.0), pm.add(n.own[kOwnExponent], pm.c(2.0))));
}

class BlinnPhongEmitter final : public BeckmannProfileEmitter {
public:
    BlinnPhongEmitter() { traits.samplesNormals = true; }

    NdfParams params(LaneEmitter& lane) const override {
        NdfParams n;
        n.own[kOwnExponent] = lane.scalarParam(lane.material.ndf, kExponent, false);
        return n;
    }

    // mz^e = exp(e/2 log1p(-(mx^2 + my^2))) in the precise type: mz itself
    // is too coarse in float once e is large (1e6).
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& hD = geo.hD;
        // ln mz: near the pole from sin^2 (log1p(-s2)/2 keeps the small
        // angle exact), near the horizon from mz itself (where 1 - s2 would
        // cancel).
        Value* s2 = pm.minnum(pm.fma(hD[0], hD[0], pm.mul(hD[1], hD[1])), pm.c(1.0));
        Value* lnz = pm.select(pm.lt(s2, pm.c(0.5)), pm.mul(pm.c(0.5), pm.log1p(pm.neg(s2))), pm.log(hD[2]));
        Value* E = n.own[kOwnExponent];
        Value* p = lane.expTail(pm.neg(pm.mul(E, lnz)));
        p = pm.select(pm.eq(E, pm.c(0.0)), pm.c(1.0), p);
        Value* norm = pm.mul(pm.add(E, pm.c(2.0)), pm.c(1.0 / (2 * kPi)));
        return pm.mul(norm, p);
    }

    void smithAlphas(LaneEmitter& lane, const NdfParams& n, Value*& ax, Value*& ay, bool& isotropic) const override {
        MathEmitter& fm = lane.floatMath();
        ax = ay = fm.convert(equivalentAlpha(lane, n), fm.type());
        isotropic = true;
    }

    Value* energyAlpha(LaneEmitter& lane, const NdfParams& n) const override { return equivalentAlpha(lane, n); }

    // D(m) (n.m) has the polar CDF 1 - mz^(e + 2): sin^2 theta = 1 - (1 -
    // u)^(2 / (e + 2)), through expm1 and log1p so that narrow lobes (e up
    // to 2e8) keep their small angles.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* y = pm.div(pm.mul(pm.c(2.0), pm.log1p(pm.neg(u1))), pm.add(n.own[kOwnExponent], pm.c(2.0)));
        return lane.normalFromPolar(pm.neg(lane.expm1(y)), u2);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_BlinnPhongEmitter() {
    static const BlinnPhongEmitter emitter;
    return {{ModelSlot::Ndf, "blinn_phong", &emitter}};
}

}  // namespace facet
