// Material: the methods of the checked form (Material.h): lobe slots, the
// single-lobe accessor of the compiled backends, input slots and what the
// models read.
#include "Material.h"

#include "Diagnostics.h"

#include <utility>

namespace facet {

const CheckedInput* CheckedMaterial::findInput(std::string_view n) const {
    for (const CheckedInput& in : inputs)
        if (in.name == n) return &in;
    return nullptr;
}

ModelUse& CheckedLobe::use(ModelSlot slot) {
    switch (slot) {
        case ModelSlot::Ndf: return ndf;
        case ModelSlot::Masking: return masking;
        case ModelSlot::Fresnel: return fresnel;
        case ModelSlot::Energy: return energy;
        case ModelSlot::Diffuse: return diffuse;
    }
    internal_error << "bad slot";
}

const ModelUse& CheckedLobe::use(ModelSlot slot) const { return const_cast<CheckedLobe&>(*this).use(slot); }

ModelSlot CheckedLobe::slotOf(const ModelUse& u) const {
    for (int s = 0; s < kModelSlotCount; ++s)
        if (&use(ModelSlot(s)) == &u) return ModelSlot(s);
    internal_error << "a model use of another lobe";
}

const char* bsdfKindName(BsdfKind kind) {
    switch (kind) {
        case BsdfKind::Lobe: return "lobe";
        case BsdfKind::Scale: return "scale";
        case BsdfKind::Sum: return "sum";
        case BsdfKind::Mix: return "mix";
        case BsdfKind::Layer: return "layer";
    }
    return "?";
}

std::string printBsdf(const CheckedMaterial& m, const BsdfNode& node) {
    auto child = [&](int i) { return printBsdf(m, m.bsdf.at(size_t(i))); };
    switch (node.kind) {
        case BsdfKind::Lobe: return m.lobes.at(size_t(node.lobe)).name;
        case BsdfKind::Scale: return "(" + printExpr(*node.weight) + " * " + child(node.a) + ")";
        case BsdfKind::Sum: return "(" + child(node.a) + " + " + child(node.b) + ")";
        case BsdfKind::Mix: return "mix(" + child(node.a) + ", " + child(node.b) + ", " + printExpr(*node.weight) + ")";
        case BsdfKind::Layer:
            return "layer(" + child(node.a) + ", " + child(node.b) +
                   (node.weight ? ", weight = " + printExpr(*node.weight) : std::string()) + ")";
    }
    return "?";
}

std::string compiledBackendsRefuse(const CheckedMaterial& m) {
    // A lone diffuse lobe (`lobe x { diffuse = ... } bsdf = x;`) has no
    // microfacet term for the lowering either: phase 2 lowers it with the
    // combinations.
    if (!m.combinesLobes() && !m.singleLobe().hasNdf())
        return "material '" + m.name +
               "' is a diffuse lobe alone (no ndf); the compiled backends do not support that yet, use --backend interp";
    if (!m.combinesLobes()) return "";
    return "material '" + m.name +
           "' combines lobes; the compiled backends do not support that yet, use --backend interp";
}

const CheckedLobe& CheckedMaterial::singleLobe() const {
    internal_assert(!combinesLobes() && !bsdf.empty() && bsdf[0].kind == BsdfKind::Lobe)
        << "material '" << name << "' combines lobes; callers check combinesLobes() first";
    return lobes.at(size_t(bsdf[0].lobe));
}

CheckedLobe& CheckedMaterial::singleLobe() {
    return const_cast<CheckedLobe&>(std::as_const(*this).singleLobe());
}

std::string CheckedMaterial::slotName(int slot) const {
    for (const CheckedInput& in : inputs) {
        if (slot < in.firstSlot || slot >= in.firstSlot + in.slotCount()) continue;
        if (in.type == ValueType::Float) return in.name;
        static const char* channels[3] = {"r", "g", "b"};
        return in.name + "." + channels[slot - in.firstSlot];
    }
    return {};
}

std::vector<double> CheckedMaterial::defaultSlots() const {
    std::vector<double> slots(slotCount);
    for (const CheckedInput& in : inputs)
        for (int i = 0; i < in.slotCount(); ++i) slots[in.firstSlot + i] = in.defaultValue[i];
    return slots;
}

CheckedMaterial::Reads CheckedMaterial::readByModels() const {
    Reads read{std::vector<bool>(inputs.size(), false), std::vector<bool>(lets.size(), false)};
    // Names an expression uses; lets are followed once each (a let only
    // names lets defined before it, so the walk ends).
    std::vector<const Expr*> pending;
    for (const CheckedLobe& lobe : lobes)
        for (int s = 0; s < kModelSlotCount; ++s)
            for (const ExprPtr& arg : lobe.use(ModelSlot(s)).args)
                if (arg) pending.push_back(arg.get());
    for (const BsdfNode& node : bsdf)
        if (node.weight) pending.push_back(node.weight.get());
    while (!pending.empty()) {
        const Expr& e = *pending.back();
        pending.pop_back();
        switch (e.kind) {
            case ExprKind::Number: break;
            case ExprKind::Name: {
                const auto& n = static_cast<const NameExpr&>(e);
                if (n.binding == BindingKind::Input) read.inputs.at(size_t(n.index)) = true;
                else if (n.binding == BindingKind::Let && !read.lets.at(size_t(n.index))) {
                    read.lets[size_t(n.index)] = true;
                    pending.push_back(lets[size_t(n.index)].value.get());
                }
                break;
            }
            case ExprKind::Unary: pending.push_back(static_cast<const UnaryExpr&>(e).operand.get()); break;
            case ExprKind::Binary:
                pending.push_back(static_cast<const BinaryExpr&>(e).lhs.get());
                pending.push_back(static_cast<const BinaryExpr&>(e).rhs.get());
                break;
            case ExprKind::Call:
                for (const Argument& a : static_cast<const CallExpr&>(e).args) pending.push_back(a.value.get());
                break;
        }
    }
    return read;
}

}  // namespace facet
