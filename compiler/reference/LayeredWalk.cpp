// LayeredWalk: the position-free random walk of a dielectric interface over
// a base lobe; see the header for the model and the estimator.
#include "LayeredWalk.h"

#include "Diagnostics.h"
#include "Sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace facet {
namespace {

using V = Vec3<double>;

V negated(const V& v) { return {-v.x, -v.y, -v.z}; }

// The walk stops after this many meetings with the base (Russian roulette
// ends nearly every walk long before; the limit bounds the time of one).
constexpr int kMaxLayerBounces = 256;

}  // namespace

std::string LayeredWalk::unsupported(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base) {
    (void)base;  // any lobe: the base is evaluated and sampled as the interpreter does
    std::string why = MicrosurfaceWalk::unsupported(top);
    if (!why.empty()) return "the top: " + why;
    if (top.fresnel->refractiveIndexParam < 0)
        return std::string("the top's Fresnel is '") + top.fresnel->name +
               "': the layered walk reads the top as a dielectric boundary and needs fresnel = dielectric(eta)";
    return "";
}

LayeredWalk::LayeredWalk(const ResolvedMaterial<double>& top, const ResolvedMaterial<double>& base,
                         LayerAbsorption absorption)
    : top_(top), base_(base), absorption_(absorption), boundary_(top) {
    internal_assert(unsupported(top, base).empty()) << "layered walk: " << unsupported(top, base);
    for (int ch = 0; ch < 3; ++ch) eta_[ch] = top.fresnelArgs.channel(top.fresnel->refractiveIndexParam, ch);
}

double LayeredWalk::transmittance(const V& w, int ch) const {
    double sigma = absorption_.sigma[ch];
    return sigma == 0 ? 1.0 : std::exp(-sigma / std::fabs(w.z));
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
    InterfaceExit in = boundary_.cross(wo, eta, random);
    InterfaceExit toward = boundary_.cross(wi, eta, random);  // the next events' crossing from wi (adjoint: weight 1)
    if (!in.valid || !in.transmitted) return f;
    std::array<double, 3> beta{};
    for (int ch = 0; ch < 3; ++ch) beta[ch] = channels[ch] ? transmittance(in.w, ch) / (eta * eta) : 0.0;
    bool nee = toward.valid && toward.transmitted;
    V w = in.w;  // going down
    for (int depth = 0; depth < kMaxLayerBounces; ++depth) {
        V atBase = negated(w);
        if (nee) {
            std::array<double, 3> fb = base_.brdf(negated(toward.w), atBase);
            for (int ch = 0; ch < 3; ++ch) f[ch] += beta[ch] * fb[ch] * transmittance(toward.w, ch);
        }
        SampleResult<double> s = sampleBase(base_, atBase, random);
        if (!(s.pdf > 0) || !(s.wi.z > 0)) break;
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= s.weight[ch] * transmittance(s.wi, ch);
        InterfaceExit back = boundary_.cross(negated(s.wi), 1 / eta, random);
        if (!back.valid || back.transmitted) break;  // leaving: its light was counted by the next events
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= transmittance(back.w, ch);
        w = back.w;
        if (roulette(beta, depth, random)) break;
    }
    return f;
}

WalkSample LayeredWalk::sampleChannels(const V& wo, double eta, const std::array<bool, 3>& channels,
                                       WalkRandom& random) const {
    WalkSample out;
    InterfaceExit first = boundary_.cross(wo, eta, random);
    if (!first.valid) return out;
    out.order = 1;
    std::array<double, 3> beta{};
    for (int ch = 0; ch < 3; ++ch) beta[ch] = channels[ch] ? 1.0 : 0.0;
    if (!first.transmitted) {  // reflected by the boundary
        out.wi = first.w, out.weight = beta;
        return out;
    }
    for (int ch = 0; ch < 3; ++ch) beta[ch] *= transmittance(first.w, ch) / (eta * eta);
    V w = first.w;
    for (int depth = 0; depth < kMaxLayerBounces; ++depth) {
        SampleResult<double> s = sampleBase(base_, negated(w), random);
        ++out.order;
        if (!(s.pdf > 0) || !(s.wi.z > 0)) return out;
        for (int ch = 0; ch < 3; ++ch) beta[ch] *= s.weight[ch] * transmittance(s.wi, ch);
        InterfaceExit back = boundary_.cross(negated(s.wi), 1 / eta, random);
        ++out.order;
        if (!back.valid) return out;
        if (back.transmitted) {  // out of the layer: radiance back by eta^2
            for (int ch = 0; ch < 3; ++ch) beta[ch] *= eta * eta;
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
    // The boundary's own reflection (its next events; none when index-matched).
    if (eta_[0] != 1 || eta_[1] != 1 || eta_[2] != 1) {
        f = boundary_.pathBrdfCos(wi, wo, random);
        for (int ch = 0; ch < 3; ++ch) f[ch] = eta_[ch] == 1 ? 0.0 : f[ch] / wi.z;
    }
    forEachEta(eta_, [&](double eta, const std::array<bool, 3>& same) {
        std::array<double, 3> part = walkChannels(wi, wo, eta, same, random);
        for (int k = 0; k < 3; ++k)
            if (same[k]) f[k] += part[k];
    });
    return f;
}

WalkSample LayeredWalk::sample(const V& wo, WalkRandom& random) const {
    WalkSample out;
    if (!(wo.z > 0)) return out;
    // One walk per distinct eta; a dispersive top leaves in one direction
    // per eta, so its sample keeps the first group's direction and reports
    // the others' weights only through albedo().
    forEachEta(eta_, [&](double eta, const std::array<bool, 3>& same) {
        WalkSample part = sampleChannels(wo, eta, same, random);
        if (same[0]) out.wi = part.wi, out.order = part.order;
        out.abandoned |= part.abandoned;
        for (int k = 0; k < 3; ++k)
            if (same[k]) out.weight[k] = part.weight[k];
    });
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
