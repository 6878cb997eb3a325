// ReferenceModels: the three hand-written baseline BRDFs (see ReferenceModels.h).
//
// How they are written, and why:
// - float throughout, one branch-free loop per model over SoA arrays with
//   __restrict pointers, so that GCC/Clang vectorize the whole lane with
//   -O3 -march=native. Conditions are combined with `&` and resolved with
//   selects at the end (a `&&` or a conditional division is control flow
//   that stops GCC's if-conversion).
// - Loops are instantiated per input layout (caller array or default), so
//   a NULL input costs no load and no per-lane test.
// - std::exp / std::erfc are declared with GCC's `simd` attribute: glibc's
//   libmvec has vector versions (_ZGVeN16v_expf, ...) but math.h declares
//   them only under -ffast-math. Declaring them lets the vectorizer call
//   them without fast-math, so the results keep IEEE arithmetic elsewhere.
// - Algebra a renderer engineer would use: height-correlated Smith GGX as
//   the fused visibility term V = G / (4 n.wi n.wo) (one division, two
//   square roots, no cancellation at grazing angles); isotropic GGX D as
//   alpha^2 / (pi (sin^2 + alpha^2 cos^2)^2) with sin^2 from components.
//   These are the SPEC formulas rearranged, not approximations.
#include "ReferenceModels.h"

#include "AotMath.h"

#include <cmath>
#include <algorithm>

