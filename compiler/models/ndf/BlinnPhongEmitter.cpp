// blinn_phong: the normalized Blinn-Phong NDF as IR (the reference is
// BlinnPhong.cpp), with the Beckmann-profile Smith Lambda at its
// equivalent alpha sqrt(2 / (e + 2)) for the masking, and visible-normal
// sampling through its own slope distribution, whose marginal is the
// slope-form Student-t p_nu(x) = c_nu (1 + x^2)^(-(nu+1)/2), nu = e + 2
// (numeric/StudentT.h describes it; the IR below is written from the
// formulas, for a per-lane nu): the exact Smith Lambda that normalizes the
// visible normals, and their inversion by a fixed number of Newton steps on
// closed-form CDFs (StudentSlopeEmitter.h, which student_t shares). In
// double whatever the kernel's math: in float the tails of the fraction
// lose up to 8% (and the normals 3e-5).
#include "BeckmannProfileEmitter.h"
#include "Immortal.h"
#include "StudentSlopeEmitter.h"

#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kExponent = 0;
constexpr int kOwnExponent = 0;  // NdfParams::own: the clamped exponent, precise type

// Steps of the continued fraction of the Student-t tail and of each Newton
// inversion: with the switch at x^2 nu = 12.25 the fraction converges in at
// most 20 steps for any nu >= 2 (34 for nu down to 1), and 16 leave the
// sampled normals within 2e-11 of the fully converged ones (the fraction
// within 7e-9 relative for any nu >= 1); 32 Newton steps (starting from the
// bracket's midpoint, bisections while the lobe is narrower than the
// bracket) converge for every exponent from 0 to 2e8 (within 2e-11 of the
// reference's inversion at u from 2^-32 to 1 - 2^-24, theta_o up to 89.9;
// 24 steps leave 5e-5 at e = 2e8, u = 2^-32).
constexpr int kFractionSteps = 16;
constexpr int kNewtonSteps = 32;
constexpr double kTailSwitch = 12.25;

// Gamma(a + 1/2) / Gamma(a) for a >= 1: shifted to a >= 40 by R(a) = R(a +
// 1) a / (a + 1/2) (selects: a fixed 39 steps), then Stirling's series of
// the difference of the log-gammas (B_2k / (2k (2k - 1)) for k = 1..6 is
// below 1e-22 at a = 40).
Value* gammaHalfRatio(MathEmitter& pm, Value* a) {
    Value* scale = pm.c(1.0);
    for (int k = 0; k < 39; ++k) {
        Value* small = pm.lt(a, pm.c(40.0));
        scale = pm.select(small, pm.mul(scale, pm.div(a, pm.add(a, pm.c(0.5)))), scale);
        a = pm.select(small, pm.add(a, pm.c(1.0)), a);
    }
    Value* b = pm.add(a, pm.c(0.5));
    Value* ia = pm.div(pm.c(1.0), a);
    Value* ib = pm.div(pm.c(1.0), b);
    // ln a / 2 + (a log1p(1/(2a)) - 1/2): absolute accuracy for large a.
    Value* lnR = pm.fma(pm.log(a), pm.c(0.5), pm.fma(a, pm.log1p(pm.mul(ia, pm.c(0.5))), pm.c(-0.5)));
    const double coef[6] = {1.0 / 12, -1.0 / 360, 1.0 / 1260, -1.0 / 1680, 1.0 / 1188, -691.0 / 360360};
    Value *pa = ia, *pb = ib, *ia2 = pm.mul(ia, ia), *ib2 = pm.mul(ib, ib);
    for (double c : coef) {
        lnR = pm.fma(pm.c(c), pm.sub(pb, pa), lnR);
        pa = pm.mul(pa, ia2), pb = pm.mul(pb, ib2);
    }
    return pm.mul(scale, pm.exp(lnR));
}

