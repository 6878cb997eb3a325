// Interpreter: the reference formulas (SPEC section 3), one term at a time.
// QuadMath.h first: the __float128 math overloads must be declared before
// any template that calls them (Builtins.h, <complex>); see QuadMath.h.
#include "QuadMath.h"
#include "Interpreter.h"

#include "Diagnostics.h"
#include "KullaContyEval.h"
#include "Quadrature.h"

#include <cmath>
#include <complex>

namespace facet {

namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

template <typename Real>
Real sq(Real x) { return x * x; }

template <typename Real>
bool finite(Real x) { using std::isfinite; return isfinite(x); }

// expm1(y)/y, continuous through y = 0 (where it is 1).
template <typename Real>
Real expm1OverX(Real y) {
    using std::expm1;
    if (y == 0) return 1;
    return expm1(y) / y;
}

// cos of the half angle, wi.h = wo.h = |wi + wo| / 2 for unit vectors (at most 1).
template <typename Real>
Real halfAngleCos(const Vec3<Real>& wi, const Vec3<Real>& wo) {
    using std::sqrt;
    Real len = sqrt(sq(wi.x + wo.x) + sq(wi.y + wo.y) + sq(wi.z + wo.z));
    return len / 2 < 1 ? len / 2 : Real(1);
}

// sin^2 of the half angle, 1 - (wi.h)^2 = |wi - wo|^2 / 4 for unit vectors:
// from the difference of the directions, so that it keeps its relative
// accuracy near wi = wo, where 1 - c^2 computed from c cancels (hard cases).
template <typename Real>
Real halfAngleSin2(const Vec3<Real>& wi, const Vec3<Real>& wo) {
    Real s2 = (sq(wi.x - wo.x) + sq(wi.y - wo.y) + sq(wi.z - wo.z)) / 4;
    return s2 < 1 ? s2 : Real(1);
}

// log(expm1(y)/y) without overflow for large y (the GTR normalization at
// large gamma: expm1((1 - gamma) ln a^2) overflows long before the
// normalized D does).
template <typename Real>
Real logExpm1OverX(Real y) {
    using std::expm1; using std::log;
    if (y > 1) return y + log(-expm1(-y)) - log(y);
    return log(expm1OverX(y));
}

// ---- double-Real arithmetic for the directions ----
//
// eval() takes directions that are unit only within 1e-3 (float inputs are
// off by ~1e-8) and normalizes them. The normalized components carry a
// rounding error of 1 ulp, which is harmless except in wi + wo when the two
// are nearly opposite: that error, along the directions, is perpendicular to
// their small sum and turns h by ulp / |wi + wo| (1e-12 rad at |wi + wo| =
// 1e-4, a 1e-9 relative error in D for alpha = 1e-4). So the normalization
// and the sum are computed as unevaluated sums hi + lo (Dekker / Knuth
// error-free transformations with fma), and rounded once at the end.
template <typename Real>
struct DD {
    Real hi, lo;
};
template <typename Real>
DD<Real> twoSum(Real a, Real b) {
    Real s = a + b, bb = s - a;
    return {s, (a - (s - bb)) + (b - bb)};
}
template <typename Real>
DD<Real> twoProd(Real a, Real b) {
    using std::fma;
    Real p = a * b;
    return {p, fma(a, b, -p)};
}
template <typename Real>
DD<Real> ddAdd(DD<Real> a, DD<Real> b) {
    DD<Real> s = twoSum(a.hi, b.hi);
    Real lo = s.lo + a.lo + b.lo;
    return twoSum(s.hi, lo);
}

// w / |w| for both directions, as Real, and their sum, rounded once.
template <typename Real>
void normalizedPair(const Real wi[3], const Real wo[3], Vec3<Real>& ui, Vec3<Real>& uo, Vec3<Real>& sum) {
    using std::fma; using std::sqrt;
    DD<Real> unit[2][3];
    const Real* ws[2] = {wi, wo};
    for (int d = 0; d < 2; ++d) {
        const Real* w = ws[d];
        DD<Real> s2{0, 0};
        for (int k = 0; k < 3; ++k) s2 = ddAdd(s2, twoProd(w[k], w[k]));
        // len = sqrt(s2) to double-Real: one Newton correction of sqrt(hi).
        Real l0 = sqrt(s2.hi);
        Real l1 = (fma(-l0, l0, s2.hi) + s2.lo) / (2 * l0);
        // 1 / len: q0 = 1 / l0 corrected for both the division's rounding and l1.
        Real q0 = 1 / l0;
        Real q1 = q0 * (fma(-q0, l0, Real(1)) - q0 * l1);
        for (int k = 0; k < 3; ++k) {
            DD<Real> p = twoProd(w[k], q0);
            unit[d][k] = twoSum(p.hi, p.lo + w[k] * q1);
        }
    }
    Real* outI[3] = {&ui.x, &ui.y, &ui.z};
    Real* outO[3] = {&uo.x, &uo.y, &uo.z};
    Real* outS[3] = {&sum.x, &sum.y, &sum.z};
    for (int k = 0; k < 3; ++k) {
        *outI[k] = unit[0][k].hi + unit[0][k].lo;
        *outO[k] = unit[1][k].hi + unit[1][k].lo;
        DD<Real> s = ddAdd(unit[0][k], unit[1][k]);
        *outS[k] = s.hi + s.lo;
    }
}

}  // namespace

