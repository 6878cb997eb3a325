// none, schlick, dielectric, conductor: the Fresnel terms as IR (the
// references are Fresnel.cpp). F is returned in the precise type: with
// f0 = 0, Schlick's (1 - c)^5 can be far below float range where F D G /
// (4 ci co) is not. The exact terms are rearranged for float lanes: pbrt's
// g - c = e / (g + c) for the dielectric, and for the conductor reflection
// amplitudes that do not cancel as N -> 1, sharing one division.
#include "lowering/LaneEmitter.h"
#include "Immortal.h"

#include "FresnelAverage.h"
#include "Specialize.h"

#include <algorithm>

namespace facet {
namespace {

using llvm::Value;

// The neutral F_avg library cannot see the catalog; its clamp of eta must be
// the catalog's domain, or folded and tabulated averages would disagree
// with the interpreter's at the domain's edge.
static_assert(kFresnelAverageMinEta == kMinEta, "F_avg clamps eta to the catalog's domain");

constexpr int kF0 = 0, kSchlickEta = 1;  // schlick: exactly one is given
constexpr int kEta = 0, kK = 1;          // dielectric(eta), conductor(eta, k)

// Normal-incidence reflectance ((eta - 1)/(eta + 1))^2, precise type.
LVal f0FromEta(LaneEmitter& lane, const LVal& eta) {
    MathEmitter& pm = lane.preciseMath();
    return lane.map({eta}, true, [&](auto& x) {
        Value* r = pm.div(pm.sub(x[0], pm.c(1.0)), pm.add(x[0], pm.c(1.0)));
        return pm.mul(r, r);
    });
}

// f0 + (1 - f0)(1 - c)^5 per channel, precise type.
LVal schlick(LaneEmitter& lane, const LaneGeometry& geo, const LVal& f0) {
    MathEmitter& pm = lane.preciseMath();
    Value* q = geo.oneMinusCosD;
    Value* q2 = pm.mul(q, q);
    Value* q5 = pm.mul(pm.mul(q2, q2), q);
    return lane.map({f0}, true, [&](auto& x) { return pm.fma(pm.sub(pm.c(1.0), x[0]), q5, x[0]); });
}

// The arithmetic of an exact term: float where the plan keeps it there
// (constant, well-conditioned parameters), the precise type otherwise; and
// cos(theta_d) and its square in it.
struct ExactTermMath {
    MathEmitter& m;
    bool inFloat;
    Value *one, *c, *c2;
};
ExactTermMath exactTermMath(LaneEmitter& lane, const LaneGeometry& geo) {
    const bool inFloat = lane.plan.fresnel.exactInFloat;
    MathEmitter& m = inFloat ? lane.floatMath() : lane.preciseMath();
    Value* one = m.c(1.0);
    Value* c = lane.fresnelCos(m, geo);
    return {m, inFloat, one, c, nullptr};
}

const Expr* constantArg(const ModelUse& use, int p) {
    return use.has(p) && isConstantExpr(*use.args[p]) ? use.args[p].get() : nullptr;
}

// Whether parameter p is a constant whose every channel satisfies `holds`
// (false for a per-lane or missing argument).
template <typename Holds>
bool everyConstantChannel(const ModelUse& use, int p, Holds holds) {
    const Expr* arg = constantArg(use, p);
    if (!arg) return false;
    for (double v : constantValue(*arg))
        if (!holds(v)) return false;
    return true;
}

class NoFresnelEmitter final : public FresnelEmitter {
public:
    bool atMostOne() const override { return true; }
    bool canVanish() const override { return false; }
    bool floatFirstCapable(const ModelUse&) const override { return true; }
    bool halfAngleInFloatOk(const ModelUse&, const FresnelPlan&) const override { return true; }
    bool atLeast(const ModelUse&, double bound) const override { return bound <= 1.0; }
    LVal F(LaneEmitter& lane, const LaneGeometry&) const override { return LVal::scalar(lane.preciseMath().c(1.0)); }
    Value* average(LaneEmitter& lane, const FresnelAverageArgs&, int) const override {
        return lane.preciseMath().c(1.0);
    }
};

class SchlickEmitter final : public FresnelEmitter {
public:
    bool atMostOne() const override { return true; }
    // The float-first body takes f0 as given; from eta it would round f0 in float.
    bool floatFirstCapable(const ModelUse& use) const override { return use.has(kF0); }
    // Only 1 - cos enters, which the float half angle keeps without cancellation.
    bool halfAngleInFloatOk(const ModelUse&, const FresnelPlan&) const override { return true; }
    // F = f0 + (1 - f0) q^5 with f0 in [0, 1] and q^5 >= 0 is never below
    // f0 (the fma of non-negative terms rounds to a value >= f0), so a
    // constant f0 >= bound (given, or from a constant eta) settles it.
    // (Exactly one of f0 and eta is given.)
    bool atLeast(const ModelUse& use, double bound) const override {
        return everyConstantChannel(use, kF0, [&](double v) { return std::min(v, 1.0) >= bound; }) ||
               everyConstantChannel(use, kSchlickEta, [&](double v) {
                   double n = std::max(v, kMinEta), r = (n - 1) / (n + 1);
                   return r * r >= bound;
               });
    }
    LVal F(LaneEmitter& lane, const LaneGeometry& geo) const override { return schlick(lane, geo, f0(lane)); }
    FresnelAverageArgs averageArgs(LaneEmitter& lane) const override {
        FresnelAverageArgs args;
        args.a = f0(lane).c;
        return args;
    }
    // 2 Int (f0 + (1 - f0)(1 - mu)^5) mu dmu = (20 f0 + 1)/21
    Value* average(LaneEmitter& lane, const FresnelAverageArgs& args, int ch) const override {
        MathEmitter& pm = lane.preciseMath();
        return pm.mul(pm.fma(pm.c(20.0), pm.convert(args.a[ch], pm.type()), pm.c(1.0)), pm.c(1.0 / 21));
    }

private:
    static LVal f0(LaneEmitter& lane) {
        const ModelUse& use = lane.material.singleLobe().fresnel;
        return use.has(kF0) ? lane.rgbParam(use, kF0, false) : f0FromEta(lane, lane.rgbParam(use, kSchlickEta, false));
    }
};

// F_avg of a per-lane dielectric eta from the table of F_avg / s over
// sqrt(s), s = (eta - 1)/(eta + 1), for eta >= 1; eta < 1 by the
// reciprocity F_avg(eta) = 1 - eta^2 (1 - F_avg(1/eta)).
Value* dielectricAverageLookup(LaneEmitter& lane, Value* eta) {
    MathEmitter& pm = lane.preciseMath();
    const FresnelAverageTables& t = fresnelAverageTables();
    auto* table = lane.floatTable(t.dielectric, "facet_favg_dielectric");
    Value* n = pm.convert(eta, pm.type());
    Value* below = pm.lt(n, pm.c(1.0));
    // s of max(n, 1/n) is |n - 1|/(n + 1): no rounded 1/n, whose error would
    // be ~6% of s at n = 1 - 1e-6 in float.
    Value* sPos = pm.div(pm.abs(pm.sub(n, pm.c(1.0))), pm.add(n, pm.c(1.0)));
    const double last = FresnelAverageTables::kDielectricCount - 1;
    Value* u = pm.minnum(pm.maxnum(pm.mul(pm.sqrt(sPos), pm.c(last)), pm.c(0.0)), pm.c(last));
    Value* j = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, u), pm.c(last - 1));
    Value* fa = pm.mul(sPos, lane.lerpFetch(table, j, pm.sub(u, j)));  // the table holds F_avg / s
    // Below 1, 1 - n^2 (1 - fa) as (1 - n)(1 + n) + n^2 fa: F_avg ~ 1 - n^2 is
    // small near n = 1, where 1 - n is exact and 1 - fa rounded to float
    // would be off by ~1% of it.
    Value* reciprocal = pm.fma(pm.mul(n, n), fa, pm.mul(pm.sub(pm.c(1.0), n), pm.add(pm.c(1.0), n)));
    return pm.select(below, reciprocal, fa);
}

