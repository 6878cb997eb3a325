// ggx: the GGX NDF and its Smith terms as IR (the reference is Ggx.cpp).
// Written for float lanes: D as one fraction, the Smith Lambda without
// cancellation, and the root form R(v) = (n.v)(1 + 2 Lambda(v)) that turns
// the height-correlated denominator into sums of positive terms.
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

#include <cmath>

namespace facet {
namespace {

constexpr int kAlphaX = 0, kAlphaY = 1;

using llvm::Value;

class GgxEmitter final : public NdfEmitter {
public:
    GgxEmitter() {
        traits.dFromUnnormalizedHalf = true;
        traits.floatFirstBody = true;
        traits.guardedFastBody = true;
        traits.smithRootSums = true;
        traits.samplesNormals = true;
        traits.samplesVisibleNormals = true;
        traits.floatFirstSampler = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.singleLobe().ndf, kAlphaX, kAlphaY);
    }

    // D(h) in the precise type; even the float value is carried on in it,
    // because D can be far below float range where D G / (ci co) is not.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& fm = lane.floatMath();
        MathEmitter& pm = lane.preciseMath();
        if (!lane.body.guarded() && lane.body.precise == Precision::Double) {
            // The precise body of an exact kernel: D in double, so that an
            // alpha beyond float range or alphas far apart (ggx(1e30),
            // alpha_x = 1e30 with alpha_y = 1e-30), whose D or lobe can still
            // be a normal float at grazing h, get the reference's value
            // instead of a float 0 or Inf/Inf.
            // From u = wi + wo (geo.slopeH, h up to scale; |u|^2 = l2, null
            // for a unit u): D is homogeneous of degree 0 in u, D = a^2
            // |u|^4 / (pi (ux^2 + uy^2 + a^2 uz^2)^2), so it waits neither
            // for |u|'s square root nor for the division that normalizes h
            // (a one-lane call's longest chain), and the half angle may stay
            // in float (NdfLoweringTraits::dFromUnnormalizedHalf).
            const std::array<Value*, 3>& u = geo.slopeH;
            Value* l2 = geo.slopeHLen2;
            Value *x2 = pm.mul(u[0], u[0]), *y2 = pm.mul(u[1], u[1]), *z2 = pm.mul(u[2], u[2]);
            Value *num, *t;
            if (n.isotropic) {
                Value* a2 = pm.mul(n.axD, n.axD);
                num = pm.mul(a2, pm.c(1.0 / kPi));
                t = pm.fma(a2, z2, pm.add(x2, y2));
            } else {
                // 1 / (pi ax ay (x2/ax^2 + y2/ay^2 + z2)^2), scaled by ax ay
                // so that nothing overflows for ax ay within double range.
                Value* axy = pm.mul(n.axD, n.ayD);
                num = pm.mul(axy, pm.c(1.0 / kPi));
                t = pm.add(pm.fma(pm.div(n.ayD, n.axD), x2, pm.mul(pm.div(n.axD, n.ayD), y2)), pm.mul(axy, z2));
            }
            if (!l2) return pm.div(num, pm.mul(t, t));
            Value* r = pm.div(l2, t);
            return pm.mul(num, pm.mul(r, r));
        }
        // In float, h is the unit h or, in the float-first body (the plan
        // leaves the unit h out there), u = wi + wo with |u|^2 = l2: D is
        // homogeneous of degree 0 in u, so D then waits neither for |u|'s
        // square root nor for the division that normalizes h. The lobe
        // range guard catches what u's range changes (|u|^2 >= 1e-8 there).
        const std::array<Value*, 3>& h = geo.slopeH;
        Value* l2 = geo.slopeHLen2;
        internal_assert(h[0]) << "GGX's float D without h";
        internal_assert(!l2 || lane.body.guarded()) << "GGX's float D from wi + wo outside a guarded body";
        if (n.isotropic) {
            // 1 / (pi a^2 (s2/a^2 + mz^2)^2) = a^2 / (pi (s2 + a^2 mz^2)^2): one
            // division; from u, a^2 |u|^4 / (pi (s2 + a^2 uz^2)^2).
            Value* a2 = fm.mul(n.ax, n.ax);
            Value* s2 = fm.fma(h[0], h[0], fm.mul(h[1], h[1]));
            Value* t = fm.fma(a2, fm.mul(h[2], h[2]), s2);
            Value* num = l2 ? fm.mul(a2, fm.mul(l2, l2)) : a2;
            Value* D = fm.div(fm.mul(num, fm.c(1.0 / kPi)), fm.mul(t, t));
            // Guarded body: D/4 also as a fraction, so that the lobe divides
            // once (LaneEmitter::quarterDOver). a^2 = Inf there gives a NaN
            // lobe, which the lobe range guard rejects.
            if (lane.body.guarded()) lane.setQuarterDFraction(fm.mul(num, fm.c(0.25 / kPi)), fm.mul(t, t));
            // A body that sums the rounded unit directions (the guarded fast
            // body, without correctedSums) has h off by an angle up to d ~
            // 1e-7 / |wi + wo| = 5e-8 / (wo.h). With s = sin theta_h of the
            // computed h, t = s^2 + a^2 mz^2 then moves by up to |1 - a^2|
            // (2 s d + d^2), D twice that relative to t (the d^2 part
            // matters where d exceeds s: a computed h of exactly n for a
            // true theta_h of 1e-5). The body distrusts the lanes where that
            // may exceed 2e-4, 2 |1 - a^2| (2 s d + d^2) > 2e-4 t, through
            // (x + y)^2 <= 2 (x^2 + y^2) and d^2 = 2.5e-15 / c^2 (c = wo.h)
            // without a square root or division:
            //   2e-6 (1 - a^2)^2 (s^2 c^2 + 6.25e-16) > (t c^2)^2
            // (NaN distrusts too); its fallback body recomputes them. Only
            // lanes near the peak of a small alpha or with a small wi + wo
            // qualify: none of 262144 drawn as the bench's regular sample
            // is, where alpha (wo.h) < 5e-4, the same bound taken over all
            // theta_h, takes 2.7% (docs/numerics.md).
            if (lane.body.guarded() && !lane.body.correctedSums) {
                internal_assert(!l2) << "the guarded fast body's D guard takes the unit h";
                Value* cosD = fm.convert(geo.cosD, fm.type());
                Value* c2 = fm.mul(cosD, cosD);
                Value* k = fm.fma(fm.neg(a2), fm.c(std::sqrt(2e-6)), fm.c(std::sqrt(2e-6)));  // sqrt(2e-6) (1 - a^2)
                Value* lhs = fm.mul(fm.mul(k, k), fm.fma(s2, c2, fm.c(6.25e-16)));
                Value* tc2 = fm.mul(t, c2);
                lane.distrust(lane.builder.CreateNot(fm.le(lhs, fm.mul(tc2, tc2))));
            }
            // a^2 beyond float (alpha > 1.8e19): D < 1e-38 / mz^4 is 0, not Inf/Inf.
            return pm.convert(fm.select(fm.isFinite(a2), D, fm.c(0.0)), pm.type());
        }
        if (lane.body.guarded()) {
            // Guarded body: D = (ax ay / N)^2 ax ay / pi, N = ay^2 mx^2 + ax^2
            // my^2 + (ax ay)^2 mz^2 (the form below times (ax ay)^2): one
            // division instead of three. N >= min(ax, ay, ax ay)^2 / 3 is
            // normal for alpha >= 1e-4; where r = ax ay / N or its square
            // over- or underflows (alphas far apart or beyond ~1e9), or
            // (ax ay)^2 overflows (NaN), D is Inf, NaN or below 1e-38, and
            // the lobe range guard sends the lane to the other body. From u,
            // N is |u|^2 times N of the unit h: r = ax ay |u|^2 / N.
            Value* axy = fm.mul(n.ax, n.ay);
            Value* N = fm.fma(fm.mul(axy, axy), fm.mul(h[2], h[2]),
                              fm.fma(fm.mul(n.ay, n.ay), fm.mul(h[0], h[0]), fm.mul(fm.mul(n.ax, n.ax), fm.mul(h[1], h[1]))));
            Value* r = fm.div(l2 ? fm.mul(axy, l2) : axy, N);
            return pm.convert(fm.mul(fm.mul(r, r), fm.mul(axy, fm.c(1.0 / kPi))), pm.type());
        }
        Value* t = fm.fma(h[2], h[2], lane.slope2(n, h));
        return pm.convert(fm.div(fm.c(1.0 / kPi), fm.mul(fm.mul(n.ax, n.ay), fm.mul(t, t))), pm.type());
    }