namespace facet::aot {
namespace {

// An input slot is either a caller array or the default for every lane;
// the loops are instantiated for both (template flag), so a default costs no
// load. Arrays arrive as __restrict parameters of non-inlined loop
// functions: GCC drops restrict when the callee is inlined into a lambda,
// and then the run-time alias checks (six inputs and an input slot against
// three outputs) exceed its versioning limit and the loop stays scalar.

bool finite3(float x, float y, float z) { return std::isfinite(x) & std::isfinite(y) & std::isfinite(z); }

// One lane's geometry after the SPEC 2 checks.
struct Frame {
    float ix, iy, iz, ox, oy, oz;  // unit wi, wo
    float hx, hy, hz;              // unit half vector
    float ih, oh;                  // wi.h, wo.h
    bool ok;                       // the directions are valid (else: 0, counted)
    bool lit;                      // both above the horizon and wi + wo != 0
};

inline Frame frame(float ix, float iy, float iz, float ox, float oy, float oz) {
    Frame f;
    float li = std::sqrt(ix * ix + iy * iy + iz * iz), lo = std::sqrt(ox * ox + oy * oy + oz * oz);
    f.ok = finite3(ix, iy, iz) & finite3(ox, oy, oz) & (std::fabs(li - 1.0f) <= kUnitTolerance) &
           (std::fabs(lo - 1.0f) <= kUnitTolerance);
    float ri = 1.0f / li, ro = 1.0f / lo;
    f.ix = ix * ri, f.iy = iy * ri, f.iz = iz * ri;
    f.ox = ox * ro, f.oy = oy * ro, f.oz = oz * ro;
    float hx = f.ix + f.ox, hy = f.iy + f.oy, hz = f.iz + f.oz;
    float hl2 = hx * hx + hy * hy + hz * hz;
    f.lit = (f.iz > 0.0f) & (f.oz > 0.0f) & (hl2 > 0.0f);
    float rh = 1.0f / std::sqrt(hl2);
    f.hx = hx * rh, f.hy = hy * rh, f.hz = hz * rh;
    f.ih = f.ix * f.hx + f.iy * f.hy + f.iz * f.hz;
    f.oh = f.ox * f.hx + f.oy * f.hy + f.oz * f.hz;
    return f;
}

// Roughness input -> alpha: clamp to the declared range [0, 1], square,
// clamp to the smallest evaluable alpha. `ok` drops non-finite inputs.
inline float alphaOf(float roughness, bool& ok) {
    ok = ok & std::isfinite(roughness);
    float r = minf(maxf(roughness, 0.0f), 1.0f);
    return maxf(r * r, kMinAlpha);
}

// Writes one lane: zero unless valid and lit; an output that is not finite
// or negative makes the lane invalid (SPEC 2). Returns 1 for an invalid lane.
// The validity is one expression of plain booleans (no select between
// booleans: GCC 12 cannot vectorize a select whose operands are masks).
inline int32_t store(const Frame& f, bool inputsOk, float r, float g, float b, float* __restrict outR,
                     float* __restrict outG, float* __restrict outB, int64_t i) {
    bool sane = std::isfinite(r) & std::isfinite(g) & std::isfinite(b) & (r >= 0.0f) & (g >= 0.0f) & (b >= 0.0f);
    bool valid = f.ok & inputsOk & (sane | !f.lit);
    bool show = valid & f.lit;
    outR[i] = show ? r : 0.0f;
    outG[i] = show ? g : 0.0f;
    outB[i] = show ? b : 0.0f;
    return valid ? 0 : 1;
}

// ggxVisibilityTerm (AotMath.h), 0 where wi or wo is behind the microfacet.
inline float ggxVisibility(const Frame& f, float ax2, float ay2) {
    float v = ggxVisibilityTerm(f.ix, f.iy, f.iz, f.ox, f.oy, f.oz, ax2, ay2);
    return ((f.ih > 0.0f) & (f.oh > 0.0f)) ? v : 0.0f;
}

// ---- (a) GGX + height-correlated Smith + Schlick rgb ----

template <bool HasRough>
[[gnu::noinline]] int32_t ggxSchlickLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                       const float* __restrict wz, const float* __restrict vx, const float* __restrict vy,
                       const float* __restrict vz, float* __restrict outR, float* __restrict outG,
                       float* __restrict outB, const float* __restrict rough) {
    int32_t invalid = 0;  // int32: GCC cannot vectorize a 64-bit count next to float lanes
    for (int64_t i = 0; i < n; ++i) {
        Frame f = frame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        bool inOk = true;
        float alpha = alphaOf(HasRough ? rough[i] : kGgxSchlickRoughness, inOk);
        float a2 = alpha * alpha;
        // D = a^2 / (pi (sin^2 + a^2 cos^2)^2), sin^2 from the components.
        float den = f.hx * f.hx + f.hy * f.hy + a2 * f.hz * f.hz;
        float d = a2 * kInvPi / (den * den);
        float spec = d * ggxVisibility(f, a2, a2);
        float q = 1.0f - minf(maxf(f.ih, 0.0f), 1.0f);
        float q2 = q * q, q5 = q2 * q2 * q;
        float fr = kGgxSchlickF0[0] + (1.0f - kGgxSchlickF0[0]) * q5;
        float fg = kGgxSchlickF0[1] + (1.0f - kGgxSchlickF0[1]) * q5;
        float fb = kGgxSchlickF0[2] + (1.0f - kGgxSchlickF0[2]) * q5;
        invalid += store(f, inOk, fr * spec, fg * spec, fb * spec, outR, outG, outB, i);
    }
    return invalid;
}

// ---- (a)'s sampler: GGX visible normals by spherical caps ----

// 1 + Lambda(w) of isotropic GGX times 2 n.w: n.w + sqrt((n.w)^2 + a^2
// (wx^2 + wy^2)), without the division by n.w (the ratios below cancel it).
inline float ggxLambdaTerm(float x, float y, float z, float a2) { return std::sqrt(z * z + a2 * (x * x + y * y)); }

// wo's validity and unit vector (SPEC 2), shared by sample and pdf.
struct View {
    float x, y, z;
    bool ok;
};
inline View view(float x, float y, float z) {
    float len = std::sqrt(x * x + y * y + z * z);
    View v;
    v.ok = finite3(x, y, z) & (std::fabs(len - 1.0f) <= kUnitTolerance);
    float r = 1.0f / len;
    v.x = x * r, v.y = y * r, v.z = z * r;
    return v;
}

// D(m) / (4 (n.wo) (1 + Lambda(wo))) = D(m) / (2 (co + So)), So =
// ggxLambdaTerm(wo); m unit with m.z >= 0.
inline float ggxVisiblePdf(float mx, float my, float mz, float a2, float co, float so) {
    float den = mx * mx + my * my + a2 * mz * mz;
    float d = a2 * kInvPi / (den * den);
    return d / (2.0f * (co + so));
}

template <bool HasRough>
[[gnu::noinline]] int32_t ggxSchlickSampleLoop(int64_t n, const float* __restrict vx, const float* __restrict vy,
                                               const float* __restrict vz, const float* __restrict u0,
                                               const float* __restrict u1, const float* __restrict u2,
                                               float* __restrict outX, float* __restrict outY,
                                               float* __restrict outZ, float* __restrict outPdf,
                                               float* __restrict outR, float* __restrict outG,
                                               float* __restrict outB, const float* __restrict rough) {
    int32_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        View o = view(vx[i], vy[i], vz[i]);
        bool ok = o.ok & (u0[i] >= 0.0f) & (u0[i] < 1.0f) & (u1[i] >= 0.0f) & (u1[i] < 1.0f) & (u2[i] >= 0.0f) &
                  (u2[i] < 1.0f);
        float alpha = alphaOf(HasRough ? rough[i] : kGgxSchlickRoughness, ok);
        float a2 = alpha * alpha;
        // wo in the stretched (alpha = 1) configuration, where the visible
        // normals are uniform on the spherical cap above -wo'.
        float sx = alpha * o.x, sy = alpha * o.y, sz = o.z;
        float rs = 1.0f / std::sqrt(sx * sx + sy * sy + sz * sz);
        sx *= rs, sy *= rs, sz *= rs;
        float phi = 2.0f * kPi * u1[i];
        float z = (1.0f - u2[i]) * (1.0f + sz) - sz;
        float r = std::sqrt(maxf((1.0f - z) * (1.0f + z), 0.0f));
        // sin(phi) as cos(phi - pi/2): GCC merges sinf and cosf of one
        // argument into a scalar sincos call, which keeps the loop from
        // vectorizing (the shift costs at most ~1e-7 absolute in sin).
        float hx = r * cosf(phi) + sx, hy = r * cosf(phi - 0.5f * kPi) + sy, hz = z + sz;
        float mx = alpha * hx, my = alpha * hy, mz = maxf(hz, 0.0f);
        float ml2 = mx * mx + my * my + mz * mz;
        // Computed unconditionally and then selected: a division inside a
        // conditional keeps GCC from vectorizing the loop.
        float rm = 1.0f / std::sqrt(maxf(ml2, 1e-30f));
        mx *= rm, my *= rm, mz = ml2 > 0.0f ? mz * rm : 1.0f;
        float om = o.x * mx + o.y * my + o.z * mz;
        float ix = 2.0f * om * mx - o.x, iy = 2.0f * om * my - o.y, iz = 2.0f * om * mz - o.z;
        float so = ggxLambdaTerm(o.x, o.y, o.z, a2);
        float pdfAll = ggxVisiblePdf(mx, my, mz, a2, o.z, so);
        // A product rather than a select: GCC cannot vectorize the select
        // of booleans that folding a select into the checks below makes
        // (pdfAll is finite for a unit m and alpha > 0).
        float pdf = pdfAll * float(om > 0.0f);
        // weight = F G2 / G1(wo) = F ci (co + So) / (ci So + co Si).
        float si = ggxLambdaTerm(ix, iy, iz, a2);
        float ratio = iz * (o.z + so) / (iz * so + o.z * si);
        float q = 1.0f - minf(maxf(om, 0.0f), 1.0f);
        float q2 = q * q, q5 = q2 * q2 * q;
        float fr = kGgxSchlickF0[0] + (1.0f - kGgxSchlickF0[0]) * q5;
        float fg = kGgxSchlickF0[1] + (1.0f - kGgxSchlickF0[1]) * q5;
        float fb = kGgxSchlickF0[2] + (1.0f - kGgxSchlickF0[2]) * q5;
        bool lit = (iz > 0.0f) & (om > 0.0f);
        float wr = lit ? fr * ratio : 0.0f, wg = lit ? fg * ratio : 0.0f, wb = lit ? fb * ratio : 0.0f;
        // The checks read the unselected values, for the reason given at pdf.
        float lr = fr * ratio, lg = fg * ratio, lb = fb * ratio;
        bool saneLit = std::isfinite(lr) & std::isfinite(lg) & std::isfinite(lb) & (lr >= 0.0f) & (lg >= 0.0f) &
                       (lb >= 0.0f);
        bool sane = std::isfinite(pdf) & (pdf >= 0.0f) & (!lit | saneLit);
        bool above = o.z > 0.0f;
        bool valid = ok & (sane | !above);
        bool show = valid & above;
        outX[i] = show ? ix : 0.0f, outY[i] = show ? iy : 0.0f, outZ[i] = show ? iz : 0.0f;
        outPdf[i] = show ? pdf : 0.0f;
        outR[i] = show ? wr : 0.0f, outG[i] = show ? wg : 0.0f, outB[i] = show ? wb : 0.0f;
        invalid += valid ? 0 : 1;
    }
    return invalid;
}

