// MicrosurfaceWalk: the multiple-scattering microfacet BSDF of Heitz, Hanika,
// d'Eon & Dachsbacher 2016 as a stochastic reference (SPEC 13): a random
// walk of a ray on the Smith microsurface of a lobe's NDF, scattered by each
// microfacet it meets (reflected; on a dielectric, reflected or refracted),
// until it leaves the surface.
//
// The microsurface is the one Smith's height-correlated masking assumes: an
// uncorrelated random surface with the lobe's distribution of normals and a
// height distribution that does not matter (any gives the same BSDF); the
// walk uses the uniform one, so that a height is its own CDF value c in
// [0, 1] and is tracked as c alone. A ray at height c going in direction w
// meets the surface again with probability 1 - c^Lambda(w) (w upward;
// always when w points down, where Lambda(w) = -1 - Lambda(-w)); the facet
// it meets is a visible normal of -w, D_-w(m) = <-w, m>+ D(m) / A(-w), A the
// projected area. Each reflection multiplies the path's weight by the
// Fresnel term of the lobe at the facet.
//
// What the walk needs from the catalog: D, the exact Smith Lambda of D
// (NdfFormulas::visibleCosLambda) and a visible-normal sampler that also
// takes directions below the horizon (a ray going up meets facets facing
// down its path), i.e. the NDFs with NdfEntry::visibleNormals.
//
// A lobe with a `dielectric` Fresnel is walked as Heitz et al.'s dielectric
// microsurface (their section 5; MicrosurfaceDielectric.cpp): at each facet
// the ray reflects with probability F and otherwise refracts into the other
// medium, where it walks the same surface from below (heights and
// directions negated, eta inverted) until it comes back or leaves downward.
// The lobe's reflection is the walks that leave upward; what leaves
// downward is the transmission (cross(), the layered walk's interface).
//
// Two estimators, both unbiased, seeded and with a standard error:
//   - sample(): the walk from wo; it leaves in direction wi with weight
//     f (n.wi) / pdf = the product of the Fresnel terms met (1 with F = 1:
//     the walk conserves energy by construction; 1 for a dielectric's walks
//     that leave upward, F being the choice there), and the number of facets
//     met on the way (its scattering order);
//   - brdf(): f(wi, wo) by next-event estimation at every reflection of the
//     walk from wo: the phase function D_v(h) F(v.h) / (4 <v, h>) toward wi
//     (v = -w, h the half vector of v and wi) times the probability c^Lambda(wi)
//     that wi leaves from that height unshadowed. The sum over a path
//     estimates f (n.wi); order 1 alone is the single-scattering lobe with
//     height-correlated Smith masking, exactly in expectation.
// Both can keep one scattering order or cut the walk after a given order.
//
// The reference is in double; it is a Monte Carlo estimate, so its accuracy is
// its standard error, not double's resolution.
#pragma once

#include "Interpreter.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

