// ModelCatalog: everything Facet knows about each model, one entry per model.
//
// A material names five models (ndf, masking, fresnel, energy, diffuse).
// Each model is one catalog entry, defined in one file under
// compiler/models/<slot>/: its names and aliases, its parameters with their
// domains (the clamps every evaluator applies), the ways of writing its
// arguments, its traits (what the checker, the tables, the physics checks,
// the previews and the generators need to know about it), and its reference
// formulas (and, for NDFs, samplers), evaluated by the interpreter in
// double, long double and __float128, and in float: the SPEC formula in
// float that the hard-case tests hold fast mode's accuracy against. The LLVM lowering writes its own
// formulas independently (the differential tests compare the two), so
// nothing here emits IR.
//
// Every other part of Facet asks the catalog ("is this masking a Smith
// form?", "which roughness does this NDF's table use?") instead of
// switching on model kinds. The entries register themselves: the build
// lists every file of compiler/models/<slot>/ in a generated registry, so
// adding a model means adding its file.
#pragma once

#include "AST.h"
#include "Immortal.h"

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace facet {

// ---- the language side of a model -----------------------------------------

// A canonical parameter of a model: its name and type as the language sees
// it, and its domain. Every evaluator clamps the argument to [lo, hi] in
// double before anything else (a NaN stays NaN and invalidates the lane).
struct ModelParam {
    const char* name;
    ValueType type;
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    // Short tag in the names of tables keyed by this parameter (gtr's gamma
    // "g", schlick_smith's k "k"); only for tableShapeParams.
    const char* tableTag = "";
    // The value tools use where a material gives none (previews comparing
    // NDFs at matched roughness); only for tableShapeParams.
    double typical = 0;
};

// One way of writing a model's arguments, e.g. ggx(alpha) or
// ggx(alpha_x, alpha_y). Each written parameter fills one or more canonical
// parameters (ggx(alpha) fills both alpha_x and alpha_y).
struct ModelForm {
    struct Param {
        const char* name;
        ValueType type;
        std::vector<int> targets;
    };
    std::vector<Param> params;
};

constexpr int kMaxModelParams = 4;

// A way of writing a model in a generated test material (the hard-case
// sample's combinations): a key for the material name, the input
// declarations its arguments use, the statement's right-hand side, and any
// other statement it needs.
struct ModelExample {
    std::string key, inputs, stmt;
    // More statements of the example's material (most examples need none:
    // the default initializer lets their braced lists leave it out).
    std::string extra = {};
    // Combined only with the representative models of the other slots (a
    // variant that differs from another example only in how a parameter is
    // computed, independently of the other terms).
    bool sparse = false;
};

// A whole material body that drives one model to the edges of its domain
// (extreme constants, clamped inputs), for the hard-case sample.
struct ModelHardCase {
    std::string name, body;
};

// The part of an entry that the checker and every tool read.
struct ModelInfo {
    ModelSlot slot;
    // The model's index in its slot: where it is listed among the slot's
    // models (help texts, generated test cases). The ids of a slot are 0..n-1.
    int id = 0;
    const char* name;
    std::vector<const char*> aliases;
    std::vector<ModelParam> canonical;  // at most kMaxModelParams
    std::vector<ModelForm> forms;       // at least one (an empty form for no arguments)
    // masking: a Smith form, which needs the NDF's Lambda.
    // ndf: has a closed-form Smith Lambda (see also NdfEntry::tabulatedLambda).
    bool smith = false;
    const char* summary;
    // Canonical parameters that must be per-material constants when a table
    // (Kulla-Conty) is built for this model: the table is keyed by them.
    std::vector<int> tableShapeParams;
    // Test coverage: how generated materials write the model, whether it is
    // among the few a sparse example is combined with, and its extremes.
    std::vector<ModelExample> examples;
    bool representative = false;
    std::vector<ModelHardCase> hardCases;
};

// ---- resolved arguments -----------------------------------------------------

template <typename Real>
struct Vec3 {
    Real x, y, z;
};

// A model's canonical arguments for one evaluation, clamped to their
// domains, plus up to two values the entry derives from them once (the
// Gaussian NDF's normalization). Float parameters use channel 0.
template <typename Real>
struct ModelArgs {
    std::array<std::array<Real, 3>, kMaxModelParams> value{};
    std::array<bool, kMaxModelParams> given{};  // false where the written form left it unset
    std::array<Real, 2> derived{};
    Real operator[](int p) const { return value[p][0]; }
    Real channel(int p, int ch) const { return value[p][ch]; }
    void set(int p, Real x) { value[p] = {x, x, x}, given[p] = true; }
};

// The same arguments in another real type, each value converted.
template <typename To, typename From>
ModelArgs<To> convertArgs(const ModelArgs<From>& a) {
    ModelArgs<To> out;
    for (int p = 0; p < kMaxModelParams; ++p)
        for (int ch = 0; ch < 3; ++ch) out.value[p][ch] = To(a.value[p][ch]);
    out.given = a.given;
    for (size_t i = 0; i < a.derived.size(); ++i) out.derived[i] = To(a.derived[i]);
    return out;
}

template <typename Real>
struct ResolvedMaterial;

// ---- reference formulas, one interface per slot -----------------------------

// An NDF's reference formulas in one real type.
template <typename Real>
struct NdfFormulas {
    virtual ~NdfFormulas() = default;
    // D(m) for a unit m with m.z > 0.
    virtual Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const = 0;
    // (n.v) Lambda(v), v.z >= 0, for NDFs with a closed-form Lambda (finite
    // at grazing, where Lambda itself grows like 1/(n.v)).
    virtual Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const;
    // Whole-lobe NDFs (ward): the lobe without F, f = F lobe, for the unit
    // half vector h and cosines ci, co > 0.
    virtual Real wholeLobe(const ModelArgs<Real>& a, const Vec3<Real>& h, Real ci, Real co) const;
    // Fills a.derived from the clamped parameters (valid ones only).
    virtual void derive(ModelArgs<Real>& a) const { (void)a; }

    // Importance sampling (SPEC 8): microfacet normals m (m.z >= 0) from two
    // uniform numbers u1, u2 in [0, 1).
    // NDF sampling: m with density normalPdf(a, m) per solid angle of m. The
    // default inverts the polar CDF of D(m) (n.m) numerically (in
    // models/NdfSampling.cpp), which is exact only for an isotropic D;
    // entries with a closed-form inversion or an anisotropic D override it.
    virtual Vec3<Real> sampleNormal(const ModelArgs<Real>& a, Real u1, Real u2) const;
    // The density of sampleNormal, D(m) (n.m) unless an entry samples
    // something else (ward: the Beckmann NDF of its exponent).
    virtual Real normalPdf(const ModelArgs<Real>& a, const Vec3<Real>& m) const { return D(a, m) * m.z; }
    // Visible-normal sampling, NdfEntry::visibleNormals only: m with density
    // (wo.m)+ D(m) / A(wo), A(wo) the projected area (n.wo)(1 + Lambda(wo)),
    // Lambda from visibleCosLambda, which must be Lambda exactly for this D
    // (or the density does not integrate to 1). For n.wo > 0, and also below
    // the horizon, where A(wo) = (n.-wo) Lambda(-wo) > 0 (the random walk on
    // the microsurface meets the surface going up, MicrosurfaceWalk.h).
    virtual Vec3<Real> sampleVisibleNormal(const ModelArgs<Real>& a, const Vec3<Real>& wo, Real u1, Real u2) const;
    // (n.v) Lambda(v) with the Lambda that normalizes the visible normals:
    // the exact Smith Lambda of D. cosLambda, unless the masking's Lambda is
    // an approximation for this D (blinn_phong: Beckmann's at an equivalent
    // roughness, SPEC 3), where the entry gives the exact one here.
    virtual Real visibleCosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const { return cosLambda(a, v); }
};

// The geometry a masking term sees: the directions, the microfacet normal,
// and wi.h, wo.h (equal for the half vector, which keeps f reciprocal).
template <typename Real>
struct MaskingGeometry {
    Vec3<Real> wi, wo, h;
    Real ih, oh;
};

template <typename Real>
struct MaskingFormulas {
    virtual ~MaskingFormulas() = default;
    // G(wi, wo, h).
    virtual Real G(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g) const = 0;
    // scale G / ((n.wi)(n.wo)) formed without G or the product of the
    // cosines (no 0/0 or 0 * Inf where they underflow together at grazing);
    // scale > 0, and for Smith forms g.oh > 0.
    virtual Real GOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g, Real scale) const = 0;
    // For a pair on opposite sides of the surface (SPEC 11), with both
    // directions mirrored above it (z -> |z|): scale G / ((n.wi)(n.wo)) of
    // the transmission form. Only for entries with `transmission`.
    virtual Real transmittedGOverCosines(const ResolvedMaterial<Real>& r, const MaskingGeometry<Real>& g,
                                         Real scale) const {
        (void)r, (void)g, (void)scale;
        return Real(-1);  // never called: the checker refuses transmission without the form
    }
};

