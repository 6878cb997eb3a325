// The Smith masking-shadowing forms of Heitz 2014 built on the NDF's Lambda:
// separable (uncorrelated), height-correlated, direction-correlated and
// height-direction-correlated. Each GOverCosines is its G divided by
// (n.wi)(n.wo), formed from (n.v) Lambda(v), which stays finite at grazing.
#include "QuadMath.h"
#include "Immortal.h"
#include "Interpreter.h"
#include "models/ModelMath.h"

#include <limits>

namespace facet::models {
namespace {

// The cosines for the products with (n.v) Lambda below: at grazing a
// subnormal cosine times a small (n.v) Lambda underflows to 0 (1e-320 x
// 1e-5 in double, where gaussian's and abc's Lambdas are that small), which
// would make G / (ci co) Inf where it is finite. Cosines below the square
// root of the smallest normal number (2^-511 in double) are multiplied by
// its inverse `up`, an exact power of two, and the result by up again.
template <typename Real>
struct ScaledCosines {
    Real ci, co, up;
};

template <typename Real>
ScaledCosines<Real> scaledCosines(const MaskingGeometry<Real>& g) {
    using std::sqrt;
    const Real tiny = sqrt(std::numeric_limits<Real>::min());
    if (g.wi.z >= tiny || g.wo.z >= tiny) return {g.wi.z, g.wo.z, Real(1)};
    return {g.wi.z / tiny, g.wo.z / tiny, 1 / tiny};
}

// lambda(phi) of Heitz 2014 / Ashikhmin et al., phi the azimuth between wi and wo.
template <typename Real>
Real azimuthWeight(const MaskingGeometry<Real>& g) {
    using std::abs; using std::atan2;
    const Vec3<Real>&wi = g.wi, &wo = g.wo;
    Real phi = atan2(abs(wi.x * wo.y - wi.y * wo.x), wi.x * wo.x + wi.y * wo.y);
    return Real(4.41) * phi / (Real(4.41) * phi + 1);
}

template <typename Real>
struct SeparableSmith final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const override {
        return 1 / ((1 + r.lambda(g.wi)) * (1 + r.lambda(g.wo)));
    }
    // G1(v) / (n.v) = 1 / ((n.v) + (n.v) Lambda(v))
    Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const override {
        return scale / (g.wi.z + r.cosLambda(g.wi)) / (g.wo.z + r.cosLambda(g.wo));
    }
    // Uncorrelated heights: the two sides' masking are independent either way.
    Real transmittedGOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g,
                                 Real scale) const override {
        return GOverCosines(r, g, scale);
    }
};

// Heitz 2014, section 6 (transmission): a facet at height h (CDF c) is seen
// from above with probability c^Lambda(wi) and from below with (1 -
// c)^Lambda(wo); over the heights, G = B(1 + Lambda(wi), 1 + Lambda(wo)), the
// Beta function (not the reflection form 1 / (1 + Li + Lo), which pbrt-v4
// reuses for transmission). Formed in logarithms: at grazing Lambda grows
// like 1/(n.w) and G like (n.w)^(1 + Lo), both far below the range of a
// product of the factors.
template <typename Real>
Real heightCorrelatedTransmission(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) {
    using std::exp; using std::isinf; using std::lgamma; using std::log;
    Real li = r.lambda(g.wi), lo = r.lambda(g.wo);
    if (isinf(li) || isinf(lo)) return 0;  // a grazing direction (n.w underflowed in Lambda = (n.w Lambda) / n.w)
    Real logG = lgamma(1 + li) + lgamma(1 + lo) - lgamma(2 + li + lo);
    return scale * exp(logG - log(g.wi.z) - log(g.wo.z));
}

template <typename Real>
struct HeightCorrelatedSmith final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const override {
        return 1 / (1 + r.lambda(g.wi) + r.lambda(g.wo));
    }
    // 1 / (ci co (1 + Li + Lo)), ci co (1 + Li + Lo) = (ci' co' / up + co'
    // (n.wi) Li + ci' (n.wo) Lo) / up for the scaled cosines.
    Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const override {
        auto [ci, co, up] = scaledCosines(g);
        return scale / (ci * co / up + co * r.cosLambda(g.wi) + ci * r.cosLambda(g.wo)) * up;
    }
    Real transmittedGOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g,
                                 Real scale) const override {
        return heightCorrelatedTransmission(r, g, scale);
    }
};