template <bool HasRough>
[[gnu::noinline]] int32_t ggxSchlickPdfLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                                            const float* __restrict wz, const float* __restrict vx,
                                            const float* __restrict vy, const float* __restrict vz,
                                            float* __restrict outPdf, const float* __restrict rough) {
    int32_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        View w = view(wx[i], wy[i], wz[i]), o = view(vx[i], vy[i], vz[i]);
        bool ok = w.ok & o.ok;
        float alpha = alphaOf(HasRough ? rough[i] : kGgxSchlickRoughness, ok);
        float a2 = alpha * alpha;
        // The half vector, turned to the upper hemisphere.
        float hx = w.x + o.x, hy = w.y + o.y, hz = w.z + o.z;
        float hl2 = hx * hx + hy * hy + hz * hz;
        float rh = hl2 > 0.0f ? 1.0f / std::sqrt(maxf(hl2, 1e-30f)) : 0.0f;
        rh = hz < 0.0f ? -rh : rh;
        float mx = hx * rh, my = hy * rh, mz = hz * rh;
        float om = o.x * mx + o.y * my + o.z * mz;
        float so = ggxLambdaTerm(o.x, o.y, o.z, a2);
        float pdf = ggxVisiblePdf(mx, my, mz, a2, o.z, so);
        bool counted = (o.z > 0.0f) & (om > 0.0f) & (hl2 > 0.0f);
        bool valid = ok & ((!counted) | (std::isfinite(pdf) & (pdf >= 0.0f)));
        outPdf[i] = valid & counted ? pdf : 0.0f;
        invalid += valid ? 0 : 1;
    }
    return invalid;
}

