// RoughGlassModel: reference model (d) of `facet bench`, a rough glass over
// the whole sphere (SPEC 11) written by hand as a renderer engineer would:
// isotropic GGX, the separable Smith masking G1(wi) G1(wo) (what Mitsuba 3's
// roughdielectric uses), the exact dielectric Fresnel term with total
// internal reflection, eta = 1.5, reflection and refraction (Walter et al.
// 2007), radiance transport. bench/models/rough_glass.mat is its material.
//
// Written like ReferenceModels.cpp (float, one branch-free loop over SoA
// arrays that GCC vectorizes) from the formulas, not from Facet's code:
// in wo's frame (z times the sign of n.wo, so that wo is above and the far
// side has the relative index eta' = eta or 1/eta),
//   reflection (n.wi > 0):  h = (wi + wo)/|wi + wo|, f = F D G / (4 |n.wi| |n.wo|),
//   refraction (n.wi < 0):  v = eta' wi + wo, m = v/|v| turned up,
//                           f = (1 - F) D G |wi.m| |wo.m| / (|n.wi| |n.wo| |v|^2),
// F at wo.m with eta', 0 where the facet faces away from either direction.
// The contract version checks and renormalizes the directions and the
// roughness input (SPEC 2) as the other models do; the bare one trusts them.
//
// Its importance sampler and density (roughGlassSample / roughGlassPdf),
// from Walter et al. 2007 with visible normals, in the same frame: m drawn
// from D_wo(m) = G1(wo) (wo.m) D(m) / (n.wo) by spherical caps (Dupuy &
// Benyoub 2023; u[1] the azimuth, u[2] the height on the cap), reflection
// if u[0] (F + T) < F at wo.m (T = 1 - F in a form without cancellation),
// else Snell's refraction about m (none past the critical angle, where T =
// 0); pdf = share D_wo(m) J, J = 1 / (4 wo.m) or eta'^2 |wi.m| / (eta' wi.m
// + wo.m)^2; a draw that leaves no direction on the branch's side is no
// sample. weight = f |n.wi| / pdf, which for separable Smith reduces to
// G1(wi) (reflection) or G1(wi) / eta'^2 (refraction, radiance): F or T,
// D and G1(wo) cancel, so the weight keeps its precision near the critical
// angle. These draw what Facet's reference sampler draws for the same u.
#include "ReferenceModels.h"

#include "AotMath.h"

#include <algorithm>

