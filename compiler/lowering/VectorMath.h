// VectorMath: elementary functions emitted as straight-line LLVM IR (one
// exception: gaussianQuantile branches around its rare far-tail step).
//
// Every function here is written once against IRBuilder and works for any
// floating type the builder is given: float or double, scalar or a vector of
// any width. That is how the SIMD kernels keep exp, log, pow, erfcx and atan2
// vectorized (no per-lane calls into scalar libm) and how the scalar kernel
// gets the very same formulas, so scalar and SIMD agree bit for bit.
//
// Accuracy (exact mode), measured against long double in tests/jit/MathTests:
//   exp, log (float): <= 1 ulp;  log1p (float): <= 2 ulp
//   pow  (float, computed through double log/exp): <= 1 ulp
//   erfcx (float, 0 <= x <= 4): fit 1.0e-9 relative + rounding
//   erfcxWide (double, 0 <= x <= 8): 1e-15 relative (series 1e-15 + rounding)
//   atan2 (float): <= 3 ulp
//   sinCosTurns: Taylor remainder below 1e-16 (double), 2e-9 (float)
#pragma once

#include <llvm/IR/IRBuilder.h>

#include <array>
#include <utility>

namespace facet {

class MathEmitter {
public:
    // `type` is the floating type to compute in: float, double, or a vector of either.
    // `fast`: shorter polynomials (about 1e-6 relative instead of 1 ulp) and
    // pow in the emitter's own type instead of through double.
    MathEmitter(llvm::IRBuilder<>& builder, llvm::Type* type, bool fast = false);
    bool fast() const { return fast_; }

    llvm::Type* type() const { return type_; }
    llvm::Type* intType() const { return intType_; }
    bool isDouble() const { return isDouble_; }
    unsigned width() const;  // 1 for scalars

    llvm::Value* c(double v);  // constant (splatted for vectors)
    llvm::Value* ci(int64_t v);  // integer constant of intType()

    // Arithmetic shorthands (fmuladd lets the backend fuse where it can).
    llvm::Value* add(llvm::Value* a, llvm::Value* b);
    llvm::Value* sub(llvm::Value* a, llvm::Value* b);
    llvm::Value* mul(llvm::Value* a, llvm::Value* b);
    llvm::Value* div(llvm::Value* a, llvm::Value* b);
    llvm::Value* neg(llvm::Value* a);
    llvm::Value* fma(llvm::Value* a, llvm::Value* b, llvm::Value* c);
    llvm::Value* select(llvm::Value* cond, llvm::Value* a, llvm::Value* b);
    llvm::Value* lt(llvm::Value* a, llvm::Value* b);   // ordered <
    llvm::Value* le(llvm::Value* a, llvm::Value* b);
    llvm::Value* gt(llvm::Value* a, llvm::Value* b);
    llvm::Value* ge(llvm::Value* a, llvm::Value* b);
    llvm::Value* eq(llvm::Value* a, llvm::Value* b);
    llvm::Value* isNan(llvm::Value* a);
    llvm::Value* isFinite(llvm::Value* a);
    // NaN, +-inf or below zero (-0 is not).
    llvm::Value* isNanInfOrNegative(llvm::Value* a);
    // Whether any of up to four values is NaN, +-inf or below zero (the
    // same test, for the values of one lane).
    llvm::Value* anyNanInfOrNegative(const std::vector<llvm::Value*>& xs);
    // Not in [lo, hi] (0 < lo <= hi, finite): below, above, NaN, -0 or 0.
    llvm::Value* outside(llvm::Value* a, double lo, double hi);
    llvm::Value* abs(llvm::Value* a);
    llvm::Value* sqrt(llvm::Value* a);
    // sqrt(a) and sqrt(x); in one-lane code by one packed instruction.
    std::pair<llvm::Value*, llvm::Value*> sqrtBoth(llvm::Value* a, llvm::Value* x);
    // min/max that propagate NaN from either operand.
    llvm::Value* min(llvm::Value* a, llvm::Value* b);
    llvm::Value* max(llvm::Value* a, llvm::Value* b);
    // min/max where NaN operands are not a concern (faster: maxnum).
    llvm::Value* minnum(llvm::Value* a, llvm::Value* b);
    llvm::Value* maxnum(llvm::Value* a, llvm::Value* b);
    llvm::Value* rint(llvm::Value* a);
    // Horner evaluation of sum coeffs[i] x^i.
    llvm::Value* poly(llvm::Value* x, std::initializer_list<double> coeffs);
    // The same sum by Estrin's scheme: pairs c[i] + c[i+1] x combined with
    // x^2, x^4, ..., a dependency chain of about log2(n) FMAs instead of
    // n - 1, for a multiplication or two more. For series on the latency
    // path of a one-lane call; in a SIMD body, where throughput counts,
    // Horner does less work.
    llvm::Value* polyEstrin(llvm::Value* x, std::initializer_list<double> coeffs);

