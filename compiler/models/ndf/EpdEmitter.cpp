// epd: the exponential power distribution of slopes as IR (the reference is
// Epd.cpp), in log form in the precise type from u = wi + wo (h up to
// scale); its Smith Lambda from the tabulated one the plan carries
// (TabulatedLambdaEmitter.h); NDF sampling by a bracketed Newton inversion
// of the regularized incomplete gamma function, in double.
#include "TabulatedLambdaEmitter.h"
#include "Immortal.h"

#include "LambdaTable.h"
#include "Specialize.h"

#include <algorithm>
#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlphaX = 0, kAlphaY = 1, kP = 2;
constexpr int kOwnP = 0, kOwnLogNorm = 1;  // NdfParams::own, precise type: p, log(p / (pi Gamma(1/p)))

// The incomplete gamma function at y: its series (P) below y = a + 2 with
// kSeriesTerms terms, its continued fraction (Q) above with kFractionDepth
// levels; both reach 1e-15 relative for 1/4 <= a <= 4 (the slowest: the
// series at a = 4, y = 6, the fraction at a = 1/4, y = 9/4).
constexpr int kSeriesTerms = 36;
constexpr int kFractionDepth = 40;
constexpr int kNewtonSteps = 12;

// lgamma(x) in double for x in [1/4, 4]: lgamma(x + 8) by Stirling's series
// to z^-13 (the first term left out is below 1e-15 at z = 8.25) less the
// log of x (x + 1) ... (x + 7).
Value* logGamma(MathEmitter& dm, Value* x) {
    Value* prod = x;
    for (int k = 1; k < 8; ++k) prod = dm.mul(prod, dm.add(x, dm.c(k)));
    Value* z = dm.add(x, dm.c(8.0));
    Value* w = dm.div(dm.c(1.0), z);
    Value* series = dm.mul(w, dm.poly(dm.mul(w, w), {1.0 / 12, -1.0 / 360, 1.0 / 1260, -1.0 / 1680, 1.0 / 1188,
                                                     -691.0 / 360360, 1.0 / 156}));
    Value* stirling = dm.add(dm.fma(dm.sub(z, dm.c(0.5)), dm.log(z), dm.neg(z)), dm.c(0.5 * std::log(2 * kPi)));
    return dm.sub(dm.add(stirling, series), dm.log(prod));
}

class EpdEmitter final : public NdfEmitter {
public:
    EpdEmitter() {
        traits.dFromUnnormalizedHalf = true;
        traits.samplesNormals = true;
    }

    // The normalization's log once per kernel for a constant p, per lane
    // otherwise.
    NdfParams params(LaneEmitter& lane) const override {
        const ModelUse& use = lane.material.singleLobe().ndf;
        NdfParams n = lane.roundedAlphaParams(use, kAlphaX, kAlphaY, {kP});
        MathEmitter& pm = lane.preciseMath();
        const Expr& arg = *use.args[kP];
        if (isConstantExpr(arg)) {
            const ModelParam& dom = use.model->canonical[kP];
            double p = std::clamp(constantValue(arg)[0], dom.lo, dom.hi);
            n.own[kOwnLogNorm] = pm.c(std::log(p / kPi) - std::lgamma(1 / p));
        } else {
            MathEmitter& dm = lane.doubleMath();
            Value* p = dm.convert(n.own[kOwnP], dm.type());
            Value* logNorm = dm.sub(dm.log(dm.mul(p, dm.c(1 / kPi))), logGamma(dm, dm.div(dm.c(1.0), p)));
            n.own[kOwnLogNorm] = pm.convert(logNorm, pm.type());
        }
        return n;
    }

