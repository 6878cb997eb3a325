// sgd: the shifted gamma distribution as IR (the reference is Sgd.cpp): D
// in log form in the precise type; the normalization, an upper incomplete
// gamma function, and the NDF sampler's inversion of it in double.
#include "ShapeNdfEmitter.h"
#include "Immortal.h"
#include "TabulatedLambdaEmitter.h"

#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlpha = 0, kP = 1;
constexpr int kOwnAlpha = 0, kOwnP = 1, kOwnLogNorm = 2;  // NdfParams::own, precise type: alpha, p, -ln(pi N)
// ln Gamma(a, x) for a in [-1, 1]: Legendre's continued fraction from x = 2
// up, with kFractionDepth levels evaluated backwards; below 2, Gamma(a, 2)
// plus the integral from x to 2 of t^(a-1) e^-t, its series to kSeriesTerms
// terms. Both within 2e-15 relative over a in [-1, 1] (the slowest: the
// fraction at x = 2).
constexpr int kFractionDepth = 50;
constexpr int kSeriesTerms = 24;
constexpr int kNewtonSteps = 24;
constexpr double kSplit = 2;

// ln Gamma(a, y) by the continued fraction y^a e^-y / (y + 1 - a - 1 (1 -
// a) / (y + 3 - a - 2 (2 - a) / ...)), for y >= 2.
Value* logGammaFraction(MathEmitter& dm, Value* a, Value* y) {
    Value* ym = dm.sub(y, a);
    Value* f = dm.add(ym, dm.c(2.0 * kFractionDepth + 1));
    for (int i = kFractionDepth; i >= 1; --i)
        f = dm.sub(dm.add(ym, dm.c(2.0 * i - 1)), dm.div(dm.mul(dm.c(i), dm.sub(dm.c(i), a)), f));
    return dm.sub(dm.sub(dm.mul(a, dm.log(y)), y), dm.log(f));
}

// ln Gamma(a, x): the fraction at x >= 2; below, Gamma(a, 2) (given as its
// log) plus sum (-1)^n / n! (2^k - x^k) / k, k = a + n, whose terms n = 0,
// 1 (k may be 0 or negative) are 2^k L phi(-k L), L = ln(2/x), and the
// rest plain differences (at most 2^n / n! in size against a total above
// Gamma(1, 2) / 3).
Value* logUpperGamma(MathEmitter& dm, Value* a, Value* x, Value* logGammaAt2) {
    Value* above = logGammaFraction(dm, a, dm.maxnum(x, dm.c(kSplit)));
    Value* xs = dm.minnum(x, dm.c(kSplit));
    Value* L = dm.log(dm.div(dm.c(kSplit), xs));
    Value* pow2a = dm.exp(dm.mul(a, dm.c(std::log(kSplit))));
    Value* a1 = dm.add(a, dm.c(1.0));
    Value* sum = dm.mul(dm.mul(pow2a, L), expm1OverXDouble(dm, dm.neg(dm.mul(a, L))));
    sum = dm.sub(sum, dm.mul(dm.mul(dm.mul(pow2a, dm.c(kSplit)), L), expm1OverXDouble(dm, dm.neg(dm.mul(a1, L)))));
    Value* powX = dm.exp(dm.mul(a1, dm.log(xs)));  // x^(a+1)
    Value* pow2 = dm.mul(pow2a, dm.c(kSplit));     // 2^(a+1)
    double fact = 1;
    for (int n = 2; n < kSeriesTerms; ++n) {
        powX = dm.mul(powX, xs);
        pow2 = dm.mul(pow2, dm.c(kSplit));
        fact *= n;
        Value* t = dm.div(dm.sub(pow2, powX), dm.mul(dm.add(a, dm.c(n)), dm.c(fact)));
        sum = n % 2 ? dm.sub(sum, t) : dm.add(sum, t);
    }
    Value* below = dm.log(dm.add(dm.exp(logGammaAt2), sum));
    return dm.select(dm.ge(x, dm.c(kSplit)), above, below);
}

class SgdEmitter final : public NdfEmitter {
public:
    SgdEmitter() {
        traits.isotropicOnly = true;
        traits.samplesNormals = true;
    }

    // -ln(pi N), N = alpha Gamma(1 - p, alpha), folded for constant alpha
    // and p.
    NdfParams params(LaneEmitter& lane) const override {
        ShapeParams s = shapeParams(lane, kAlpha, kP);  // own[kOwnAlpha], own[kOwnP]
        MathEmitter& dm = lane.doubleMath();
        Value* alpha = s.first;
        Value* a = dm.sub(dm.c(1.0), s.second);
        Value* logGammaA = logUpperGamma(dm, a, alpha, logGammaFraction(dm, a, dm.c(kSplit)));
        Value* logNorm = dm.neg(dm.add(dm.log(dm.mul(alpha, dm.c(kPi))), logGammaA));
        s.n.own[kOwnLogNorm] = lane.preciseMath().convert(logNorm, lane.preciseMath().type());
        return s.n;
    }

