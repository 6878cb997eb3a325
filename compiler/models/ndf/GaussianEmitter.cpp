// gaussian: the Gaussian NDF in theta as IR (the reference is
// Gaussian.cpp). Its normalization N(alpha) has no closed form: a constant
// alpha folds it at compile time, a per-lane alpha interpolates a table of
// ln N over ln alpha embedded in the kernel (both from the neutral
// numeric/GaussianNormalization.h). Its NDF sampler inverts the polar CDF
// by Newton's method on Gauss-Legendre quadratures of the density.
#include "TabulatedLambdaEmitter.h"
#include "Immortal.h"
#include "lowering/LaneEmitter.h"

#include "GaussianNormalization.h"
#include "Quadrature.h"
#include "Specialize.h"

#include <llvm/IR/Constants.h>

#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlpha = 0;
constexpr int kOwnNorm = 0;  // NdfParams::own: N(alpha), precise type

// The sampler draws theta in [0, top], top = min(pi/2, 6 alpha): beyond 6
// alpha lies exp(-36) of the mass, 4e-9 of the least a float u leaves
// above the sample (2^-24).
constexpr double kTopAlphas = 6;
constexpr int kQuadratureNodes = 12;
constexpr int kNewtonSteps = 5;
constexpr double kTiny = 1e-30;  // a positive floor for logarithms, normal in float

// N(alpha) per lane: 4-point Lagrange in double, entries fetched with gathers.
Value* normLookup(LaneEmitter& lane, Value* alpha) {
    const GaussianNormTable& t = gaussianNormTable();
    MathEmitter& dm = lane.doubleMath();
    llvm::GlobalVariable* gv = lane.doubleTable(t.q, "facet_gaussian_norm_table");
    double h = (GaussianNormTable::kX1 - GaussianNormTable::kX0) / (GaussianNormTable::kSize - 1);
    Value* x = dm.log(dm.convert(alpha, dm.type()));
    Value* u = dm.div(dm.sub(x, dm.c(GaussianNormTable::kX0)), dm.c(h));
    // Alphas beyond the table use its ends (N is flat in log alpha there).
    u = dm.minnum(dm.maxnum(u, dm.c(0.0)), dm.c(GaussianNormTable::kSize - 1.0));
    Value* q = lane.lagrangeFetch(gv, GaussianNormTable::kSize, u);
    return lane.preciseMath().convert(dm.exp(q), lane.preciseMath().type());
}

class GaussianEmitter final : public NdfEmitter {
public:
    GaussianEmitter() {
        traits.isotropicOnly = true;
        traits.samplesNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        const ModelUse& use = lane.material.singleLobe().ndf;
        NdfParams n = lane.alphaParams(use, kAlpha, kAlpha, true);
        const Expr& arg = *use.args[kAlpha];
        if (isConstantExpr(arg)) {
            double alpha = std::max(constantValue(arg)[0], use.model->canonical[kAlpha].lo);
            n.own[kOwnNorm] = lane.preciseMath().c(gaussianNdfNorm<double>(alpha));
        } else {
            n.own[kOwnNorm] = normLookup(lane, n.axD);
        }
        lane.roundAlphas(n);
        return n;
    }