// sqrt(s2)^p for s2 + c2 = 1 (cos^p from cos^2 and sin^2): through
// log1p(-c2) where c2 is small, so that a large p keeps its accuracy; 1
// for p = 0, 0 for s2 = 0 and p > 0.
Value* powRoot(MathEmitter& pm, Value* s2, Value* c2, Value* p) {
    Value* L = pm.select(pm.lt(c2, pm.c(0.5)), pm.log1p(pm.neg(c2)), pm.log(s2));
    Value* r = pm.exp(pm.mul(pm.mul(p, pm.c(0.5)), L));
    r = pm.select(pm.gt(s2, pm.c(0.0)), r, pm.c(0.0));
    return pm.select(pm.eq(p, pm.c(0.0)), pm.c(1.0), r);
}

// The slope-form Student-t of nu degrees of freedom (per lane): its
// normalization and the coefficients of the continued fractions of its
// tail, prepared once and read by every tail evaluation.
struct StudentT {
    Value *nu, *a, *norm;  // a = nu/2, norm = c_nu = Gamma(a + 1/2) / (sqrt(pi) Gamma(a))
    // The odd contraction of the fraction of I_z(A, B) = z^A (1 - z)^B / (A
    // B(A, B)) / g, g = B_0 + A_1/(B_1 + A_2/(B_2 + ...)): A_m = alpha_m z^2,
    // B_m = (1 - z) + z beta_m; for (A, B) = (a, 1/2) (direct) and (1/2, a).
    std::array<Value*, kFractionSteps + 1> alphaDirect{}, betaDirect{}, alphaSwapped{}, betaSwapped{};
};

// beta_m = 1 + (d_2m + d_2m+1)/z without cancellation, and alpha_m = -d_2m-1
// d_2m / z^2, of the fraction of I_z(A, B) (A & S 26.5.8: d_2m+1 = -(A + m)(A +
// B + m) z / ((A + 2m)(A + 2m + 1)), d_2m = m (B - m) z / ((A + 2m - 1)(A + 2m))).
void fractionCoefficients(MathEmitter& pm, Value* A, Value* B, std::array<Value*, kFractionSteps + 1>& alpha,
                          std::array<Value*, kFractionSteps + 1>& beta) {
    for (int m = 0; m <= kFractionSteps; ++m) {
        Value* M = pm.c(double(m));
        Value* A2m = pm.add(A, pm.c(2.0 * m));
        // (A + 2m)(A + 2m + 1) - (A + m)(A + B + m) = A (2m + 1 - B) + m (3m + 2 - B).
        Value* num = pm.fma(A, pm.sub(pm.c(2.0 * m + 1), B), pm.mul(M, pm.sub(pm.c(3.0 * m + 2), B)));
        Value* bt = pm.div(num, pm.mul(A2m, pm.add(A2m, pm.c(1.0))));
        if (m > 0) {
            Value* evenNum = pm.mul(M, pm.sub(B, M));  // d_2m / z, over (A + 2m - 1)(A + 2m)
            Value* even = pm.div(evenNum, pm.mul(pm.sub(A2m, pm.c(1.0)), A2m));
            bt = pm.add(bt, even);
            // -d_2m-1 / z at m - 1: (A + m - 1)(A + B + m - 1) / ((A + 2m - 2)(A + 2m - 1)).
            Value* Am1 = pm.add(A, pm.c(m - 1.0));
            Value* odd = pm.div(pm.mul(Am1, pm.add(Am1, B)), pm.mul(pm.sub(A2m, pm.c(2.0)), pm.sub(A2m, pm.c(1.0))));
            alpha[m] = pm.mul(odd, even);
        }
        beta[m] = bt;
    }
}

