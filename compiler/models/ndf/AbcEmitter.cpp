// abc: the ABC distribution as IR (the reference is Abc.cpp): D in log
// form in the precise type, its normalization and the NDF sampler's CDF
// inversion in double.
#include "ShapeNdfEmitter.h"
#include "Immortal.h"
#include "TabulatedLambdaEmitter.h"

#include <cmath>

namespace facet {

using llvm::Value;

// The Taylor series sum y^k/(k+1)! to k = 14 for |y| < 1/2 (the first term
// left out is below 2e-18), the quotient above (where e^y - 1 no longer
// cancels).
Value* expm1OverXDouble(MathEmitter& dm, Value* y) {
    double coeff[15];
    double fact = 1;
    for (int k = 0; k < 15; ++k) fact *= k + 1, coeff[k] = 1 / fact;
    Value* series = dm.c(coeff[14]);
    for (int k = 13; k >= 0; --k) series = dm.fma(series, y, dm.c(coeff[k]));
    Value* direct = dm.div(dm.sub(dm.exp(y), dm.c(1.0)), y);
    return dm.select(dm.lt(dm.abs(y), dm.c(0.5)), series, direct);
}

ShapeParams shapeParams(LaneEmitter& lane, int p0, int p1) {
    const ModelUse& use = lane.material.singleLobe().ndf;
    MathEmitter& dm = lane.doubleMath();
    ShapeParams s;
    s.n.isotropic = true;
    s.n.own[0] = lane.scalarParam(use, p0, false);
    s.n.own[1] = lane.scalarParam(use, p1, false);
    s.first = dm.convert(s.n.own[0], dm.type());
    s.second = dm.convert(s.n.own[1], dm.type());
    return s;
}

namespace {

constexpr int kB = 0, kC = 1;
constexpr int kOwnB = 0, kOwnC = 1, kOwnLogNorm = 2;  // NdfParams::own, precise type: b, c, ln A
constexpr int kNewtonSteps = 14;

// The mass Int_1^(1+d) (1 + d - t) t^-c dt in double, L = ln(1 + d): from
// the integrals of t^-c and t^(1-c), ((1 + d) L phi((1 - c) L) - d) / (2 -
// c), or regrouped (L phi((2 - c) L) - d) / (1 - c), phi(y) = (e^y - 1)/y;
// each is exact at the other's pole (c = 2, c = 1), so the first serves
// |c - 2| > 1/2 and the second the rest.
Value* mass(MathEmitter& dm, Value* d, Value* c) {
    Value* L = dm.log1p(d);
    Value* oneMinusC = dm.sub(dm.c(1.0), c);
    Value* twoMinusC = dm.sub(dm.c(2.0), c);
    Value* away = dm.div(dm.sub(dm.mul(dm.mul(dm.add(d, dm.c(1.0)), L), expm1OverXDouble(dm, dm.mul(oneMinusC, L))), d),
                         twoMinusC);
    Value* near = dm.div(dm.sub(dm.mul(L, expm1OverXDouble(dm, dm.mul(twoMinusC, L))), d), oneMinusC);
    return dm.select(dm.gt(dm.abs(twoMinusC), dm.c(0.5)), away, near);
}

class AbcEmitter final : public NdfEmitter {
public:
    AbcEmitter() {
        traits.isotropicOnly = true;
        traits.samplesNormals = true;
    }

    // ln A = 2 ln b - ln(2 pi N(b, c)), folded for constant b and c.
    NdfParams params(LaneEmitter& lane) const override {
        ShapeParams s = shapeParams(lane, kB, kC);  // own[kOwnB], own[kOwnC]
        MathEmitter& dm = lane.doubleMath();
        Value* b = s.first;
        Value* logNorm = dm.sub(dm.mul(dm.log(b), dm.c(2.0)), dm.log(dm.mul(mass(dm, b, s.second), dm.c(2 * kPi))));
        s.n.own[kOwnLogNorm] = lane.preciseMath().convert(logNorm, lane.preciseMath().type());
        return s.n;
    }

    // ln D = ln A - c ln(1 + b x), x = 1 - mz = (mx^2 + my^2) / (1 + mz).
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& h = geo.hD;
        Value* x = pm.div(pm.fma(h[0], h[0], pm.mul(h[1], h[1])), pm.add(h[2], pm.c(1.0)));
        Value* logD = pm.sub(n.own[kOwnLogNorm], pm.mul(n.own[kOwnC], pm.log1p(pm.mul(n.own[kOwnB], x))));
        return pm.exp(logD);
    }

    // Its Smith Lambda from the plan's table in (a, alpha), at energyAlpha
    // (TabulatedLambdaEmitter.h).
    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // The Kulla-Conty table's roughness: 1 / sqrt(1 + b/2), where c = 2 has
    // GGX's peak (the catalog entry's equivalentAlphas).
    Value* energyAlpha(LaneEmitter& lane, const NdfParams& n) const override {
        MathEmitter& pm = lane.preciseMath();
        return pm.div(pm.c(1.0), pm.sqrt(pm.fma(n.own[kOwnB], pm.c(0.5), pm.c(1.0))));
    }