    // vz Lambda = vz (sqrt(1 + proj/vz^2) - 1)/2 = proj / (2 (vz + sqrt(vz^2 + proj))):
    // no cancellation for small proj, no overflow for small vz. (proj = Inf
    // for alpha beyond ~1e19: Lambda = Inf, G = 0, not Inf/Inf.)
    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        MathEmitter& fm = lane.floatMath();
        Value* proj = lane.smithProjection(*this, n, v);
        Value* vz = v[2];
        Value* cl = fm.div(proj, fm.mul(fm.c(2.0), fm.add(vz, fm.sqrt(fm.fma(vz, vz, proj)))));
        return fm.select(fm.isFinite(proj), cl, proj);
    }

    // R^2 = z^2 + a^2 (x^2 + y^2). For a unit v and one alpha with a^2 <= 2
    // (the plan's range of alpha), R^2 = z^2 + a^2 (1 - z^2) needs neither
    // x nor y (nor, in the float-first body, their corrections): with z
    // within a relative e of the unit v's, 1 - z^2 by one fma is off by
    // 2 e z^2, which moves R^2 by 2 e z^2 |1 - a^2| <= 2 e R^2; |v|^2 = 1 +
    // d moves it by a^2 d <= 2 d R^2 more. A larger alpha scales both
    // errors by a^2 where z is near 1 (docs/numerics.md).
    Value* smithRootSquared(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v,
                            bool unit) const override {
        MathEmitter& fm = lane.floatMath();
        const double alphaHi = lane.plan.param(ModelSlot::Ndf, kAlphaX).range.hi;
        if (unit && n.isotropic && alphaHi * alphaHi <= 2.0) {
            Value* z = v[2];
            return fm.fma(fm.mul(n.ax, n.ax), fm.fma(fm.neg(z), z, fm.c(1.0)), fm.mul(z, z));
        }
        return fm.fma(v[2], v[2], lane.smithProjection(*this, n, v));
    }

    // (n.v)(1 + Lambda(v)) = ((n.v) + R(v)) / 2: a sum of positive terms, no
    // division. R in float, as eval's Smith forms take it, so that a float
    // body's sampler and eval share R(wo).
    Value* visibleSmithSum(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        MathEmitter& fm = lane.floatMath();
        MathEmitter& pm = lane.preciseMath();
        std::array<Value*, 3> vLane;
        for (int i = 0; i < 3; ++i) vLane[i] = fm.convert(v[i], fm.type());
        Value* root = pm.convert(fm.sqrt(smithRootSquared(lane, n, vLane, true)), pm.type());
        return pm.mul(pm.add(v[2], root), pm.c(0.5));
    }

    // The standard slope radius has the CDF r^2 / (1 + r^2).
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        return lane.stretchedSlopeNormal(n, pm.div(u1, pm.sub(pm.c(1.0), u1)), u2);
    }

    // In the space stretched to alpha = 1 the visible normals of the view
    // direction v are v + c for c uniform on the part of the unit sphere
    // with c.z >= -v.z (Dupuy & Benyoub 2023): c.z uniform in [-v.z, 1], its
    // azimuth 2 pi u1. Unstretching v + c gives m.
    std::array<Value*, 3> sampleVisibleNormal(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& wo,
                                              Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        Value *vx = pm.mul(n.axD, wo[0]), *vy = pm.mul(n.ayD, wo[1]);
        // |v| before normalizing is R(wo): in float the same value as the
        // density's and eval's, one square root for the three.
        Value* len = pm.isDouble() ? pm.sqrt(pm.fma(vx, vx, pm.fma(vy, vy, pm.mul(wo[2], wo[2]))))
                                   : pm.sqrt(smithRootSquared(lane, n, wo, true));
        Value* inv = pm.div(pm.c(1.0), len);
        vx = pm.mul(vx, inv), vy = pm.mul(vy, inv);
        Value* vz = pm.mul(wo[2], inv);
        // c.z = z = (1 - u2)(1 + v.z) - v.z, taken apart so that nothing
        // cancels: 1 - z = u2 (1 + v.z), 1 + z = (1 - u2)(1 + v.z) + (1 - v.z)
        // and z + v.z = (1 - u2)(1 + v.z). (The radius sqrt(1 - z^2) of z
        // rounded near the pole would be off by sqrt(2 ulp): 5e-4 in float.)
        Value* onePlusVz = pm.add(pm.c(1.0), vz);
        Value* oneMinusU2 = pm.sub(pm.c(1.0), u2);
        Value* oneMinusZ = pm.mul(u2, onePlusVz);
        Value* onePlusZ = pm.fma(oneMinusU2, onePlusVz, pm.sub(pm.c(1.0), vz));
        Value* r = pm.sqrt(pm.maxnum(pm.mul(oneMinusZ, onePlusZ), pm.c(0.0)));  // v.z may round above 1
        auto [sinPhi, cosPhi] = pm.sinCosTurns(u1);
        Value* hx = pm.fma(r, cosPhi, vx);
        Value* hy = pm.fma(r, sinPhi, vy);
        Value* hz = pm.mul(oneMinusU2, onePlusVz);
        // In float, v + c carries an absolute error of a few ulp (its
        // components cancel near c = -v), which moves D of the drawn m
        // relative to itself by ~1e-6 / |v + c|: a guarded body leaves
        // |v + c|^2 < 0.03 to the precise body, so that the pdf stays within
        // exact mode's 1e-5 (docs/numerics.md).
        if (lane.body.guarded())
            lane.distrust(pm.lt(pm.fma(hx, hx, pm.fma(hy, hy, pm.mul(hz, hz))), pm.c(0.03)));
        Value* mx = pm.mul(n.axD, hx);
        Value* my = pm.mul(n.ayD, hy);
        Value* len2 = pm.fma(mx, mx, pm.fma(my, my, pm.mul(hz, hz)));
        // v + c = 0 only where c is the cap's pole -v, a null set: n there.
        Value* ok = pm.gt(len2, pm.c(0.0));
        Value* mInv = pm.div(pm.c(1.0), pm.sqrt(len2));
        return {pm.select(ok, pm.mul(mx, mInv), pm.c(0.0)), pm.select(ok, pm.mul(my, mInv), pm.c(0.0)),
                pm.select(ok, pm.mul(hz, mInv), pm.c(1.0))};
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_GgxEmitter() {
    static const GgxEmitter& emitter = immortal<GgxEmitter>();
    return {{ModelSlot::Ndf, "ggx", &emitter}};
}

}  // namespace facet