class DielectricEmitter final : public FresnelEmitter {
public:
    // Float is enough for a constant eta in [1.01, 1e3] in every channel: no
    // critical angle (where F depends on sqrt(g^2) with g^2 -> 0, turning
    // float rounding of cos into visible error) and no eta - 1 cancellation.
    // The formula is then well-conditioned in cos(theta), which comes
    // rounded from the double geometry; tests/jit and the differential
    // tests measure that the error stays within the rest of the kernel's.
    bool evaluableInFloat(const ModelUse& use) const override {
        return everyConstantChannel(use, kEta, [](double v) { return v >= 1.01 && v <= 1e3; });
    }
    bool substitutableBySchlick() const override { return true; }

    // With a constant eta > 1 in every channel, also once rounded to float,
    // g^2 = e + c^2 > 0 in either type (e = (eta - 1)(eta + 1) is then at
    // least 2^-22, and c^2 >= 0): there is no critical angle, and the
    // total-reflection test and the clamp of g^2 would only cost each
    // channel three vector operations.
    static bool etaAboveOne(const ModelUse& use) {
        return everyConstantChannel(use, kEta, [](double v) { return static_cast<float>(v) > 1.0f; });
    }

    LVal F(LaneEmitter& lane, const LaneGeometry& geo) const override {
        const ModelUse& use = lane.material.singleLobe().fresnel;
        if (lane.plan.fresnel.substituteSchlick) {
            // Schlick with f0 = ((eta - 1)/(eta + 1))^2: only chosen by a
            // tolerance that its measured error meets.
            return schlick(lane, geo, f0FromEta(lane, lane.rgbParam(use, kEta, false)));
        }
        auto [m, inFloat, one, c, c2] = exactTermMath(lane, geo);
        MathEmitter& pm = lane.preciseMath();
        LVal eta = lane.rgbParam(use, kEta, inFloat, lane.maxFresnelIndex());
        const bool totalReflectionPossible = !etaAboveOne(use);
        c2 = m.mul(c, c);
        return lane.map({eta}, true, [&](auto& x) {
            return pm.convert(reflectance(lane, m, x[0], c, c2, totalReflectionPossible), pm.type());
        });
    }