    // In v = ln t, t = 1 + b (1 - mz), the mass of D(m) mz below t is
    // proportional to Q(v) = (b - (t - 1)) v phi((1 - c) v) + M(t - 1), M
    // the mass above (split of (1 + b - s) = (1 + b - t) + (t - s)), with
    // Q' = (b - (t - 1)) t^(1 - c) and Q(ln(1 + b)) = M(b). The density
    // t^-c dt alone (the factor 1 + b - t dropped, nearly constant where a
    // narrow lobe has its mass) has the quantile ln t = L g(u), g(u) =
    // log1p(u expm1(k)) / k, k = (1 - c) L (g = u at k = 0): dropping a
    // falling factor moves mass up, so the root lies below L g(u), and, the
    // factor being at most b, above L g(u M(b) / (b L phi(k))).
    // Newton starts at the upper end, exact for a narrow lobe. Lanes above
    // the median solve for the mass beyond t instead, R = (1 + b)^(2-c) l
    // (phi(-(1 - c) l) - phi(-(2 - c) l)) = (1 - u) M(b), l = L - v (R' =
    // -Q' in v), so that cos theta = (1 + b)(1 - e^-l)/b keeps its relative
    // accuracy toward the horizon.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        Value* b = dm.convert(n.own[kOwnB], dm.type());
        Value* c = dm.convert(n.own[kOwnC], dm.type());
        Value* u = dm.convert(u1, dm.type());
        Value* oneMinusC = dm.sub(dm.c(1.0), c);
        Value* L = dm.log1p(b);
        Value* k = dm.mul(oneMinusC, L);
        Value* kZero = dm.eq(k, dm.c(0.0));
        Value* kSafe = dm.select(kZero, dm.c(1.0), k);
        Value* expm1K = dm.mul(kSafe, expm1OverXDouble(dm, kSafe));
        auto quantile = [&](Value* w) {
            return dm.mul(L, dm.select(kZero, w, dm.div(dm.log1p(dm.mul(w, expm1K)), kSafe)));
        };
        Value* total = mass(dm, b, c);
        Value* ratio = dm.div(total, dm.mul(dm.mul(b, L), expm1OverXDouble(dm, k)));
        Value* hi = dm.minnum(quantile(u), L);
        Value* lo = dm.minnum(quantile(dm.mul(u, ratio)), hi);
        Value* target = dm.mul(u, total);
        Value* upper = dm.gt(u, dm.c(0.5));
        Value* T = dm.add(b, dm.c(1.0));
        Value* twoMinusC = dm.sub(dm.c(2.0), c);
        Value* top = dm.exp(dm.mul(twoMinusC, L));
        Value* upperTarget = dm.mul(dm.sub(dm.c(1.0), u), total);
        // Upper lanes start where R ~ (1 + b)^(2-c) l^2 / 2 (the density
        // near the horizon) meets their target.
        Value* l0 = dm.sqrt(dm.div(dm.mul(upperTarget, dm.c(2.0)), top));
        Value* v0 = dm.select(upper, dm.minnum(dm.maxnum(dm.sub(L, l0), lo), hi), hi);
        auto eval = [&](Value* v) {
            Value* d = dm.mul(v, expm1OverXDouble(dm, v));  // t - 1
            Value* rest = dm.sub(b, d);
            Value* q = dm.add(dm.mul(dm.mul(rest, v), expm1OverXDouble(dm, dm.mul(oneMinusC, v))), mass(dm, d, c));
            Value* l = dm.sub(L, v);
            Value* R = dm.mul(dm.mul(top, l), dm.sub(expm1OverXDouble(dm, dm.neg(dm.mul(oneMinusC, l))),
                                                    expm1OverXDouble(dm, dm.neg(dm.mul(twoMinusC, l)))));
            Value* slope = dm.mul(rest, dm.exp(dm.mul(oneMinusC, v)));
            return LaneEmitter::NewtonTerms{dm.select(upper, dm.sub(upperTarget, R), dm.sub(q, target)), slope};
        };
        Value* v = lane.bracketedNewton(dm, eval, v0, lo, hi, kNewtonSteps);
        Value* d = dm.mul(v, expm1OverXDouble(dm, v));
        Value* x = dm.minnum(dm.div(d, b), dm.c(1.0));
        // 1 + b - t = (1 + b)(1 - e^-l), l = L - v exact near the horizon.
        Value* l = dm.sub(L, v);
        Value* restUpper = dm.mul(dm.mul(T, l), expm1OverXDouble(dm, dm.neg(l)));
        Value* mz = dm.maxnum(dm.div(dm.select(upper, restUpper, dm.sub(b, d)), b), dm.c(0.0));
        Value* s2 = dm.mul(x, dm.sub(dm.c(2.0), x));
        return lane.normalFromPolar(pm.convert(s2, pm.type()), u2, pm.convert(dm.mul(mz, mz), pm.type()));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_AbcEmitter() {
    static const AbcEmitter& emitter = immortal<AbcEmitter>();
    return {{ModelSlot::Ndf, "abc", &emitter, lambdaTableEmbedding}};
}

}  // namespace facet
