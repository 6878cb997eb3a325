// MicrosurfaceDielectric: the random walk on a dielectric microsurface
// (Heitz et al. 2016, section 5), the members of MicrosurfaceWalk for a lobe
// whose Fresnel is `dielectric` and the boundary crossing the layered walk
// uses. The header says what the walk is.
//
// Below the surface the walk uses the symmetry of the microsurface: seen
// from below with every direction negated, the lower side is the upper side
// of the same kind of surface (the NDFs are symmetric under m -> -m with
// z kept, and the uniform heights under h -> -h, which maps the height CDF
// c to 1 - c). So a ray in the lower medium travelling along w at height
// c is walked as a ray along -w at 1 - c above, and a facet it meets is the
// negated visible normal of -v.
#include "MicrosurfaceWalk.h"

#include <cmath>

namespace facet {
namespace {

using V = Vec3<double>;

double dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V negated(const V& v) { return {-v.x, -v.y, -v.z}; }
V normalized(const V& v) {
    double len = std::sqrt(dot(v, v));
    return {v.x / len, v.y / len, v.z / len};
}

// The refraction of a ray arriving along -v at the facet m (v.m = c > 0),
// eta = far index / near index, given the far side's cos ct.
V refract(const V& v, const V& m, double c, double ct, double eta) {
    double k = c / eta - ct;
    return normalized({-v.x / eta + k * m.x, -v.y / eta + k * m.y, -v.z / eta + k * m.z});
}

}  // namespace

double MicrosurfaceWalk::dielectricPhase(const V& v, bool outside, const V& wi, double eta) const {
    if (outside) {
        // Reflection on the upper side: D_v(h) F / (4 v.h) = D(h) F / (4 A(v)).
        V h = {v.x + wi.x, v.y + wi.y, v.z + wi.z};
        double len = std::sqrt(dot(h, h));
        if (!(len > 0)) return 0;
        h = {h.x / len, h.y / len, h.z / len};
        double c = dot(v, h);
        if (!(h.z > 0 && c > 0)) return 0;
        return lobe_.D(h) * dielectricReflectance(std::min(1.0, c), eta) / (4 * projectedArea(v));
    }
    // Refraction from the lower medium (index eta relative to the upper)
    // up to wi: the facet m faces the lower medium (m.z < 0), m along
    // -(eta v + wi); density D_v(m) (1 - F) |wi.m| / (eta v.m + wi.m)^2, with
    // D_v(m) = (v.m) D(-m) / A_lower(v), A_lower(v) = A(-v) by the symmetry.
    V m = {eta * v.x + wi.x, eta * v.y + wi.y, eta * v.z + wi.z};
    double len = std::sqrt(dot(m, m));
    if (!(len > 0)) return 0;
    m = {-m.x / len, -m.y / len, -m.z / len};
    if (m.z > 0) m = negated(m);
    double cv = dot(v, m), ci = dot(wi, m);
    if (!(cv > 0 && ci < 0)) return 0;
    double F = dielectricReflectance(std::min(1.0, cv), 1 / eta);
    double denominator = eta * cv + ci;
    return cv * lobe_.D(negated(m)) / projectedArea(negated(v)) * (1 - F) * -ci / (denominator * denominator);
}

MicrosurfaceWalk::DielectricPath MicrosurfaceWalk::dielectricWalk(const V& wo, double eta, WalkRandom& random,
                                                                  WalkOrders orders, const V* wi, double* sum) const {
    DielectricPath path;
    double lambdaI = wi ? lambdaAbove(*wi) : 0.0;
    V w = negated(wo);  // the ray's direction of travel
    double c = 1;       // its height as the upper side's CDF
    bool outside = true;
    for (int order = 0; order <= kMaxWalkSteps; ++order) {
        double next = outside ? nextHeight(w, c, random.next()) : nextHeight(negated(w), 1 - c, random.next());
        if (next < 0) {  // it leaves: upward from above, downward from below
            path.exit = {w, !outside, true};
            path.order = order;
            return path;
        }
        c = outside ? next : 1 - next;
        V v = negated(w);
        if (wi && orders.counts(order + 1)) {
            double unshadowed = lambdaI == 0 ? 1.0 : std::exp(lambdaI * std::log(c));
            *sum += dielectricPhase(v, outside, *wi, eta) * unshadowed;
        }
        if ((orders.maxOrder > 0 && order + 1 >= orders.maxOrder) || (orders.onlyOrder > 0 && order + 1 >= orders.onlyOrder)) {
            path.order = order + 1;  // cut: no exit
            return path;
        }
        V m = outside ? visibleNormal(v, random) : negated(visibleNormal(negated(v), random));
        double cosVm = std::min(1.0, dot(v, m)), etaHere = outside ? eta : 1 / eta;
        double sin2t = (1 - cosVm * cosVm) / (etaHere * etaHere);
        if (random.next() < dielectricReflectance(cosVm, etaHere) || sin2t >= 1) {
            double d = 2 * dot(w, m);
            w = normalized({w.x - d * m.x, w.y - d * m.y, w.z - d * m.z});
        } else {
            w = refract(v, m, cosVm, std::sqrt(1 - sin2t), etaHere);
            outside = !outside;
        }
    }
    path.order = kMaxWalkSteps;
    return path;  // abandoned: exit.valid = false
}

InterfaceExit MicrosurfaceWalk::cross(const V& from, double eta, WalkRandom& random) const {
    if (eta == 1) return {negated(from), true, true};  // index-matched: no boundary
    if (from.z > 0) return dielectricWalk(from, eta, random, {}, nullptr, nullptr).exit;
    // From below: the same walk in the negated frame, where from's side is
    // above and the far side (still eta relative to it) below.
    InterfaceExit e = dielectricWalk(negated(from), eta, random, {}, nullptr, nullptr).exit;
    e.w = negated(e.w);
    return e;
}

WalkSample MicrosurfaceWalk::sampleDielectric(const V& wo, WalkRandom& random, WalkOrders orders) const {
    // One walk per distinct eta (a dispersive boundary sends each its own
    // way); the sample keeps the first group's direction.
    WalkSample s;
    if (!(wo.z > 0)) return s;
    forEachEta(eta_, [&](double eta, const std::array<bool, 3>& same) {
        DielectricPath p = dielectricWalk(wo, eta, random, orders, nullptr, nullptr);
        bool reflected = p.exit.valid && !p.exit.transmitted && orders.counts(p.order);
        for (int k = 0; k < 3; ++k)
            if (same[k]) s.weight[k] = reflected ? 1.0 : 0.0;
        if (same[0]) {
            s.order = p.order, s.transmitted = p.exit.valid && p.exit.transmitted;
            if (reflected) s.wi = p.exit.w;
        }
        s.abandoned |= !p.exit.valid && p.order >= kMaxWalkSteps;
    });
    return s;
}

std::array<double, 3> MicrosurfaceWalk::pathBrdfCosDielectric(const V& wi, const V& wo, WalkRandom& random,
                                                              WalkOrders orders, bool* abandoned) const {
    std::array<double, 3> out{};
    if (abandoned) *abandoned = false;
    if (!(wi.z > 0) || !(wo.z > 0)) return out;
    forEachEta(eta_, [&](double eta, const std::array<bool, 3>& same) {
        double sum = 0;
        DielectricPath p = dielectricWalk(wo, eta, random, orders, &wi, &sum);
        if (!p.exit.valid && p.order >= kMaxWalkSteps) {
            if (abandoned) *abandoned = true;
            sum = 0;
        }
        for (int k = 0; k < 3; ++k)
            if (same[k]) out[k] = sum;
    });
    return out;
}

}  // namespace facet
