// ValueRange: interval arithmetic over the material language (see the header).
#include "ValueRange.h"

#include "Builtins.h"
#include "Diagnostics.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <fmt/format.h>

namespace facet {

namespace {

// A result computed in double and rounded (in the kernel, possibly in
// float, op by op) lies within a few float ulps of the exact value: widen
// outward by 2^-20 relative, which also covers the double bounds' own
// rounding. Zero stays exact (x - x and 0 * y are exact), and a bound
// beyond float's range becomes infinite, since float evaluation overflows
// there.
double widenDown(double x) {
    if (std::isnan(x) || x < -double(FLT_MAX)) return -INFINITY;
    return x > 0 ? x * (1 - 0x1p-20) : x * (1 + 0x1p-20);
}
double widenUp(double x) {
    if (std::isnan(x) || x > double(FLT_MAX)) return INFINITY;
    return x > 0 ? x * (1 + 0x1p-20) : x * (1 - 0x1p-20);
}

ValueRange make(double lo, double hi, bool maybeNaN) { return {widenDown(lo), widenUp(hi), maybeNaN}; }

bool contains(const ValueRange& r, double v) { return r.lo <= v && v <= r.hi; }
bool unbounded(const ValueRange& r) { return std::isinf(r.lo) || std::isinf(r.hi); }

// A product bound where 0 * Inf stands for the products of nearby values
// (0 there); the NaN of an exact 0 * Inf is reported separately.
double boundProduct(double a, double b) { return (a == 0 || b == 0) ? 0.0 : a * b; }

ValueRange add(const ValueRange& a, const ValueRange& b) {
    bool nan = a.maybeNaN || b.maybeNaN || (a.hi == INFINITY && b.lo == -INFINITY) ||
               (a.lo == -INFINITY && b.hi == INFINITY);
    double lo = (a.lo == -INFINITY || b.lo == -INFINITY) ? -INFINITY : a.lo + b.lo;
    double hi = (a.hi == INFINITY || b.hi == INFINITY) ? INFINITY : a.hi + b.hi;
    return make(lo, hi, nan);
}

ValueRange negate(const ValueRange& a) { return {-a.hi, -a.lo, a.maybeNaN}; }

ValueRange mul(const ValueRange& a, const ValueRange& b) {
    bool nan = a.maybeNaN || b.maybeNaN || (contains(a, 0) && unbounded(b)) || (contains(b, 0) && unbounded(a));
    double p[] = {boundProduct(a.lo, b.lo), boundProduct(a.lo, b.hi), boundProduct(a.hi, b.lo),
                  boundProduct(a.hi, b.hi)};
    return make(*std::min_element(p, p + 4), *std::max_element(p, p + 4), nan);
}

// x * x: never negative, which the product of two intervals does not know.
ValueRange square(const ValueRange& a) {
    double l = std::fabs(a.lo), h = std::fabs(a.hi);
    double lo = contains(a, 0) ? 0.0 : std::min(l, h) * std::min(l, h);
    return make(lo, std::max(l, h) * std::max(l, h), a.maybeNaN);
}

ValueRange div(const ValueRange& a, const ValueRange& b) {
    // A divisor that can come near 0 (or underflow to it) gives anything.
    const double tiny = 1e-30;
    if (b.lo <= tiny && b.hi >= -tiny) return ValueRange::any();
    if (unbounded(a) && unbounded(b)) return ValueRange::any();  // Inf / Inf
    double q[] = {a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi};
    return make(*std::min_element(q, q + 4), *std::max_element(q, q + 4), a.maybeNaN || b.maybeNaN);
}

// x^k for an integer k, as the lowering's repeated squaring computes it.
ValueRange powInt(const ValueRange& x, long k) {
    if (k == 0) return ValueRange::exactly(1.0);
    long e = std::labs(k);
    ValueRange r;
    if (e % 2 == 0) {
        ValueRange s = square(x);
        r = make(std::pow(s.lo, double(e / 2)), std::pow(s.hi, double(e / 2)), x.maybeNaN);
    } else {
        r = make(std::pow(x.lo, double(e)), std::pow(x.hi, double(e)), x.maybeNaN);
    }
    return k < 0 ? div(ValueRange::exactly(1.0), r) : r;
}

ValueRange unite(const ValueRange& a, const ValueRange& b) {
    return {std::min(a.lo, b.lo), std::max(a.hi, b.hi), a.maybeNaN || b.maybeNaN};
}

ValueRange builtin(BuiltinFn fn, const std::vector<ValueRange>& a) {
    switch (fn) {
        case BuiltinFn::Sqrt:
            if (a[0].lo >= 0) return make(std::sqrt(a[0].lo), std::sqrt(a[0].hi), a[0].maybeNaN);
            return make(0.0, std::sqrt(std::max(a[0].hi, 0.0)), true);
        case BuiltinFn::Exp: return make(std::exp(a[0].lo), std::exp(a[0].hi), a[0].maybeNaN);
        case BuiltinFn::Log:
            if (a[0].lo >= 0) return make(std::log(a[0].lo), std::log(a[0].hi), a[0].maybeNaN);
            return make(-INFINITY, std::log(std::max(a[0].hi, 0.0)), true);
        case BuiltinFn::Pow:
            // C's pow of a base >= 0 is in [0, Inf] and NaN only from a NaN
            // operand; a negative base with a non-integer exponent is NaN.
            if (a[0].lo >= 0) return {0.0, INFINITY, a[0].maybeNaN || a[1].maybeNaN};
            return ValueRange::any();
        case BuiltinFn::Abs: {
            const ValueRange& x = a[0];
            if (x.lo >= 0) return x;
            if (x.hi <= 0) return negate(x);
            return {0.0, std::max(-x.lo, x.hi), x.maybeNaN};
        }
        // min, max and clamp propagate NaN (Builtins.h).
        case BuiltinFn::Min: return {std::min(a[0].lo, a[1].lo), std::min(a[0].hi, a[1].hi), a[0].maybeNaN || a[1].maybeNaN};
        case BuiltinFn::Max: return {std::max(a[0].lo, a[1].lo), std::max(a[0].hi, a[1].hi), a[0].maybeNaN || a[1].maybeNaN};
        case BuiltinFn::Clamp:
            // The result is lo, hi, or x where lo <= x <= hi (lo wins when
            // the bounds are inverted).
            return {std::min(a[1].lo, a[2].lo), std::max(a[1].hi, a[2].hi),
                    a[0].maybeNaN || a[1].maybeNaN || a[2].maybeNaN};
        case BuiltinFn::Mix: return add(mul(add(a[1], negate(a[0])), a[2]), a[0]);
        case BuiltinFn::PhongExponent:
            return add(div(ValueRange::exactly(2.0), square(square(a[0]))), ValueRange::exactly(-2.0));
        case BuiltinFn::BeckmannToPhong:
            return add(div(ValueRange::exactly(2.0), square(a[0])), ValueRange::exactly(-2.0));
        case BuiltinFn::Rgb: return unite(unite(a[0], a[1]), a[2]);
    }
    internal_error << "unknown builtin";
}

// Whether two expressions are one value (x * x, a let times itself).
bool sameValue(const Expr& a, const Expr& b) {
    if (&a == &b) return true;
    if (a.kind != ExprKind::Name || b.kind != ExprKind::Name) return false;
    const auto &na = static_cast<const NameExpr&>(a), &nb = static_cast<const NameExpr&>(b);
    return na.binding == nb.binding && na.index == nb.index && na.binding != BindingKind::Unresolved;
}


}  // namespace

ValueRange ValueRange::exactly(double v) {
    if (std::isnan(v)) return any();
    return {v, v, false};
}

bool ValueRange::withinFloat() const { return lo >= -double(FLT_MAX) && hi <= double(FLT_MAX); }

ValueRange ValueRange::clampedTo(double cl, double ch) const {
    double l = std::max(cl, std::min(lo, ch)), h = std::max(cl, std::min(hi, ch));
    if (maybeNaN) {
        // minnum(NaN, ch) = ch (no minnum without an upper bound), then
        // maxnum(NaN, cl) = cl.
        double image = std::isfinite(ch) ? std::max(ch, cl) : cl;
        l = std::min(l, image), h = std::max(h, image);
    }
    return {l, h, false};
}

std::string ValueRange::str() const {
    return fmt::format("[{}, {}]{}", lo, hi, maybeNaN ? " or NaN" : "");
}

ValueRanges::ValueRanges(const CheckedMaterial& material) {
    for (const CheckedInput& in : material.inputs)
        inputs_.push_back(in.hasRange ? ValueRange::between(in.lo, in.hi)
                                      : ValueRange::between(-double(FLT_MAX), double(FLT_MAX)));
    for (const CheckedLet& let : material.lets) lets_.push_back(of(*let.value));
}

ValueRange ValueRanges::of(const Expr& e) const {
    switch (e.kind) {
        case ExprKind::Number: {
            // A literal the expression type may round (to float) is widened.
            double v = static_cast<const NumberExpr&>(e).value;
            return double(float(v)) == v ? ValueRange::exactly(v) : make(v, v, std::isnan(v));
        }
        case ExprKind::Name: {
            const auto& n = static_cast<const NameExpr&>(e);
            if (n.binding == BindingKind::Input) return inputs_.at(n.index);
            if (n.binding == BindingKind::Let && n.index < int(lets_.size())) return lets_.at(n.index);
            return ValueRange::any();
        }
        case ExprKind::Unary: return negate(of(*static_cast<const UnaryExpr&>(e).operand));
        case ExprKind::Binary: {
            const auto& bin = static_cast<const BinaryExpr&>(e);
            ValueRange l = of(*bin.lhs);
            switch (bin.op) {
                case BinaryOp::Add: return add(l, of(*bin.rhs));
                case BinaryOp::Sub: return add(l, negate(of(*bin.rhs)));
                case BinaryOp::Mul: return sameValue(*bin.lhs, *bin.rhs) ? square(l) : mul(l, of(*bin.rhs));
                case BinaryOp::Div: return div(l, of(*bin.rhs));
                case BinaryOp::Pow:
                    if (auto k = smallIntegerConstant(*bin.rhs)) return powInt(l, *k);
                    return builtin(BuiltinFn::Pow, {l, of(*bin.rhs)});
            }
            break;
        }
        case ExprKind::Call: {
            const auto& call = static_cast<const CallExpr&>(e);
            if (!call.function) return ValueRange::any();
            if (call.function->id == BuiltinFn::Pow)
                if (auto k = smallIntegerConstant(*call.args.at(1).value)) return powInt(of(*call.args[0].value), *k);
            std::vector<ValueRange> args;
            for (const Argument& a : call.args) args.push_back(of(*a.value));
            return builtin(call.function->id, args);
        }
    }
    internal_error << "unknown expression kind";
}

ValueRange ValueRanges::argument(const ModelUse& use, int p) const {
    return use.has(p) ? of(*use.args[p]) : ValueRange::any();
}

}  // namespace facet