namespace facet::aot {
namespace {

constexpr float kRoughGlassRoughness = 0.4f;
constexpr float kRoughGlassEta = 1.5f;

// F for the relative index eta (< 1: 1 past the critical angle), c in [0, 1].
inline float fresnelAcross(float c, float eta) {
    float e = eta * eta - 1.0f;
    float g2 = e + c * c;
    float g = std::sqrt(maxf(g2, 0.0f));
    float gp = g + c, gm = e / gp;
    float A = gm / gp;
    float B = (c * gp - 1.0f) / (c * gm + 1.0f);
    float F = 0.5f * A * A * (1.0f + B * B);
    return g2 > 0.0f ? F : 1.0f;
}

// 2 |n.v| / (1 + Lambda) of GGX times nothing else: G1(v) = 2 z / (z + sqrt(z^2 + a^2 (x^2 + y^2))), z = |n.v|.
inline float ggxG1(float x, float y, float z, float a2) {
    return 2.0f * z / (z + std::sqrt(z * z + a2 * (x * x + y * y)));
}

// Isotropic GGX D(m), m unit: a^2 / (pi (sin^2 + a^2 cos^2)^2).
inline float ggxD(float mx, float my, float mz, float a2) {
    float den = mx * mx + my * my + a2 * mz * mz;
    return a2 * kInvPi / (den * den);
}

// f of unit wi, wo (either side), alpha^2 = a2, where the facet the pair
// selects faces both directions (`faces`; f = 0 elsewhere).
struct Value {
    float f;
    bool faces;
};

inline Value roughGlass(float ix, float iy, float iz, float ox, float oy, float oz, float a2) {
    float sign = oz > 0.0f ? 1.0f : -1.0f;
    float izf = iz * sign, ozf = oz * sign;  // wo's frame: ozf > 0
    bool reflected = izf > 0.0f;
    float eta = oz > 0.0f ? kRoughGlassEta : 1.0f / kRoughGlassEta;
    float k = reflected ? 1.0f : eta;  // h ~ k wi + wo
    float hx = k * ix + ox, hy = k * iy + oy, hz = k * izf + ozf;
    float len2 = hx * hx + hy * hy + hz * hz;
    float s = (hz < 0.0f ? -1.0f : 1.0f) / std::sqrt(len2);
    hx *= s, hy *= s, hz *= s;
    float ih = ix * hx + iy * hy + izf * hz, oh = ox * hx + oy * hy + ozf * hz;
    float d = ggxD(hx, hy, hz, a2);
    float ci = std::fabs(iz), co = std::fabs(oz);
    float g = ggxG1(ix, iy, ci, a2) * ggxG1(ox, oy, co, a2);
    float F = fresnelAcross(minf(maxf(oh, 0.0f), 1.0f), eta);
    float fr = F * d * g / (4.0f * ci * co);
    float denT = eta * ih + oh;
    float ft = (1.0f - F) * d * g * std::fabs(ih) * oh / (ci * co * denT * denT);
    // wi.h on wi's side (a product, not a select between masks, which GCC
    // 12 does not vectorize).
    bool faces = (oh > 0.0f) & (ih * izf > 0.0f) & (len2 > 0.0f) & (ci > 0.0f);
    return {reflected ? fr : ft, faces};
}

// Finite as an ordered compare (NaN fails it): std::isfinite here keeps GCC
// 12 from vectorizing the contract loop.
inline bool finite(float x) { return std::fabs(x) <= 3.40282347e38f; }
inline bool finite3(float x, float y, float z) { return finite(x) & finite(y) & finite(z); }

// A lane's directions and roughness, and whether they are valid.
struct Lane {
    float ix, iy, iz, ox, oy, oz, r;
    float ok;  // 1 or 0: a float, so that GCC keeps the mask in float lanes
};

// std::fabs(x) <= tol as a float comparison GCC keeps in float lanes.
inline bool near1(float len) { return std::fabs(len - 1.0f) <= kUnitTolerance; }

// The contract's checks (SPEC 2): finite unit directions within 1e-3,
// renormalized; a finite roughness, clamped to its declared range.
inline Lane checkedLane(float ix, float iy, float iz, float ox, float oy, float oz, float r) {
    float li = std::sqrt(ix * ix + iy * iy + iz * iz), lo = std::sqrt(ox * ox + oy * oy + oz * oz);
    Lane l;
    bool ok = finite3(ix, iy, iz) & finite3(ox, oy, oz) & near1(li) & near1(lo) & finite(r);
    l.ok = ok ? 1.0f : 0.0f;
    float ri = 1.0f / li, ro = 1.0f / lo;
    l.ix = ix * ri, l.iy = iy * ri, l.iz = iz * ri, l.ox = ox * ro, l.oy = oy * ro, l.oz = oz * ro;
    l.r = minf(maxf(r, 0.0f), 1.0f);
    return l;
}

// The contract version (Validate) or the bare one.
template <bool Validate, bool HasRough>
[[gnu::noinline]] int32_t roughGlassLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                         const float* __restrict wz, const float* __restrict vx,
                                         const float* __restrict vy, const float* __restrict vz,
                                         float* __restrict outR, float* __restrict outG, float* __restrict outB,
                                         const float* __restrict rough) {
    int32_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        const float r = HasRough ? rough[i] : kRoughGlassRoughness;
        Lane l = Validate ? checkedLane(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i], r)
                          : Lane{wx[i], wy[i], wz[i], vx[i], vy[i], vz[i], r, 1.0f};
        float alpha = maxf(l.r * l.r, kMinAlpha);
        Value v = roughGlass(l.ix, l.iy, l.iz, l.ox, l.oy, l.oz, alpha * alpha);
        // As ReferenceModels.cpp's store(): valid unless a check fails or the
        // value of a facing pair is not finite and >= 0; 0 unless shown.
        bool sane = finite(v.f) & (v.f >= 0.0f);
        bool valid = (l.ok > 0.0f) & (sane | !v.faces);
        bool show = valid & v.faces;
        float out = show ? v.f : 0.0f;
        outR[i] = out, outG[i] = out, outB[i] = out;
        invalid += valid ? 0 : 1;
    }
    return Validate ? invalid : 0;
}