    llvm::Value* exp(llvm::Value* x);
    // exp(x) for x the caller has bounded to [-700, 700] (double) or
    // [-85, 85] (float), where the result is a normal number: the same
    // values as exp() there, without its clamping, NaN/overflow selects and
    // two-step scaling (about 15 operations fewer). `floatResult`: in
    // double, for a value that only ever reaches float (the NDF tails): the
    // Taylor series to r^9, within 1e-11 of exp() (9.4e-12 measured,
    // MathTests), far below float rounding, instead of r^13 (full double
    // precision).
    llvm::Value* expNormal(llvm::Value* x, bool floatResult = false);
    llvm::Value* log(llvm::Value* x);
    llvm::Value* log1p(llvm::Value* x);
    // pow with C semantics for the cases a material can reach: negative base
    // with an integer exponent, pow(x, 0) = 1, pow(0, y).
    llvm::Value* pow(llvm::Value* x, llvm::Value* y);
    // exp(x^2) erfc(x), the scaled complementary error function, for 0 <= x <= 4.
    llvm::Value* erfcx(llvm::Value* x);
    // The same for 0 <= x <= 8 to double precision (for double callers that
    // invert a CDF built from it, where erfcx()'s 1e-9 moves the root).
    llvm::Value* erfcxWide(llvm::Value* x);
    // y with erfc(-y)/2 = u (the quantile of the density exp(-y^2)/sqrt(pi)),
    // clamped to [-limit, limit], limit <= 8: within 1e-15 of long double
    // for u in [1e-30, 1 - 2^-24] (a fit and one Halley step; a second for
    // u below 2.8e-8, in a branch taken only when a lane needs it). Double
    // only.
    llvm::Value* gaussianQuantile(llvm::Value* u, double limit);
    // atan2(y, x) for y >= 0, in [0, pi].
    llvm::Value* atan2(llvm::Value* y, llvm::Value* x);
    // sin(2 pi t) and cos(2 pi t) for t in [-1, 1] (turns: an azimuth from a
    // uniform number). The reduction to a quarter turn is exact in the
    // argument's own type (t - k/4), so no 2 pi is rounded before it; then
    // Taylor series on [-pi/4, pi/4] (double: to r^16, below 1e-16;
    // float: to r^10, below 2e-9).
    std::pair<llvm::Value*, llvm::Value*> sinCosTurns(llvm::Value* t);
    // 2^n for an integer-valued n given in this floating type, with 2^n a
    // normal number: n in [-126, 127] (float) or [-1022, 1023] (double).
    llvm::Value* exp2Int(llvm::Value* n);

    // The same value in another floating type of the same width.
    llvm::Value* convert(llvm::Value* v, llvm::Type* to);

    llvm::IRBuilder<>& b;

private:
    // e^r for x = n ln 2 + r (sets n): the part exp() and expNormal() share.
    llvm::Value* expReduced(llvm::Value* x, llvm::Value*& n, bool floatResult = false);
    llvm::Value* intrinsic(llvm::Intrinsic::ID id, llvm::Value* a);
    llvm::Value* intrinsic(llvm::Intrinsic::ID id, llvm::Value* a, llvm::Value* c);
    llvm::Type* type_;
    llvm::Type* intType_;
    bool isDouble_;
    bool fast_;
};

// One i1 from a lane mask (i1 or <W x i1>): whether any lane is set, or all
// are, for the branches around work only some lanes need.
llvm::Value* anyLane(llvm::IRBuilder<>& b, llvm::Value* mask);
llvm::Value* allLanes(llvm::IRBuilder<>& b, llvm::Value* mask);

// Three lane values as a vector (a direction, a normal): their dot
// product, a lane-wise choice between two vectors, and a constant vector.
using LaneVec3 = std::array<llvm::Value*, 3>;
llvm::Value* dot(MathEmitter& m, const LaneVec3& a, const LaneVec3& b);
LaneVec3 selectVec(MathEmitter& m, llvm::Value* cond, const LaneVec3& a, const LaneVec3& b);
LaneVec3 constantVec(MathEmitter& m, double x, double y, double z);

}  // namespace facet
