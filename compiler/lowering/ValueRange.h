// ValueRange: which values a material's expressions can take on a valid
// lane, as an interval and whether NaN is possible.
//
// The lowering tests every model parameter for NaN and for overflowing
// float, and some emitters have cheaper forms that hold only within a
// range (GGX's Smith root from n.v alone needs alpha^2 <= 2). An input
// with a declared range is clamped to it before anything reads it, so
// `let alpha = roughness * roughness` with `roughness in 0 .. 1` can never
// be NaN or beyond float, and both tests would be dead code in every lane.
// This pass finds that out once, for the plan (LoweringPlan::params).
//
// The analysis is conservative: every value an expression can take, in
// double or in float, lies in its range (each result is widened by a few
// float ulps, and a bound beyond float's range counts as infinite), and
// maybeNaN is false only where no lane can produce NaN. Inputs without a
// range are any finite value: a non-finite input makes the lane invalid
// before its value matters.
#pragma once

#include "Material.h"

#include <cmath>
#include <string>
#include <vector>

namespace facet {

struct ValueRange {
    double lo = -INFINITY, hi = INFINITY;  // closed; infinite bounds are reachable
    bool maybeNaN = true;

    static ValueRange any() { return {}; }
    static ValueRange exactly(double v);
    static ValueRange between(double lo, double hi) { return {lo, hi, false}; }

    // Every value, rounded to float, is finite.
    bool withinFloat() const;
    // The values clamped to [lo, hi] as the lowering clamps a parameter
    // (minnum/maxnum: a NaN becomes a bound, the lane is invalid anyway).
    ValueRange clampedTo(double lo, double hi) const;
    std::string str() const;  // "[0, 1]", "[0, inf] or NaN"
};

// Ranges of one checked material's inputs and lets, computed once.
class ValueRanges {
public:
    explicit ValueRanges(const CheckedMaterial& material);
    // The range of e (an expression of the material: inputs and lets
    // resolved by the checker).
    ValueRange of(const Expr& e) const;
    // The range of model argument p of `use` before its domain clamp (any()
    // where the form leaves it unset).
    ValueRange argument(const ModelUse& use, int p) const;

private:
    std::vector<ValueRange> inputs_, lets_;
};

}  // namespace facet
