// AotMath: what the hand-written baselines (ReferenceModels.cpp, the
// contract baseline, and BareModels.cpp, the bare one) share: the constants
// of the bench/models/*.mat twins and the float BRDF terms, written for
// GCC's vectorizer (see ReferenceModels.cpp for how and why).
#pragma once

#include <cmath>

#if defined(__GNUC__) && !defined(__clang__)
extern "C" float expf(float) __attribute__((simd("notinbranch")));
extern "C" float erfcf(float) __attribute__((simd("notinbranch")));
extern "C" float cosf(float) __attribute__((simd("notinbranch")));
#endif

namespace facet::aot {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.318309886183790671538f;
constexpr float kInvSqrtPi = 0.564189583547756286948f;
constexpr float kUnitTolerance = 1e-3f;  // SPEC 2
constexpr float kMinAlpha = 1e-4f;       // SPEC 3: alpha is clamped to >= 1e-4

// ---- the constants shared with bench/models/*.mat (keep them identical) ----
// (a) ggx_schlick.mat
constexpr float kGgxSchlickRoughness = 0.4f;
constexpr float kGgxSchlickF0[3] = {0.955f, 0.638f, 0.538f};
// (b) beckmann_conductor.mat (gold, Johnson & Christy 1972)
constexpr float kBeckmannRoughness = 0.3f;
constexpr float kGoldEta[3] = {0.14f, 0.43f, 1.38f};
constexpr float kGoldK[3] = {3.697f, 2.455f, 1.914f};
// (c) aniso_ggx_dielectric.mat (N-BK7 glass)
constexpr float kAnisoRoughnessX = 0.2f;
constexpr float kAnisoRoughnessY = 0.5f;
constexpr float kGlassEta[3] = {1.5145f, 1.5185f, 1.5253f};

// min/max as compare-and-select: std::fmin/fmax are libm calls under GCC
// (they must handle NaN), which block vectorization. Here NaN never reaches
// them from a valid lane.
inline float maxf(float a, float b) { return a > b ? a : b; }
inline float minf(float a, float b) { return a < b ? a : b; }

// V = G2 / (4 n.wi n.wo) for height-correlated Smith GGX, with
// p(v) = vx^2 ax^2 + vy^2 ay^2:
//   1 + Li + Lo = (sqrt(ci^2 + p(wi))/ci + sqrt(co^2 + p(wo))/co) / 2
//   V = 1 / (2 (co sqrt(ci^2 + p(wi)) + ci sqrt(co^2 + p(wo))))
inline float ggxVisibilityTerm(float ix, float iy, float iz, float ox, float oy, float oz, float ax2, float ay2) {
    float pi = ix * ix * ax2 + iy * iy * ay2;
    float po = ox * ox * ax2 + oy * oy * ay2;
    float a = oz * std::sqrt(iz * iz + pi);
    float b = iz * std::sqrt(oz * oz + po);
    return 0.5f / (a + b);
}

// Beckmann Smith G1 = 1 / (1 + Lambda(a)), a = cot(theta) / alpha:
// Lambda = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 (SPEC 3, exact form).
// Beyond a = 4, Lambda < 5e-10 and 1 + Lambda rounds to 1 in float, so a
// is clamped to 4 (exact in float; also a = inf at v = n). That keeps
// libmvec's vector erfcf/expf off their slow paths: they call the scalar
// function for every lane whose result underflows, and most lanes would
// (a ~ 1/alpha). The clamp is applied to the denominator: GCC turns
// f(min(a, 4)) into a < 4 ? f(a) : f(4) (folding f(4)) and then calls the
// vector f on the unclamped a, which is exactly the slow path.
inline float beckmannG1(float vx, float vy, float vz, float alpha) {
    float s = std::sqrt(vx * vx + vy * vy);
    float a = vz / (alpha * maxf(s, vz * (0.25f / alpha)));  // min(cot / alpha, 4)
    float lambda = 0.5f * (std::exp(-a * a) * kInvSqrtPi / a - std::erfc(a));
    return 1.0f / (1.0f + maxf(lambda, 0.0f));
}

// Exact conductor Fresnel (Born & Wolf): with N = eta + ik, c = cos theta,
// t0 = eta^2 - k^2 - s^2, a2b2 = |N^2 - s^2| = sqrt(t0^2 + 4 eta^2 k^2),
// a = Re sqrt(N^2 - s^2). Per-channel constants are folded by the compiler.
inline float conductorF(float c, float s2, float eta, float k) {
    float n2 = eta * eta, k2 = k * k;
    float t0 = n2 - k2 - s2;
    float a2b2 = std::sqrt(t0 * t0 + 4.0f * n2 * k2);
    float a = std::sqrt(maxf(0.5f * (a2b2 + t0), 0.0f));
    float c2 = c * c;
    float t1 = a2b2 + c2, t2 = 2.0f * c * a;
    float rs = (t1 - t2) / (t1 + t2);
    float t3 = c2 * a2b2 + s2 * s2, t4 = t2 * s2;
    float rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5f * (rs + rp);
}

// Exact dielectric Fresnel for eta > 1 (no total internal reflection from
// outside): g = sqrt(eta^2 - 1 + c^2), and g - c = (eta^2 - 1)/(g + c)
// without cancellation.
inline float dielectricF(float c, float eta) {
    float e2m1 = eta * eta - 1.0f;
    float g = std::sqrt(maxf(e2m1 + c * c, 0.0f));
    float gp = g + c, gm = e2m1 / gp;
    float A = gm / gp;
    float B = (c * gp - 1.0f) / (c * gm + 1.0f);
    return 0.5f * A * A * (1.0f + B * B);
}

}  // namespace facet::aot
