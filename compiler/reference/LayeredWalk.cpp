// LayeredWalk: the position-free random walk of a dielectric interface over
// a base lobe; see the header for the model and the estimator.
#include "LayeredWalk.h"

#include "Diagnostics.h"
#include "Sampling.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

namespace facet {
namespace {

using V = Vec3<double>;

double dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V flipZ(const V& v) { return {v.x, v.y, -v.z}; }
V negated(const V& v) { return {-v.x, -v.y, -v.z}; }
V normalized(const V& v) {
    double len = std::sqrt(dot(v, v));
    return {v.x / len, v.y / len, v.z / len};
}

// Unpolarized Fresnel reflectance of a dielectric boundary for light at
// cos c (> 0) on the near side, eta = far index / near index; 1 past the
// critical angle. Written from the s and p amplitudes, independently of the
// catalog's g-form (models/fresnel).
double dielectricReflectance(double c, double eta) {
    double sin2t = (1 - c * c) / (eta * eta);
    if (sin2t >= 1) return 1;
    double ct = std::sqrt(1 - sin2t);
    double rs = (c - eta * ct) / (c + eta * ct), rp = (eta * c - ct) / (eta * c + ct);
    return (rs * rs + rp * rp) / 2;
}

// The walk stops after this many meetings with the base (Russian roulette
// ends nearly every walk long before; the limit bounds the time of one).
constexpr int kMaxLayerBounces = 256;

}  // namespace

struct LayeredWalk::Crossing {
    V w{};                 // the new direction (away from the interface)
    double weight = 0;     // f |n.w| / pdf of the drawn direction
    bool transmitted = false;
    bool valid = false;    // false: the direction died (masked, or below its side)
};

std::string LayeredWalk::unsupported(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base) {
    (void)base;  // any lobe: the base is evaluated and sampled as the interpreter does
    std::string why = MicrosurfaceWalk::unsupported(top);
    if (!why.empty()) return "the top: " + why;
    if (std::strcmp(top.fresnel->name, "dielectric") != 0)
        return std::string("the top's Fresnel is '") + top.fresnel->name +
               "': the layered walk reads the top as a dielectric interface and needs fresnel = dielectric(eta)";
    return "";
}

LayeredWalk::LayeredWalk(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base,
                         LayerAbsorption absorption)
    : top_(top), base_(base), absorption_(absorption) {
    internal_assert(unsupported(top, base).empty()) << "layered walk: " << unsupported(top, base);
    for (int ch = 0; ch < 3; ++ch) eta_[ch] = top.fresnelArgs.channel(0, ch);
}

double LayeredWalk::lambda(const V& w) const {
    V up{w.x, w.y, std::fabs(w.z)};
    double cl = top_.ndf->formulas.get<double>().visibleCosLambda(top_.ndfArgs, up);
    return cl == 0 ? 0.0 : cl / up.z;
}

double LayeredWalk::transmittance(const V& w, int ch) const {
    double sigma = absorption_.sigma[ch];
    return sigma == 0 ? 1.0 : std::exp(-sigma / std::fabs(w.z));
}

double LayeredWalk::interfaceReflection(const V& wi, const V& wo, int ch) const {
    if (!(wi.z > 0 && wo.z > 0) || eta_[ch] == 1) return 0;
    V h = normalized({wi.x + wo.x, wi.y + wo.y, wi.z + wo.z});
    double F = dielectricReflectance(std::min(1.0, dot(wo, h)), eta_[ch]);
    return top_.D(h) * F / (4 * wi.z * wo.z * (1 + lambda(wi) + lambda(wo)));
}

LayeredWalk::Crossing LayeredWalk::scatter(const V& w, double eta, bool transmitOnly, bool radiance,
                                           WalkRandom& random) const {
    Crossing out;
    bool below = w.z < 0;
    V up = below ? flipZ(w) : w;  // in the frame where w's side is up
    double u0 = random.next(), u1 = random.next(), u2 = random.next();
    if (!(up.z > 0)) return out;
    if (eta == 1) {  // index-matched: the interface is not there
        out.w = negated(w), out.weight = 1, out.transmitted = out.valid = true;
        return out;
    }
    V m = top_.ndf->formulas.get<double>().sampleVisibleNormal(top_.ndfArgs, up, u1, u2);
    double c = dot(up, m);
    if (!(c > 0)) return out;
    double F = dielectricReflectance(std::min(1.0, c), eta);
    double g1 = 1 + lambda(up);  // 1 / G1(w)
    V o;
    if (!transmitOnly && u0 < F) {
        o = {2 * c * m.x - up.x, 2 * c * m.y - up.y, 2 * c * m.z - up.z};
        if (!(o.z > 0)) return out;
        out.weight = g1 / (g1 + lambda(o));  // G2 / G1
    } else {
        double sin2t = (1 - c * c) / (eta * eta);
        if (sin2t >= 1) return out;  // total internal reflection: nothing refracts
        double ct = std::sqrt(1 - sin2t);
        o = normalized({-up.x / eta + (c / eta - ct) * m.x, -up.y / eta + (c / eta - ct) * m.y,
                        -up.z / eta + (c / eta - ct) * m.z});
        if (!(o.z < 0)) return out;
        out.weight = g1 / (g1 + lambda(o)) * (transmitOnly ? 1 - F : 1.0) / (radiance ? eta * eta : 1.0);
        out.transmitted = true;
    }
    out.w = below ? flipZ(o) : o;
    out.valid = out.weight > 0;
    return out;
}

namespace {

// A direction from the base for the walk arriving along -wo (wo up): the
// lobe's reference sampler, or the cosine lobe for a diffuse lobe. Weight
// f (n.wi) / pdf per channel; wi = 0 when there is none.
SampleResult<double> sampleBase(const ResolvedMaterial<double>& base, const V& wo, WalkRandom& random) {
    std::array<double, 3> u{random.next(), random.next(), random.next()};
    if (base.ndf) return sampleBrdf(base, wo, u);
    SampleResult<double> s;
    double r = std::sqrt(u[1]), phi = 2 * std::numbers::pi * u[2];
    s.wi = {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - u[1]))};
    s.pdf = s.wi.z / std::numbers::pi;
    if (s.pdf > 0) {
        std::array<double, 3> f = base.brdf(s.wi, wo);
        for (int ch = 0; ch < 3; ++ch) s.weight[ch] = f[ch] * std::numbers::pi;
    }
    return s;
}