    LVal refractiveIndex(LaneEmitter& lane) const override {
        return lane.rgbParam(lane.material.singleLobe().fresnel, kEta, false, lane.maxFresnelIndex());
    }
    Value* reflectanceAcross(LaneEmitter& lane, Value* eta, Value* c) const override {
        MathEmitter& m = lane.preciseMath();
        return reflectance(lane, m, eta, c, m.mul(c, c), true);
    }
    // T = 1 - F = 2 c g (1 / (c + g)^2 + eta^2 / (eta^2 c + g)^2) (1 - rs^2
    // and 1 - rp^2 with the reference's rs, rp): every term positive, so T
    // keeps its relative precision where F -> 1 (grazing); 0 past the
    // critical angle.
    Value* transmittanceAcross(LaneEmitter& lane, Value* eta, Value* c) const override {
        MathEmitter& m = lane.preciseMath();
        Value* g2 = m.fma(c, c, m.mul(m.sub(eta, m.c(1.0)), m.add(eta, m.c(1.0))));
        Value* T = transmittanceFromG(m, eta, c, m.sqrt(m.maxnum(g2, m.c(0.0))));
        return m.select(lane.builder.CreateAnd(m.gt(g2, m.c(0.0)), m.gt(c, m.c(0.0))), T, m.c(0.0));
    }
    // g = eta cos(theta_t) from the refracted direction's own cosine.
    Value* pairTransmittance(LaneEmitter& lane, Value* eta, Value* c, Value* ct) const override {
        MathEmitter& m = lane.preciseMath();
        Value* g = m.mul(eta, ct);
        Value* T = transmittanceFromG(m, eta, c, g);
        return m.select(lane.builder.CreateAnd(m.gt(g, m.c(0.0)), m.gt(c, m.c(0.0))), T, m.c(0.0));
    }

    FresnelAverageArgs averageArgs(LaneEmitter& lane) const override {
        FresnelAverageArgs args;
        args.constant = constantArg(lane.material.singleLobe().fresnel, kEta) != nullptr;
        if (!args.constant) args.a = lane.rgbParam(lane.material.singleLobe().fresnel, kEta, false).c;
        return args;
    }
    Value* average(LaneEmitter& lane, const FresnelAverageArgs& args, int ch) const override {
        if (args.constant) {
            double eta = std::max(constantValue(*lane.material.singleLobe().fresnel.args[kEta])[ch], kMinEta);
            return lane.preciseMath().c(fresnelAverageDielectric(eta));
        }
        return dielectricAverageLookup(lane, args.a[ch]);
    }

private:
    static Value* transmittanceFromG(MathEmitter& m, Value* eta, Value* c, Value* g) {
        Value* n2 = m.mul(eta, eta);
        Value *a = m.add(c, g), *b = m.fma(n2, c, g);
        Value* sum = m.add(m.div(m.c(1.0), m.mul(a, a)), m.div(n2, m.mul(b, b)));
        return m.mul(m.mul(m.c(2.0), m.mul(c, g)), sum);
    }

