// Material: a checked material, the form every evaluator consumes.
//
// The checker turns a MaterialDecl into a CheckedMaterial: inputs with their
// constant defaults and ranges and their slots in the flat input array, lets
// in definition order, its lobes (each with the five model uses, argument
// expressions in canonical parameter order, see Builtins.h) and the tree
// that combines them. Every expression is typed and every name resolved.
#pragma once

#include "AST.h"
#include "Builtins.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facet {

struct CheckedInput {
    SourceLoc loc;
    std::string name;
    ValueType type = ValueType::Float;
    std::array<double, 3> defaultValue{};  // float inputs use [0]
    bool hasRange = false;
    double lo = 0, hi = 0;
    int firstSlot = 0;  // float inputs take one slot, rgb inputs three
    int slotCount() const { return type == ValueType::Rgb ? 3 : 1; }
};

struct CheckedLet {
    SourceLoc loc;
    std::string name;
    ExprPtr value;
};

struct ModelUse {
    SourceLoc loc;  // of the model name (or of the material, for a default `none`)
    const ModelInfo* model = nullptr;
    std::vector<ExprPtr> args;  // canonical order; null where the form leaves it unset
    bool isotropic = false;     // ndf written with one alpha (alpha_x and alpha_y share it)

    bool has(int p) const { return p < int(args.size()) && args[p] != nullptr; }
};

// Where a lobe scatters (SPEC 11): `scatter = reflect | transmit | both`.
enum class Scatter { Reflect, Transmit, Both };
const char* scatterName(Scatter scatter);
// Which way light travels through a refracting lobe (SPEC 11; the compile
// option transport=): radiance (f of a path traced from the camera, pbrt-v4's
// TransportMode::Radiance, with the 1/eta^2 of transmitted radiance) or
// importance (its adjoint).
enum class Transport { Radiance, Importance };

// One lobe (SPEC 10): the five model uses of a one-lobe material. A lobe
// with no ndf (ndf.model null) is a diffuse lobe: only `diffuse` is set, the
// other uses are `none`.
struct CheckedLobe {
    SourceLoc loc;  // of the lobe's name (of the material, for the implicit lobe)
    std::string name;
    bool implicit = false;  // the model statements of a material without lobe blocks
    ModelUse ndf, masking, fresnel, energy, diffuse;
    // SPEC 11: what the lobe scatters into, and whether it is a thin-walled
    // sheet (the same interface on both sides). The locations are of the
    // statements, or the lobe's where they are left out.
    Scatter scatter = Scatter::Reflect;
    bool thin = false;
    SourceLoc scatterLoc, thinLoc;

    bool hasNdf() const { return ndf.model != nullptr; }
    // Multiple-scattering compensation from a tabulated albedo (kulla_conty).
    bool compensatesEnergy() const { return energy.model && energyEntry(*energy.model).compensates; }
    // Multiple scattering by a random walk on the microsurface (random_walk).
    bool walksMicrosurface() const { return energy.model && energyEntry(*energy.model).walks; }
    // The lobe scatters over the whole sphere (both directions on either
    // side; the dielectric lobe of SPEC 11) rather than as a BRDF above the
    // surface: it transmits or is a thin sheet.
    bool wholeSphere() const { return scatter != Scatter::Reflect || thin; }
    ModelUse& use(ModelSlot slot);
    const ModelUse& use(ModelSlot slot) const;
    // The slot of `use`, one of this lobe's own uses.
    ModelSlot slotOf(const ModelUse& use) const;
};

// A node of the combination `bsdf = EXPR;`, kept as a plain tree in
// CheckedMaterial::bsdf (children before their parents).
enum class BsdfKind {
    Lobe,   // lobes[lobe]
    Scale,  // weight * a           (weight float or rgb, clamped to >= 0)
    Sum,    // a + b
    Mix,    // (1 - weight) a + weight b   (weight clamped to [0, 1])
    Layer,  // layer(top = a, base = b, weight), weight null for 1 (SPEC 10)
};
const char* bsdfKindName(BsdfKind kind);
struct CheckedMaterial;
struct BsdfNode;
// A combination in source syntax: "layer(coat, (0.5 * base))".
std::string printBsdf(const CheckedMaterial& material, const BsdfNode& node);

