// beckmann: the Beckmann NDF and the Beckmann-profile Smith Lambda as IR
// (the reference is Beckmann.cpp). D is evaluated from wi + wo in the
// precise type: its exponent amplifies the rounding of h by its own size.
#include "BeckmannProfileEmitter.h"
#include "Immortal.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <utility>
#include <vector>

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
constexpr double kLowerPart = 0.7;  // u below: invert C; above: the tail mass S
// Halley's steps from the tabulated start: a lane stops at the step that
// moved it by at most 2^-9 max(|v|, 1) (its error is then of the order of
// that step cubed, ~1e-8, below what the float results resolve); one step
// for nearly every lane, at most kNewtonSteps (bisecting) where the start
// is poor.
constexpr int kNewtonSteps = 5;
constexpr double kSettledStep = 0x1p-9;

// ---- the starts: the root at nodes over the view and u ----------------------
//
// x(tanT, u) is smooth in variables that follow its shape: the view in rows
// (tanT uniform on [0, 1/8], where hi = 8; then c = sqrt(hi/8) from 1 to 0,
// denser toward grazing, where hi = cot theta_o moves the root most; the
// rows meet at tanT = 1/8, the kink of hi = min(cot, 8)), u in columns: p =
// sqrt(-ln u) below 0.7 (x ~ -p in the Gaussian tail), q = -ln(1 - u)
// above, where the table holds z = ln(hi - x), the Newton variable of that
// part (linear in q where the density vanishes linearly at hi). Bilinear
// interpolation in float nodes puts the start within 1.5e-4 of the root
// (relative, or absolute below 1) for half the lanes and 1.5e-3 for 99% of
// them (measured against a 25-digit bisection over random views and u,
// docs/perf-log.md); Halley's steps then use the kernel's own CDF, so the
// table sets only how many steps a lane takes. Baked once per process (a
// few ms) and embedded in the kernel (its bytes are in the cache key).
constexpr int kRowsTan = 8, kRowsHi = 32, kRows = kRowsTan + kRowsHi + 1;
constexpr int kCols = 129;
const double kP0 = std::sqrt(-std::log(kLowerPart)), kP1 = 8;
const double kQ0 = -std::log(1 - kLowerPart), kQ1 = 16.7;  // float u: q <= 24 ln 2 = 16.64

double tanOfRow(int r) {
    if (r <= kRowsTan) return double(r) / (8 * kRowsTan);
    const double c = 1 - double(r - kRowsTan) / kRowsHi;
    return 1 / std::max(8 * c * c, 1 / kMaxTan);
}

// The standard slope CDF C(x) = erfc(-x)/2 + tanT exp(-x^2)/(2 sqrt(pi)) in
// double (the tail mass C(hi) - C(x) keeps 2e-9 relative down to u = 1 -
// 2^-24, below the float nodes' rounding), its density, and the root for
// one node by Newton's method on the logarithm, bracketed (bisecting where a
// step leaves the bracket), from the previous node's root.
struct SlopeCdf {
    double tanT, hi, k;
    explicit SlopeCdf(double t) : tanT(t), hi(t > 0 ? std::min(1 / t, kSlopeTail) : kSlopeTail), k(t / std::sqrt(kPi)) {}
    double C(double x) const { return std::erfc(-x) / 2 + k * std::exp(-x * x) / 2; }
    double density(double x) const { return std::max(1 - x * tanT, 0.0) * std::exp(-x * x) / std::sqrt(kPi); }
    // v in [lo, hi] with g(v) = 0, g increasing; g returns {g, g'}.
    template <typename G>
    static double root(const G& g, double lo, double hi, double v) {
        for (int i = 0; i < 100; ++i) {
            auto [f, d] = g(v);
            (f > 0 ? hi : lo) = v;
            double next = v - f / d;
            if (!(next > lo && next < hi)) next = (lo + hi) / 2;
            if (std::fabs(next - v) <= 1e-9 * std::max(1.0, std::fabs(v)) || hi - lo <= 1e-12) return next;
            v = next;
        }
        return v;
    }
    double lowerRoot(double u, double start) const {  // C(x) = u C(hi)
        const double target = u * C(hi);
        if (target <= C(-kSlopeTail)) return -kSlopeTail;
        auto g = [&](double x) {
            double c = C(x);
            return std::pair{std::log(c / target), density(x) / c};
        };
        return root(g, -kSlopeTail, hi, std::clamp(start, -kSlopeTail, hi));
    }
    double upperRoot(double oneMinusU, double start) const {  // z = ln(hi - x), S(x) = (1 - u) C(hi)
        const double total = C(hi), rest = oneMinusU * total, zHi = std::log(hi + kSlopeTail);
        if (rest >= total - C(-kSlopeTail)) return zHi;
        auto g = [&](double z) {
            double d = std::exp(z), x = hi - d, sMass = total - C(x);
            return std::pair{std::log(std::max(sMass, 1e-300) / rest), density(x) * d / sMass};
        };
        return root(g, -60.0, zHi, std::clamp(start, -60.0, zHi));
    }
};