template <typename Real>
Real gaussianNdfNorm(Real alpha) {
    using std::cos; using std::exp; using std::min; using std::sin;
    // A small memo per thread: resolve() runs for every evaluation and a
    // sample mostly shares a few alphas, while the quadrature costs 512
    // exp/cos/sin (milliseconds in __float128).
    constexpr int kMemo = 4;
    thread_local Real memoAlpha[kMemo] = {-1, -1, -1, -1}, memoNorm[kMemo] = {};
    thread_local int memoNext = 0;
    for (int i = 0; i < kMemo; ++i)
        if (memoAlpha[i] == alpha) return memoNorm[i];
    // The integrand is negligible beyond 8 alpha (exp(-64)).
    Real upper = min(kPi<Real> / 2, 8 * alpha);
    auto f = [&](Real t) { return exp(-t * t / (alpha * alpha)) * cos(t) * sin(t); };
    static const quadrature::GaussLegendre<Real>& gl8 = quadrature::gaussLegendre<Real>(8);
    Real norm = 2 * kPi<Real> * quadrature::integrateUniform(f, Real(0), upper, 64, gl8);
    memoAlpha[memoNext] = alpha;
    memoNorm[memoNext] = norm;
    memoNext = (memoNext + 1) % kMemo;
    return norm;
}