namespace facet {

// The walk's random numbers: xoshiro256** (Blackman & Vigna), its state
// filled by splitmix64 from (seed, path), so that every walk of an estimate
// has its own stream: an estimate's walks do not depend on how many numbers
// the walks before them used (a walk cut early leaves the next one as it
// was), and a seed gives the same numbers on every platform. Uniform
// doubles in [0, 1) from the 53 high bits.
//
// Or, for the random-walk lobe (energy = random_walk, WalkLobe.h), the
// counter stream the kernels compute per lane in 32-bit integers: number k
// is walkHash(seed + k 0x9e3779b9) >> 8, times 2^-24.
class WalkRandom {
public:
    WalkRandom(uint64_t seed, uint64_t path) {
        uint64_t x = seed;
        x = splitmix64(x) ^ path;  // the seed hashed first, so that nearby seeds do not share streams
        for (uint64_t& word : state_) word = splitmix64(x);
    }
    static WalkRandom counterStream(uint32_t seed) {
        WalkRandom r(0, 0);
        r.counter_ = true, r.seed32_ = seed;
        return r;
    }
    double next() {
        if (counter_) return double(walkHash(seed32_ + 0x9e3779b9u * count_++) >> 8) * 0x1p-24;
        return double(nextBits() >> 11) * 0x1p-53;
    }
    // Wellons's lowbias32 integer hash (a bijection of 32-bit words).
    static uint32_t walkHash(uint32_t x) {
        x ^= x >> 16, x *= 0x7feb352du, x ^= x >> 15, x *= 0x846ca68bu, x ^= x >> 16;
        return x;
    }

private:
    static uint64_t splitmix64(uint64_t& x) {
        uint64_t z = (x += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    uint64_t nextBits() {
        uint64_t result = rotl(state_[1] * 5, 7) * 9, t = state_[1] << 17;
        state_[2] ^= state_[0], state_[3] ^= state_[1], state_[1] ^= state_[2], state_[0] ^= state_[3];
        state_[2] ^= t, state_[3] = rotl(state_[3], 45);
        return result;
    }
    std::array<uint64_t, 4> state_{};
    bool counter_ = false;
    uint32_t seed32_ = 0, count_ = 0;
};

// Which reflections count: `onlyOrder` > 0 keeps that scattering order
// alone; `maxOrder` > 0 ends every walk after that many reflections (a path
// cut there has no direction and weight 0); orders below `minOrder` do not
// count (the random-walk lobe adds orders >= 2 to its exact order 1).
struct WalkOrders {
    int onlyOrder = 0;
    int maxOrder = 0;
    int minOrder = 1;
    bool counts(int order) const {
        return order >= minOrder && (onlyOrder == 0 || order == onlyOrder) && (maxOrder == 0 || order <= maxOrder);
    }
};

// The mean of `paths` independent estimates per channel and its standard
// error (the sample standard deviation over sqrt(paths)).
struct WalkEstimate {
    std::array<double, 3> mean{}, stdError{};
    int64_t paths = 0;
    // Walks given up after kMaxWalkSteps reflections (counted as 0; none in
    // any test so far).
    int64_t abandoned = 0;
};

// Running mean and variance per channel (Welford's update) of independent
// estimates, for WalkEstimate.
struct WalkAccumulator {
    std::array<double, 3> mean{}, m2{};
    int64_t n = 0;
    void add(const std::array<double, 3>& x) {
        ++n;
        for (int ch = 0; ch < 3; ++ch) {
            double d = x[ch] - mean[ch];
            mean[ch] += d / double(n);
            m2[ch] += d * (x[ch] - mean[ch]);
        }
    }
    WalkEstimate estimate(int64_t abandoned = 0) const {
        WalkEstimate e;
        e.mean = mean, e.paths = n, e.abandoned = abandoned;
        for (int ch = 0; ch < 3; ++ch) e.stdError[ch] = n > 1 ? std::sqrt(m2[ch] / double(n - 1) / double(n)) : 0.0;
        return e;
    }
};

// One walk of sample(): wi = (0, 0, 0) and weight 0 when the walk was cut by
// WalkOrders::maxOrder or abandoned.
struct WalkSample {
    Vec3<double> wi{};
    std::array<double, 3> weight{};
    int order = 0;  // reflections (and refractions) before it left
    bool abandoned = false;
    bool transmitted = false;  // a dielectric walk that left downward (wi = 0, weight 0)
};

// How a walk through a dielectric boundary left it (MicrosurfaceWalk::cross).
struct InterfaceExit {
    Vec3<double> w{};          // the direction it left in (away from the surface)
    bool transmitted = false;  // on the far side from where it came
    bool valid = false;        // false: abandoned
};

// Unpolarized Fresnel reflectance of a dielectric boundary for light at cos
// c (> 0) on the near side, eta = far index / near index; 1 past the
// critical angle. Written from the s and p amplitudes, independently of the
// catalog's g-form (models/fresnel), for the walks that refract.
inline double dielectricReflectance(double c, double eta) {
    double sin2t = (1 - c * c) / (eta * eta);
    if (sin2t >= 1) return 1;
    double ct = std::sqrt(1 - sin2t);
    double rs = (c - eta * ct) / (c + eta * ct), rp = (eta * c - ct) / (eta * c + ct);
    return (rs * rs + rp * rp) / 2;
}

// Calls fn(eta, channels) once per distinct value of eta over the three
// channels, `channels` marking those that have it: a dispersive boundary
// refracts each value its own way, so each is walked on its own.
template <typename Fn>
void forEachEta(const std::array<double, 3>& eta, Fn&& fn) {
    std::array<bool, 3> done{};
    for (int ch = 0; ch < 3; ++ch) {
        if (done[ch]) continue;
        std::array<bool, 3> same{};
        for (int k = ch; k < 3; ++k)
            if (!done[k] && eta[k] == eta[ch]) same[k] = done[k] = true;
        fn(eta[ch], same);
    }
}

// A walk longer than this (reflections) is abandoned: with F = 1 and
// alpha = 1 fewer than one walk in 1e6 reaches order 30, so the limit only
// guards against a model that traps the ray.
inline constexpr int kMaxWalkSteps = 1 << 20;

class MicrosurfaceWalk {
public:
    // Why the walk cannot run on this lobe ("" when it can): a diffuse lobe,
    // a whole-lobe model (ward), or an NDF without an exact Smith Lambda and
    // visible-normal sampler.
    static std::string unsupported(const ResolvedMaterial<double>& lobe);

    // `lobe` must be supported (internal error otherwise); its masking,
    // energy and diffuse terms are ignored: the walk is the specular lobe's
    // multiple-scattering BSDF, with the lobe's Fresnel term at each facet.
    explicit MicrosurfaceWalk(const ResolvedMaterial<double>& lobe);

    // One walk from the unit direction wo (n.wo > 0).
    WalkSample sample(const Vec3<double>& wo, WalkRandom& random, WalkOrders orders = {}) const;
    // One walk's next-event estimate of f(wi, wo) (n.wi), per channel (unit
    // wi and wo; 0 when either is at or below the horizon).
    std::array<double, 3> pathBrdfCos(const Vec3<double>& wi, const Vec3<double>& wo, WalkRandom& random,
                                      WalkOrders orders = {}, bool* abandoned = nullptr) const;

    // f(wi, wo) from `paths` walks from wo (pathBrdfCos / (n.wi)), walk k
    // drawing from WalkRandom(seed, k).
    WalkEstimate brdf(const Vec3<double>& wi, const Vec3<double>& wo, int64_t paths, uint64_t seed,
                      WalkOrders orders = {}) const;
    // The directional albedo Int f (n.wi) dwi at wo: the mean weight of
    // `paths` samples (those of the orders kept).
    WalkEstimate albedo(const Vec3<double>& wo, int64_t paths, uint64_t seed, WalkOrders orders = {}) const;

    // The lobe's Fresnel is `dielectric`: the walk refracts as well.
    bool dielectric() const { return dielectric_; }
    // One walk through the microsurface read as a dielectric boundary, for a
    // ray arriving along -from (`from` points away from the surface on its
    // own side, above or below it); eta: the index of the far side over
    // from's side (the top lobe's eta seen from above, 1 / eta from below).
    // Needs no dielectric Fresnel of the lobe: eta is given.
    InterfaceExit cross(const Vec3<double>& from, double eta, WalkRandom& random) const;

    // The projected area A(v) = Int <v, m>+ D(m) dm of the microsurface seen
    // from v, any unit v: (n.v)(1 + Lambda(v)) above the horizon and
    // (n.-v) Lambda(-v) below it.
    double projectedArea(const Vec3<double>& v) const;
    // A visible normal of v (any unit v that meets the surface: A(v) > 0),
    // from the catalog's sampler.
    Vec3<double> visibleNormal(const Vec3<double>& v, WalkRandom& random) const;

private:
    // The height c' in (0, 1] where a ray at height c in direction w meets
    // the surface next, or a negative value when it leaves.
    double nextHeight(const Vec3<double>& w, double c, double u) const;
    // Lambda(v) for n.v > 0 (+Inf at the horizon when anything is masked).
    double lambdaAbove(const Vec3<double>& v) const;

    // The dielectric walk from above (n.wo > 0), eta of the medium below:
    // how it leaves, its order, and with `wi` (above) the next-event
    // estimate of f(wi, wo) (n.wi) for the orders kept added to *sum.
    struct DielectricPath {
        InterfaceExit exit;
        int order = 0;
    };
    DielectricPath dielectricWalk(const Vec3<double>& wo, double eta, WalkRandom& random, WalkOrders orders,
                                  const Vec3<double>* wi, double* sum) const;
    // The density of leaving a facet toward wi (above the surface) for a
    // ray seen from v at a vertex on the upper (outside) or lower side.
    double dielectricPhase(const Vec3<double>& v, bool outside, const Vec3<double>& wi, double eta) const;
    WalkSample sampleDielectric(const Vec3<double>& wo, WalkRandom& random, WalkOrders orders) const;
    std::array<double, 3> pathBrdfCosDielectric(const Vec3<double>& wi, const Vec3<double>& wo, WalkRandom& random,
                                                WalkOrders orders, bool* abandoned) const;

    const ResolvedMaterial<double>& lobe_;
    bool dielectric_ = false;
    std::array<double, 3> eta_{};  // a dielectric's eta per channel
};

}  // namespace facet
