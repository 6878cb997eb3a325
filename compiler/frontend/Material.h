// Material: a checked material, the form every evaluator consumes.
//
// The checker turns a MaterialDecl into a CheckedMaterial: inputs with their
// constant defaults and ranges and their slots in the flat input array, lets
// in definition order, and the five model uses with their argument
// expressions in canonical parameter order (see Builtins.h). Every
// expression is typed and every name resolved.
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

struct CheckedMaterial {
    SourceLoc loc;
    std::string name;
    std::vector<CheckedInput> inputs;
    std::vector<CheckedLet> lets;
    ModelUse ndf, masking, fresnel, energy, diffuse;
    int slotCount = 0;

    // Multiple-scattering compensation from a tabulated albedo (kulla_conty).
    bool compensatesEnergy() const { return energy.model && energyEntry(*energy.model).compensates; }

    const CheckedInput* findInput(std::string_view name) const;
    ModelUse& use(ModelSlot slot);
    const ModelUse& use(ModelSlot slot) const;
    // The slot of `use`, one of this material's own uses.
    ModelSlot slotOf(const ModelUse& use) const;
    // Name of a float slot as shown to API users: "roughness", or "tint.r".
    std::string slotName(int slot) const;
    // Default values of all slots, in slot order.
    std::vector<double> defaultSlots() const;
    // Which inputs and lets (in their vectors' order) the model arguments
    // read, directly or through lets. What nothing reads cannot change f:
    // every evaluator skips it, so that a non-finite value in an unread
    // input does not invalidate the lane and compiled kernels never load it.
    struct Reads {
        std::vector<bool> inputs, lets;
        std::vector<bool> slots;  // per slot of the flat input array: read through its input
    };
    Reads readByModels() const;
};

// All materials of one file, checked.
struct CheckedProgram {
    std::shared_ptr<const std::string> file;
    std::vector<CheckedMaterial> materials;
    // The named material, or the first when name is empty; null if absent.
    const CheckedMaterial* find(std::string_view name) const;
};

}  // namespace facet