template <typename Real>
Real ResolvedMaterial<Real>::D(const Vec3<Real>& m) const {
    using std::atan2; using std::exp; using std::pow; using std::sqrt;
    if (m.z <= 0) return 0;
    const Real pi = kPi<Real>;
    Real x2 = m.x * m.x, y2 = m.y * m.y, z2 = m.z * m.z;
    switch (ndf) {
        case NdfModel::Ggx: {
            // 1 / (pi ax ay (mx^2/ax^2 + my^2/ay^2 + mz^2)^2)
            Real t = x2 / sq(alphaX) + y2 / sq(alphaY) + z2;
            return 1 / (pi * alphaX * alphaY * t * t);
        }
        case NdfModel::Beckmann: {
            // exp(-(mx^2/ax^2 + my^2/ay^2)/mz^2) / (pi ax ay mz^4)
            Real e = (x2 / sq(alphaX) + y2 / sq(alphaY)) / z2;
            Real num = exp(-e);
            if (num == 0) return 0;  // the tail underflowed (mz^4 may have too: no 0/0)
            return num / (pi * alphaX * alphaY * z2 * z2);
        }
        case NdfModel::BlinnPhong: {
            // (e + 2)/(2 pi) mz^e. Near mz = 1, mz^e = exp(e/2 log1p(-(mx^2 + my^2))):
            // pow(mz, e) would carry the rounding of mz (1e-16 absolute)
            // amplified by e (1e6 and more) where the lobe is; sin^2 from the
            // components does not. Near mz = 0 (grazing h) 1 - sin^2 cancels
            // instead and pow(mz, e) is the accurate form.
            using std::log1p;
            Real s2 = x2 + y2;
            Real p = exponent == 0 ? Real(1)
                     : z2 < Real(0.5) ? pow(m.z, exponent)
                                      : exp(exponent / 2 * log1p(-s2));
            return (exponent + 2) / (2 * pi) * p;
        }
        case NdfModel::Gtr: {
            // c / (1 + (a^2 - 1) mz^2)^gamma with c = (g-1)(a^2-1) / (pi (1 - (a^2)^(1-g))),
            // rewritten as c = phi(L) / (pi phi((1-g) L)), L = ln a^2,
            // phi(y) = expm1(y)/y, which is exact at the limits g = 1 and a = 1.
            Real a2 = sq(alphaX);
            Real L = std::log(a2);
            // In log form: for large gamma, phi((1-g) L) and t^gamma overflow or
            // underflow while their ratio is moderate.
            Real yy = (1 - gamma) * L;
            Real logD;
            if (yy > 1) {
                // log phi(yy) = yy + log(-expm1(-yy)) - log(yy), and yy - gamma log t
                // = -L - gamma log(t / a^2) with t / a^2 = 1 + s2 (1 - a^2) / a^2:
                // the two terms of size gamma L cancel analytically, not in rounding
                // (at the peak the exponent is then exact for any gamma).
                using std::expm1; using std::log1p;
                logD = logExpm1OverX(L) - L - std::log(-expm1(-yy)) + std::log(yy) -
                       gamma * log1p((x2 + y2) * ((1 - a2) / a2));
            } else {
                Real t = a2 * z2 + x2 + y2;  // = 1 + (a^2 - 1) mz^2 for a unit m
                logD = logExpm1OverX(L) - logExpm1OverX(yy) - gamma * std::log(t);
            }
            return exp(logD) / pi;
        }
        case NdfModel::Gaussian: {
            Real theta = atan2(sqrt(x2 + y2), m.z);
            return exp(-theta * theta / sq(alphaX)) / gaussianNorm;
        }
        case NdfModel::Ward: break;
    }
    internal_error << "D() called for ndf without a microfacet distribution";
}

template <typename Real>
Real ResolvedMaterial<Real>::lambda(const Vec3<Real>& v) const {
    // Lambda = ((n.v) Lambda) / (n.v): at grazing Lambda grows like 1/(n.v)
    // and overflows to +Inf (G1 = 0, the right limit), never to NaN.
    Real cl = cosLambda(v);
    return cl == 0 ? Real(0) : cl / v.z;
}

// (n.v) Lambda(v). Finite for every n.v >= 0 (it tends to alpha(v) sin(theta)
// times a constant at grazing), so G / ((n.wi)(n.wo)) can be formed from it
// without overflow or 0/0 (GOverCosines).
template <typename Real>
Real ResolvedMaterial<Real>::cosLambda(const Vec3<Real>& v) const {
    using std::erfc; using std::exp; using std::sqrt;
    Real ax = alphaX, ay = alphaY;
    if (ndf == NdfModel::BlinnPhong) ax = ay = sqrt(2 / (exponent + 2));
    // (vx^2 ax^2 + vy^2 ay^2) = alpha(v)^2 sin^2(theta_v)
    Real proj = sq(v.x * ax) + sq(v.y * ay);
    if (proj == 0) return 0;  // v = n: nothing is masked
    switch (ndf) {
        case NdfModel::Ggx: {
            // Lambda = (-1 + sqrt(1 + x)) / 2 = x / (2 (1 + sqrt(1 + x))), x = proj / vz^2
            // (no cancellation for small x); times vz:
            return proj / (2 * (v.z + sqrt(sq(v.z) + proj)));
        }
        case NdfModel::Beckmann:
        case NdfModel::BlinnPhong: {
            // Walter et al. 2007: Lambda = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)),
            // a = cot(theta_v) / alpha_v = vz / s, s = sqrt(proj), written with erfc so
            // that it does not cancel for large a; times vz, using vz / a = s:
            Real s = sqrt(proj), a = v.z / s;
            return (s * exp(-a * a) / sqrt(kPi<Real>) - v.z * erfc(a)) / 2;
        }
        default: break;
    }
    internal_error << "Smith Lambda requested for an NDF without a closed form";
}