constexpr int64_t kChunk = int64_t(1) << 30;  // the loops count in 32 bits

template <bool Validate>
int64_t run(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
            float* const rgb[3]) {
    const float* rough = inputs ? inputs[0] : nullptr;
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        int64_t m = std::min(kChunk, n - start);
        auto at = [&](auto* p) { return p + start; };
        invalid += rough ? roughGlassLoop<Validate, true>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]), at(wo[1]),
                                                          at(wo[2]), at(rgb[0]), at(rgb[1]), at(rgb[2]), at(rough))
                         : roughGlassLoop<Validate, false>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]),
                                                           at(wo[1]), at(wo[2]), at(rgb[0]), at(rgb[1]), at(rgb[2]),
                                                           nullptr);
    }
    return invalid;
}

// ---- the sampler and its density ----

// 1 - F at cos c > 0 with g = eta cos(theta_t) (0 past the critical angle):
// 1 - rs^2 = 4 c g / (c + g)^2, 1 - rp^2 = 4 eta^2 c g / (eta^2 c + g)^2,
// every term positive, so T keeps its relative precision where F -> 1.
inline float transmittance(float c, float g, float eta2) {
    float a = c + g, b = eta2 * c + g;
    return 2.0f * c * g * (1.0f / (a * a) + eta2 / (b * b));
}

// wo checked (SPEC 2) and in its own frame: z = |n.wo| (wo above), the far
// side's relative index eta' and 1/eta', the sign that takes z back.
struct View {
    float x, y, z, sign, eta, inv;
    bool ok, seen;  // valid; n.wo != 0 (else no sample, no density)
};

inline View viewOf(float x, float y, float z) {
    float len = std::sqrt(x * x + y * y + z * z), r = 1.0f / len;
    View v;
    v.ok = finite3(x, y, z) & near1(len);
    v.seen = z != 0.0f;
    bool up = z > 0.0f;
    v.x = x * r, v.y = y * r, v.z = std::fabs(z) * r;
    v.sign = up ? 1.0f : -1.0f;
    v.eta = up ? kRoughGlassEta : 1.0f / kRoughGlassEta;
    v.inv = up ? 1.0f / kRoughGlassEta : kRoughGlassEta;
    return v;
}

// alpha from a roughness input (clamped to its range); ok drops a non-finite one.
inline float alphaOf(float roughness, bool& ok) {
    ok = ok & finite(roughness);
    float r = minf(maxf(roughness, 0.0f), 1.0f);
    return maxf(r * r, kMinAlpha);
}

// D_wo(m) / (4 wo.m) = D(m) / (2 (n.wo + sqrt((n.wo)^2 + a^2 (wo_x^2 + wo_y^2))))
// (G1(wo) / (n.wo) of GGX), wo above.
inline float visibleOver4om(const View& o, float mx, float my, float mz, float a2) {
    return ggxD(mx, my, mz, a2) / (2.0f * (o.z + std::sqrt(o.z * o.z + a2 * (o.x * o.x + o.y * o.y))));
}