// Rows 0 .. kRows - 1: x below 0.7; rows kRows .. 2 kRows - 1: z above.
const std::vector<float>& slopeStarts() {
    static const std::vector<float> table = [] {
        std::vector<float> t(size_t(2 * kRows * kCols));
        for (int r = 0; r < kRows; ++r) {
            const SlopeCdf cdf(tanOfRow(r));
            double x = 0, z = 0;
            for (int j = 0; j < kCols; ++j) {
                const double p = kP0 + (kP1 - kP0) * j / (kCols - 1), q = kQ0 + (kQ1 - kQ0) * j / (kCols - 1);
                x = cdf.lowerRoot(std::exp(-p * p), x);
                z = cdf.upperRoot(std::exp(-q), z);
                t[size_t(r * kCols + j)] = float(x);
                t[size_t((kRows + r) * kCols + j)] = float(z);
            }
        }
        return t;
    }();
    return table;
}

// One standard (alpha = 1) visible slope for the view at tan(theta_o) =
// tanT (Heitz & d'Eon 2014): x in [-8, hi], hi = min(cot theta_o, 8), with
// the CDF C(x) = erfc(-x)/2 + tanT exp(-x^2) / (2 sqrt(pi)) at the fraction
// u of C(hi); tanT = 0 gives the Gaussian erfc(-x)/2 = u. Both C and the
// tail mass S(x) = C(hi) - C(x) are log-concave (the density is), and their
// logarithms are nearly linear in the variables the two parts of [0, 1)
// invert in: for u < 0.7 log C in x, which goes as -x^2 in the tail; above
// it log S in z = ln(hi - x), which goes as 2 z where the density vanishes
// linearly at hi (tanT > 1/8) and as -x^2 in the Gaussian tail. Halley's
// steps on them from the tabulated start (slopeStarts), bracketed: x in
// [-8, hi], z from ln of the bound S(hi - d) <= d max density up to ln 16
// (hi <= 8). Always in double, fast kernels too: near u = 1 the root moves
// by S's relative error, S = C(hi) - C(x) is 6e-8 of C there, and C needs
// erfc to double precision. tanT and u in double.
Value* visibleSlope(LaneEmitter& lane, Value* tanT, Value* u) {
    MathEmitter& pm = lane.doubleMath();
    llvm::IRBuilder<>& b = lane.builder;
    const double rootPi = std::sqrt(kPi);
    tanT = pm.minnum(tanT, pm.c(kMaxTan));
    Value* hi = pm.minnum(pm.div(pm.c(1.0), tanT), pm.c(kSlopeTail));  // tanT = 0: 1/0 = inf, then 8
    Value* k = pm.mul(tanT, pm.c(1 / rootPi));
    // C(x) with erfc(-x) = exp(-x^2) erfcx(-x) for x <= 0 and 2 - exp(-x^2)
    // erfcx(x) above; where asked, the density rho = (1 - x tanT)+
    // exp(-x^2)/sqrt(pi) and its slope rho' = -(tanT + 2 x (1 - x tanT)+)
    // exp(-x^2)/sqrt(pi).
    auto cdf = [&](Value* x, Value** density, Value** densitySlope) {
        Value* e = pm.expNormal(pm.neg(pm.mul(x, x)));
        Value* ex = pm.erfcxWide(pm.minnum(pm.abs(x), pm.c(kSlopeTail)));
        Value* below = pm.mul(pm.mul(e, pm.add(ex, k)), pm.c(0.5));
        Value* above = pm.fma(pm.mul(e, pm.c(-0.5)), pm.sub(ex, k), pm.c(1.0));
        Value* g = pm.maxnum(pm.fma(pm.neg(x), tanT, pm.c(1.0)), pm.c(0.0));
        Value* eScaled = pm.mul(e, pm.c(1 / rootPi));
        if (density) *density = pm.mul(g, eScaled);
        if (densitySlope) *densitySlope = pm.neg(pm.mul(pm.fma(pm.add(x, x), g, tanT), eScaled));
        return pm.select(pm.gt(x, pm.c(0.0)), above, below);
    };
    Value* total = cdf(hi, nullptr, nullptr);
    Value* lower = pm.lt(u, pm.c(kLowerPart));
    Value* target = pm.mul(u, total);                    // C(x) for u below 0.7
    Value* oneMinusU = pm.sub(pm.c(1.0), u);             // exact above 0.5
    Value* rest = pm.mul(oneMinusU, total);              // S(x) above

    // The start and the brackets need no more than float: row and column
    // coordinates (clamped to the table), read bilinearly.
    MathEmitter& fm = lane.floatMath();
    Value* tanF = fm.convert(tanT, fm.type());
    Value* hiF = fm.convert(hi, fm.type());
    Value* uF = fm.convert(u, fm.type());  // u is a float's value
    Value* rowTan = fm.mul(tanF, fm.c(8.0 * kRowsTan));
    Value* rowHi = fm.fma(fm.sqrt(fm.mul(hiF, fm.c(1 / kSlopeTail))), fm.c(-double(kRowsHi)), fm.c(double(kRows - 1)));
    Value* row = fm.select(fm.le(tanF, fm.c(1 / kSlopeTail)), rowTan, rowHi);
    // ln u below, ln(1 - u) above (1 - u exact in float for u >= 1/2).
    Value* lnPart = fm.log(fm.maxnum(fm.select(lower, uF, fm.sub(fm.c(1.0), uF)), fm.c(FLT_MIN)));
    Value* p = fm.sqrt(fm.neg(lnPart));
    Value* col = fm.select(lower, fm.mul(fm.sub(p, fm.c(kP0)), fm.c((kCols - 1) / (kP1 - kP0))),
                           fm.mul(fm.sub(fm.neg(lnPart), fm.c(kQ0)), fm.c((kCols - 1) / (kQ1 - kQ0))));
    auto cell = [&](Value* v, int nodes, Value*& index, Value*& frac) {
        v = fm.minnum(fm.maxnum(v, fm.c(0.0)), fm.c(nodes - 1.0));
        index = fm.minnum(lane.intrinsic(llvm::Intrinsic::floor, v), fm.c(nodes - 2.0));
        frac = fm.sub(v, index);
    };
    Value *ri, *rt, *ci, *ct;
    cell(row, kRows, ri, rt);
    cell(col, kCols, ci, ct);
    ri = fm.select(lower, ri, fm.add(ri, fm.c(double(kRows))));  // the z rows follow the x rows
    llvm::GlobalVariable* starts = lane.floatTable(slopeStarts(), "facet_beckmann_slope_starts");
    Value* start = pm.convert(lane.bilerpFetch(starts, kCols, ri, ci, rt, ct, &fm), pm.type());

    // The brackets: x in [-8, hi] below; above, S(hi - d) <= d max density
    // <= d (1 + 8 tanT)/sqrt(pi) bounds z = ln d from below (in float, less
    // a margin far beyond its rounding), and hi - x <= 16 from above.
    Value* zLo = fm.sub(fm.add(lnPart, fm.log(fm.div(fm.mul(fm.convert(total, fm.type()), fm.c(rootPi)),
                                                   fm.fma(tanF, fm.c(kSlopeTail), fm.c(1.0))))),
                        fm.c(1e-3));
    Value* lo = pm.select(lower, pm.c(-kSlopeTail), pm.convert(zLo, pm.type()));
    Value* top = pm.select(lower, hi, pm.c(std::log(2 * kSlopeTail)));
    // Beyond the last column below (u < e^-64, u = 0 too) the root is the
    // clamp -8 itself: start there, where the bisection keeps it.
    Value* v0 = pm.select(b.CreateAnd(lower, fm.ge(p, fm.c(kP1))), pm.c(-kSlopeTail), pm.minnum(pm.maxnum(start, lo), top));

    auto slopeAt = [&](Value* v) {
        Value* x = pm.select(lower, v, pm.sub(hi, pm.exp(v)));
        return pm.minnum(pm.maxnum(x, pm.c(-kSlopeTail)), hi);
    };
    // Halley's steps: phi = ln(C/target) in x, phi' = rho/C, phi'' = rho'/C
    // - phi'^2; or phi = ln(S/rest) in z (d = hi - x = e^z, dS/dz = rho d),
    // phi' = rho d/S, phi'' = d (rho - d rho')/S - phi'^2.
    auto eval = [&](Value* v) {
        Value* x = slopeAt(v);
        Value *density, *densitySlope;
        Value* c = cdf(x, &density, &densitySlope);
        Value* s = pm.sub(total, c);
        Value* d = pm.sub(hi, x);
        // ln(C/target) (+inf at target = 0: the root is -8) or ln(S/rest)
        // (-inf where S rounds to 0 or below: the root is further from hi).
        Value* ratio = pm.select(lower, pm.div(c, target), pm.div(s, rest));
        Value* phi = pm.log(pm.maxnum(ratio, pm.c(0.0)));
        Value* inv = pm.div(pm.c(1.0), pm.select(lower, c, s));
        Value* slope = pm.mul(pm.select(lower, density, pm.mul(density, d)), inv);
        Value* bend = pm.select(lower, densitySlope, pm.mul(d, pm.fma(pm.neg(d), densitySlope, density)));
        Value* curvature = pm.fma(bend, inv, pm.neg(pm.mul(slope, slope)));
        return LaneEmitter::NewtonTerms{phi, slope, curvature};
    };
    return slopeAt(lane.bracketedNewton(pm, eval, v0, lo, top, kNewtonSteps, kSettledStep, 1.0));
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
    auto tables = [](const CheckedMaterial&) {
        const std::vector<float>& t = slopeStarts();
        return std::vector<EmbeddedTable>{{"facet_beckmann_slope_starts", t.data(), t.size() * sizeof(float)}};
    };
    return {{ModelSlot::Ndf, "beckmann", &emitter, tables}};
}

}  // namespace facet
