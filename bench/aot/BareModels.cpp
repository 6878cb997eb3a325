// BareModels: the three reference BRDFs as the loop a renderer engineer
// writes for their own renderer, the "bare" baseline of `facet bench`: the
// same formulas in float as ReferenceModels.cpp, but the host promises what
// the contract baseline checks, so there is no validation (finite, unit
// directions; finite inputs), no renormalization of wi and wo, no roughness
// range clamp of the roughness inputs, no invalid-lane count (always 0) and
// no output check. What stays is part of the BRDF: alpha >= 1e-4 (SPEC 3),
// f = 0 below the horizon and where wi or wo is behind the microfacet. restrict SoA loops, built -O3 -march=native -fno-math-errno
// -fno-trapping-math like the contract baseline (bench/CMakeLists.txt), and
// vectorized (-fopt-info-vec-optimized lists each loop; tests/bench checks
// the values on valid inputs).
#include "ReferenceModels.h"

#include "AotMath.h"

namespace facet::aot {
namespace {

// The half vector and the cosines every model needs, from unit wi, wo.
struct BareFrame {
    float hx, hy, hz, ih, oh;
    bool lit;  // both above the horizon
};

inline BareFrame bareFrame(float ix, float iy, float iz, float ox, float oy, float oz) {
    BareFrame f;
    float hx = ix + ox, hy = iy + oy, hz = iz + oz;
    float rh = 1.0f / std::sqrt(hx * hx + hy * hy + hz * hz);
    f.hx = hx * rh, f.hy = hy * rh, f.hz = hz * rh;
    f.ih = ix * f.hx + iy * f.hy + iz * f.hz;
    f.oh = ox * f.hx + oy * f.hy + oz * f.hz;
    f.lit = (iz > 0.0f) & (oz > 0.0f) & (f.ih > 0.0f) & (f.oh > 0.0f);
    return f;
}

template <bool HasRough>
[[gnu::noinline]] void bareGgxSchlickLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                          const float* __restrict wz, const float* __restrict vx,
                                          const float* __restrict vy, const float* __restrict vz,
                                          float* __restrict outR, float* __restrict outG, float* __restrict outB,
                                          const float* __restrict rough) {
    for (int64_t i = 0; i < n; ++i) {
        BareFrame f = bareFrame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        float r = HasRough ? rough[i] : kGgxSchlickRoughness;
        float alpha = maxf(r * r, kMinAlpha), a2 = alpha * alpha;
        float den = f.hx * f.hx + f.hy * f.hy + a2 * f.hz * f.hz;
        float d = a2 * kInvPi / (den * den);
        float spec = d * ggxVisibilityTerm(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i], a2, a2);
        spec = f.lit ? spec : 0.0f;
        float q = 1.0f - f.ih;
        float q2 = q * q, q5 = q2 * q2 * q;
        outR[i] = (kGgxSchlickF0[0] + (1.0f - kGgxSchlickF0[0]) * q5) * spec;
        outG[i] = (kGgxSchlickF0[1] + (1.0f - kGgxSchlickF0[1]) * q5) * spec;
        outB[i] = (kGgxSchlickF0[2] + (1.0f - kGgxSchlickF0[2]) * q5) * spec;
    }
}

template <bool HasRough>
[[gnu::noinline]] void bareBeckmannConductorLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                                 const float* __restrict wz, const float* __restrict vx,
                                                 const float* __restrict vy, const float* __restrict vz,
                                                 float* __restrict outR, float* __restrict outG,
                                                 float* __restrict outB, const float* __restrict rough) {
    for (int64_t i = 0; i < n; ++i) {
        BareFrame f = bareFrame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        float r = HasRough ? rough[i] : kBeckmannRoughness;
        float alpha = maxf(r * r, kMinAlpha), a2 = alpha * alpha;
        // D = exp(-tan^2 / a^2) / (pi a^2 cos^4); the exponent clamped at 87
        // where exp leaves float's normal range (libmvec's slow path), as
        // the contract baseline does.
        float z2 = f.hz * f.hz, sin2h = f.hx * f.hx + f.hy * f.hy, den = a2 * z2;
        bool tail = sin2h * (1.0f / 87.0f) > den;
        float e = sin2h / maxf(den, sin2h * (1.0f / 87.0f));
        float scale = tail ? 0.0f : kInvPi / (den * z2);
        float d = std::exp(-e) * scale;
        float g = beckmannG1(wx[i], wy[i], wz[i], alpha) * beckmannG1(vx[i], vy[i], vz[i], alpha);
        float spec = f.lit ? d * g / (4.0f * wz[i] * vz[i]) : 0.0f;
        float c = f.ih, s2 = (1.0f - c) * (1.0f + c);
        outR[i] = conductorF(c, s2, kGoldEta[0], kGoldK[0]) * spec;
        outG[i] = conductorF(c, s2, kGoldEta[1], kGoldK[1]) * spec;
        outB[i] = conductorF(c, s2, kGoldEta[2], kGoldK[2]) * spec;
    }
}