// Russian roulette after `depth` bounces: true when the walk ends here;
// otherwise beta is reweighted by the survival probability.
bool roulette(std::array<double, 3>& beta, int depth, WalkRandom& random) {
    if (depth < 3) return false;
    double most = std::max({beta[0], beta[1], beta[2]});
    if (most >= 0.25) return false;
    double q = std::max(0.0, 1 - most);
    if (random.next() < q) return true;
    for (double& b : beta) b /= 1 - q;
    return false;
}

}  // namespace

std::array<double, 3> LayeredWalk::walkChannels(const V& wi, const V& wo, double eta, const std::array<bool, 3>& channels,
                                                WalkRandom& random) const {
    std::array<double, 3> f{};
    for (int ch = 0; ch < 3; ++ch)
        if (channels[ch]) f[ch] = interfaceReflection(wi, wo, ch);
    Crossing in = scatter(wo, eta, true, true, random);
    Crossing toward = scatter(wi, eta, true, false, random);  // the next events' refraction from wi
    if (!in.valid) return f;
    std::array<double, 3> beta{};
    for (int ch = 0; ch < 3; ++ch) beta[ch] = channels[ch] ? in.weight * transmittance(in.w, ch) : 0.0;
    V w = in.w;  // going down
    for (int depth = 0; depth < kMaxLayerBounces; ++depth) {
        V atBase = negated(w);
        if (toward.valid) {
            std::array<double, 3> fb = base_.brdf(negated(toward.w), atBase);
            for (int ch = 0; ch < 3; ++ch)
                f[ch] += beta[ch] * fb[ch] * toward.weight * transmittance(toward.w, ch);
        }
        SampleResult<double> s = sampleBase(base_, atBase, random);
        if (!(s.pdf > 0) || !(s.wi.z > 0)) break;
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= s.weight[ch] * transmittance(s.wi, ch);
        Crossing back = scatter(negated(s.wi), 1 / eta, false, true, random);
        if (!back.valid || back.transmitted) break;  // leaving: its light was counted by the next events
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= back.weight * transmittance(back.w, ch);
        w = back.w;
        if (roulette(beta, depth, random)) break;
    }
    return f;
}

