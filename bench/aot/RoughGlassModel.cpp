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
    float den = hx * hx + hy * hy + a2 * hz * hz;
    float d = a2 * kInvPi / (den * den);
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

template <bool Validate>
int64_t run(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
            float* const rgb[3]) {
    constexpr int64_t kChunk = int64_t(1) << 30;  // the loop counts in 32 bits
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

}  // namespace

int64_t roughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]) {
    return run<true>(n, wi, wo, inputs, rgb);
}

int64_t bareRoughGlass(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                       float* const rgb[3]) {
    return run<false>(n, wi, wo, inputs, rgb);
}

}  // namespace facet::aot