template <typename Real>
struct FresnelFormulas {
    virtual ~FresnelFormulas() = default;
    // F of channel ch at c = wi.h, given also s2 = 1 - c^2 (accurate near c = 1).
    virtual Real F(const ModelArgs<Real>& a, Real c, Real s2, int ch) const = 0;
    // 1 - F, the share a refracting boundary transmits (SPEC 11); a model
    // whose F nears 1 (grazing facets) forms it without that cancellation.
    virtual Real transmittance(const ModelArgs<Real>& a, Real c, Real s2, int ch) const { return 1 - F(a, c, s2, ch); }
    // The same for a refracted pair, given also the far side's cosine ct
    // (> 0): near the critical angle ct from 1 - c^2 cancels, and the pair
    // knows it directly.
    virtual Real pairTransmittance(const ModelArgs<Real>& a, Real c, Real ct, int ch) const {
        (void)ct;
        return transmittance(a, c, (1 - c) * (1 + c), ch);
    }
    // F_avg = 2 Int_0^1 F(mu) mu dmu in closed form, if the model has one.
    virtual std::optional<Real> closedFormAverage(const ModelArgs<Real>& a, int ch) const {
        (void)a, (void)ch;
        return std::nullopt;
    }
};

template <typename Real>
struct DiffuseFormulas {
    virtual ~DiffuseFormulas() = default;
    // The diffuse base of channel ch (no cosine factor).
    virtual Real value(const ModelArgs<Real>& a, int ch) const = 0;
};