template <bool HasRough>
[[gnu::noinline]] int32_t roughGlassSampleLoop(int64_t n, const float* __restrict vx, const float* __restrict vy,
                                               const float* __restrict vz, const float* __restrict u0,
                                               const float* __restrict u1, const float* __restrict u2,
                                               float* __restrict outX, float* __restrict outY,
                                               float* __restrict outZ, float* __restrict outPdf,
                                               float* __restrict outR, float* __restrict outG,
                                               float* __restrict outB, const float* __restrict rough) {
    int32_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        View o = viewOf(vx[i], vy[i], vz[i]);
        bool ok = o.ok & (u0[i] >= 0.0f) & (u0[i] < 1.0f) & (u1[i] >= 0.0f) & (u1[i] < 1.0f) & (u2[i] >= 0.0f) &
                  (u2[i] < 1.0f);
        float alpha = alphaOf(HasRough ? rough[i] : kRoughGlassRoughness, ok), a2 = alpha * alpha;
        // The visible normal: stretched to alpha = 1, c + wo' with c uniform
        // on the cap c.z >= -wo'.z of the unit sphere; unstretched to m.
        float sx = alpha * o.x, sy = alpha * o.y;
        float rs = 1.0f / std::sqrt(sx * sx + sy * sy + o.z * o.z);
        sx *= rs, sy *= rs;
        float sz = o.z * rs;
        float phi = 2.0f * kPi * u1[i];
        float cz = (1.0f - u2[i]) * (1.0f + sz) - sz;
        float cr = std::sqrt(maxf((1.0f - cz) * (1.0f + cz), 0.0f));
        // sin as cos(phi - pi/2): sinf and cosf of one argument become a
        // scalar sincos call, which would keep the loop scalar.
        float mx = alpha * (cr * cosf(phi) + sx), my = alpha * (cr * cosf(phi - 0.5f * kPi) + sy);
        float mz = maxf(cz + sz, 0.0f);
        float ml2 = mx * mx + my * my + mz * mz;
        float rm = 1.0f / std::sqrt(maxf(ml2, 1e-30f));  // unconditional: no division under a condition
        mx *= rm, my *= rm, mz = ml2 > 0.0f ? mz * rm : 1.0f;
        float om = o.x * mx + o.y * my + o.z * mz;
        // The branch: reflection with probability F / (F + T) at wo.m.
        float c = minf(maxf(om, 0.0f), 1.0f), eta2 = o.eta * o.eta;
        float g2 = eta2 - 1.0f + c * c, g = std::sqrt(maxf(g2, 0.0f));
        float F = fresnelAcross(c, o.eta), T = transmittance(c, g, eta2), total = F + T;
        bool reflect = u0[i] * total < F;
        // Reflection about m, or refraction: cos theta_t = g / eta',
        // wi = -wo / eta' + (wo.m / eta' - cos theta_t) m.
        float ct = g * o.inv, k = om * o.inv - ct;
        float rx = 2.0f * om * mx - o.x, ry = 2.0f * om * my - o.y, rz = 2.0f * om * mz - o.z;
        float tx = k * mx - o.x * o.inv, ty = k * my - o.y * o.inv, tz = k * mz - o.z * o.inv;
        float ix = reflect ? rx : tx, iy = reflect ? ry : ty, iz = reflect ? rz : tz;
        // pdf = share D_wo(m) J: for a refraction 4 (wo.m) J = 4 (wo.m) eta'^2 ct / (wo.m - eta' ct)^2.
        float den = om - o.eta * ct;
        float toRefraction = 4.0f * om * eta2 * ct / (den * den);
        float share = (reflect ? F : T) / total;
        // Times 0 where wi is not on the branch's side (no sample; past the
        // critical angle ct = 0 does it) or m is in the surface (density 0):
        // products, as these tests in `sampled` become selects of booleans.
        float jac = reflect ? float(rz > 0.0f) : toRefraction * float(tz < 0.0f);
        float pdf = share * visibleOver4om(o, mx, my, mz, a2) * jac * float(mz > 0.0f);
        // weight = G1(wi), over eta'^2 for a refraction.
        float ci = std::fabs(iz);
        float g1 = 2.0f * ci / (ci + std::sqrt(ci * ci + a2 * (ix * ix + iy * iy)));
        float w = reflect ? g1 : g1 * o.inv * o.inv;
        bool sampled = o.seen & (om > 0.0f) & (pdf > 0.0f);
        bool sane = finite(pdf) & finite(w) & (w >= 0.0f) & finite3(ix, iy, iz);
        bool valid = ok & (sane | !sampled);
        bool show = valid & sampled;
        outX[i] = show ? ix : 0.0f, outY[i] = show ? iy : 0.0f, outZ[i] = show ? iz * o.sign : 0.0f;
        outPdf[i] = show ? pdf : 0.0f;
        float out = show ? w : 0.0f;
        outR[i] = out, outG[i] = out, outB[i] = out;
        invalid += valid ? 0 : 1;
    }
    return invalid;
}