    // Its Smith Lambda from the plan's table in (a, alpha)
    // (TabulatedLambdaEmitter.h).
    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // theta^2/alpha^2 is an exponent too: precise type.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& hD = geo.hD;
        Value* theta = pm.atan2(pm.sqrt(pm.fma(hD[0], hD[0], pm.mul(hD[1], hD[1]))), hD[2]);
        Value* e = pm.div(pm.mul(theta, theta), pm.mul(n.axD, n.axD));
        return pm.div(lane.expTail(e), n.own[kOwnNorm]);
    }

    // theta from the polar CDF P(theta) = Int_0^theta f, f(t) = exp(-t^2/alpha^2)
    // sin t cos t, at the fraction u1 of P(pi/2) = N(alpha)/(2 pi), as in
    // NDF sampling (density D(m) (n.m)); the azimuth is 2 pi u2. Each half
    // of the range inverts its own tail, which a 12-point Gauss-Legendre
    // rule on [0, theta] or [theta, top] resolves to 1e-9 relative or
    // better, so that nothing cancels near u1 = 1: below the median
    // ln P(theta) = ln(u1 N/(2 pi)) in ln theta (P goes as theta^2 at 0),
    // above it ln S(theta) = ln((1 - u1) N/(2 pi)) for the mass above,
    // S(theta) = Int_theta^top f, in d = top - theta. The start takes
    // 1 - exp(-sin^2(theta)/alpha^2) uniform on [0, 1 - exp(-1/alpha^2)],
    // exact in both limits (the Rayleigh law of a small alpha, sin^2(theta)
    // uniform for a large one); above the median corrected twice for the
    // factor exp(-(theta^2 - sin^2 theta)/alpha^2) that law leaves out of
    // the tail, which matters for alpha near 0.35, where the tail reaches
    // pi/2. Five bracketed steps then reach 6e-11 in theta (measured
    // against fourteen over 4e5 random (alpha, u1), alpha 1e-4 .. 1e4, u1
    // from 1e-13 to 1 - 2^-24).
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        llvm::IRBuilder<>& b = lane.builder;
        Value* alpha = n.axD;
        Value* a2 = pm.mul(alpha, alpha);
        Value* total = pm.mul(n.own[kOwnNorm], pm.c(1 / (2 * kPi)));
        Value* top = pm.minnum(pm.mul(alpha, pm.c(kTopAlphas)), pm.c(kPi / 2));
        auto density = [&](Value* t) {
            auto [s, c] = pm.sinCosTurns(pm.mul(t, pm.c(1 / (2 * kPi))));
            return pm.mul(lane.expTail(pm.div(pm.mul(t, t), a2)), pm.mul(s, c));
        };
        const quadrature::GaussLegendre<double>& gl = quadrature::gaussLegendre<double>(kQuadratureNodes);
        auto integral = [&](Value* from, Value* to) {
            Value* half = pm.mul(pm.sub(to, from), pm.c(0.5));
            Value* mid = pm.mul(pm.add(to, from), pm.c(0.5));
            Value* sum = pm.c(0.0);
            for (size_t i = 0; i < gl.x.size(); ++i)
                sum = pm.fma(pm.c(gl.w[i]), density(pm.fma(half, pm.c(gl.x[i]), mid)), sum);
            return pm.mul(sum, half);
        };
        Value* lower = pm.lt(u1, pm.c(0.5));
        Value* rest = pm.sub(pm.c(1.0), u1);  // exact
        Value* target = pm.mul(u1, total);    // P(theta) below the median
        Value* restMass = pm.mul(rest, total);  // S(theta) above it
        // The start: the law's fraction p of its mass lies below sin^2(theta) = q,
        // q = -alpha^2 ln(1 - p (1 - exp(-1/alpha^2))).
        Value* oneMinusE = pm.neg(lane.expm1(pm.neg(pm.div(pm.c(1.0), a2))));
        auto startAt = [&](Value* p, Value*& q) {
            q = pm.mul(pm.neg(a2), pm.log1p(pm.neg(pm.mul(p, oneMinusE))));
            q = pm.minnum(pm.maxnum(q, pm.c(0.0)), pm.c(1.0));
            return pm.atan2(pm.sqrt(q), pm.sqrt(pm.sub(pm.c(1.0), q)));
        };
        Value* qBelow;
        Value* thetaBelow = startAt(u1, qBelow);
        Value* q;
        Value* thetaAbove = startAt(u1, q);
        for (int fix = 0; fix < 2; ++fix) {
            Value* ratio = pm.exp(pm.neg(pm.div(pm.sub(pm.mul(thetaAbove, thetaAbove), q), a2)));
            thetaAbove = startAt(pm.sub(pm.c(1.0), pm.minnum(pm.div(rest, ratio), pm.c(1.0))), q);
        }
        // Brackets: P(theta) <= theta^2/2 (f <= t) and S(top - d) <= d/2 (f <= 1/2).
        Value* lo = pm.select(lower, pm.log(pm.maxnum(pm.sqrt(pm.add(target, target)), pm.c(kTiny))),
                              pm.add(restMass, restMass));
        Value* hi = pm.select(lower, pm.log(top), top);
        Value* v0 = pm.select(lower, pm.log(pm.maxnum(thetaBelow, pm.c(kTiny))), pm.sub(top, thetaAbove));
        v0 = pm.minnum(pm.maxnum(v0, lo), hi);
        auto thetaAt = [&](Value* v) {
            Value* theta = pm.select(lower, pm.exp(v), pm.sub(top, v));
            return pm.minnum(pm.maxnum(theta, pm.c(0.0)), top);
        };
        auto eval = [&](Value* v) {
            Value* theta = thetaAt(v);
            Value* mass = integral(pm.select(lower, pm.c(0.0), theta), pm.select(lower, theta, top));
            Value* ratio = pm.div(mass, pm.select(lower, target, restMass));
            // u1 = 0: the root is theta = 0, below every v (phi = +inf).
            Value* none = b.CreateAnd(lower, pm.eq(target, pm.c(0.0)));
            Value* phi = pm.select(none, pm.c(INFINITY), pm.log(pm.maxnum(ratio, pm.c(0.0))));
            // d mass / d v: f(theta) theta below (v = ln theta), f(theta) above (v = top - theta).
            Value* slope = pm.div(pm.mul(density(theta), pm.select(lower, theta, pm.c(1.0))), mass);
            return LaneEmitter::NewtonTerms{phi, slope};
        };
        Value* theta = thetaAt(lane.bracketedNewton(pm, eval, v0, lo, hi, kNewtonSteps));
        auto [s, c] = pm.sinCosTurns(pm.mul(theta, pm.c(1 / (2 * kPi))));
        return lane.normalFromPolar(pm.mul(s, s), u2, pm.mul(c, c));
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_GaussianEmitter() {
    static const GaussianEmitter& emitter = immortal<GaussianEmitter>();
    // The normalization table only where alpha is known per lane
    // (params()), and the Lambda table under a Smith masking.
    auto tables = [](const CheckedMaterial& material) -> std::vector<EmbeddedTable> {
        std::vector<EmbeddedTable> out = lambdaTableEmbedding(material);
        if (isConstantExpr(*material.singleLobe().ndf.args[kAlpha])) return out;
        const std::vector<double>& q = gaussianNormTable().q;
        out.push_back({"facet_gaussian_norm_table", q.data(), q.size() * sizeof(double)});
        return out;
    };
    return {{ModelSlot::Ndf, "gaussian", &emitter, tables}};
}

}  // namespace facet
