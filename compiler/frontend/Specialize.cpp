// Specialize: input binding and constant folding (see Specialize.h).
#include "Specialize.h"

#include "BsdfFolding.h"

#include "ExprEval.h"

#include <fmt/format.h>

namespace facet {

bool isConstantExpr(const Expr& e) {
    if (e.kind == ExprKind::Number) return true;
    if (e.kind != ExprKind::Call) return false;
    const auto& call = static_cast<const CallExpr&>(e);
    if (!call.function || call.function->id != BuiltinFn::Rgb) return false;
    for (const Argument& a : call.args)
        if (a.value->kind != ExprKind::Number) return false;
    return true;
}

std::array<double, 3> constantValue(const Expr& e) {
    internal_assert(isConstantExpr(e)) << "constantValue of a non-constant expression";
    if (e.kind == ExprKind::Number) {
        double v = static_cast<const NumberExpr&>(e).value;
        return {v, v, v};
    }
    const auto& call = static_cast<const CallExpr&>(e);
    std::array<double, 3> out;
    for (int i = 0; i < 3; ++i) out[i] = static_cast<const NumberExpr&>(*call.args[i].value).value;
    return out;
}

namespace {

ExprPtr makeConstant(const SourceLoc& loc, const Value<double>& v) {
    if (!v.rgb) {
        auto n = std::make_shared<NumberExpr>(loc, v.c[0]);
        n->type = ValueType::Float;
        return n;
    }
    std::vector<Argument> args;
    for (int i = 0; i < 3; ++i) {
        auto n = std::make_shared<NumberExpr>(loc, v.c[i]);
        n->type = ValueType::Float;
        args.push_back({"", loc, n});
    }
    auto call = std::make_shared<CallExpr>(loc, "rgb", std::move(args));
    call->function = findBuiltinFunction("rgb");
    call->type = ValueType::Rgb;
    return call;
}

// Replaces bound inputs and constant lets by their values, renumbers the
// remaining inputs and lets, and folds constant subtrees.
class Folder : public ExprMutator {
public:
    std::vector<ExprPtr> inputConstant;  // per old input index: constant or null
    std::vector<int> inputRemap;         // old input index -> new index
    std::vector<ExprPtr> letConstant;    // per old let index: constant or null
    std::vector<int> letRemap;           // old let index -> new index (-1 if folded away)