// The real types of every entry's formulas, filled by makeFormulas.
template <template <typename> class Formulas>
struct FormulaSet {
    const Formulas<float>* f = nullptr;
    const Formulas<double>* d = nullptr;
    const Formulas<long double>* ld = nullptr;
    const Formulas<__float128>* q = nullptr;
    template <typename Real>
    const Formulas<Real>& get() const {
        if constexpr (std::is_same_v<Real, float>) return *f;
        else if constexpr (std::is_same_v<Real, double>) return *d;
        else if constexpr (std::is_same_v<Real, long double>) return *ld;
        else return *q;
    }
};

// Instantiates an entry's formula template for the four real types
// (static instances: the formulas are stateless).
template <template <typename> class Base, template <typename> class Impl>
FormulaSet<Base> makeFormulas() {
    static const Impl<float>& f = immortal<Impl<float>>();
    static const Impl<double>& d = immortal<Impl<double>>();
    static const Impl<long double>& ld = immortal<Impl<long double>>();
    static const Impl<__float128>& q = immortal<Impl<__float128>>();
    return {&f, &d, &ld, &q};
}

// ---- entries -----------------------------------------------------------------

// Domain limits shared by the entries.
constexpr double kMinAlpha = 1e-4;        // SPEC 3: smaller alpha is a delta lobe
constexpr double kMaxPhongExponent = 2e8; // = beckmann_to_phong(kMinAlpha)
constexpr double kMinEta = 1e-4;