    // F at cos c (c2 = c^2) for the index n, in `m`.
    static Value* reflectance(LaneEmitter& lane, MathEmitter& m, Value* n, Value* c, Value* c2,
                              bool totalReflectionPossible) {
        Value* one = m.c(1.0);
        // g^2 = eta^2 - sin^2 = (eta^2 - 1) + c^2 and, with gp = g + c,
        // g - c = (eta^2 - 1)/gp (pbrt's form, no cancellation):
        //   A = (g - c)/(g + c) = e/gp^2,   e = eta^2 - 1,
        //   B = (c gp - 1)/(c (g - c) + 1) = gp (c gp - 1)/den,
        //   den = c e + gp = g + c eta^2 > 0,
        //   F = A^2 (1 + B^2) / 2 = r^2 (den^2 + b^2) / 2,
        //   r = e/(gp^2 den),   b = gp (c gp - 1),
        // with one division and each factor within the type's range for
        // every eta up to maxFresnelIndex (r^2 and the sum are bounded
        // where e^2 (den^2 + b^2) would not be).
        Value* e = m.mul(m.sub(n, one), m.add(n, one));
        Value* g2 = m.add(e, c2);
        Value* g = m.sqrt(totalReflectionPossible ? m.maxnum(g2, m.c(0.0)) : g2);
        Value* gp = m.add(g, c);
        Value* den = m.fma(c, e, gp);
        Value* r = m.div(e, m.mul(m.mul(gp, gp), den));
        Value* b = m.mul(gp, m.fma(c, gp, m.c(-1.0)));
        Value* halfSum = m.mul(m.c(0.5), m.fma(den, den, m.mul(b, b)));
        Value* F = m.mul(m.mul(r, r), halfSum);
        if (totalReflectionPossible) {
            Value* totalReflection = lane.builder.CreateOr(m.le(g2, m.c(0.0)), m.eq(gp, m.c(0.0)));
            F = m.select(totalReflection, one, F);
        }
        return F;
    }
};

// F_avg of a per-lane conductor: Schlick's average at the conductor's F0
// plus a tabulated residual over (eta/(eta+1), sqrt(k)/(sqrt(k)+1)), bilinear.
Value* conductorAverageLookup(LaneEmitter& lane, Value* eta, Value* k) {
    MathEmitter& pm = lane.preciseMath();
    const FresnelAverageTables& t = fresnelAverageTables();
    auto* table = lane.floatTable(t.conductor, "facet_favg_conductor");
    Value* n = pm.convert(eta, pm.type());
    Value* kk = pm.convert(k, pm.type());
    Value *nm = pm.sub(n, pm.c(1.0)), *np = pm.add(n, pm.c(1.0)), *k2 = pm.mul(kk, kk);
    Value* F0 = pm.div(pm.fma(nm, nm, k2), pm.fma(np, np, k2));
    Value* base = pm.mul(pm.fma(pm.c(20.0), F0, pm.c(1.0)), pm.c(1.0 / 21));
    const int N = FresnelAverageTables::kConductorCount;
    const double last = N - 1;
    Value* sk = pm.sqrt(kk);
    Value* ua = pm.minnum(pm.mul(pm.div(n, np), pm.c(last)), pm.c(last));
    Value* ub = pm.minnum(pm.mul(pm.div(sk, pm.add(sk, pm.c(1.0))), pm.c(last)), pm.c(last));
    Value* ia = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, ua), pm.c(last - 1));
    Value* ib = pm.minnum(lane.intrinsic(llvm::Intrinsic::floor, ub), pm.c(last - 1));
    return pm.add(base, lane.bilerpFetch(table, N, ib, ia, pm.sub(ub, ib), pm.sub(ua, ia)));
}

class ConductorEmitter final : public FresnelEmitter {
public:
    // Float is enough for constants with |c^2 + e| >= 0.1 for every c in
    // [0, 1] (e = N^2 - 1), eta and k <= 1e3: near g^2 = 0 F has the
    // square-root singularity of a critical angle (k = 0, eta < 1) or
    // cancels (N -> 1), where float rounding of c shows (1.7e-5 for eta =
    // 0.05, k = 0).
    bool evaluableInFloat(const ModelUse& use) const override {
        const Expr *etaArg = constantArg(use, kEta), *kArg = constantArg(use, kK);
        if (!etaArg || !kArg) return false;
        std::array<double, 3> ev = constantValue(*etaArg), kv = constantValue(*kArg);
        for (int ch = 0; ch < 3; ++ch) {
            double n = std::max(ev[ch], kMinEta), kk = std::max(kv[ch], 0.0);
            double er = (n - 1) * (n + 1) - kk * kk, ei = 2 * n * kk;
            double nearestReal = er >= 0 ? er : (er <= -1 ? -(er + 1) : 0.0);
            if (!(nearestReal * nearestReal + ei * ei >= 0.01 && n <= 1e3 && kk <= 1e3)) return false;
        }
        return true;
    }

