// MicrosurfaceWalk: the random walk on the Smith microsurface (Heitz et al.
// 2016); see the header for the model and its two estimators.
#include "MicrosurfaceWalk.h"

#include "Diagnostics.h"

#include <cmath>

namespace facet {
namespace {

using V = Vec3<double>;

double dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

V normalized(const V& v) {
    double len = std::sqrt(dot(v, v));
    return {v.x / len, v.y / len, v.z / len};
}

// The mirror direction of w about the facet normal m: w - 2 (w.m) m.
V reflect(const V& w, const V& m) {
    double d = 2 * dot(w, m);
    return {w.x - d * m.x, w.y - d * m.y, w.z - d * m.z};
}

}  // namespace

std::string MicrosurfaceWalk::unsupported(const ResolvedMaterial<double>& lobe) {
    if (!lobe.ndf) return "a diffuse lobe has no microsurface";
    if (lobe.ndf->wholeLobe) return std::string("'") + lobe.ndf->name + "' is a whole lobe, not a distribution of microfacet normals";
    if (!lobe.ndf->visibleNormals)
        return std::string("'") + lobe.ndf->name + "' has no exact Smith Lambda with a visible-normal sampler (the walk needs both)";
    return "";
}

MicrosurfaceWalk::MicrosurfaceWalk(const ResolvedMaterial<double>& lobe) : lobe_(lobe) {
    internal_assert(unsupported(lobe).empty()) << "microsurface walk on an unsupported lobe: " << unsupported(lobe);
    int etaParam = lobe.fresnel->refractiveIndexParam;
    dielectric_ = etaParam >= 0;
    for (int ch = 0; ch < 3; ++ch) eta_[ch] = dielectric_ ? lobe.fresnelArgs.channel(etaParam, ch) : 1.0;
}

double MicrosurfaceWalk::lambdaAbove(const V& v) const {
    double cl = lobe_.ndf->formulas.get<double>().visibleCosLambda(lobe_.ndfArgs, v);
    return cl == 0 ? 0.0 : cl / v.z;  // cl > 0 at v.z = 0 gives +Inf: every grazing ray is stopped
}

double MicrosurfaceWalk::projectedArea(const V& v) const {
    const auto& ndf = lobe_.ndf->formulas.get<double>();
    if (v.z >= 0) return v.z + ndf.visibleCosLambda(lobe_.ndfArgs, v);
    return ndf.visibleCosLambda(lobe_.ndfArgs, V{-v.x, -v.y, -v.z});
}

double MicrosurfaceWalk::nextHeight(const V& w, double c, double u) const {
    // With v = 1 - u in (0, 1]: upward, the ray leaves when v < c^Lambda
    // (the probability that nothing above c blocks it), else it meets the
    // surface at c' = c v^(-1/Lambda); downward, Lambda(w) = -1 - Lambda(-w)
    // and c' = c v^(1/(1 + Lambda(-w))), always a meeting. In logs, so that
    // c' keeps its relative precision however small c gets.
    double v = 1 - u;
    if (w.z > 0) {
        double lambda = lambdaAbove(w);
        if (lambda == 0) return -1;  // nothing masks this direction
        double logC = std::log(c);
        if (std::log(v) < lambda * logC) return -1;
        double next = std::exp(logC - std::log(v) / lambda);
        return next < 1 ? next : 1.0;
    }
    double lambdaDown = w.z < 0 ? lambdaAbove(V{-w.x, -w.y, -w.z}) : 0.0;
    if (w.z == 0) return c;  // exactly grazing: Lambda = +Inf, met at once
    return c * std::exp(std::log(v) / (1 + lambdaDown));
}

V MicrosurfaceWalk::visibleNormal(const V& v, WalkRandom& random) const {
    double u1 = random.next(), u2 = random.next();
    return lobe_.ndf->formulas.get<double>().sampleVisibleNormal(lobe_.ndfArgs, v, u1, u2);
}

WalkSample MicrosurfaceWalk::sample(const V& wo, WalkRandom& random, WalkOrders orders) const {
    if (dielectric_) return sampleDielectric(wo, random, orders);
    WalkSample s;
    if (!(wo.z > 0)) return s;
    std::array<double, 3> weight{1, 1, 1};
    V w{-wo.x, -wo.y, -wo.z};  // the ray's direction of travel
    double c = 1;              // its height, as the height CDF: above everything
    for (int order = 0; order <= kMaxWalkSteps; ++order) {
        c = nextHeight(w, c, random.next());
        s.order = order;
        if (c < 0) {  // it leaves (never before the first reflection: wo's ray goes down)
            if (orders.counts(order)) s.wi = w, s.weight = weight;
            return s;
        }
        if (orders.maxOrder > 0 && order == orders.maxOrder) {  // cut before reflection maxOrder + 1
            s.order = order + 1;
            return s;
        }
        V v{-w.x, -w.y, -w.z};
        V m = visibleNormal(v, random);
        double cosVm = dot(v, m);
        for (int ch = 0; ch < 3; ++ch) weight[ch] *= lobe_.F(cosVm, ch);
        w = normalized(reflect(w, m));
    }
    s.abandoned = true;
    return s;
}

std::array<double, 3> MicrosurfaceWalk::pathBrdfCos(const V& wi, const V& wo, WalkRandom& random, WalkOrders orders,
                                                    bool* abandoned) const {
    if (dielectric_) return pathBrdfCosDielectric(wi, wo, random, orders, abandoned);
    std::array<double, 3> sum{};
    if (abandoned) *abandoned = false;
    if (!(wi.z > 0) || !(wo.z > 0)) return sum;
    std::array<double, 3> weight{1, 1, 1};
    double lambdaI = lambdaAbove(wi);
    V w{-wo.x, -wo.y, -wo.z};
    double c = 1;
    for (int order = 1; order <= kMaxWalkSteps; ++order) {
        c = nextHeight(w, c, random.next());
        if (c < 0) return sum;
        V v{-w.x, -w.y, -w.z};
        if (orders.counts(order)) {
            // Next event toward wi: the phase function D_v(h) F / (4 v.h) =
            // D(h) F / (4 A(v)) at the half vector of v and wi, times
            // G1(wi) from height c, c^Lambda(wi).
            V h = {v.x + wi.x, v.y + wi.y, v.z + wi.z};
            double len = std::sqrt(dot(h, h));
            if (len > 0) {
                h = {h.x / len, h.y / len, h.z / len};
                double cosVh = dot(v, h);
                if (h.z > 0 && cosVh > 0) {
                    double phase = lobe_.D(h) / (4 * projectedArea(v));
                    double unshadowed = lambdaI == 0 ? 1.0 : std::exp(lambdaI * std::log(c));
                    for (int ch = 0; ch < 3; ++ch) sum[ch] += weight[ch] * lobe_.F(cosVh, ch) * phase * unshadowed;
                }
            }
        }
        if (orders.maxOrder > 0 && order >= orders.maxOrder) return sum;
        if (orders.onlyOrder > 0 && order >= orders.onlyOrder) return sum;
        V m = visibleNormal(v, random);
        double cosVm = dot(v, m);
        for (int ch = 0; ch < 3; ++ch) weight[ch] *= lobe_.F(cosVm, ch);
        w = normalized(reflect(w, m));
    }
    if (abandoned) *abandoned = true;
    return {};
}

WalkEstimate MicrosurfaceWalk::brdf(const V& wi, const V& wo, int64_t paths, uint64_t seed, WalkOrders orders) const {
    WalkAccumulator acc;
    int64_t abandoned = 0;
    for (int64_t k = 0; k < paths; ++k) {
        WalkRandom random(seed, uint64_t(k));
        bool lost = false;
        std::array<double, 3> x = pathBrdfCos(wi, wo, random, orders, &lost);
        abandoned += lost;
        for (double& value : x) value /= wi.z;
        acc.add(x);
    }
    return acc.estimate(abandoned);
}

WalkEstimate MicrosurfaceWalk::albedo(const V& wo, int64_t paths, uint64_t seed, WalkOrders orders) const {
    WalkAccumulator acc;
    int64_t abandoned = 0;
    for (int64_t k = 0; k < paths; ++k) {
        WalkRandom random(seed, uint64_t(k));
        WalkSample s = sample(wo, random, orders);
        abandoned += s.abandoned;
        acc.add(s.weight);
    }
    return acc.estimate(abandoned);
}

}  // namespace facet