template <typename Real>
struct DirectionCorrelatedSmith final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const override {
        using std::min;
        Real g1i = 1 / (1 + r.lambda(g.wi)), g1o = 1 / (1 + r.lambda(g.wo));
        Real w = azimuthWeight(g);
        return w * g1i * g1o + (1 - w) * min(g1i, g1o);
    }
    // ai = ci (1 + Li): G1i G1o / (ci co) = 1 / (ai ao), min(G1i, G1o) / (ci co) = 1 / max(ai co, ao ci)
    // (the products with the scaled cosines, then times up).
    Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const override {
        using std::max;
        auto [ci, co, up] = scaledCosines(g);
        Real ai = g.wi.z + r.cosLambda(g.wi), ao = g.wo.z + r.cosLambda(g.wo);
        Real w = azimuthWeight(g);
        return w * scale / ai / ao + (1 - w) * (scale / max(ai * co, ao * ci) * up);
    }
    // Directions on opposite sides see different sides of the surface: no
    // directional correlation is left, and the form is the separable one.
    Real transmittedGOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g,
                                 Real scale) const override {
        return scale / (g.wi.z + r.cosLambda(g.wi)) / (g.wo.z + r.cosLambda(g.wo));
    }
};

template <typename Real>
struct HeightDirectionCorrelatedSmith final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const override {
        using std::max; using std::min;
        Real li = r.lambda(g.wi), lo = r.lambda(g.wo);
        return 1 / (1 + max(li, lo) + azimuthWeight(g) * min(li, lo));
    }
    Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const override {
        using std::max; using std::min;
        auto [ci, co, up] = scaledCosines(g);
        Real li = co * r.cosLambda(g.wi), lo = ci * r.cosLambda(g.wo);  // ci co Li, ci co Lo (times up)
        return scale / (ci * co / up + max(li, lo) + azimuthWeight(g) * min(li, lo)) * up;
    }
    // As for direction-correlated: across the surface only the heights correlate.
    Real transmittedGOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g,
                                 Real scale) const override {
        return heightCorrelatedTransmission(r, g, scale);
    }
};

MaskingEntry smith(int id, const char* name, const char* summary) {
    MaskingEntry e = makeEntry<MaskingEntry>(ModelSlot::Masking, id, name, summary);
    e.smith = true;
    e.transmission = true;
    e.examples = {{name, "", name}};
    return e;
}

}  // namespace

std::vector<const ModelInfo*> facetModels_masking_Smith() {
    static const MaskingEntry& separable = immortal<MaskingEntry>([] {
        MaskingEntry e = smith(6, "smith_separable", "uncorrelated Smith (Heitz 2014)");
        e.formulas = makeFormulas<MaskingFormulas, SeparableSmith>();
        return e;
    }());
    static const MaskingEntry& height = immortal<MaskingEntry>([] {
        MaskingEntry e = smith(7, "smith_height_correlated", "height-correlated Smith (Heitz 2014)");
        e.representative = true;
        e.heightCorrelated = true;
        e.formulas = makeFormulas<MaskingFormulas, HeightCorrelatedSmith>();
        return e;
    }());
    static const MaskingEntry& direction = immortal<MaskingEntry>([] {
        MaskingEntry e = smith(8, "smith_direction_correlated", "direction-correlated Smith (Heitz 2014, Ashikhmin et al.)");
        e.albedoKinks.atWoH = e.albedoKinks.azimuthal = true;
        e.formulas = makeFormulas<MaskingFormulas, DirectionCorrelatedSmith>();
        return e;
    }());
    static const MaskingEntry& heightDirection = immortal<MaskingEntry>([] {
        MaskingEntry e = smith(9, "smith_height_direction_correlated", "height-direction-correlated Smith (Heitz 2014)");
        e.albedoKinks.atWoH = e.albedoKinks.azimuthal = true;
        e.formulas = makeFormulas<MaskingFormulas, HeightDirectionCorrelatedSmith>();
        return e;
    }());
    return {&separable, &height, &direction, &heightDirection};
}

}  // namespace facet::models