    LVal F(LaneEmitter& lane, const LaneGeometry& geo) const override {
        const ModelUse& use = lane.material.singleLobe().fresnel;
        auto [m, inFloat, one, c, c2] = exactTermMath(lane, geo);
        MathEmitter& pm = lane.preciseMath();
        LVal eta = lane.rgbParam(use, kEta, inFloat, lane.maxFresnelIndex());
        LVal k = lane.rgbParam(use, kK, inFloat, lane.maxFresnelIndex());
        c2 = m.mul(c, c);
        Value* s2 = m.convert(geo.sin2D, m.type());
        return lane.map({eta, k}, true, [&](auto& x) {
            // N = eta + ik, e = N^2 - 1, g = N cos(theta_t) = sqrt(e + c^2)
            // (principal root), and the reflection amplitudes written so
            // that nothing cancels as N -> 1 (F -> 0 exactly there):
            //   rs = -e / (c + g)^2,  rp = e (N^2 c^2 - s2) / (N^2 c + g)^2.
            // The Born-Wolf real form cancels near eta = 1, k = 0, where
            // rounding noise of either sign made F negative. Only squared
            // moduli are needed, and one division serves both quotients.
            Value *n = x[0], *kk = x[1];
            Value* n2k2 = m.sub(m.mul(n, n), m.mul(kk, kk));                             // Re N^2
            Value* er = m.fma(m.sub(n, one), m.add(n, one), m.neg(m.mul(kk, kk)));       // Re e
            Value* ei = m.mul(m.mul(m.c(2.0), n), kk);                                   // Im e = Im N^2
            Value* e2 = m.fma(er, er, m.mul(ei, ei));
            // g^2 = e + c^2 = N^2 - s2: whichever real part cancels less.
            Value* viaE = m.add(er, c2);
            Value* viaN = m.sub(n2k2, s2);
            Value* useN = m.lt(m.add(m.abs(n2k2), s2), m.add(m.abs(er), c2));
            Value* zr = m.select(useN, viaN, viaE);
            // Principal sqrt of zr + i ei (ei >= 0): the larger part by
            // sqrt((|z| + |zr|)/2), the other as ei / (2 larger).
            Value* mod = m.sqrt(m.fma(zr, zr, m.mul(ei, ei)));
            Value* right = m.ge(zr, m.c(0.0));
            Value* majorSq = m.mul(m.c(0.5), m.add(mod, m.abs(zr)));
            Value* major = m.sqrt(majorSq);
            Value* q1r = m.fma(n2k2, c2, m.neg(s2));  // N^2 c^2 - s2
            Value* q1i = m.mul(ei, c2);
            Value *invRs, *invRp;  // 1/|c + g|^2, 1/|N^2 c + g|^2
            if (inFloat) {
                // Everything scaled by 2 major, G = 2 major g = (2 major^2, ei)
                // or (ei, 2 major^2): the minor part needs no division, and
                // S = 4 major^2 |c + g|^2, P = 4 major^2 |N^2 c + g|^2 share
                // one: 1/|c + g|^2 = 4 major^2 P / (S P). In range because
                // evaluableInFloat bounds the constants: major^2 >= |g^2|/2
                // >= 0.05, |c + g|^2 >= |g|^2 (Re g, c >= 0) and
                // |N^2 c + g|^2 >= |g|^2 (Re(conj(N^2) g) >= 0: arg g lies
                // between arg N^2 / 2 and pi/2), so S P >= 4e-4; and with
                // eta, k <= 1e3, S P <= 6e32 < FLT_MAX.
                Value* twoMajorSq = m.add(majorSq, majorSq);
                Value* Gr = m.select(right, twoMajorSq, ei);
                Value* Gi = m.select(right, ei, twoMajorSq);
                Value* cs = m.mul(m.add(major, major), c);
                Value* sr = m.add(cs, Gr);
                Value* S = m.fma(sr, sr, m.mul(Gi, Gi));
                Value* pr = m.fma(n2k2, cs, Gr);
                Value* pi = m.fma(ei, cs, Gi);
                Value* P = m.fma(pr, pr, m.mul(pi, pi));
                Value* q = m.div(m.add(twoMajorSq, twoMajorSq), m.mul(S, P));
                invRs = m.mul(P, q);
                invRp = m.mul(S, q);
            } else {
                Value* minor = m.select(m.gt(major, m.c(0.0)), m.div(ei, m.mul(m.c(2.0), major)), m.c(0.0));
                Value* gr = m.select(right, major, minor);
                Value* gi = m.select(right, minor, major);
                Value* cg = m.add(c, gr);
                Value* rsDen = m.fma(cg, cg, m.mul(gi, gi));  // |c + g|^2
                Value* q2r = m.fma(n2k2, c, gr);               // N^2 c + g
                Value* q2i = m.fma(ei, c, gi);
                Value* rpDen = m.fma(q2r, q2r, m.mul(q2i, q2i));
                // In double one division serves both: 1/rsDen = rpDen q, 1/rpDen =
                // rsDen q (rsDen ~ |N|^2 and rpDen ~ |N|^6 at most: their product
                // stays finite). In float (|N| up to 1e9 in fast mode) it would not.
                if (m.isDouble()) {
                    Value* q = m.div(one, m.mul(rsDen, rpDen));
                    invRs = m.mul(rpDen, q);
                    invRp = m.mul(rsDen, q);
                } else {
                    invRs = m.div(one, rsDen);
                    invRp = m.div(one, rpDen);
                }
            }
            Value* rs = m.mul(m.mul(e2, invRs), invRs);
            Value* rp = m.mul(m.mul(e2, invRp), m.mul(m.fma(q1r, q1r, m.mul(q1i, q1i)), invRp));
            Value* F = m.mul(m.c(0.5), m.add(rs, rp));
            // e = 0 (N = 1): no interface, F = 0 (also at c = 0, where both quotients are 0/0).
            return pm.convert(m.select(m.gt(e2, m.c(0.0)), F, m.c(0.0)), pm.type());
        });
    }