// ---- (b) Beckmann + separable Smith + conductor ----

template <bool HasRough>
[[gnu::noinline]] int32_t beckmannConductorLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                              const float* __restrict wz, const float* __restrict vx, const float* __restrict vy,
                              const float* __restrict vz, float* __restrict outR, float* __restrict outG,
                              float* __restrict outB, const float* __restrict rough) {
    int32_t invalid = 0;  // int32: GCC cannot vectorize a 64-bit count next to float lanes
    for (int64_t i = 0; i < n; ++i) {
        Frame f = frame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        bool inOk = true;
        float alpha = alphaOf(HasRough ? rough[i] : kBeckmannRoughness, inOk);
        float a2 = alpha * alpha;
        // D = exp(-e) / (pi a^2 cos^4), e = tan^2 / a^2. Past e = 87 exp(-e) leaves float's normal range
        // (and libmvec's fast path, see beckmannG1); D is then 0 to float
        // precision (< 2e-38 / (pi a^2 cos^4)): e is clamped to 87 through
        // its denominator and the zero goes into the scale factor (exp(x) * 0
        // cannot be folded, so the clamp stays).
        float z2 = f.hz * f.hz, sin2h = f.hx * f.hx + f.hy * f.hy, den = a2 * z2;
        bool tail = sin2h * (1.0f / 87.0f) > den;
        float e = sin2h / maxf(den, sin2h * (1.0f / 87.0f));
        float scale = tail ? 0.0f : kInvPi / (den * z2);
        float d = std::exp(-e) * scale;
        float g = beckmannG1(f.ix, f.iy, f.iz, alpha) * beckmannG1(f.ox, f.oy, f.oz, alpha);
        g = ((f.ih > 0.0f) & (f.oh > 0.0f)) ? g : 0.0f;
        float spec = d * g / (4.0f * f.iz * f.oz);
        float c = minf(maxf(f.ih, 0.0f), 1.0f);
        float s2 = (1.0f - c) * (1.0f + c);
        float fr = conductorF(c, s2, kGoldEta[0], kGoldK[0]);
        float fg = conductorF(c, s2, kGoldEta[1], kGoldK[1]);
        float fb = conductorF(c, s2, kGoldEta[2], kGoldK[2]);
        invalid += store(f, inOk, fr * spec, fg * spec, fb * spec, outR, outG, outB, i);
    }
    return invalid;
}