template <bool HasRough>
[[gnu::noinline]] int32_t roughGlassPdfLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                            const float* __restrict wz, const float* __restrict vx,
                                            const float* __restrict vy, const float* __restrict vz,
                                            float* __restrict outPdf, const float* __restrict rough) {
    int32_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        View o = viewOf(vx[i], vy[i], vz[i]);
        float li = std::sqrt(wx[i] * wx[i] + wy[i] * wy[i] + wz[i] * wz[i]), ri = 1.0f / li;
        bool ok = o.ok & finite3(wx[i], wy[i], wz[i]) & near1(li);
        float alpha = alphaOf(HasRough ? rough[i] : kRoughGlassRoughness, ok), a2 = alpha * alpha;
        float ix = wx[i] * ri, iy = wy[i] * ri, iz = wz[i] * ri * o.sign;  // wo's frame
        bool reflected = iz > 0.0f;
        // The facet: (wi + wo) or (eta' wi + wo), normalized, turned up.
        float k = reflected ? 1.0f : o.eta;
        float hx = k * ix + o.x, hy = k * iy + o.y, hz = k * iz + o.z;
        float len2 = hx * hx + hy * hy + hz * hz;
        float rh = (hz < 0.0f ? -1.0f : 1.0f) / std::sqrt(maxf(len2, 1e-30f));
        float mx = hx * rh, my = hy * rh, mz = hz * rh;
        float im = ix * mx + iy * my + iz * mz, om = o.x * mx + o.y * my + o.z * mz;
        // The shares at wo.m; a refracted pair's T from its own cos theta_t = |wi.m|.
        float c = minf(maxf(om, 0.0f), 1.0f), eta2 = o.eta * o.eta;
        float gc = std::sqrt(maxf(eta2 - 1.0f + c * c, 0.0f));
        float F = fresnelAcross(c, o.eta), T = transmittance(c, reflected ? gc : o.eta * std::fabs(im), eta2);
        float share = (reflected ? F : T) / (F + T);
        float toRefraction = 4.0f * om * eta2 * std::fabs(im) / len2;
        float pdf = share * visibleOver4om(o, mx, my, mz, a2) * (reflected ? 1.0f : toRefraction);
        bool counted = o.seen & (iz != 0.0f) & (len2 > 0.0f) & (om > 0.0f) & (mz > 0.0f) & (reflected | (im < 0.0f));
        bool valid = ok & ((!counted) | (finite(pdf) & (pdf >= 0.0f)));
        outPdf[i] = valid & counted ? pdf : 0.0f;
        invalid += valid ? 0 : 1;
    }
    return invalid;
}

}  // namespace

int64_t roughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]) {
    return run<true>(n, wi, wo, inputs, rgb);
}

int64_t bareRoughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                       float* const rgb[3]) {
    return run<false>(n, wi, wo, inputs, rgb);
}

int64_t roughGlassSample(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                         float* const wi[3], float* pdf, float* const weight[3]) {
    const float* rough = inputs ? inputs[0] : nullptr;
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        int64_t m = std::min(kChunk, n - start);
        auto at = [&](auto* p) { return p + start; };
        invalid += rough ? roughGlassSampleLoop<true>(m, at(wo[0]), at(wo[1]), at(wo[2]), at(u[0]), at(u[1]),
                                                      at(u[2]), at(wi[0]), at(wi[1]), at(wi[2]), at(pdf),
                                                      at(weight[0]), at(weight[1]), at(weight[2]), at(rough))
                         : roughGlassSampleLoop<false>(m, at(wo[0]), at(wo[1]), at(wo[2]), at(u[0]), at(u[1]),
                                                       at(u[2]), at(wi[0]), at(wi[1]), at(wi[2]), at(pdf),
                                                       at(weight[0]), at(weight[1]), at(weight[2]), nullptr);
    }
    return invalid;
}

int64_t roughGlassPdf(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* pdf) {
    const float* rough = inputs ? inputs[0] : nullptr;
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        int64_t m = std::min(kChunk, n - start);
        auto at = [&](auto* p) { return p + start; };
        invalid += rough ? roughGlassPdfLoop<true>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]), at(wo[1]),
                                                   at(wo[2]), at(pdf), at(rough))
                         : roughGlassPdfLoop<false>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]), at(wo[1]),
                                                    at(wo[2]), at(pdf), nullptr);
    }
    return invalid;
}

}  // namespace facet::aot
