// BsdfCombination: the `bsdf = EXPR;` checker (see BsdfCombination.h).
#include "BsdfCombination.h"

#include <fmt/format.h>

namespace facet {

namespace {

bool isCombinator(const CallExpr& call) { return call.callee == "mix" || call.callee == "layer"; }

class BsdfBuilder {
public:
    BsdfBuilder(const BsdfCheckContext& context, std::vector<BsdfNode>& nodes) : cx_(context), nodes_(nodes) {}

    // True when `e` denotes a combination of lobes rather than a number: it
    // names a lobe or calls layer somewhere. (A weight never does.)
    bool isCombination(const Expr& e) const {
        switch (e.kind) {
            case ExprKind::Number: return false;
            case ExprKind::Name: return cx_.findLobe(static_cast<const NameExpr&>(e).name) >= 0;
            case ExprKind::Unary: return isCombination(*static_cast<const UnaryExpr&>(e).operand);
            case ExprKind::Binary: {
                const auto& b = static_cast<const BinaryExpr&>(e);
                return isCombination(*b.lhs) || isCombination(*b.rhs);
            }
            case ExprKind::Call: {
                const auto& call = static_cast<const CallExpr&>(e);
                // layer(...) always; mix(...) when it mixes lobes (else it
                // is the builtin mix of numbers, e.g. inside a weight).
                if (call.callee == "layer") return true;
                for (const Argument& a : call.args)
                    if (isCombination(*a.value)) return true;
                return false;
            }
        }
        return false;
    }

    // combination := LOBE | combination '+' combination | weight '*' combination
    //              | combination '*' weight | 'mix' '(' combination ',' combination ',' weight ')'
    //              | 'layer' '(' combination ',' combination [ ',' 'weight' '=' weight ] ')'
    int combination(Expr& e) {
        if (!isCombination(e)) {
            if (e.kind == ExprKind::Name) {
                const auto& n = static_cast<const NameExpr&>(e);
                return fail(e.loc, fmt::format("unknown lobe '{}' in bsdf (lobes: {})", n.name, lobeList()));
            }
            return fail(e.loc, fmt::format("expected a lobe or a combination of lobes here, found the number "
                                           "expression '{}'",
                                           printExpr(e)));
        }
        switch (e.kind) {
            case ExprKind::Name: return add({BsdfKind::Lobe, e.loc, cx_.findLobe(static_cast<NameExpr&>(e).name), -1, -1, nullptr});
            case ExprKind::Binary: return binary(static_cast<BinaryExpr&>(e));
            case ExprKind::Call: return call(static_cast<CallExpr&>(e));
            default:
                return fail(e.loc, "lobes cannot be negated; combine them with '+', a weight '*', mix(...) or layer(...)");
        }
    }

private:
    int binary(BinaryExpr& b) {
        bool left = isCombination(*b.lhs), right = isCombination(*b.rhs);
        if (b.op == BinaryOp::Add) {
            int x = combination(*b.lhs);
            int y = x < 0 ? -1 : combination(*b.rhs);
            if (y < 0) return -1;
            return add({BsdfKind::Sum, b.loc, -1, x, y, nullptr});
        }
        if (b.op == BinaryOp::Mul) {
            if (left && right)
                return fail(b.rhs->loc, "a weight must be a float or rgb number, found a lobe (lobes are added "
                                        "with '+', not multiplied)");
            Expr& weight = left ? *b.rhs : *b.lhs;
            int child = combination(left ? *b.lhs : *b.rhs);
            if (child < 0 || !typeWeight(weight)) return -1;
            return add({BsdfKind::Scale, b.loc, -1, child, -1, left ? b.rhs : b.lhs});
        }
        return fail(b.loc, fmt::format("'{}' cannot combine lobes; use '+', a weight '*', mix(...) or layer(...)",
                                       binaryOpSpelling(b.op)));
    }

    int call(CallExpr& c) {
        if (!isCombinator(c))
            return fail(c.loc, fmt::format("function '{}' takes numbers, not lobes", c.callee));
        const bool isMix = c.callee == "mix";
        // mix(X, Y, T): three positional; layer(TOP, BASE [, weight = W]).
        size_t positional = 0;
        ExprPtr weight;
        for (Argument& a : c.args) {
            if (a.name.empty()) {
                if (weight) return fail(a.value->loc, fmt::format("positional argument after 'weight =' in {}", c.callee));
                ++positional;
            } else if (!isMix && a.name == "weight" && !weight) {
                weight = a.value;
            } else {
                return fail(a.nameLoc, fmt::format("{} takes no argument '{}' ({})", c.callee, a.name, usage(isMix)));
            }
        }
        if (isMix ? positional != 3 : positional != 2)
            return fail(c.loc, fmt::format("{} takes {}, got {} argument{}", c.callee, usage(isMix), c.args.size(),
                                           c.args.size() == 1 ? "" : "s"));
        int x = combination(*c.args[0].value);
        int y = x < 0 ? -1 : combination(*c.args[1].value);
        if (y < 0) return -1;
        if (isMix) weight = c.args[2].value;
        if (weight && !typeWeight(*weight)) return -1;
        return add({isMix ? BsdfKind::Mix : BsdfKind::Layer, c.loc, -1, x, y, weight});
    }

    static const char* usage(bool isMix) {
        return isMix ? "(X, Y, T): two combinations of lobes and a weight T in [0, 1]"
                     : "(TOP, BASE) or (TOP, BASE, weight = W)";
    }

    // A weight is a number: float or rgb, never a lobe.
    bool typeWeight(Expr& weight) {
        if (isCombination(weight)) {
            fail(weight.loc, "a weight must be a float or rgb number, found a lobe");
            return false;
        }
        return cx_.typeWeight(weight) != ValueType::Unknown;
    }

    std::string lobeList() const {
        std::string out;
        for (const std::string& n : cx_.lobeNames) out += (out.empty() ? "" : ", ") + n;
        return out.empty() ? "none" : out;
    }

    int add(BsdfNode node) {
        nodes_.push_back(std::move(node));
        return int(nodes_.size()) - 1;
    }

    int fail(const SourceLoc& loc, std::string message) {
        cx_.diags.error(loc, std::move(message));
        return -1;
    }

    const BsdfCheckContext& cx_;
    std::vector<BsdfNode>& nodes_;
};

}  // namespace

int buildBsdfTree(Expr& expr, const BsdfCheckContext& context, std::vector<BsdfNode>& nodes) {
    return BsdfBuilder(context, nodes).combination(expr);
}

}  // namespace facet
