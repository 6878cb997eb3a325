// Material: the methods of the checked form (Material.h): lobe slots, the
// single-lobe accessor of the compiled backends, input slots and what the
// models read.
#include "Material.h"

#include "Diagnostics.h"
#include "KullaConty.h"

#include <utility>
#include <vector>

namespace facet {

const CheckedInput* CheckedMaterial::findInput(std::string_view n) const {
    for (const CheckedInput& in : inputs)
        if (in.name == n) return &in;
    return nullptr;
}

const char* scatterName(Scatter scatter) {
    switch (scatter) {
        case Scatter::Reflect: return "reflect";
        case Scatter::Transmit: return "transmit";
        case Scatter::Both: return "both";
    }
    return "?";
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
    // SPEC 11's lobes: the compiled backends evaluate and sample one alone
    // (LaneDielectric.cpp, LaneDielectricSampling.cpp) and its compensation
    // (WholeSphereEnergy.cpp), whose crossing shares they take from the
    // lobe's index when the kernel is built.
    for (const CheckedLobe& lobe : m.lobes) {
        if (!lobe.wholeSphere()) continue;
        std::string what = "material '" + m.name + "': lobe '" + lobe.name + "' scatters below the surface (" +
                           (lobe.thin ? std::string("thin = true") : "scatter = " + std::string(scatterName(lobe.scatter))) + ")";
        if (m.combinesLobes())
            return what + " in a combination of lobes, which only the reference evaluates so far; use --backend interp";
        const int eta = fresnelEntry(*lobe.fresnel.model).refractiveIndexParam;
        const CheckedInput* input =
            eta >= 0 && lobe.fresnel.has(eta) ? inputUsed(*lobe.fresnel.args[size_t(eta)], m) : nullptr;
        if (lobe.compensatesEnergy() && input)
            return what + " with energy = kulla_conty and an index that reads input '" + input->name +
                   "': the compiled kernels take the sheet's crossing share, an integral over its index, when they "
                   "are built; bind it (--set " + input->name + "=VALUE) or use --backend interp";
    }
    // A layer's tables are baked when the kernel is compiled, from constant
    // parameters: a per-lane table (3D over the top's parameters) is not
    // built yet. Binding the input (`--set`) makes it constant.
    for (size_t i = 0; i < m.bsdf.size(); ++i) {
        const BsdfNode& n = m.bsdf[i];
        if (n.kind != BsdfKind::Layer) continue;
        if (std::string input = layerTableInput(m, int(i)); !input.empty())
            return "material '" + m.name + "': the compiled backends need the parameters of " + printBsdf(m, n) +
                   " that its albedo tables depend on to be constant, but they read input '" + input +
                   "'; bind it (--set " + input + "=VALUE) or use --backend interp";
    }
    return "";
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

CheckedMaterial::Reads CheckedMaterial::readsOf(std::vector<const Expr*> pending) const {
    Reads read{std::vector<bool>(inputs.size(), false), std::vector<bool>(lets.size(), false),
               std::vector<bool>(size_t(slotCount), false)};
    // Names an expression uses; lets are followed once each (a let only
    // names lets defined before it, so the walk ends).
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
    for (size_t k = 0; k < inputs.size(); ++k)
        for (int s = 0; s < inputs[k].slotCount(); ++s) read.slots.at(size_t(inputs[k].firstSlot + s)) = read.inputs[k];
    return read;
}

CheckedMaterial::Reads CheckedMaterial::readByModels() const {
    std::vector<const Expr*> all;
    for (const CheckedLobe& lobe : lobes)
        for (int s = 0; s < kModelSlotCount; ++s)
            for (const ExprPtr& arg : lobe.use(ModelSlot(s)).args)
                if (arg) all.push_back(arg.get());
    for (const BsdfNode& node : bsdf)
        if (node.weight) all.push_back(node.weight.get());
    return readsOf(std::move(all));
}

CheckedMaterial lobeView(const CheckedMaterial& m, int lobe) {
    CheckedMaterial view;
    view.loc = m.loc;
    view.name = m.name;
    view.inputs = m.inputs;
    view.lets = m.lets;
    view.slotCount = m.slotCount;
    view.lobes.push_back(m.lobes.at(size_t(lobe)));
    BsdfNode root;
    root.loc = view.lobes[0].loc;
    root.lobe = 0;
    view.bsdf.push_back(root);
    return view;
}

bool isLambertianTree(const CheckedMaterial& m, int node) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    switch (n.kind) {
        case BsdfKind::Lobe: return !m.lobes.at(size_t(n.lobe)).hasNdf();
        case BsdfKind::Layer: return false;
        default: return isLambertianTree(m, n.a) && (n.b < 0 || isLambertianTree(m, n.b));
    }
}

namespace {

// The expressions a layer's tables are computed from (LayerAlbedo.h): the
// whole top sub-expression (its albedo, Fresnel included), and, unless the
// base is Lambertian, the base's arguments other than its Fresnel terms
// (the base enters the balance with Fresnel 1) and its weights.
void layerTableExprs(const CheckedMaterial& m, int node, bool withFresnel, std::vector<const Expr*>& out) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    if (n.weight) out.push_back(n.weight.get());
    if (n.kind == BsdfKind::Lobe) {
        const CheckedLobe& lobe = m.lobes.at(size_t(n.lobe));
        for (int s = 0; s < kModelSlotCount; ++s) {
            if (ModelSlot(s) == ModelSlot::Fresnel && !withFresnel) continue;
            for (const ExprPtr& arg : lobe.use(ModelSlot(s)).args)
                if (arg) out.push_back(arg.get());
        }
        return;
    }
    if (n.a >= 0) layerTableExprs(m, n.a, withFresnel, out);
    if (n.b >= 0) layerTableExprs(m, n.b, withFresnel, out);
}

}  // namespace

std::string samplerlessWhat(const CheckedMaterial& m) {
    if (m.combinesLobes()) return "a combination of lobes, sampled by the reference's mixture";
    const CheckedLobe& lobe = m.singleLobe();
    if (!lobe.hasNdf()) return "a diffuse lobe alone";
    return std::string("ndf ") + lobe.ndf.model->name + ", masking " + lobe.masking.model->name;
}

std::string layerTableInput(const CheckedMaterial& m, int layer) {
    const BsdfNode& n = m.bsdf.at(size_t(layer));
    std::vector<const Expr*> exprs;
    layerTableExprs(m, n.a, true, exprs);
    if (!isLambertianTree(m, n.b)) layerTableExprs(m, n.b, false, exprs);
    CheckedMaterial::Reads read = m.readsOf(std::move(exprs));
    for (size_t i = 0; i < m.inputs.size(); ++i)
        if (read.inputs[i]) return m.inputs[i].name;
    return "";
}

}  // namespace facet