struct BsdfNode {
    BsdfKind kind = BsdfKind::Lobe;
    SourceLoc loc;
    int lobe = -1;         // Lobe: index into CheckedMaterial::lobes
    int a = -1, b = -1;    // children: indices into CheckedMaterial::bsdf
    ExprPtr weight;        // Scale, Mix, Layer (null: no weight given)
};

struct CheckedMaterial {
    SourceLoc loc;
    std::string name;
    std::vector<CheckedInput> inputs;
    std::vector<CheckedLet> lets;
    // The lobes in source order; a material without lobe blocks has one
    // implicit lobe named after the material, and bsdf = that lobe.
    std::vector<CheckedLobe> lobes;
    std::vector<BsdfNode> bsdf;  // the combination; the root is bsdf.back()
    int slotCount = 0;

    const BsdfNode& bsdfRoot() const { return bsdf.back(); }
    // True unless the combination is one lobe alone (every material
    // without lobe blocks, or `bsdf = NAME;`).
    bool combinesLobes() const { return bsdf.size() != 1; }
    // The one lobe of a material that does not combine lobes: what the
    // compiled backends handle (they reject combinations before lowering).
    const CheckedLobe& singleLobe() const;
    CheckedLobe& singleLobe();

    const CheckedInput* findInput(std::string_view name) const;
    // Name of a float slot as shown to API users: "roughness", or "tint.r".
    std::string slotName(int slot) const;
    // Default values of all slots, in slot order.
    std::vector<double> defaultSlots() const;
    // Which inputs and lets (in their vectors' order) the model arguments
    // of any lobe and the combination's weights read, directly or through
    // lets. What nothing reads cannot change f: every evaluator skips it,
    // so that a non-finite value in an unread input does not invalidate the
    // lane and compiled kernels never load it.
    struct Reads {
        std::vector<bool> inputs, lets;
        std::vector<bool> slots;  // per slot of the flat input array: read through its input
    };
    Reads readByModels() const;
    // What the expressions `exprs` read, directly or through lets.
    Reads readsOf(std::vector<const Expr*> exprs) const;
};

// The material with lobe `lobe` alone (same inputs, lets and slots; bsdf =
// that lobe): what the one-lobe lowering plans and emits for each lobe of a
// combination.
CheckedMaterial lobeView(const CheckedMaterial& material, int lobe);
// Whether the sub-expression `node` is Lambertian: diffuse lobes (no NDF)
// combined by weights, sums and mixes, no layer.
bool isLambertianTree(const CheckedMaterial& material, int node);
// Why a material has no compiled sampler, for messages: "ndf X, masking Y"
// of its lobe, or "a combination of lobes".
std::string samplerlessWhat(const CheckedMaterial& material);
// The first input that the tables of the layer node `layer` depend on
// (LayerAlbedo.h), "" when they are constant.
std::string layerTableInput(const CheckedMaterial& material, int layer);

// The message with which the compiled backends refuse a material, "" when
// they take it: a layer whose tables would depend on a per-lane input, a
// lobe below the surface with energy compensation or in a combination.
// Every command that compiles,
// verifies or benchmarks a material reports it at the material's name.
std::string compiledBackendsRefuse(const CheckedMaterial& material);

// All materials of one file, checked.
struct CheckedProgram {
    std::shared_ptr<const std::string> file;
    std::vector<CheckedMaterial> materials;
    // The named material, or the first when name is empty; null if absent.
    const CheckedMaterial* find(std::string_view name) const;
};

}  // namespace facet