// ---- (c) anisotropic GGX + height-correlated Smith + dielectric ----

template <bool HasRoughX, bool HasRoughY>
[[gnu::noinline]] int32_t anisoGgxDielectricLoop(int64_t n, const float* __restrict wx, const float* __restrict wy,
                               const float* __restrict wz, const float* __restrict vx, const float* __restrict vy,
                               const float* __restrict vz, float* __restrict outR, float* __restrict outG,
                               float* __restrict outB, const float* __restrict roughX,
                               const float* __restrict roughY) {
    int32_t invalid = 0;  // int32: GCC cannot vectorize a 64-bit count next to float lanes
    for (int64_t i = 0; i < n; ++i) {
        Frame f = frame(wx[i], wy[i], wz[i], vx[i], vy[i], vz[i]);
        bool inOk = true;
        float ax = alphaOf(HasRoughX ? roughX[i] : kAnisoRoughnessX, inOk);
        float ay = alphaOf(HasRoughY ? roughY[i] : kAnisoRoughnessY, inOk);
        // D = 1 / (pi ax ay t^2), t = hx^2/ax^2 + hy^2/ay^2 + hz^2. With
        // T = t ax^2 ay^2 (no division): D = (ax ay)^3 / (pi T^2), one
        // division per lane instead of three. T >= 1e-16 hz^2: no underflow.
        float ax2 = ax * ax, ay2 = ay * ay, axy = ax * ay;
        float t = f.hx * f.hx * ay2 + f.hy * f.hy * ax2 + f.hz * f.hz * (ax2 * ay2);
        float d = axy * axy * axy * kInvPi / (t * t);
        float spec = d * ggxVisibility(f, ax2, ay2);
        float c = minf(maxf(f.ih, 0.0f), 1.0f);
        float fr = dielectricF(c, kGlassEta[0]);
        float fg = dielectricF(c, kGlassEta[1]);
        float fb = dielectricF(c, kGlassEta[2]);
        invalid += store(f, inOk, fr * spec, fg * spec, fb * spec, outR, outG, outB, i);
    }
    return invalid;
}

// The loops count invalid lanes in 32 bits; batches are split in chunks
// small enough for that count.
constexpr int64_t kChunk = int64_t(1) << 30;

// One chunk: directions, outputs and the input slots (null: default).
struct Chunk {
    int64_t n;
    const float *ix, *iy, *iz, *ox, *oy, *oz;
    float *r, *g, *b;
    const float* in[2];
};

template <typename Loop>
int64_t chunked(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                float* const rgb[3], int slots, Loop&& loop) {
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        Chunk c{std::min(kChunk, n - start), wi[0] + start, wi[1] + start, wi[2] + start, wo[0] + start,
                wo[1] + start, wo[2] + start, rgb[0] + start, rgb[1] + start, rgb[2] + start, {nullptr, nullptr}};
        for (int s = 0; s < slots; ++s) c.in[s] = inputs && inputs[s] ? inputs[s] + start : nullptr;
        invalid += loop(c);
    }
    return invalid;
}

}  // namespace

int64_t ggxSchlick(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                   float* const rgb[3]) {
    return chunked(n, wi, wo, inputs, rgb, 1, [](const Chunk& c) {
        return c.in[0] ? ggxSchlickLoop<true>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, c.in[0])
                       : ggxSchlickLoop<false>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, nullptr);
    });
}

