// beckmann: the Beckmann NDF and the Beckmann-profile Smith Lambda as IR
// (the reference is Beckmann.cpp). D is evaluated from wi + wo in the
// precise type: its exponent amplifies the rounding of h by its own size.
#include "BeckmannProfileEmitter.h"
#include "Immortal.h"

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

// The visible slopes x are drawn on [-kSlopeTail, hi]: below -8 the CDF
// holds less than 1e-28 of its mass.
constexpr double kSlopeTail = 8;
// Beyond this tan(theta_o) (n.wo below ~1e-8 alpha) the slope density
// (1 - x tan)+ exp(-x^2) is -x exp(-x^2) to within 1/tan: the lanes draw
// from tan = 1e8, whose slopes differ from the limit's by ~1e-8.
constexpr double kMaxTan = 1e8;
constexpr int kNewtonSteps = 5;
constexpr double kLowerPart = 0.7;  // u below: invert C; above: the tail mass S

// One standard (alpha = 1) visible slope for the view at tan(theta_o) =
// tanT (Heitz & d'Eon 2014): x in [-8, hi], hi = min(cot theta_o, 8), with
// the CDF C(x) = erfc(-x)/2 + tanT exp(-x^2) / (2 sqrt(pi)) at the fraction
// u of C(hi); tanT = 0 gives the Gaussian erfc(-x)/2 = u. Both C and the
// tail mass S(x) = C(hi) - C(x) are log-concave (the density is), and their
// logarithms are nearly linear in the variables the two parts of [0, 1)
// invert in: for u < 0.7 log C in x, which goes as -x^2 in the tail; above
// it log S in z = ln(hi - x), which goes as 2 z where the density vanishes
// linearly at hi (tanT > 1/8) and as -x^2 in the Gaussian tail. The
// starting points bound the root: from C <= exp(-x^2) (1 + tanT/sqrt(pi))/2
// for x <= 0 below, and above from S >= the mass of each of the density's
// parts (the quadratic at hi, the Rayleigh term -x tanT exp(-x^2), the
// Gaussian) where that part is the whole, which is why those starts serve
// the tail above 0.7 and not the middle; five bracketed Newton steps then
// reach 1e-12 in x (checked against a long double bisection over 5e5
// (tanT, u) pairs, tanT from 0 to 1e14, u down to 1e-17 and up to
// 1 - 2^-24, and densely over u in [0.45, 0.8]). Always in double, fast
// kernels too: near u = 1 the root moves by S's relative error, S = C(hi) -
// C(x) is 6e-8 of C there, and C needs erfc to double precision. tanT and u
// in double.
Value* visibleSlope(LaneEmitter& lane, Value* tanT, Value* u) {
    MathEmitter& pm = lane.doubleMath();
    llvm::IRBuilder<>& b = lane.builder;
    const double rootPi = std::sqrt(kPi);
    tanT = pm.minnum(tanT, pm.c(kMaxTan));
    Value* hi = pm.minnum(pm.div(pm.c(1.0), tanT), pm.c(kSlopeTail));  // tanT = 0: 1/0 = inf, then 8
    Value* k = pm.mul(tanT, pm.c(1 / rootPi));
    // C(x) (and the density, times sqrt(pi)) with erfc(-x) = exp(-x^2) erfcx(-x)
    // for x <= 0 and 2 - exp(-x^2) erfcx(x) above.
    auto cdf = [&](Value* x, Value** density) {
        Value* e = pm.expNormal(pm.neg(pm.mul(x, x)));
        Value* ex = pm.erfcxWide(pm.minnum(pm.abs(x), pm.c(kSlopeTail)));
        Value* below = pm.mul(pm.mul(e, pm.add(ex, k)), pm.c(0.5));
        Value* above = pm.fma(pm.mul(e, pm.c(-0.5)), pm.sub(ex, k), pm.c(1.0));
        if (density) *density = pm.mul(pm.maxnum(pm.fma(pm.neg(x), tanT, pm.c(1.0)), pm.c(0.0)), pm.mul(e, pm.c(1 / rootPi)));
        return pm.select(pm.gt(x, pm.c(0.0)), above, below);
    };
    Value* total = cdf(hi, nullptr);
    Value* lower = pm.lt(u, pm.c(kLowerPart));
    Value* target = pm.mul(u, total);                    // C(x) for u below 0.7
    Value* rest = pm.mul(pm.sub(pm.c(1.0), u), total);  // S(x) above (1 - u exact)
    // Below: C(x) <= exp(-x^2) A0 with A0 = C(0) bounds x from below.
    Value* a0 = pm.mul(pm.add(pm.c(1.0), k), pm.c(0.5));
    Value* xLow = pm.neg(pm.sqrt(pm.maxnum(pm.log(pm.div(a0, target)), pm.c(0.0))));  // target = 0: -inf
    xLow = pm.maxnum(xLow, pm.c(-kSlopeTail));
    // Above: the quadratic S = K d^2 / 2 at hi (K = tanT exp(-hi^2)/sqrt(pi),
    // the density's slope there), the Rayleigh part's mass tanT (exp(-hi^2)
    // - exp(-x^2)) / (2 sqrt(pi)) = S for x = -sqrt(hi^2 - ln(1 - 2 S/K)),
    // and the Gaussian tail exp(-x^2)/2 = S; each d = hi - x bounds the
    // root's from above where its part is the whole density.
    Value* K = pm.mul(k, pm.expNormal(pm.neg(pm.mul(hi, hi))));
    Value* dq2 = pm.div(pm.mul(pm.c(2.0), rest), K);  // tanT = 0: inf
    Value* dq = pm.sqrt(dq2);
    Value* dr = pm.add(hi, pm.sqrt(pm.sub(pm.mul(hi, hi), pm.log1p(pm.neg(pm.minnum(dq2, pm.c(0.5)))))));
    Value* lg = pm.log(pm.div(pm.c(0.5), rest));
    Value* dg = pm.sub(hi, pm.sqrt(pm.maxnum(lg, pm.c(0.0))));
    dg = pm.select(b.CreateAnd(pm.gt(lg, pm.c(0.0)), pm.gt(dg, pm.c(0.0))), dg, pm.c(INFINITY));
    // S(hi - d) <= d max density <= d (1 + 8 tanT)/sqrt(pi): ln of that d
    // bounds z from below.
    Value* zLo = pm.log(pm.div(pm.mul(rest, pm.c(rootPi)), pm.fma(tanT, pm.c(kSlopeTail), pm.c(1.0))));
    Value* zHi = pm.log(pm.add(hi, pm.c(kSlopeTail)));
    Value* z0 = pm.log(pm.minnum(pm.minnum(dq, dr), dg));
    z0 = pm.minnum(pm.maxnum(z0, zLo), zHi);

    auto slopeAt = [&](Value* v) {
        Value* x = pm.select(lower, v, pm.sub(hi, pm.exp(v)));
        return pm.minnum(pm.maxnum(x, pm.c(-kSlopeTail)), hi);
    };
    auto eval = [&](Value* v) {
        Value* x = slopeAt(v);
        Value* density;
        Value* c = cdf(x, &density);
        Value* s = pm.sub(total, c);
        // ln(C/target) (+inf at target = 0: the root is -8) or ln(S/rest)
        // (-inf where S rounds to 0 or below: the root is further from hi).
        Value* ratio = pm.select(lower, pm.div(c, target), pm.div(s, rest));
        Value* phi = pm.log(pm.maxnum(ratio, pm.c(0.0)));
        Value* slope = pm.select(lower, pm.div(density, c), pm.div(pm.mul(density, pm.sub(hi, x)), s));
        return LaneEmitter::NewtonTerms{phi, slope};
    };
    Value* v0 = pm.select(lower, xLow, z0);
    Value* lo = pm.select(lower, pm.c(-kSlopeTail), zLo);
    Value* top = pm.select(lower, hi, zHi);
    return slopeAt(lane.bracketedNewton(pm, eval, v0, lo, top, kNewtonSteps));
}