template <typename Real>
Real ResolvedMaterial<Real>::smithG1(const Vec3<Real>& v, const Vec3<Real>& m) const {
    if (v.x * m.x + v.y * m.y + v.z * m.z <= 0) return 0;
    return 1 / (1 + lambda(v));
}

template <typename Real>
Real ResolvedMaterial<Real>::G(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real cosHalf) const {
    using std::atan2; using std::max; using std::min; using std::abs;
    Real ci = wi.z, co = wo.z, nh = h.z;
    // For the half vector, wi.h = wo.h = |wi + wo| / 2 (cosHalf). Using that
    // one value for both keeps f exactly reciprocal; the two dot products
    // differ by rounding amplified by 1/|wi + wo| when the directions are
    // nearly opposite.
    Real ih = cosHalf >= 0 ? cosHalf : wi.x * h.x + wi.y * h.y + wi.z * h.z;
    Real oh = cosHalf >= 0 ? cosHalf : wo.x * h.x + wo.y * h.y + wo.z * h.z;
    // lambda(phi) of Heitz 2014 / Ashikhmin et al., phi the azimuth between wi and wo.
    auto azimuthWeight = [&] {
        Real phi = atan2(abs(wi.x * wo.y - wi.y * wo.x), wi.x * wo.x + wi.y * wo.y);
        return Real(4.41) * phi / (Real(4.41) * phi + 1);
    };
    switch (masking) {
        case MaskingModel::None: return 1;
        case MaskingModel::Implicit: return ci * co;
        case MaskingModel::CookTorrance: return min(Real(1), min(2 * nh * co / oh, 2 * nh * ci / oh));
        case MaskingModel::Kelemen: return ci * co / (oh * oh);
        case MaskingModel::Neumann: return ci * co / max(ci, co);
        case MaskingModel::SchlickSmith: {
            auto g1 = [&](Real c) { return c / (c * (1 - schlickK) + schlickK); };
            return g1(ci) * g1(co);
        }
        case MaskingModel::SmithSeparable:
            if (ih <= 0 || oh <= 0) return 0;
            return 1 / ((1 + lambda(wi)) * (1 + lambda(wo)));
        case MaskingModel::SmithHeightCorrelated:
            if (ih <= 0 || oh <= 0) return 0;
            return 1 / (1 + lambda(wi) + lambda(wo));
        case MaskingModel::SmithDirectionCorrelated: {
            if (ih <= 0 || oh <= 0) return 0;
            Real g1i = 1 / (1 + lambda(wi)), g1o = 1 / (1 + lambda(wo));
            Real w = azimuthWeight();
            return w * g1i * g1o + (1 - w) * min(g1i, g1o);
        }
        case MaskingModel::SmithHeightDirectionCorrelated: {
            if (ih <= 0 || oh <= 0) return 0;
            Real li = lambda(wi), lo = lambda(wo);
            return 1 / (1 + max(li, lo) + azimuthWeight() * min(li, lo));
        }
    }
    internal_error << "unknown masking model";
}