int64_t beckmannConductor(int64_t n, const float* const wi[3], const float* const wo[3],
                          const float* const* inputs, float* const rgb[3]) {
    return chunked(n, wi, wo, inputs, rgb, 1, [](const Chunk& c) {
        return c.in[0]
                   ? beckmannConductorLoop<true>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, c.in[0])
                   : beckmannConductorLoop<false>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, nullptr);
    });
}

int64_t anisoGgxDielectric(int64_t n, const float* const wi[3], const float* const wo[3],
                           const float* const* inputs, float* const rgb[3]) {
    return chunked(n, wi, wo, inputs, rgb, 2, [](const Chunk& c) {
        const float *x = c.in[0], *y = c.in[1];
        if (x && y) return anisoGgxDielectricLoop<true, true>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, x, y);
        if (x) return anisoGgxDielectricLoop<true, false>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, x, y);
        if (y) return anisoGgxDielectricLoop<false, true>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, x, y);
        return anisoGgxDielectricLoop<false, false>(c.n, c.ix, c.iy, c.iz, c.ox, c.oy, c.oz, c.r, c.g, c.b, x, y);
    });
}

int64_t ggxSchlickSample(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                         float* const wi[3], float* pdf, float* const weight[3]) {
    const float* rough = inputs ? inputs[0] : nullptr;
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        int64_t m = std::min(kChunk, n - start);
        auto at = [&](auto* p) { return p + start; };
        invalid += rough ? ggxSchlickSampleLoop<true>(m, at(wo[0]), at(wo[1]), at(wo[2]), at(u[0]), at(u[1]), at(u[2]),
                                                      at(wi[0]), at(wi[1]), at(wi[2]), at(pdf), at(weight[0]),
                                                      at(weight[1]), at(weight[2]), at(rough))
                         : ggxSchlickSampleLoop<false>(m, at(wo[0]), at(wo[1]), at(wo[2]), at(u[0]), at(u[1]),
                                                       at(u[2]), at(wi[0]), at(wi[1]), at(wi[2]), at(pdf),
                                                       at(weight[0]), at(weight[1]), at(weight[2]), nullptr);
    }
    return invalid;
}

int64_t ggxSchlickPdf(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                      float* pdf) {
    const float* rough = inputs ? inputs[0] : nullptr;
    int64_t invalid = 0;
    for (int64_t start = 0; start < n; start += kChunk) {
        int64_t m = std::min(kChunk, n - start);
        auto at = [&](auto* p) { return p + start; };
        invalid += rough ? ggxSchlickPdfLoop<true>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]), at(wo[1]),
                                                   at(wo[2]), at(pdf), at(rough))
                         : ggxSchlickPdfLoop<false>(m, at(wi[0]), at(wi[1]), at(wi[2]), at(wo[0]), at(wo[1]),
                                                    at(wo[2]), at(pdf), nullptr);
    }
    return invalid;
}

const std::vector<ReferenceModel>& referenceModels() {
    static const std::vector<ReferenceModel> models = {
        {"ggx_schlick", "ggx_schlick.mat", "GGX + Smith height-correlated + Schlick (rgb f0)", {"roughness"},
         &ggxSchlick, &ggxSchlickSample, &ggxSchlickPdf, &bareGgxSchlick},
        {"beckmann_conductor", "beckmann_conductor.mat", "Beckmann + Smith separable + conductor (gold)",
         {"roughness"}, &beckmannConductor, nullptr, nullptr, &bareBeckmannConductor},
        {"aniso_ggx_dielectric", "aniso_ggx_dielectric.mat",
         "anisotropic GGX + Smith height-correlated + dielectric (N-BK7)", {"roughness_x", "roughness_y"},
         &anisoGgxDielectric, nullptr, nullptr, &bareAnisoGgxDielectric},
        {"rough_glass", "rough_glass.mat", "GGX + Smith separable + dielectric (1.5), reflection and refraction",
         {"roughness"}, &roughGlass, &roughGlassSample, &roughGlassPdf, &bareRoughGlass, true},
    };
    return models;
}

const ReferenceModel* findReferenceModel(std::string_view name) {
    for (const ReferenceModel& m : referenceModels())
        if (name == m.name) return &m;
    return nullptr;
}

}  // namespace facet::aot