StudentT studentT(MathEmitter& pm, Value* nu) {
    StudentT t;
    t.nu = nu;
    t.a = pm.mul(nu, pm.c(0.5));
    t.norm = pm.mul(gammaHalfRatio(pm, t.a), pm.c(1.0 / std::sqrt(kPi)));
    fractionCoefficients(pm, t.a, pm.c(0.5), t.alphaDirect, t.betaDirect);
    fractionCoefficients(pm, pm.c(0.5), t.a, t.alphaSwapped, t.betaSwapped);
    return t;
}

// The upper tail Int_x^inf p_nu at x >= 0 from s2 = x^2/(1 + x^2) and c2 =
// 1/(1 + x^2): I_z(a, 1/2) / 2 with z = c2 beyond x^2 nu = 12.25, else (1 -
// I_{1-z}(1/2, a)) / 2, each by its contracted fraction (modified Lentz,
// kFractionSteps steps); z^a (1 - z)^(1/2) / B(a, 1/2) = c2^a sqrt(s2) c_nu.
Value* studentTail(MathEmitter& pm, const StudentT& t, Value* s2, Value* c2) {
    Value* direct = pm.ge(pm.mul(s2, t.nu), pm.mul(c2, pm.c(kTailSwitch)));
    Value* z = pm.select(direct, c2, s2);
    Value* w = pm.select(direct, s2, c2);
    Value* z2 = pm.mul(z, z);
    const double tiny = pm.isDouble() ? 1e-290 : 1e-30;
    auto guard = [&](Value* v) { return pm.select(pm.lt(pm.abs(v), pm.c(tiny)), pm.c(tiny), v); };
    Value* f = guard(pm.fma(z, pm.select(direct, t.betaDirect[0], t.betaSwapped[0]), w));
    Value *c = f, *d = pm.c(0.0);
    for (int m = 1; m <= kFractionSteps; ++m) {
        Value* A = pm.mul(pm.select(direct, t.alphaDirect[m], t.alphaSwapped[m]), z2);
        Value* B = pm.fma(z, pm.select(direct, t.betaDirect[m], t.betaSwapped[m]), w);
        d = pm.div(pm.c(1.0), guard(pm.fma(A, d, B)));
        c = guard(pm.add(B, pm.div(A, c)));
        f = pm.mul(f, pm.mul(c, d));
    }
    Value* logZ = pm.select(pm.lt(s2, pm.c(0.5)), pm.log1p(pm.neg(s2)), pm.log(c2));
    Value* front = pm.mul(pm.mul(pm.exp(pm.mul(t.a, logZ)), pm.sqrt(s2)), t.norm);
    Value* ratio = pm.div(front, f);  // front * fraction
    Value* tail = pm.select(direct, pm.div(ratio, pm.mul(t.a, pm.c(2.0))), pm.sub(pm.c(0.5), ratio));
    return pm.select(pm.gt(c2, pm.c(0.0)), tail, pm.c(0.0));
}

}  // namespace

// c_nu sin^nu theta / (nu - 1) - cos theta T_nu(cot theta), at least 0 (as
// the reference).
Value* studentSlopeCosLambda(MathEmitter& dm, Value* nu, const std::array<Value*, 3>& v) {
    StudentT t = studentT(dm, nu);
    Value* s2 = dm.fma(v[0], v[0], dm.mul(v[1], v[1]));
    Value* c2 = dm.mul(v[2], v[2]);
    Value* first = dm.div(dm.mul(t.norm, powRoot(dm, s2, c2, t.nu)), dm.sub(t.nu, dm.c(1.0)));
    Value* cl = dm.sub(first, dm.mul(v[2], studentTail(dm, t, c2, s2)));
    return dm.select(dm.eq(s2, dm.c(0.0)), dm.c(0.0), dm.maxnum(cl, dm.c(0.0)));
}