    // log D = log N - e^p - log(ax ay) - 4 log mz, e^p = exp(p (log s - 2
    // log|uz|)), s = ux^2/ax^2 + uy^2/ay^2, mz^-4 = |u|^4 / uz^4: no
    // overflow of e, e^p or mz^-4 toward the horizon. s = 0 gives log s =
    // -inf and e^p = 0.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& u = geo.slopeH;
        Value* s = n.isotropic ? pm.div(pm.fma(u[0], u[0], pm.mul(u[1], u[1])), pm.mul(n.axD, n.axD))
                               : pm.add(pm.div(pm.mul(u[0], u[0]), pm.mul(n.axD, n.axD)),
                                        pm.div(pm.mul(u[1], u[1]), pm.mul(n.ayD, n.ayD)));
        Value* logUz = pm.log(pm.abs(u[2]));
        Value* power = pm.exp(pm.mul(n.own[kOwnP], pm.fma(logUz, pm.c(-2.0), pm.log(s))));
        Value* logAlphas = n.isotropic ? pm.mul(pm.log(n.axD), pm.c(2.0)) : pm.add(pm.log(n.axD), pm.log(n.ayD));
        Value* logD = pm.sub(pm.fma(logUz, pm.c(-4.0), pm.sub(n.own[kOwnLogNorm], power)), logAlphas);
        // |u|^2 (1 where slopeHLen2 is null, u = h): mz^-4 = |u|^4 / uz^4.
        if (geo.slopeHLen2) logD = pm.add(logD, pm.mul(pm.log(geo.slopeHLen2), pm.c(2.0)));
        return pm.exp(logD);
    }

    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // The standard squared slope is r2 = y^a, a = 1/p, y ~ Gamma(a): y from
    // the incomplete gamma function, in v = log y. Below the median the
    // root of log P(a, y) = log u1, started at the series' leading term
    // y^a / Gamma(a + 1) = u1; above it the root of -log Q(a, y) = -log(1 -
    // u1), started at the tail's y = T - lgamma(a) + (a - 1) log y, T =
    // -log(1 - u1). d log P / dv = y^a e^-y / (Gamma(a) P), likewise for Q.
    // Brackets: P <= y^a / Gamma(a + 1) (the root lies above (log u1 +
    // lgamma(a + 1)) / a - 2), the median lies below a + 1, and Q < 1 - u1
    // at y = 2 T + 4 a + 10 for a <= 4.
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        Value* a = dm.div(dm.c(1.0), dm.convert(n.own[kOwnP], dm.type()));
        Value* lgA = logGamma(dm, a);
        Value* lgA1 = dm.add(lgA, dm.log(a));
        Value* u = dm.convert(u1, dm.type());
        Value* lower = dm.lt(u, dm.c(0.5));
        Value* logU = dm.log(dm.maxnum(u, dm.c(1e-300)));
        Value* T = dm.neg(dm.log(dm.sub(dm.c(1.0), u)));
        Value* target = dm.select(lower, logU, T);
        Value* lo = dm.sub(dm.div(dm.add(dm.select(lower, logU, dm.c(std::log(0.5))), lgA1), a), dm.c(2.0));
        Value* hi = dm.select(lower, dm.log(dm.add(a, dm.c(1.0))),
                              dm.log(dm.add(dm.fma(T, dm.c(2.0), dm.mul(a, dm.c(4.0))), dm.c(10.0))));
        Value* tailY = dm.sub(T, lgA);
        tailY = dm.fma(dm.sub(a, dm.c(1.0)), dm.log(dm.maxnum(tailY, dm.c(1.0))), tailY);
        Value* v0 = dm.select(lower, dm.div(dm.add(logU, lgA1), a), dm.log(dm.maxnum(tailY, dm.c(1e-300))));
        v0 = dm.minnum(dm.maxnum(v0, lo), hi);
        auto eval = [&](Value* v) {
            Value* y = dm.exp(v);
            Value* logPre = dm.sub(dm.sub(dm.mul(a, v), y), lgA);
            Value* sum = dm.c(1.0);
            for (int k = kSeriesTerms; k >= 1; --k) sum = dm.fma(dm.div(y, dm.add(a, dm.c(k))), sum, dm.c(1.0));
            Value* logPSeries = dm.add(logPre, dm.log(dm.div(sum, a)));
            Value* frac = dm.add(y, dm.c(2.0 * kFractionDepth + 1));
            Value* ym = dm.sub(y, a);
            for (int i = kFractionDepth; i >= 1; --i) {
                Value* num = dm.mul(dm.c(-i), dm.sub(dm.c(i), a));
                frac = dm.add(dm.add(ym, dm.c(2.0 * i - 1)), dm.div(num, frac));
            }
            Value* logQFraction = dm.sub(logPre, dm.log(frac));
            Value* series = dm.lt(y, dm.add(a, dm.c(2.0)));
            Value* logP = dm.select(series, logPSeries, dm.log1p(dm.neg(dm.exp(logQFraction))));
            Value* logQ = dm.select(series, dm.log1p(dm.neg(dm.exp(logPSeries))), logQFraction);
            Value* phi = dm.sub(dm.select(lower, logP, dm.neg(logQ)), target);
            Value* slope = dm.exp(dm.sub(logPre, dm.select(lower, logP, logQ)));
            return LaneEmitter::NewtonTerms{phi, slope};
        };
        Value* v = lane.bracketedNewton(dm, eval, v0, lo, hi, kNewtonSteps);
        Value* r2 = dm.select(dm.gt(u, dm.c(0.0)), dm.exp(dm.mul(a, v)), dm.c(0.0));
        return lane.stretchedSlopeNormal(n, pm.convert(r2, pm.type()), u2);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_EpdEmitter() {
    static const EpdEmitter& emitter = immortal<EpdEmitter>();
    return {{ModelSlot::Ndf, "epd", &emitter, lambdaTableEmbedding}};
}

}  // namespace facet