template <bool HasRoughX, bool HasRoughY>
[[gnu::noinline]] void bareAnisoGgxDielectricLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                                  const float* __restrict wz, const float* __restrict vx,
                                                  const float* __restrict vy, const float* __restrict vz,
                                                  float* __restrict outR, float* __restrict outG,
                                                  float* __restrict outB, const float* __restrict roughX,
                                                  const float* __restrict roughY) {
    for (int64_t i = 0; i < n; ++i) {
        BareFrame f = bareFrame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        float rx = HasRoughX ? roughX[i] : kAnisoRoughnessX, ry = HasRoughY ? roughY[i] : kAnisoRoughnessY;
        float ax = maxf(rx * rx, kMinAlpha), ay = maxf(ry * ry, kMinAlpha);
        // D = (ax ay)^3 / (pi T^2), T = hx^2 ay^2 + hy^2 ax^2 + hz^2 ax^2 ay^2.
        float ax2 = ax * ax, ay2 = ay * ay, axy = ax * ay;
        float t = f.hx * f.hx * ay2 + f.hy * f.hy * ax2 + f.hz * f.hz * (ax2 * ay2);
        float d = axy * axy * axy * kInvPi / (t * t);
        float spec = d * ggxVisibilityTerm(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i], ax2, ay2);
        spec = f.lit ? spec : 0.0f;
        outR[i] = dielectricF(f.ih, kGlassEta[0]) * spec;
        outG[i] = dielectricF(f.ih, kGlassEta[1]) * spec;
        outB[i] = dielectricF(f.ih, kGlassEta[2]) * spec;
    }
}

const float* slot(const float* const* inputs, int s) { return inputs ? inputs[s] : nullptr; }

}  // namespace

int64_t bareGgxSchlick(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                       float* const rgb[3]) {
    if (const float* r = slot(inputs, 0))
        bareGgxSchlickLoop<true>(n, wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], rgb[0], rgb[1], rgb[2], r);
    else
        bareGgxSchlickLoop<false>(n, wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], rgb[0], rgb[1], rgb[2], nullptr);
    return 0;
}

int64_t bareBeckmannConductor(int64_t n, const float* const wi[3], const float* const wo[3],
                              const float* const* inputs, float* const rgb[3]) {
    if (const float* r = slot(inputs, 0))
        bareBeckmannConductorLoop<true>(n, wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], rgb[0], rgb[1], rgb[2], r);
    else
        bareBeckmannConductorLoop<false>(n, wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], rgb[0], rgb[1], rgb[2],
                                         nullptr);
    return 0;
}

int64_t bareAnisoGgxDielectric(int64_t n, const float* const wi[3], const float* const wo[3],
                               const float* const* inputs, float* const rgb[3]) {
    const float *x = slot(inputs, 0), *y = slot(inputs, 1);
    auto run = [&](auto loop) { loop(n, wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], rgb[0], rgb[1], rgb[2], x, y); };
    if (x && y) run(bareAnisoGgxDielectricLoop<true, true>);
    else if (x) run(bareAnisoGgxDielectricLoop<true, false>);
    else if (y) run(bareAnisoGgxDielectricLoop<false, true>);
    else run(bareAnisoGgxDielectricLoop<false, false>);
    return 0;
}

}  // namespace facet::aot