// The rows of a Lambda table in (a, alpha): the range of alpha (in the
// equivalentAlphas sense) that the NDF's domain reaches with the shape
// values (beyond it Lambda is that of the nearest end: its parameters clamp
// there, and a row beyond a clamp would put a kink into the interpolation),
// and s, about the exponent with which the lobe falls in b = 1/alpha^2 - 1
// near alpha = 1 (so that the rows resolve its change there), and the
// rows' step in asinh(s b) (1/16 in log alpha toward alpha = 0).
struct LambdaRows {
    double alphaLo = kMinAlpha, alphaHi = 1;
    double scale = 1;
    double step = 1.0 / 8;
};

struct NdfEntry : ModelInfo {
    // A whole BRDF lobe with its own normalization (ward): no D(m), no
    // masking term, no microfacet energy bound.
    bool wholeLobe = false;
    // Shape-invariant (Heitz 2014): D is a stretch of one slope profile, so
    // its Smith Lambda depends on a = 1 / (alpha(v) tan theta) alone.
    bool shapeInvariant = false;
    // Its Smith Lambda has no closed form and is tabulated by quadrature
    // (LambdaTable.h: in a = 1/(alpha(v) tan theta) for a shape-invariant NDF,
    // in (a, alpha) otherwise): cosLambda interpolates the table of the
    // material's tableShapeParams, which must then be constant.
    bool tabulatedLambda = false;
    // For a tabulated Lambda: why these shape values have none (e.g. an
    // infinite Lambda), or "".
    std::string (*lambdaShapeError)(const std::vector<double>& shape) = nullptr;
    // A tabulated Lambda that is not shape-invariant has a table in (a,
    // alpha) whose rows are uniform in asinh(s (1/alpha^2 - 1))
    // (LambdaTable.h), laid out for the shape values by this (null: the
    // defaults of LambdaRows).
    LambdaRows (*lambdaRows)(const std::vector<double>& shape) = nullptr;
    // Why its Smith Lambda is only an approximation ("" when exact).
    const char* lambdaNote = "";
    // Why its F = 1 albedo is not bounded by 1 whatever the masking ("" when
    // the masking decides).
    const char* energyNote = "";
    // The roughnesses (alpha_x, alpha_y) of the lobe, in the GGX/Beckmann
    // sense: what tables, previews and quadrature grids are sized by.
    std::array<double, 2> (*equivalentAlphas)(const ModelArgs<double>& a) = nullptr;
    // Arguments of the isotropic lobe with roughness alpha (the inverse of
    // equivalentAlphas) and the given values of the tableShapeParams.
    ModelArgs<double> (*argsAtAlpha)(double alpha, const std::vector<double>& shape) = nullptr;
    // Short text of the resolved parameters, for reports ("alpha=(0.1,0.2)").
    std::string (*describe)(const ModelArgs<double>& a) = nullptr;
    // Has sampleVisibleNormal: an exact visible-normal sampler and a
    // visibleCosLambda exact for its D, so that the visible-normal density
    // integrates to 1.
    bool visibleNormals = false;
    // Its emitter's visible-normal sampler also takes directions below the
    // horizon (a ray going up through the microsurface meets facets facing
    // down its path), so `energy = random_walk` compiles for it.
    bool compiledWalk = false;
    FormulaSet<NdfFormulas> formulas;
};

// How the albedo quadrature of a masking term must be graded.
struct AlbedoKinks {
    bool atWoH = false;      // min/max kinks where n.wi = n.wo (cook_torrance, neumann, direction-correlated)
    bool vCavity = false;    // and where 2 (n.h)(n.w)/(wo.h) = 1 for w = wi, wo (cook_torrance)
    bool azimuthal = false;  // depends on the azimuth between wi and wo (direction-correlated)
    bool cutLayer = false;   // rises from 0 at the azimuth cut within a layer ~mu wide (kelemen)
};

