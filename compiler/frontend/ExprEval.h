// ExprEval: evaluation of a checked expression in any real type.
//
// Shared by the checker (constant input defaults and ranges, evaluated in
// double) and the reference interpreter (lets and model arguments, in double
// or wider). Values are float or rgb; floats promote channel-wise. Builtin
// semantics come from the shared table in Builtins.h.
#pragma once

#include "AST.h"
#include "Builtins.h"
#include "Diagnostics.h"

#include <array>

namespace facet {

template <typename Real>
struct Value {
    std::array<Real, 3> c{};
    bool rgb = false;

    static Value scalar(Real v) { return {{v, v, v}, false}; }
    Real channel(int i) const { return rgb ? c[i] : c[0]; }
};

// `lookup(const NameExpr&) -> Value<Real>` resolves names.
template <typename Real, typename Lookup>
Value<Real> evaluateExpr(const Expr& e, const Lookup& lookup) {
    switch (e.kind) {
        case ExprKind::Number: return Value<Real>::scalar(Real(static_cast<const NumberExpr&>(e).value));
        case ExprKind::Name: return lookup(static_cast<const NameExpr&>(e));
        case ExprKind::Unary: {
            Value<Real> v = evaluateExpr<Real>(*static_cast<const UnaryExpr&>(e).operand, lookup);
            for (Real& x : v.c) x = -x;
            return v;
        }
        case ExprKind::Binary: {
            const auto& b = static_cast<const BinaryExpr&>(e);
            Value<Real> l = evaluateExpr<Real>(*b.lhs, lookup), r = evaluateExpr<Real>(*b.rhs, lookup);
            Value<Real> out;
            out.rgb = l.rgb || r.rgb;
            for (int i = 0; i < 3; ++i) {
                Real x = l.channel(i), y = r.channel(i);
                switch (b.op) {
                    case BinaryOp::Add: out.c[i] = x + y; break;
                    case BinaryOp::Sub: out.c[i] = x - y; break;
                    case BinaryOp::Mul: out.c[i] = x * y; break;
                    case BinaryOp::Div: out.c[i] = x / y; break;
                    case BinaryOp::Pow: {
                        Real xy[2] = {x, y};
                        out.c[i] = applyBuiltin<Real>(BuiltinFn::Pow, xy);
                        break;
                    }
                }
            }
            return out;
        }
        case ExprKind::Call: {
            const auto& call = static_cast<const CallExpr&>(e);
            internal_assert(call.function) << "unresolved call to " << call.callee;
            std::array<Value<Real>, 3> args;
            internal_assert(call.args.size() <= 3) << "builtin with more than 3 arguments";
            bool anyRgb = false;
            for (size_t i = 0; i < call.args.size(); ++i) {
                args[i] = evaluateExpr<Real>(*call.args[i].value, lookup);
                anyRgb |= args[i].rgb;
            }
            Value<Real> out;
            if (call.function->id == BuiltinFn::Rgb) {
                out.rgb = true;
                for (int i = 0; i < 3; ++i) out.c[i] = args[i].c[0];
                return out;
            }
            out.rgb = anyRgb;
            for (int ch = 0; ch < 3; ++ch) {
                Real a[3];
                for (size_t i = 0; i < call.args.size(); ++i) a[i] = args[i].channel(ch);
                out.c[ch] = applyBuiltin<Real>(call.function->id, a);
            }
            return out;
        }
    }
    internal_error << "unknown expression kind";
}

}  // namespace facet