    FresnelAverageArgs averageArgs(LaneEmitter& lane) const override {
        const ModelUse& use = lane.material.singleLobe().fresnel;
        FresnelAverageArgs args;
        args.constant = constantArg(use, kEta) && constantArg(use, kK);
        if (!args.constant) {
            args.a = lane.rgbParam(use, kEta, false).c;
            args.b = lane.rgbParam(use, kK, false).c;
        }
        return args;
    }
    Value* average(LaneEmitter& lane, const FresnelAverageArgs& args, int ch) const override {
        if (args.constant) {
            const ModelUse& use = lane.material.singleLobe().fresnel;
            double eta = std::max(constantValue(*use.args[kEta])[ch], kMinEta);
            double k = std::max(constantValue(*use.args[kK])[ch], 0.0);
            return lane.preciseMath().c(fresnelAverageConductor(eta, k));
        }
        return conductorAverageLookup(lane, args.a[ch], args.b[ch]);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_fresnel_FresnelEmitter() {
    static const NoFresnelEmitter& none = immortal<NoFresnelEmitter>();
    static const SchlickEmitter& schlick = immortal<SchlickEmitter>();
    static const DielectricEmitter& dielectric = immortal<DielectricEmitter>();
    static const ConductorEmitter& conductor = immortal<ConductorEmitter>();
    // The F_avg tables only where energy compensation needs F_avg of
    // per-lane parameters (averageArgs: constant ones are folded).
    auto dielectricTables = [](const CheckedMaterial& material) -> std::vector<EmbeddedTable> {
        if (!material.singleLobe().compensatesEnergy() || constantArg(material.singleLobe().fresnel, kEta)) return {};
        const std::vector<float>& t = fresnelAverageTables().dielectric;
        return {{"facet_favg_dielectric", t.data(), t.size() * sizeof(float)}};
    };
    auto conductorTables = [](const CheckedMaterial& material) -> std::vector<EmbeddedTable> {
        if (!material.singleLobe().compensatesEnergy() || (constantArg(material.singleLobe().fresnel, kEta) && constantArg(material.singleLobe().fresnel, kK)))
            return {};
        const std::vector<float>& t = fresnelAverageTables().conductor;
        return {{"facet_favg_conductor", t.data(), t.size() * sizeof(float)}};
    };
    return {{ModelSlot::Fresnel, "none", &none},
            {ModelSlot::Fresnel, "schlick", &schlick},
            {ModelSlot::Fresnel, "dielectric", &dielectric, dielectricTables},
            {ModelSlot::Fresnel, "conductor", &conductor, conductorTables}};
}

}  // namespace facet
