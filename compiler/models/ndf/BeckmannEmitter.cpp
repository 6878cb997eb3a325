// beckmann: the Beckmann NDF and the Beckmann-profile Smith Lambda as IR
// (the reference is Beckmann.cpp). D is evaluated from wi + wo in the
// precise type: its exponent amplifies the rounding of h by its own size.
#include "BeckmannProfileEmitter.h"

#include <cmath>

namespace facet {

using llvm::Value;

// Lambda = (exp(-a^2)/(a sqrt(pi)) - erfc(a)) / 2, a = cot(theta_v) /
// alpha_v; times vz (vz / a = s), and with erfc(a) = exp(-a^2) erfcx(a) one
// exp serves both terms: vz Lambda = exp(-a^2) (s/sqrt(pi) - vz erfcx(a)) / 2.
// The difference cancels as a grows (by 35x at a = 4), but only relative to
// Lambda, which is then below 1e-9 next to the 1 of 1 + Lambda. Beyond a =
// 4, Lambda < 2.5e-10 is below float resolution in G1: 0. The argument is
// clamped first so that exp never produces subnormals (each costs a
// microcode assist), and at 0 from below (vz < 0 in lanes below the
// horizon, whose value is discarded). With the plan's WalterFit, Walter et
// al. 2007, eq. 27 (as Lambda = 1/G1 - 1): rational in a, 0 for a >= 1.6,
// relative error in G1 below about 0.4%; times vz:
// s (1 - 1.259 a + 0.396 a^2) / (3.535 + 2.181 a).
Value* BeckmannProfileEmitter::cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const {
    MathEmitter& fm = lane.floatMath();
    Value* proj = lane.smithProjection(*this, n, v);
    Value* vz = v[2];
    Value* s = fm.sqrt(proj);
    Value* a = fm.div(vz, s);
    Value* cl;
    if (lane.plan.lambda == LambdaForm::WalterFit) {
        Value* r = fm.div(fm.mul(s, fm.poly(a, {1.0, -1.259, 0.396})), fm.poly(a, {3.535, 2.181}));
        cl = fm.select(fm.lt(a, fm.c(1.6)), r, fm.c(0.0));
    } else {
        Value* ac = fm.maxnum(fm.minnum(a, fm.c(4.0)), fm.c(0.0));
        cl = fm.mul(fm.mul(fm.c(0.5), fm.expNormal(fm.neg(fm.mul(ac, ac)))),
                    fm.sub(fm.mul(s, fm.c(1.0 / std::sqrt(kPi))), fm.mul(vz, fm.erfcx(ac))));
        cl = fm.select(fm.gt(a, fm.c(4.0)), fm.c(0.0), fm.maxnum(cl, fm.c(0.0)));
    }
    return fm.select(fm.eq(proj, fm.c(0.0)), fm.c(0.0), cl);
}

namespace {

constexpr int kAlphaX = 0, kAlphaY = 1;

class BeckmannEmitter final : public BeckmannProfileEmitter {
public:
    BeckmannEmitter() {
        traits.dFromUnnormalizedHalf = true;
        traits.samplesNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.ndf, kAlphaX, kAlphaY);
    }

    // From u = geo.slopeH, h up to scale: e is a ratio of squares of u's
    // components, and mz^4 = uz^4/|u|^4.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& u = geo.slopeH;
        Value* l2 = geo.slopeHLen2;  // |u|^2, null for |u| = 1
        Value* z2d = pm.mul(u[2], u[2]);
        Value *e, *D;
        if (n.isotropic) {
            // One division: t = 1/(a^2 uz^2), e = (ux^2 + uy^2) t, and
            // 1/(pi a^2 mz^4) = (|u|^2 t)^2 a^2 / pi.
            Value* a2 = pm.mul(n.axD, n.axD);
            Value* t = pm.div(pm.c(1.0), pm.mul(a2, z2d));
            e = pm.mul(pm.fma(u[0], u[0], pm.mul(u[1], u[1])), t);
            Value* lt = l2 ? pm.mul(l2, t) : t;
            D = pm.mul(lane.expTail(e), pm.mul(pm.mul(lt, pm.mul(lt, a2)), pm.c(1.0 / kPi)));
        } else {
            e = lane.slopeExponent(n, u);
            Value* axy = pm.mul(n.axD, n.ayD);
            Value* num = l2 ? pm.mul(lane.expTail(e), pm.mul(l2, l2)) : lane.expTail(e);
            D = pm.div(num, pm.mul(pm.mul(pm.c(kPi), axy), pm.mul(z2d, z2d)));
        }
        // exp underflowed: 0, not 0/0 when mz^4 underflows too.
        return pm.select(pm.gt(e, pm.c(lane.expTailLimit())), pm.c(0.0), D);
    }

    // The standard slope radius has the CDF 1 - exp(-r^2).
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        return lane.stretchedSlopeNormal(n, pm.neg(pm.log1p(pm.neg(u1))), u2);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_BeckmannEmitter() {
    static const BeckmannEmitter emitter;
    return {{ModelSlot::Ndf, "beckmann", &emitter}};
}

}  // namespace facet
