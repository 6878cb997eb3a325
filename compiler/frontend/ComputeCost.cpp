// ComputeCost: the cost of a material's expressions (ComputeCost.h).
#include "ComputeCost.h"

#include "Diagnostics.h"

#include <fmt/format.h>

namespace facet {

namespace {

constexpr long kPowByMultiplication = 8;  // x^k, |k| <= 64: at most 12 multiplies, usually fewer
// An input slot the material reads: its load, range clamp and finiteness
// test, and in a SIMD kernel a stream of its own (a masked load and a stage
// buffer for the last chunk, an argument of the cold fallback body), whose
// scheduling grows faster than linearly with their number.
constexpr long kReadSlotCost = 20;

long channels(const Expr& e) { return e.type == ValueType::Rgb ? 3 : 1; }

const BuiltinFunction& builtin(BuiltinFn id) {
    for (const BuiltinFunction& f : builtinFunctions())
        if (f.id == id) return f;
    internal_error << "no builtin entry";
    return builtinFunctions().front();
}

}  // namespace

// Iterative over an explicit stack: the parser bounds a tree's depth, but
// the cost must not depend on that to stay safe.
long computeCost(const Expr& root) {
    long total = 0;
    std::vector<const Expr*> pending{&root};
    while (!pending.empty()) {
        const Expr& e = *pending.back();
        pending.pop_back();
        switch (e.kind) {
            case ExprKind::Number:
            case ExprKind::Name: break;
            case ExprKind::Unary:
                total += channels(e);
                pending.push_back(static_cast<const UnaryExpr&>(e).operand.get());
                break;
            case ExprKind::Binary: {
                const auto& b = static_cast<const BinaryExpr&>(e);
                long each = 1;
                if (b.op == BinaryOp::Pow)
                    each = smallIntegerConstant(*b.rhs) ? kPowByMultiplication : builtin(BuiltinFn::Pow).cost;
                total += each * channels(e);
                pending.push_back(b.lhs.get());
                pending.push_back(b.rhs.get());
                break;
            }
            case ExprKind::Call: {
                const auto& call = static_cast<const CallExpr&>(e);
                if (call.function) {
                    long each = call.function->cost;
                    if (call.function->id == BuiltinFn::Pow && call.args.size() == 2 &&
                        smallIntegerConstant(*call.args[1].value))
                        each = kPowByMultiplication;
                    total += each * channels(e);
                }
                for (const Argument& a : call.args) pending.push_back(a.value.get());
                break;
            }
        }
    }
    return total;
}

std::optional<ComputeBudgetError> exceedsComputeBudget(const CheckedMaterial& m) {
    long total = 0;
    auto over = [&](const SourceLoc& loc, const std::string& where) -> std::optional<ComputeBudgetError> {
        if (total <= kMaxComputeCost) return std::nullopt;
        return ComputeBudgetError{
            loc, fmt::format("material '{}' computes too much to compile: at {} its inputs, lets and model "
                             "arguments already cost more than {} float operations (an rgb value counts three, exp and log {} each, "
                             "pow {}, each input read {}); simplify its expressions",
                             m.name, where, kMaxComputeCost, builtin(BuiltinFn::Exp).cost, builtin(BuiltinFn::Pow).cost,
                             kReadSlotCost)};
    };
    const CheckedMaterial::Reads reads = m.readByModels();
    for (size_t i = 0; i < m.inputs.size(); ++i) {
        if (!reads.inputs[i]) continue;  // never loaded
        total += kReadSlotCost * m.inputs[i].slotCount();
        if (auto e = over(m.inputs[i].loc, fmt::format("input '{}'", m.inputs[i].name))) return e;
    }
    for (size_t i = 0; i < m.lets.size(); ++i) {
        const CheckedLet& let = m.lets[i];
        if (!reads.lets[i]) continue;  // never lowered
        total += computeCost(*let.value);
        if (auto e = over(let.loc, fmt::format("let '{}'", let.name))) return e;
    }
    for (const CheckedLobe& lobe : m.lobes)
        for (int s = 0; s < kModelSlotCount; ++s) {
            const ModelUse& use = lobe.use(ModelSlot(s));
            for (const ExprPtr& arg : use.args)
                if (arg) total += computeCost(*arg);
            std::string where = fmt::format("the {} statement", modelSlotName(ModelSlot(s)));
            if (!lobe.implicit) where += fmt::format(" of lobe '{}'", lobe.name);
            if (auto e = over(use.loc, where)) return e;
        }
    for (const BsdfNode& node : m.bsdf) {
        if (node.weight) total += computeCost(*node.weight);
        if (auto e = over(node.loc, "the weights of the bsdf statement")) return e;
    }
    return std::nullopt;
}

}  // namespace facet