// Heitz & d'Eon 2014 on the slopes of P22: turned about n so that wo' =
// (sin t, 0, cos t), the visible x = tan psi = -cot b (b = psi + pi/2, the
// co-angle from the horizon, in which normals near it keep their relative
// accuracy) has cos t times the CDF
//   G(b) = cos t F(-cot b) + sin t c_nu sin^(nu-1) b / (nu - 1),
// F = 1 - T_nu, G' = c_nu sin^(nu-2) b (cos t sin b + sin t cos b) on (0,
// pi - t]; then y = sqrt(1 + x^2) tan chi, tan chi with the density
// p_(nu+1), drawn by its tail min(u2, 1 - u2) and the side. Quantiles
// below 2^-32 are taken at 2^-32, and b is at least 1e-20 (as the
// reference). Near the horizon G ~ b^(nu-1), as steep as b^0.02 for nu
// near 1, where Newton's method on b would bisect hundreds of times: lanes
// whose target lies below G(2^-4) solve log G = log target in log b (a
// nearly linear function there), the others G = target in b, in one
// Newton loop. m is the normal of the slopes (x, y), (cos b cos chi, -sin
// chi, sin b cos chi), turned back.
std::array<Value*, 3> studentSlopeVisibleNormal(LaneEmitter& lane, Value* nu, const std::array<Value*, 3>& wo,
                                                Value* u1, Value* u2) {
    MathEmitter& pm = lane.doubleMath();
    StudentT tx = studentT(pm, nu);
    Value* sxy = pm.sqrt(pm.fma(wo[0], wo[0], pm.mul(wo[1], wo[1])));
    Value* turned = pm.gt(sxy, pm.c(0.0));
    Value* inv = pm.div(pm.c(1.0), sxy);
    Value* cosPhi = pm.select(turned, pm.mul(wo[0], inv), pm.c(1.0));
    Value* sinPhi = pm.select(turned, pm.mul(wo[1], inv), pm.c(0.0));
    auto sinCos = [&](Value* angle) { return pm.sinCosTurns(pm.mul(angle, pm.c(1 / (2 * kPi)))); };
    Value* nuM1 = pm.sub(nu, pm.c(1.0));
    Value* nuM2 = pm.sub(nu, pm.c(2.0));
    const double halfPi = kPi / 2;
    // G(b) and G'(b).
    auto cdf = [&](Value* b) -> std::pair<Value*, Value*> {
        auto [s, c] = sinCos(b);
        Value *s2 = pm.mul(s, s), *c2 = pm.mul(c, c);
        Value* T = studentTail(pm, tx, c2, s2);  // at |x| = |cot b|
        Value* F = pm.select(pm.ge(b, pm.c(halfPi)), pm.sub(pm.c(1.0), T), T);
        Value* side = pm.div(pm.mul(pm.mul(sxy, tx.norm), powRoot(pm, s2, c2, nuM1)), nuM1);
        Value* visible = pm.maxnum(pm.fma(wo[2], s, pm.mul(sxy, c)), pm.c(0.0));
        return {pm.fma(wo[2], F, side), pm.mul(pm.mul(tx.norm, powRoot(pm, s2, c2, nuM2)), visible)};
    };
    Value* bMax = pm.add(pm.atan2(wo[2], sxy), pm.c(halfPi));
    const double floorU = 0x1p-32, floorB = 1e-20, switchB = 0x1p-4;
    Value* target = pm.mul(pm.maxnum(u1, pm.c(floorU)), cdf(bMax).first);
    Value* inLog = pm.lt(target, cdf(pm.c(switchB)).first);
    Value* logTarget = pm.log(target);
    auto phi = [&](Value* x) -> LaneEmitter::NewtonTerms {
        Value* b = pm.select(inLog, pm.exp(x), x);
        auto [G, dG] = cdf(b);
        return {pm.select(inLog, pm.sub(pm.log(G), logTarget), pm.sub(G, target)),
                pm.select(inLog, pm.div(pm.mul(b, dG), G), dG)};
    };
    Value* lo = pm.select(inLog, pm.c(std::log(floorB)), pm.c(switchB));
    Value* hi = pm.select(inLog, pm.c(std::log(switchB)), bMax);
    Value* x = lane.bracketedNewton(pm, phi, pm.mul(pm.add(lo, hi), pm.c(0.5)), lo, hi, kNewtonSteps);
    Value* b = pm.select(inLog, pm.exp(x), x);

    StudentT ty = studentT(pm, pm.add(nu, pm.c(1.0)));
    Value* lower = pm.lt(u2, pm.c(0.5));
    Value* q = pm.select(lower, u2, pm.sub(pm.c(1.0), u2));
    Value* nuYM1 = pm.sub(ty.nu, pm.c(1.0));
    auto cdfChi = [&](Value* chi) -> std::pair<Value*, Value*> {
        auto [s, c] = sinCos(chi);
        Value *s2 = pm.mul(s, s), *c2 = pm.mul(c, c);
        return {pm.neg(studentTail(pm, ty, s2, c2)), pm.mul(ty.norm, powRoot(pm, c2, s2, nuYM1))};
    };
    Value* chi = lane.invertIncreasing(pm, cdfChi, pm.neg(pm.maxnum(q, pm.c(floorU))), pm.c(0.0), pm.c(halfPi),
                                       kNewtonSteps);
    chi = pm.select(lower, pm.neg(chi), chi);

    auto [sB, cB] = sinCos(b);
    auto [sChi, cChi] = sinCos(chi);
    Value* mx = pm.mul(cB, cChi);
    Value* my = pm.neg(sChi);
    Value* mz = pm.mul(sB, cChi);
    return {pm.sub(pm.mul(cosPhi, mx), pm.mul(sinPhi, my)), pm.fma(sinPhi, mx, pm.mul(cosPhi, my)), mz};
}