// G / ((n.wi)(n.wo)): the factor of the BRDF, D G / (4 ci co), formed
// without G and the product of the cosines. At grazing both go to zero
// together (implicit: G = ci co exactly; Smith: G ~ ci / Lambda-terms), and
// the quotient of the two underflowed values is 0/0 or 0 * Inf. Each case is
// the SPEC 3 formula of G divided by ci co and simplified; the Smith forms
// use cosLambda(v) = (n.v) Lambda(v), which stays finite at grazing.
template <typename Real>
Real ResolvedMaterial<Real>::GOverCosines(const Vec3<Real>& wi, const Vec3<Real>& wo, const Vec3<Real>& h, Real oh,
                                          Real scale) const {
    using std::abs; using std::atan2; using std::max; using std::min;
    Real ci = wi.z, co = wo.z, nh = h.z;
    auto azimuthWeight = [&] {
        Real phi = atan2(abs(wi.x * wo.y - wi.y * wo.x), wi.x * wo.x + wi.y * wo.y);
        return Real(4.41) * phi / (Real(4.41) * phi + 1);
    };
    bool smith = masking == MaskingModel::SmithSeparable || masking == MaskingModel::SmithHeightCorrelated ||
                 masking == MaskingModel::SmithDirectionCorrelated ||
                 masking == MaskingModel::SmithHeightDirectionCorrelated;
    if (smith && oh <= 0) return 0;  // chi+(wi.h) chi+(wo.h)
    if (scale == 0) return 0;        // D underflowed: no 0 * Inf
    // `scale` (D) enters first and divisions are chained, so that no
    // intermediate product of small cosines underflows (double-denormal
    // directions) where the result is representable.
    switch (masking) {
        case MaskingModel::None: return scale / ci / co;
        case MaskingModel::Implicit: return scale;
        case MaskingModel::CookTorrance: {  // min(1, 2 nh co / oh, 2 nh ci / oh) / (ci co)
            Real k = scale / oh * (2 * nh);
            return min(scale / ci / co, min(k / ci, k / co));
        }
        case MaskingModel::Kelemen: return scale / oh / oh;
        case MaskingModel::Neumann: return scale / max(ci, co);
        case MaskingModel::SchlickSmith:  // G1(c) / c = 1 / (c (1 - k) + k)
            return scale / (ci * (1 - schlickK) + schlickK) / (co * (1 - schlickK) + schlickK);
        case MaskingModel::SmithSeparable:  // G1(v) / (n.v) = 1 / ((n.v) + (n.v) Lambda(v))
            return scale / (ci + cosLambda(wi)) / (co + cosLambda(wo));
        case MaskingModel::SmithHeightCorrelated:  // 1 / (ci co (1 + Li + Lo))
            return scale / (ci * co + co * cosLambda(wi) + ci * cosLambda(wo));
        case MaskingModel::SmithDirectionCorrelated: {
            // ai = ci (1 + Li): G1i G1o / (ci co) = 1 / (ai ao), min(G1i, G1o) / (ci co) = 1 / max(ai co, ao ci)
            Real ai = ci + cosLambda(wi), ao = co + cosLambda(wo);
            Real w = azimuthWeight();
            return w * scale / ai / ao + (1 - w) * scale / max(ai * co, ao * ci);
        }
        case MaskingModel::SmithHeightDirectionCorrelated: {
            Real li = co * cosLambda(wi), lo = ci * cosLambda(wo);  // ci co Li, ci co Lo
            return scale / (ci * co + max(li, lo) + azimuthWeight() * min(li, lo));
        }
    }
    internal_error << "unknown masking model";
}

template <typename Real>
Real ResolvedMaterial<Real>::F(Real c, int ch) const {
    return fresnelAt(c, (1 - c) * (1 + c), ch);
}