WalkSample LayeredWalk::sampleChannels(const V& wo, double eta, const std::array<bool, 3>& channels,
                                       WalkRandom& random) const {
    WalkSample out;
    Crossing first = scatter(wo, eta, false, true, random);
    if (!first.valid) return out;
    out.order = 1;
    std::array<double, 3> beta{};
    for (int ch = 0; ch < 3; ++ch) beta[ch] = channels[ch] ? first.weight : 0.0;
    if (!first.transmitted) {
        out.wi = first.w, out.weight = beta;
        return out;
    }
    for (int ch = 0; ch < 3; ++ch) beta[ch] *= transmittance(first.w, ch);
    V w = first.w;
    for (int depth = 0; depth < kMaxLayerBounces; ++depth) {
        SampleResult<double> s = sampleBase(base_, negated(w), random);
        ++out.order;
        if (!(s.pdf > 0) || !(s.wi.z > 0)) return out;
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= s.weight[ch] * transmittance(s.wi, ch);
        Crossing back = scatter(negated(s.wi), 1 / eta, false, true, random);
        ++out.order;
        if (!back.valid) return out;
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= back.weight;
        if (back.transmitted) {
            out.wi = back.w, out.weight = beta;
            return out;
        }
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= transmittance(back.w, ch);
        w = back.w;
        if (roulette(beta, depth, random)) return out;
    }
    out.abandoned = true;
    return out;
}

std::array<double, 3> LayeredWalk::pathBrdf(const V& wi, const V& wo, WalkRandom& random) const {
    std::array<double, 3> f{};
    if (!(wi.z > 0 && wo.z > 0)) return f;
    std::array<bool, 3> done{};
    for (int ch = 0; ch < 3; ++ch) {
        if (done[ch]) continue;
        std::array<bool, 3> same{};
        for (int k = ch; k < 3; ++k) same[k] = done[k] = !done[k] && eta_[k] == eta_[ch];
        std::array<double, 3> part = walkChannels(wi, wo, eta_[ch], same, random);
        for (int k = 0; k < 3; ++k)
            if (same[k]) f[k] = part[k];
    }
    return f;
}

WalkSample LayeredWalk::sample(const V& wo, WalkRandom& random) const {
    WalkSample out;
    if (!(wo.z > 0)) return out;
    // One walk per distinct eta; a dispersive top leaves in one direction
    // per eta, so its sample keeps the first group's direction and reports
    // the others' weights only through albedo().
    std::array<bool, 3> done{};
    for (int ch = 0; ch < 3; ++ch) {
        if (done[ch]) continue;
        std::array<bool, 3> same{};
        for (int k = ch; k < 3; ++k) same[k] = done[k] = !done[k] && eta_[k] == eta_[ch];
        WalkSample part = sampleChannels(wo, eta_[ch], same, random);
        if (ch == 0) out.wi = part.wi, out.order = part.order;
        out.abandoned |= part.abandoned;
        for (int k = 0; k < 3; ++k)
            if (same[k]) out.weight[k] = part.weight[k];
    }
    return out;
}

WalkEstimate LayeredWalk::brdf(const V& wi, const V& wo, int64_t paths, uint64_t seed) const {
    WalkAccumulator acc;
    for (int64_t k = 0; k < paths; ++k) {
        WalkRandom random(seed, uint64_t(k));
        acc.add(pathBrdf(wi, wo, random));
    }
    return acc.estimate();
}

WalkEstimate LayeredWalk::albedo(const V& wo, int64_t paths, uint64_t seed) const {
    WalkAccumulator acc;
    int64_t abandoned = 0;
    for (int64_t k = 0; k < paths; ++k) {
        WalkRandom random(seed, uint64_t(k));
        WalkSample s = sample(wo, random);
        abandoned += s.abandoned;
        acc.add(s.weight);
    }
    return acc.estimate(abandoned);
}

}  // namespace facet