class BeckmannEmitter final : public BeckmannProfileEmitter {
public:
    BeckmannEmitter() {
        traits.dFromUnnormalizedHalf = true;
        traits.samplesNormals = true;
        traits.samplesVisibleNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.singleLobe().ndf, kAlphaX, kAlphaY);
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

    // Heitz & d'Eon 2014: in the space stretched to alpha = 1, turned so
    // that wo' = (sin t, 0, cos t), the visible slopes are x from the
    // density (1 - x tan t)+ exp(-x^2) and y from exp(-y^2), independent
    // (visibleSlope); turned back and unstretched they give m.
    std::array<Value*, 3> sampleVisibleNormal(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& wo,
                                              Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* sx = pm.mul(n.axD, wo[0]);
        Value* sy = pm.mul(n.ayD, wo[1]);
        Value* sxy = pm.sqrt(pm.fma(sx, sx, pm.mul(sy, sy)));
        Value* turned = pm.gt(sxy, pm.c(0.0));  // wo = n: no azimuth, x along t
        Value* cosPhi = pm.select(turned, pm.div(sx, sxy), pm.c(1.0));
        Value* sinPhi = pm.select(turned, pm.div(sy, sxy), pm.c(0.0));
        MathEmitter& dm = lane.doubleMath();
        Value* x = pm.convert(visibleSlope(lane, dm.convert(pm.div(sxy, wo[2]), dm.type()), dm.convert(u1, dm.type())),
                              pm.type());
        // y: visibleSlope's tanT = 0, in closed form.
        Value* y = pm.convert(dm.gaussianQuantile(dm.convert(u2, dm.type()), kSlopeTail), pm.type());
        return lane.normalFromSlopes(pm.mul(n.axD, pm.fma(cosPhi, x, pm.neg(pm.mul(sinPhi, y)))),
                                     pm.mul(n.ayD, pm.fma(sinPhi, x, pm.mul(cosPhi, y))));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_BeckmannEmitter() {
    static const BeckmannEmitter& emitter = immortal<BeckmannEmitter>();
    return {{ModelSlot::Ndf, "beckmann", &emitter}};
}

}  // namespace facet