    ExprPtr mutateName(const std::shared_ptr<NameExpr>& e) override {
        const ExprPtr& k = e->binding == BindingKind::Input ? inputConstant.at(e->index) : letConstant.at(e->index);
        if (k) return k;
        auto copy = std::make_shared<NameExpr>(*e);
        copy->index = e->binding == BindingKind::Input ? inputRemap.at(e->index) : letRemap.at(e->index);
        return copy;
    }
    ExprPtr mutateUnary(const std::shared_ptr<UnaryExpr>& e) override { return fold(ExprMutator::mutateUnary(e)); }
    ExprPtr mutateBinary(const std::shared_ptr<BinaryExpr>& e) override { return fold(ExprMutator::mutateBinary(e)); }
    ExprPtr mutateCall(const std::shared_ptr<CallExpr>& e) override {
        ExprPtr r = ExprMutator::mutateCall(e);
        if (isConstantExpr(*r)) return r;  // rgb(1, 2, 3) is already a constant
        return fold(r);
    }

private:
    ExprPtr fold(const ExprPtr& e) {
        bool allConstant = true;
        auto check = [&](const ExprPtr& child) { allConstant &= isConstantExpr(*child); };
        switch (e->kind) {
            case ExprKind::Unary: check(static_cast<UnaryExpr&>(*e).operand); break;
            case ExprKind::Binary:
                check(static_cast<BinaryExpr&>(*e).lhs);
                check(static_cast<BinaryExpr&>(*e).rhs);
                break;
            case ExprKind::Call:
                for (const Argument& a : static_cast<CallExpr&>(*e).args) check(a.value);
                break;
            default: return e;
        }
        if (!allConstant) return e;
        Value<double> v = evaluateExpr<double>(*e, [](const NameExpr&) -> Value<double> {
            internal_error << "name left in a constant subtree";
        });
        // Keep non-finite results symbolic: the evaluators must see (and
        // count) the invalid parameter per lane, exactly as the reference does.
        for (int i = 0; i < (v.rgb ? 3 : 1); ++i)
            if (!std::isfinite(v.c[i])) return e;
        return makeConstant(e->loc, v);
    }
};

}  // namespace

CheckedMaterial specializeMaterial(const CheckedMaterial& material, const InputBindings& bindings,
                                   DiagnosticEngine& diags) {
    CheckedMaterial out = material;
    Folder folder;
    folder.inputConstant.resize(material.inputs.size());
    folder.inputRemap.assign(material.inputs.size(), -1);
    for (const auto& [name, values] : bindings) {
        const CheckedInput* in = material.findInput(name);
        if (!in) {
            std::string known;
            for (const CheckedInput& i : material.inputs) known += (known.empty() ? "" : ", ") + i.name;
            diags.error(material.loc, fmt::format("cannot bind '{}': material '{}' has no such input (inputs: {})",
                                                  name, material.name, known.empty() ? "none" : known));
            continue;
        }
        if (values.size() != 1 && !(values.size() == 3 && in->type == ValueType::Rgb)) {
            diags.error(material.loc, fmt::format("cannot bind '{}': a {} input takes {}, got {} values", name,
                                                  valueTypeName(in->type),
                                                  in->type == ValueType::Rgb ? "1 or 3 values" : "1 value",
                                                  values.size()));
            continue;
        }
        Value<double> v;
        v.rgb = in->type == ValueType::Rgb;
        for (int c = 0; c < 3; ++c) {
            double x = values[values.size() == 1 ? 0 : c];
            if (!std::isfinite(x)) {
                diags.error(material.loc, fmt::format("cannot bind '{}' to a non-finite value", name));
                break;
            }
            if (in->hasRange) x = std::min(std::max(x, in->lo), in->hi);
            v.c[c] = x;
        }
        folder.inputConstant[in - material.inputs.data()] = makeConstant(in->loc, v);
    }
    if (diags.hasErrors()) return out;

    out.inputs.clear();
    out.slotCount = 0;
    for (size_t i = 0; i < material.inputs.size(); ++i) {
        if (folder.inputConstant[i]) continue;
        CheckedInput in = material.inputs[i];
        in.firstSlot = out.slotCount;
        out.slotCount += in.slotCount();
        folder.inputRemap[i] = int(out.inputs.size());
        out.inputs.push_back(in);
    }
    out.lets.clear();
    folder.letConstant.resize(material.lets.size());
    folder.letRemap.assign(material.lets.size(), -1);
    for (size_t i = 0; i < material.lets.size(); ++i) {
        CheckedLet let = material.lets[i];
        let.value = folder.mutate(let.value);
        if (isConstantExpr(*let.value)) {
            folder.letConstant[i] = let.value;
            continue;
        }
        folder.letRemap[i] = int(out.lets.size());
        out.lets.push_back(let);
    }
    for (CheckedLobe& lobe : out.lobes)
        for (ModelUse* use : {&lobe.ndf, &lobe.masking, &lobe.fresnel, &lobe.energy, &lobe.diffuse})
            for (ExprPtr& arg : use->args)
                if (arg) arg = folder.mutate(arg);
    for (BsdfNode& node : out.bsdf)
        if (node.weight) node.weight = folder.mutate(node.weight);
    foldBsdfWeights(out);
    return out;
}

std::string printMaterial(const CheckedMaterial& m) {
    std::string s = fmt::format("material {} {{\n", m.name);
    for (const CheckedInput& in : m.inputs) {
        s += fmt::format("    input {} = ", in.name);
        if (in.type == ValueType::Rgb)
            s += fmt::format("rgb({}, {}, {})", in.defaultValue[0], in.defaultValue[1], in.defaultValue[2]);
        else
            s += fmt::format("{}", in.defaultValue[0]);
        if (in.hasRange) s += fmt::format(" in {} .. {}", in.lo, in.hi);
        s += fmt::format(";  // slot {}\n", in.firstSlot);
    }
    for (const CheckedLet& let : m.lets) s += fmt::format("    let {} = {};\n", let.name, printExpr(*let.value));
    // A material without lobe blocks prints as it was written; lobes print
    // as blocks, then the combination.
    for (const CheckedLobe& lobe : m.lobes) {
        const std::string indent = lobe.implicit ? "    " : "        ";
        if (!lobe.implicit) s += fmt::format("    lobe {} {{\n", lobe.name);
        for (const ModelUse* use : {&lobe.ndf, &lobe.masking, &lobe.fresnel, &lobe.energy, &lobe.diffuse}) {
            if (!use->model) continue;  // a diffuse lobe has no ndf
            s += fmt::format("{}{} = {}", indent, modelSlotName(use->model->slot), use->model->name);
            if (!use->model->canonical.empty()) {
                s += "(";
                bool first = true;
                for (size_t i = 0; i < use->args.size(); ++i) {
                    if (!use->args[i]) continue;
                    s += fmt::format("{}{} = {}", first ? "" : ", ", use->model->canonical[i].name,
                                     printExpr(*use->args[i]));
                    first = false;
                }
                s += ")";
            }
            s += ";\n";
        }
        // SPEC 11's options where they differ from the default (a lobe that
        // only reflects prints as before).
        if (lobe.scatter != Scatter::Reflect) s += fmt::format("{}scatter = {};\n", indent, scatterName(lobe.scatter));
        if (lobe.thin) s += fmt::format("{}thin = true;\n", indent);
        if (!lobe.implicit) s += "    }\n";
    }
    if (!m.lobes.empty() && !m.lobes.front().implicit) s += fmt::format("    bsdf = {};\n", printBsdf(m, m.bsdfRoot()));
    return s + "}\n";
}

}  // namespace facet
