// The masking terms that do not derive from the NDF: none, implicit, the
// V-cavity of Cook & Torrance, Kelemen's, Neumann's, and Schlick's
// approximation of Smith with a constant k. Each GOverCosines is its G
// divided by (n.wi)(n.wo) and simplified, with `scale` (D) entering first
// and divisions chained, so that no intermediate product of small cosines
// underflows (double-denormal directions) where the result is representable.
#include "QuadMath.h"
#include "Immortal.h"
#include "Interpreter.h"
#include "models/ModelMath.h"

namespace facet::models {
namespace {

template <typename Real>
struct NoMasking final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>&) const override { return 1; }
    Real GOverCosines(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g, Real scale) const override {
        return scale / g.wi.z / g.wo.z;
    }
};

template <typename Real>
struct ImplicitMasking final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g) const override { return g.wi.z * g.wo.z; }
    Real GOverCosines(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>&, Real scale) const override {
        return scale;
    }
};

template <typename Real>
struct CookTorranceMasking final : MaskingFormulas<Real> {
    // min(1, 2 nh co / oh, 2 nh ci / oh)
    Real G(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g) const override {
        using std::min;
        Real ci = g.wi.z, co = g.wo.z, nh = g.h.z, oh = g.oh;
        return min(Real(1), min(2 * nh * co / oh, 2 * nh * ci / oh));
    }
    Real GOverCosines(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g, Real scale) const override {
        using std::min;
        Real ci = g.wi.z, co = g.wo.z;
        Real k = scale / g.oh * (2 * g.h.z);
        return min(scale / ci / co, min(k / ci, k / co));
    }
};

template <typename Real>
struct KelemenMasking final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g) const override {
        return g.wi.z * g.wo.z / (g.oh * g.oh);
    }
    Real GOverCosines(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g, Real scale) const override {
        return scale / g.oh / g.oh;
    }
};

template <typename Real>
struct NeumannMasking final : MaskingFormulas<Real> {
    Real G(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g) const override {
        using std::max;
        return g.wi.z * g.wo.z / max(g.wi.z, g.wo.z);
    }
    Real GOverCosines(const ResolvedMaterial<Real>&, const MaskingGeometry<Real>& g, Real scale) const override {
        using std::max;
        return scale / max(g.wi.z, g.wo.z);
    }
};

constexpr int kSchlickK = 0;

template <typename Real>
struct SchlickSmithMasking final : MaskingFormulas<Real> {
    // G1(c) = c / (c (1 - k) + k)
    Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const override {
        Real k = r.maskingArgs[kSchlickK];
        auto g1 = [&](Real c) { return c / (c * (1 - k) + k); };
        return g1(g.wi.z) * g1(g.wo.z);
    }
    // G1(c) / c = 1 / (c (1 - k) + k)
    Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const override {
        Real k = r.maskingArgs[kSchlickK];
        return scale / (g.wi.z * (1 - k) + k) / (g.wo.z * (1 - k) + k);
    }
};

MaskingEntry empirical(int id, const char* name, const char* summary, const char* energyNote) {
    MaskingEntry e = makeEntry<MaskingEntry>(ModelSlot::Masking, id, name, summary);
    e.energyNote = energyNote;
    e.examples = {{name, "", name}};
    return e;
}

constexpr const char* kNoMicrosurface = "an empirical G with no microsurface behind it: not bounded by construction";

}  // namespace

std::vector<const ModelInfo*> facetModels_masking_Empirical() {
    static const MaskingEntry& none = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(0, "none", "G = 1",
                                   "masking none ignores shadowing: the albedo grows like 1/(2 cos theta_o)");
        e.representative = true;
        e.formulas = makeFormulas<MaskingFormulas, NoMasking>();
        return e;
    }());
    static const MaskingEntry& implicit = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(1, "implicit", "G = (n.wi)(n.wo)", kNoMicrosurface);
        e.formulas = makeFormulas<MaskingFormulas, ImplicitMasking>();
        return e;
    }());
    static const MaskingEntry& cookTorrance = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(2, "cook_torrance", "V-cavity (Cook & Torrance 1982)", "");
        e.albedoKinks.atWoH = true;
        e.albedoKinks.vCavity = true;
        e.formulas = makeFormulas<MaskingFormulas, CookTorranceMasking>();
        return e;
    }());
    static const MaskingEntry& kelemen = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(3, "kelemen", "Kelemen & Szirmay-Kalos 2001", kNoMicrosurface);
        e.albedoKinks.cutLayer = true;
        e.formulas = makeFormulas<MaskingFormulas, KelemenMasking>();
        return e;
    }());
    static const MaskingEntry& neumann = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(4, "neumann", "Neumann et al. 1999", kNoMicrosurface);
        e.albedoKinks.atWoH = true;
        e.formulas = makeFormulas<MaskingFormulas, NeumannMasking>();
        return e;
    }());
    static const MaskingEntry& schlickSmith = immortal<MaskingEntry>([] {
        MaskingEntry e = empirical(5, "schlick_smith", "Schlick 1994 approximation of Smith",
                                   "Schlick's G1 ignores the NDF: exceeds 1 for heavy-tailed (gtr gamma <= 1.5) and "
                                   "anisotropic lobes");
        e.canonical = {{"k", ValueType::Float, 0, 1, "k"}};
        e.forms = {ModelForm{{{"k", ValueType::Float, {kSchlickK}}}}};
        e.tableShapeParams = {kSchlickK};
        e.examples = {{"schlick_smith", "input k = 0.15;", "schlick_smith(k)"}};
        e.hardCases = {
            {"hcc_schlick_smith_k0", "ndf = beckmann(0.3); masking = schlick_smith(0);"},
            {"hcc_schlick_smith_k1", "ndf = ggx(0.3); masking = schlick_smith(1);"},
        };
        e.formulas = makeFormulas<MaskingFormulas, SchlickSmithMasking>();
        return e;
    }());
    return {&none, &implicit, &cookTorrance, &kelemen, &neumann, &schlickSmith};
}

}  // namespace facet::models
