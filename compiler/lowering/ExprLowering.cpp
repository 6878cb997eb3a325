// ExprLowering: the material's own expressions -- inputs, lets and model
// arguments -- as IR, and model parameters clamped to their catalog domain.
//
// They are evaluated in BodyPlan::expressions (double unless the plan
// shows that float loses nothing), with the reference's semantics: NaN
// propagates through min/max/clamp, pow has C semantics, clamps happen in
// the expression type before any conversion to float.
#include "LaneEmitter.h"

#include "Diagnostics.h"

#include <cmath>
#include <optional>

namespace facet {

using llvm::Value;


// Inputs: non-finite values are invalid (a test the plan drops where it
// trusts the inputs); in-range clamping (kept there too: measured within
// noise, and a -0 at a bound of 0 would otherwise keep its sign). Inputs, lets
// and model parameters are evaluated in the expression type: a parameter
// such as alpha enters exp() multiplied by tens in the NDF tails, and the
// user's arithmetic must not lose accuracy the reference keeps.
void LaneEmitter::lowerInputsAndLets(const std::vector<Value*>& slots) {
    MathEmitter& fm = floatMath_;
    MathEmitter& em = expressionMath();
    inputs_.clear();
    for (size_t i = 0; i < material.inputs.size(); ++i) {
        const CheckedInput& in = material.inputs[i];
        LVal v;
        if (!plan.reads.inputs[i]) {  // never loaded (KernelEntries), never referenced
            inputs_.push_back(v);
            continue;
        }
        v.rgb = in.type == ValueType::Rgb;
        for (int ch = 0; ch < in.slotCount(); ++ch) {
            Value* x = slots.at(in.firstSlot + ch);
            rejectInput([&] { return builder.CreateNot(fm.isFinite(x)); });
            x = em.convert(x, em.type());
            if (in.hasRange) x = em.maxnum(em.minnum(x, em.c(in.hi)), em.c(in.lo));
            v.c[ch] = x;
        }
        if (!v.rgb) v.c[1] = v.c[2] = v.c[0];
        inputs_.push_back(v);
    }
    lets_.clear();
    for (size_t i = 0; i < material.lets.size(); ++i)
        lets_.push_back(plan.reads.lets[i] ? lower(*material.lets[i].value) : LVal{});
}

// x^k for a small integer k, by repeated squaring.
Value* LaneEmitter::powInt(Value* x, long k) {
    MathEmitter& em = expressionMath();
    bool negative = k < 0;
    unsigned long e = negative ? -k : k;
    Value* result = em.c(1.0);
    Value* base = x;
    bool first = true;
    while (e) {
        if (e & 1) {
            result = first ? base : em.mul(result, base);
            first = false;
        }
        e >>= 1;
        if (e) base = em.mul(base, base);
    }
    return negative ? em.div(em.c(1.0), result) : result;
}

Value* LaneEmitter::applyBuiltin(BuiltinFn fn, const std::vector<Value*>& a) {
    MathEmitter& em = expressionMath();
    switch (fn) {
        case BuiltinFn::Sqrt: return em.sqrt(a[0]);
        case BuiltinFn::Pow: return em.pow(a[0], a[1]);
        case BuiltinFn::Exp: return em.exp(a[0]);
        case BuiltinFn::Log: return em.log(a[0]);
        case BuiltinFn::Abs: return em.abs(a[0]);
        case BuiltinFn::Min: return em.min(a[0], a[1]);
        case BuiltinFn::Max: return em.max(a[0], a[1]);
        case BuiltinFn::Clamp: {
            // As the reference: NaN anywhere gives NaN; otherwise lo wins
            // over hi when the bounds are inverted.
            Value* nan = builder.CreateOr(builder.CreateOr(em.isNan(a[0]), em.isNan(a[1])), em.isNan(a[2]));
            Value* r = em.select(em.lt(a[0], a[1]), a[1], em.select(em.gt(a[0], a[2]), a[2], a[0]));
            return em.select(nan, em.c(NAN), r);
        }
        case BuiltinFn::Mix: return em.fma(em.sub(a[1], a[0]), a[2], a[0]);
        case BuiltinFn::PhongExponent: {
            Value* r2 = em.mul(a[0], a[0]);
            return em.sub(em.div(em.c(2.0), em.mul(r2, r2)), em.c(2.0));
        }
        case BuiltinFn::BeckmannToPhong: return em.sub(em.div(em.c(2.0), em.mul(a[0], a[0])), em.c(2.0));
        case BuiltinFn::Rgb: break;
    }
    internal_error << "builtin has no channel-wise lowering";
}

LVal LaneEmitter::lower(const Expr& e) {
    MathEmitter& em = expressionMath();
    switch (e.kind) {
        case ExprKind::Number: return LVal::scalar(em.c(static_cast<const NumberExpr&>(e).value));
        case ExprKind::Name: {
            const auto& n = static_cast<const NameExpr&>(e);
            return n.binding == BindingKind::Input ? inputs_.at(n.index) : lets_.at(n.index);
        }
        case ExprKind::Unary: {
            LVal v = lower(*static_cast<const UnaryExpr&>(e).operand);
            return map({v}, v.rgb, [&](auto& x) { return em.neg(x[0]); });
        }
        case ExprKind::Binary: {
            const auto& bin = static_cast<const BinaryExpr&>(e);
            LVal l = lower(*bin.lhs), r = lower(*bin.rhs);
            bool rgb = l.rgb || r.rgb;
            if (bin.op == BinaryOp::Pow)
                if (auto k = smallIntegerConstant(*bin.rhs))
                    return map({l}, rgb, [&](auto& x) { return powInt(x[0], *k); });
            return map({l, r}, rgb, [&](auto& x) -> Value* {
                switch (bin.op) {
                    case BinaryOp::Add: return em.add(x[0], x[1]);
                    case BinaryOp::Sub: return em.sub(x[0], x[1]);
                    case BinaryOp::Mul: return em.mul(x[0], x[1]);
                    case BinaryOp::Div: return em.div(x[0], x[1]);
                    case BinaryOp::Pow: return em.pow(x[0], x[1]);
                }
                return nullptr;
            });
        }
        case ExprKind::Call: {
            const auto& call = static_cast<const CallExpr&>(e);
            internal_assert(call.function) << "unresolved call " << call.callee;
            std::vector<LVal> args;
            for (const Argument& a : call.args) args.push_back(lower(*a.value));
            if (call.function->id == BuiltinFn::Rgb) return {{args[0].c[0], args[1].c[0], args[2].c[0]}, true};
            if (call.function->id == BuiltinFn::Pow)
                if (auto k = smallIntegerConstant(*call.args[1].value))
                    return map({args[0]}, e.type == ValueType::Rgb, [&](auto& x) { return powInt(x[0], *k); });
            return map(args, e.type == ValueType::Rgb, [&](auto& x) { return applyBuiltin(call.function->id, x); });
        }
    }
    internal_error << "unknown expression kind";
}

// Clamps a parameter in the expression type to [lo, hi]; NaN, or infinite
// in float after clamping, marks the lane invalid (as in the reference),
// where the plan's range of the parameter leaves either possible. The
// result is float (floatResult) or the precise type.
Value* LaneEmitter::clampParam(Value* x, const ParamPlan& param, double lo, double hi, bool floatResult) {
    MathEmitter& em = expressionMath();
    if (param.testNaN) markInvalid(em.isNan(x));
    if (std::isfinite(hi)) x = em.minnum(x, em.c(hi));
    x = em.maxnum(x, em.c(lo));
    Value* xf = floatMath_.convert(x, floatMath_.type());
    // Finite in double but not in float is still an invalid lane: the float
    // formulas would overflow.
    if (param.testFloatRange) markInvalid(builder.CreateNot(floatMath_.isFinite(xf)));
    return floatResult ? xf : preciseMath_.convert(x, preciseMath_.type());
}

LVal LaneEmitter::clampedExpression(const Expr& e, double lo, double hi) {
    MathEmitter& em = expressionMath();
    LVal v = lower(e);
    return map({v}, v.rgb, [&](auto& x) {
        markInvalid(em.isNan(x[0]));
        Value* c = em.maxnum(std::isfinite(hi) ? em.minnum(x[0], em.c(hi)) : x[0], em.c(lo));
        return doubleMath_.convert(c, doubleMath_.type());
    });
}

Value* LaneEmitter::scalarParam(const ModelUse& use, int p, bool floatResult, double capHi) {
    const ModelParam& domain = use.model->canonical.at(p);
    const ParamPlan& param = plan.param(material.singleLobe().slotOf(use), p);
    return clampParam(lower(*use.args.at(p)).c[0], param, domain.lo, std::min(domain.hi, capHi), floatResult);
}

LVal LaneEmitter::rgbParam(const ModelUse& use, int p, bool floatResult, double capHi) {
    const ModelParam& domain = use.model->canonical.at(p);
    const ParamPlan& param = plan.param(material.singleLobe().slotOf(use), p);
    LVal v = lower(*use.args.at(p));
    return map({v}, true,
               [&](auto& x) { return clampParam(x[0], param, domain.lo, std::min(domain.hi, capHi), floatResult); });
}

}  // namespace facet