struct MaskingEntry : ModelInfo {
    AlbedoKinks albedoKinks;
    // Why the F = 1 albedo of this masking is not bounded by 1 by
    // construction ("" when it is).
    const char* energyNote = "";
    // The masking of the Smith microsurface with uncorrelated heights, whose
    // single scattering is order 1 of the random walk (random_walk needs it).
    bool heightCorrelated = false;
    // Has a form for transmission (transmittedGOverCosines): the lobes of
    // SPEC 11 that scatter below the surface need one.
    bool transmission = false;
    FormulaSet<MaskingFormulas> formulas;
};

struct FresnelEntry : ModelInfo {
    // F jumps at a critical angle (total internal reflection): f(wi, wo) and
    // f(wo, wi) may differ by that step where a rounding of wi.h against
    // wo.h falls on either side of it.
    bool reciprocityStep = false;
    // The parameter holding the relative index of refraction of a boundary
    // light passes through (the walks refract there and take it as the
    // layer's index); -1 for the Fresnel of an opaque surface, where the
    // walks only reflect.
    int refractiveIndexParam = -1;
    FormulaSet<FresnelFormulas> formulas;
};

struct EnergyEntry : ModelInfo {
    // Multiple-scattering compensation from a tabulated albedo (kulla_conty).
    bool compensates = false;
    // The multiple scattering of the Smith microsurface by a random walk
    // (random_walk, Heitz et al. 2016): eval adds a one-walk estimate of the
    // orders >= 2 and the sampler walks (SPEC 13, docs/sampling.md).
    bool walks = false;
};

struct DiffuseEntry : ModelInfo {
    FormulaSet<DiffuseFormulas> formulas;  // null for `none`
    bool present = false;                  // adds a diffuse base
};

// An entry of `slot` with its identity filled in and one empty form (a
// model written without arguments); the entry's file adds the rest.
template <typename Entry>
Entry makeEntry(ModelSlot slot, int id, const char* name, const char* summary) {
    Entry e;
    e.slot = slot;
    e.id = id;
    e.name = name;
    e.summary = summary;
    e.forms = {ModelForm{}};
    return e;
}

// ---- lookups -------------------------------------------------------------------

// Every entry, slot by slot, each slot in catalog order.
const std::vector<const ModelInfo*>& catalog();
std::vector<const ModelInfo*> catalogSlot(ModelSlot slot);
const ModelInfo* findModel(ModelSlot slot, std::string_view name);  // names and aliases
const ModelInfo& modelInfo(ModelSlot slot, int id);

// The entry of that name (or alias) in its slot; an internal error if there
// is none (for tools and tests that name a model in code).
const ModelInfo& modelNamed(ModelSlot slot, std::string_view name);

// The index of the canonical parameter `name` of `m`, or -1.
int paramIndex(const ModelInfo& m, std::string_view name);

// The specular lobe of this pair is sampled through visible normals (an
// NDF with an exact visible-normal sampler under a Smith masking, whose
// weight F G2 / G1 is then at most F); otherwise through NDF sampling.
inline bool samplesVisibleNormals(const NdfEntry& ndf, const MaskingEntry& masking) {
    return ndf.visibleNormals && masking.smith;
}

// The NDF has a Smith Lambda, closed-form or tabulated.
inline bool hasSmithLambda(const NdfEntry& ndf) { return ndf.smith || ndf.tabulatedLambda; }

const NdfEntry& ndfEntry(const ModelInfo& m);
const MaskingEntry& maskingEntry(const ModelInfo& m);
const FresnelEntry& fresnelEntry(const ModelInfo& m);
const EnergyEntry& energyEntry(const ModelInfo& m);
const DiffuseEntry& diffuseEntry(const ModelInfo& m);


}  // namespace facet