// Fresnel at c = wi.h, given s2 = 1 - c^2 as well (the BRDF passes it from
// the directions' difference: accurate where c -> 1). The forms below are
// the SPEC's exact formulas rearranged so that nothing cancels near eta = 1
// (F -> 0 exactly there) or at c -> 1.
template <typename Real>
Real ResolvedMaterial<Real>::fresnelAt(Real c, Real s2, int ch) const {
    using std::abs; using std::norm; using std::pow; using std::sqrt;
    switch (fresnel) {
        case FresnelModel::None: return 1;
        case FresnelModel::Schlick: {
            Real r0 = f0[ch];
            if (schlickFromEta) r0 = sq((eta[ch] - 1) / (eta[ch] + 1));
            Real q = s2 / (1 + c);  // 1 - c
            return r0 + (1 - r0) * pow(q, 5);
        }
        case FresnelModel::Dielectric: {
            // g = eta cos(theta_t) = sqrt(eta^2 - sin^2) = sqrt(e + c^2), e = eta^2 - 1.
            // Snell: past sin^2 = eta^2 (g^2 <= 0) the light is totally reflected.
            // rs = (c - g)/(c + g) = -e / (c + g)^2          (c^2 - g^2 = -e)
            // rp = (eta^2 c - g)/(eta^2 c + g) = e ((eta^2 + 1) c^2 - 1) / (eta^2 c + g)^2
            //    = e (eta^2 c^2 - s2) / (eta^2 c + g)^2   (no cancellation as eta -> 0)
            // g^2 from whichever form loses less: eta^2 - s2 near normal
            // incidence (eta -> 0), e + c^2 near grazing and for eta -> 1.
            Real n = eta[ch];
            Real e = (n - 1) * (n + 1);
            Real g2 = n * n + s2 < abs(e) + c * c ? n * n - s2 : e + c * c;
            if (g2 <= 0) return 1;
            Real g = sqrt(g2), n2 = n * n;
            Real rs = -e / sq(c + g);
            Real rp = e * (n2 * (c * c) - s2) / sq(n2 * c + g);
            return (rs * rs + rp * rp) / 2;
        }
        case FresnelModel::Conductor: {
            // Complex index N = eta + i k; the dielectric forms with complex
            // e = N^2 - 1 and g = N cos(theta_t) = sqrt(N^2 - sin^2) = sqrt(e + c^2)
            // (principal root: the transmitted wave decays into the metal).
            std::complex<Real> N(eta[ch], k[ch]);
            std::complex<Real> e = (N - Real(1)) * (N + Real(1));
            std::complex<Real> N2 = N * N;
            std::complex<Real> g = sqrt(abs(N2) + s2 < abs(e) + c * c ? N2 - s2 : e + c * c);
            std::complex<Real> rs = -e / ((c + g) * (c + g));
            std::complex<Real> rp = e * (N2 * (c * c) - s2) / ((N2 * c + g) * (N2 * c + g));
            return (norm(rs) + norm(rp)) / 2;
        }
    }
    internal_error << "unknown fresnel model";
}