namespace {

// sqrt(2 / (e + 2)) in the precise type.
Value* equivalentAlpha(LaneEmitter& lane, const NdfParams& n) {
    MathEmitter& pm = lane.preciseMath();
    return pm.sqrt(pm.div(pm.c(2.0), pm.add(n.own[kOwnExponent], pm.c(2.0))));
}

class BlinnPhongEmitter final : public BeckmannProfileEmitter {
public:
    BlinnPhongEmitter() {
        traits.samplesNormals = true;
        traits.samplesVisibleNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        NdfParams n;
        n.own[kOwnExponent] = lane.scalarParam(lane.material.singleLobe().ndf, kExponent, false);
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

    Value* visibleCosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        MathEmitter& pm = lane.preciseMath();
        MathEmitter& dm = lane.doubleMath();
        std::array<Value*, 3> vD;
        for (int i = 0; i < 3; ++i) vD[i] = dm.convert(v[i], dm.type());
        Value* e = dm.convert(n.own[kOwnExponent], dm.type());
        return pm.convert(studentSlopeCosLambda(dm, dm.add(e, dm.c(2.0)), vD), pm.type());
    }

    // Those of its slope distribution, nu = e + 2 (StudentSlopeEmitter.h),
    // in double whatever the kernel's math (see the header).
    std::array<Value*, 3> sampleVisibleNormal(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& wo,
                                              Value* u1, Value* u2) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        std::array<Value*, 3> woD;
        for (int i = 0; i < 3; ++i) woD[i] = dm.convert(wo[i], dm.type());
        Value* nu = dm.add(dm.convert(n.own[kOwnExponent], dm.type()), dm.c(2.0));
        std::array<Value*, 3> m =
            studentSlopeVisibleNormal(lane, nu, woD, dm.convert(u1, dm.type()), dm.convert(u2, dm.type()));
        for (Value*& c : m) c = pm.convert(c, pm.type());
        return m;
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_BlinnPhongEmitter() {
    static const BlinnPhongEmitter& emitter = immortal<BlinnPhongEmitter>();
    return {{ModelSlot::Ndf, "blinn_phong", &emitter}};
}

}  // namespace facet