    // ln D = -ln(pi N) - w - p ln w - 4 ln mz, w = alpha + tan^2 / alpha
    // (capped at 1e30, where exp(-w) is 0 in any type, so that p ln w stays
    // finite when tan^2 overflows toward the horizon).
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& h = geo.hD;
        Value* alpha = n.own[kOwnAlpha];
        Value* tan2 = pm.div(pm.fma(h[0], h[0], pm.mul(h[1], h[1])), pm.mul(h[2], h[2]));
        Value* w = pm.minnum(pm.add(alpha, pm.div(tan2, alpha)), pm.c(1e30));
        Value* logD = pm.sub(pm.sub(n.own[kOwnLogNorm], w), pm.mul(n.own[kOwnP], pm.log(w)));
        logD = pm.fma(pm.log(h[2]), pm.c(-4.0), logD);
        return pm.exp(logD);
    }

    // Its Smith Lambda from the plan's table in (a, alpha), at energyAlpha
    // (TabulatedLambdaEmitter.h).
    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // The Kulla-Conty table's roughness alpha / sqrt(alpha + p) (the
    // catalog entry's equivalentAlphas).
    Value* energyAlpha(LaneEmitter& lane, const NdfParams& n) const override {
        MathEmitter& pm = lane.preciseMath();
        return pm.div(n.own[kOwnAlpha], pm.sqrt(pm.add(n.own[kOwnAlpha], n.own[kOwnP])));
    }

    // w, with dw = d(tan^2)/alpha, has the density w^-p e^-w on [alpha,
    // inf): the root of -ln Gamma(a, e^v) = -ln((1 - u) Gamma(a, alpha)), a
    // = 1 - p, slope e^(a v - w) / Gamma(a, w). Brackets: the density is at
    // most alpha^-p e^-alpha, so w >= alpha + u Gamma(a, alpha) alpha^p
    // e^alpha; Gamma(a, w) <= e^-w for w >= 1, so w <= max(1, alpha, T) + 1
    // with T = -ln((1 - u) Gamma(a, alpha)). tan^2 theta = alpha (w - alpha).
    // Below the median Newton starts at the lower bracket, the first-order
    // root for a small u (exact at u = 0, where the normal is n and w -
    // alpha must be 0, not a rounding of it); above, where the tail's
    // asymptote puts it.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        Value* alpha = dm.convert(n.own[kOwnAlpha], dm.type());
        Value* p = dm.convert(n.own[kOwnP], dm.type());
        Value* a = dm.sub(dm.c(1.0), p);
        Value* u = dm.convert(u1, dm.type());
        Value* logGammaAt2 = logGammaFraction(dm, a, dm.c(kSplit));
        Value* logGammaA = logUpperGamma(dm, a, alpha, logGammaAt2);
        Value* T = dm.neg(dm.add(logGammaA, dm.log1p(dm.neg(u))));
        Value* head = dm.fma(u, dm.exp(dm.add(dm.fma(p, dm.log(alpha), logGammaA), alpha)), alpha);
        Value* lo = dm.log(head);
        Value* hi = dm.log(dm.add(dm.maxnum(dm.maxnum(dm.c(1.0), alpha), T), dm.c(1.0)));
        auto eval = [&](Value* v) {
            Value* w = dm.exp(v);
            Value* logG = logUpperGamma(dm, a, w, logGammaAt2);
            Value* slope = dm.exp(dm.sub(dm.sub(dm.mul(a, v), w), logG));
            return LaneEmitter::NewtonTerms{dm.sub(dm.neg(logG), T), slope};
        };
        // Above the median from the tail's asymptote: Gamma(a, w) ~ w^-p
        // e^-w gives w ~ T - p ln T.
        Value* tailStart = dm.log(dm.maxnum(dm.sub(T, dm.mul(p, dm.log(dm.maxnum(T, dm.c(1.0))))), dm.c(1e-300)));
        Value* v0 = dm.select(dm.lt(u, dm.c(0.5)), lo, dm.minnum(dm.maxnum(tailStart, lo), hi));
        Value* v = lane.bracketedNewton(dm, eval, v0, lo, hi, kNewtonSteps);
        // u = 0 is w = alpha, the normal n: exactly, not e^(ln alpha) - alpha
        // (a tilt of 1e-8 moves wi far at grazing wo).
        Value* tan2 = dm.mul(alpha, dm.maxnum(dm.sub(dm.exp(v), alpha), dm.c(0.0)));
        tan2 = dm.select(dm.gt(u, dm.c(0.0)), tan2, dm.c(0.0));
        Value* cos2 = dm.div(dm.c(1.0), dm.add(tan2, dm.c(1.0)));
        return lane.normalFromPolar(pm.convert(dm.mul(tan2, cos2), pm.type()), u2, pm.convert(cos2, pm.type()));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_SgdEmitter() {
    static const SgdEmitter& emitter = immortal<SgdEmitter>();
    return {{ModelSlot::Ndf, "sgd", &emitter, lambdaTableEmbedding}};
}

}  // namespace facet