template <typename Real>
std::array<Real, 3> ResolvedMaterial<Real>::brdf(const Vec3<Real>& wi, const Vec3<Real>& wo) const {
    return brdf(wi, wo, Vec3<Real>{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
}

template <typename Real>
std::array<Real, 3> ResolvedMaterial<Real>::brdf(const Vec3<Real>& wi, const Vec3<Real>& wo,
                                                 const Vec3<Real>& sum) const {
    using std::exp; using std::sqrt;
    std::array<Real, 3> out{};
    Real ci = wi.z, co = wo.z;
    if (ci <= 0 || co <= 0) return out;
    Vec3<Real> h = sum;
    Real len = sqrt(h.x * h.x + h.y * h.y + h.z * h.z);
    if (len == 0) return out;
    h = {h.x / len, h.y / len, h.z / len};
    // c = wi.h = wo.h = |wi + wo| / 2 (see G); from the given sum, which
    // eval() computes without the rounding of the normalized directions.
    Real c = len / 2 < 1 ? len / 2 : Real(1);
    Real s2 = halfAngleSin2(wi, wo);  // 1 - c^2, accurate near wi = wo
    const Real pi = kPi<Real>;
    if (ndf == NdfModel::Ward) {
        // Ward 1992: exp(-tan^2(theta_h)(cos^2(phi_h)/ax^2 + sin^2(phi_h)/ay^2)) / (4 pi ax ay sqrt(ci co))
        Real e = (sq(h.x / alphaX) + sq(h.y / alphaY)) / sq(h.z);
        Real lobe = exp(-e) / (4 * pi * alphaX * alphaY * sqrt(ci) * sqrt(co));
        for (int ch = 0; ch < 3; ++ch) out[ch] = fresnelAt(c, s2, ch) * lobe;
    } else {
        // D G / (4 ci co) as D (G / (ci co)) / 4: no 0 * Inf or 0/0 at grazing.
        Real dg = GOverCosines(wi, wo, h, c, D(h)) / 4;
        for (int ch = 0; ch < 3; ++ch) {
            Real f = fresnelAt(c, s2, ch);
            out[ch] = f == 0 ? Real(0) : f * dg;  // F = 0 (eta = 1): no 0 * Inf
        }
    }
    if (energy == EnergyModel::KullaConty) {
        std::array<Real, 3> ms = kullaContyBrdf(*this, ci, co);
        for (int ch = 0; ch < 3; ++ch) out[ch] += ms[ch];
    }
    if (diffuse == DiffuseModel::Lambert)
        for (int ch = 0; ch < 3; ++ch) out[ch] += albedo[ch] / pi;
    return out;
}

template <typename Real>
ResolvedMaterial<Real> Interpreter<Real>::resolve(const Real* slots) const {
    using std::isnan;
    const CheckedMaterial& m = material_;
    ResolvedMaterial<Real> r;
    r.ndf = m.ndfModel();
    r.masking = m.maskingModel();
    r.fresnel = m.fresnelModel();
    r.diffuse = m.diffuseModel();

    // Inputs: given or default, clamped to the declared range.
    std::vector<Value<Real>> inputs(m.inputs.size());
    for (size_t i = 0; i < m.inputs.size(); ++i) {
        const CheckedInput& in = m.inputs[i];
        Value<Real>& v = inputs[i];
        v.rgb = in.type == ValueType::Rgb;
        for (int ch = 0; ch < in.slotCount(); ++ch) {
            Real x = slots ? slots[in.firstSlot + ch] : Real(in.defaultValue[ch]);
            if (!finite(x)) r.valid = false;
            if (in.hasRange) x = x < Real(in.lo) ? Real(in.lo) : (x > Real(in.hi) ? Real(in.hi) : x);
            v.c[ch] = x;
        }
        if (!v.rgb) v.c[1] = v.c[2] = v.c[0];
    }
    std::vector<Value<Real>> lets;
    lets.reserve(m.lets.size());
    auto lookup = [&](const NameExpr& n) -> Value<Real> {
        internal_assert(n.binding != BindingKind::Unresolved) << "unresolved name " << n.name;
        return n.binding == BindingKind::Input ? inputs.at(n.index) : lets.at(n.index);
    };
    for (const CheckedLet& let : m.lets) lets.push_back(evaluateExpr<Real>(*let.value, lookup));

    // A model argument: NaN is invalid; clamping to the domain happens
    // before the finiteness test so that e.g. phong_exponent(0) = inf
    // clamps to the largest exponent instead of failing.
    auto scalarArg = [&](const ModelUse& use, int p, Real lo, Real hi) {
        Value<Real> v = evaluateExpr<Real>(*use.args[p], lookup);
        Real x = v.c[0];
        if (isnan(x)) {
            r.valid = false;
            return Real(0);
        }
        x = x < lo ? lo : (x > hi ? hi : x);
        if (!finite(x)) r.valid = false;
        return x;
    };
    auto rgbArg = [&](const ModelUse& use, int p, Real lo, Real hi) {
        Value<Real> v = evaluateExpr<Real>(*use.args[p], lookup);
        std::array<Real, 3> out;
        for (int ch = 0; ch < 3; ++ch) {
            Real x = v.channel(ch);
            if (isnan(x)) {
                r.valid = false;
                x = 0;
            }
            x = x < lo ? lo : (x > hi ? hi : x);
            if (!finite(x)) r.valid = false;
            out[ch] = x;
        }
        return out;
    };
    const Real inf = std::numeric_limits<Real>::infinity();
    const Real minAlpha = Real(kMinAlpha);
    switch (r.ndf) {
        case NdfModel::Ggx:
        case NdfModel::Beckmann:
        case NdfModel::Ward:
            r.alphaX = scalarArg(m.ndf, param::AlphaX, minAlpha, inf);
            r.alphaY = scalarArg(m.ndf, param::AlphaY, minAlpha, inf);
            break;
        case NdfModel::BlinnPhong: r.exponent = scalarArg(m.ndf, param::Exponent, 0, Real(kMaxPhongExponent)); break;
        case NdfModel::Gtr:
            r.alphaX = r.alphaY = scalarArg(m.ndf, param::GtrAlpha, minAlpha, inf);
            r.gamma = scalarArg(m.ndf, param::GtrGamma, 0, inf);
            break;
        case NdfModel::Gaussian:
            r.alphaX = r.alphaY = scalarArg(m.ndf, param::GaussianAlpha, minAlpha, inf);
            if (r.valid) r.gaussianNorm = gaussianNdfNorm(r.alphaX);
            break;
    }
    if (r.masking == MaskingModel::SchlickSmith) r.schlickK = scalarArg(m.masking, param::SchlickK, 0, 1);
    switch (r.fresnel) {
        case FresnelModel::None: break;
        case FresnelModel::Schlick:
            if (m.fresnel.has(param::F0)) {
                r.f0 = rgbArg(m.fresnel, param::F0, 0, 1);
            } else {
                r.schlickFromEta = true;
                r.eta = rgbArg(m.fresnel, param::SchlickEta, Real(kMinEta), inf);
            }
            break;
        case FresnelModel::Dielectric: r.eta = rgbArg(m.fresnel, param::DielectricEta, Real(kMinEta), inf); break;
        case FresnelModel::Conductor:
            r.eta = rgbArg(m.fresnel, param::ConductorEta, Real(kMinEta), inf);
            r.k = rgbArg(m.fresnel, param::ConductorK, 0, inf);
            break;
    }
    if (r.diffuse == DiffuseModel::Lambert) r.albedo = rgbArg(m.diffuse, param::Albedo, 0, inf);
    if (energy_ && r.valid) resolveKullaConty(r, energy_->get());
    return r;
}

template <typename Real>
EvalResult<Real> Interpreter<Real>::eval(const Real wi[3], const Real wo[3], const Real* slots) const {
    using std::abs; using std::sqrt;
    EvalResult<Real> out;
    Vec3<Real> dirs[2];
    const Real* given[2] = {wi, wo};
    for (int d = 0; d < 2; ++d) {
        const Real* w = given[d];
        if (!finite(w[0]) || !finite(w[1]) || !finite(w[2])) {
            out.valid = false;
            return out;
        }
        Real len = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (!(abs(len - 1) <= Real(kUnitTolerance))) {
            out.valid = false;
            return out;
        }
    }
    // Unit directions and wi + wo in double-Real arithmetic (see
    // normalizedPair): when wi and wo are nearly opposite, h is decided by
    // the last bits of the normalized directions.
    Vec3<Real> sum;
    normalizedPair(wi, wo, dirs[0], dirs[1], sum);
    ResolvedMaterial<Real> r = resolve(slots);
    if (!r.valid) {
        out.valid = false;
        return out;
    }
    out.rgb = r.brdf(dirs[0], dirs[1], sum);
    // A value that overflows even the reference's range (parameters far
    // outside any physical use) is reported as an invalid lane, never as Inf.
    for (Real v : out.rgb)
        if (!finite(v) || v < 0) {
            out = {};
            out.valid = false;
        }
    return out;
}

template class Interpreter<double>;
template class Interpreter<long double>;
template struct ResolvedMaterial<double>;
template struct ResolvedMaterial<long double>;
template double gaussianNdfNorm<double>(double);
template long double gaussianNdfNorm<long double>(long double);
// __float128: the high-precision reference of the hard-case checks (QuadMath.h).
template class Interpreter<__float128>;
template struct ResolvedMaterial<__float128>;
template __float128 gaussianNdfNorm<__float128>(__float128);

}  // namespace facet
