// VectorMath: the polynomial and bit-manipulation kernels behind exp, log,
// log1p, pow, erfcx and atan2 (see VectorMath.h for accuracies).
#include "VectorMath.h"

#include "Diagnostics.h"

#include <llvm/IR/Constants.h>
#include <llvm/IR/Intrinsics.h>

#include <cfloat>
#include <cmath>
#include <vector>

namespace facet {

using llvm::Value;

MathEmitter::MathEmitter(llvm::IRBuilder<>& builder, llvm::Type* type, bool fast)
    : b(builder), type_(type), fast_(fast) {
    llvm::Type* elem = type->getScalarType();
    isDouble_ = elem->isDoubleTy();
    llvm::Type* intElem = isDouble_ ? b.getInt64Ty() : b.getInt32Ty();
    if (auto* vt = llvm::dyn_cast<llvm::VectorType>(type))
        intType_ = llvm::VectorType::get(intElem, vt->getElementCount());
    else
        intType_ = intElem;
}

unsigned MathEmitter::width() const {
    if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(type_)) return vt->getNumElements();
    return 1;
}

Value* MathEmitter::c(double v) { return llvm::ConstantFP::get(type_, v); }
Value* MathEmitter::ci(int64_t v) { return llvm::ConstantInt::get(intType_, v, true); }
Value* MathEmitter::add(Value* a, Value* x) { return b.CreateFAdd(a, x); }
Value* MathEmitter::sub(Value* a, Value* x) { return b.CreateFSub(a, x); }
Value* MathEmitter::mul(Value* a, Value* x) { return b.CreateFMul(a, x); }
Value* MathEmitter::div(Value* a, Value* x) { return b.CreateFDiv(a, x); }
Value* MathEmitter::neg(Value* a) { return b.CreateFNeg(a); }
Value* MathEmitter::fma(Value* a, Value* x, Value* y) {
    return b.CreateIntrinsic(llvm::Intrinsic::fmuladd, {type_}, {a, x, y});
}
Value* MathEmitter::select(Value* cond, Value* a, Value* x) { return b.CreateSelect(cond, a, x); }
Value* MathEmitter::lt(Value* a, Value* x) { return b.CreateFCmpOLT(a, x); }
Value* MathEmitter::le(Value* a, Value* x) { return b.CreateFCmpOLE(a, x); }
Value* MathEmitter::gt(Value* a, Value* x) { return b.CreateFCmpOGT(a, x); }
Value* MathEmitter::ge(Value* a, Value* x) { return b.CreateFCmpOGE(a, x); }
Value* MathEmitter::eq(Value* a, Value* x) { return b.CreateFCmpOEQ(a, x); }
Value* MathEmitter::isNan(Value* a) { return b.CreateFCmpUNO(a, a); }
Value* MathEmitter::isFinite(Value* a) { return b.CreateFCmpOLT(abs(a), c(INFINITY)); }
Value* MathEmitter::isNanInfOrNegative(Value* a) {
    // Vectors: two compares, unordered a < 0 (NaN, -inf, negatives) or
    // a = +inf (llvm.is.fpclass would say it in one, but LLVM 19 expands it
    // into integer operations instead of vfpclassps). Scalars: not (|a| <
    // inf and a >= 0), which x86 codegen keeps in vucomiss/setcc; there the
    // two-compare form becomes sign tests through integer registers, which
    // made the scalar GGX kernel 27% slower, while it makes the SIMD kernels
    // 5-10% faster (docs/perf-log.md, 52c9884).
    if (width() == 1) return b.CreateNot(b.CreateAnd(isFinite(a), ge(a, c(0.0))));
    return b.CreateOr(b.CreateFCmpULT(a, c(0.0)), b.CreateFCmpOEQ(a, c(INFINITY)));
}

Value* MathEmitter::outside(Value* a, double lo, double hi) {
    internal_assert(lo > 0 && lo <= hi && std::isfinite(hi)) << "outside [" << lo << ", " << hi << "]";
    if (width() == 1) return b.CreateNot(b.CreateAnd(ge(a, c(lo)), le(a, c(hi))));
    // Vectors: one unsigned compare instead of two. Positive floats are
    // ordered as their bits, so a in [lo, hi] exactly when bits(a) - bits(lo)
    // (wrapping) is at most bits(hi) - bits(lo); 0, -0, negative values and
    // NaN wrap or lie above, as the ordered compares reject them. A compare
    // into a mask register costs an FMA's issue slot on the vector pipes,
    // the subtraction does not.
    const bool single = type_->getScalarType()->isFloatTy();
    auto bitsOf = [&](double x) -> uint64_t {
        if (single) return llvm::bit_cast<uint32_t>(float(x));
        return llvm::bit_cast<uint64_t>(x);
    };
    llvm::Type* intTy = single ? b.getInt32Ty() : b.getInt64Ty();
    auto splat = [&](uint64_t v) {
        return llvm::ConstantVector::getSplat(llvm::ElementCount::getFixed(unsigned(width())),
                                              llvm::ConstantInt::get(intTy, v));
    };
    Value* bits = b.CreateBitCast(a, llvm::FixedVectorType::get(intTy, unsigned(width())));
    return b.CreateICmpUGT(b.CreateSub(bits, splat(bitsOf(lo))), splat(bitsOf(hi) - bitsOf(lo)));
}

Value* MathEmitter::anyNanInfOrNegative(const std::vector<Value*>& xs) {
    internal_assert(!xs.empty() && xs.size() <= 4) << "anyNanInfOrNegative of " << xs.size() << " values";
    Value* any = nullptr;
    if (width() > 1 || xs.size() == 1 || !type_->isFloatTy()) {
        for (Value* x : xs) any = any ? b.CreateOr(any, isNanInfOrNegative(x)) : isNanInfOrNegative(x);
        return any;
    }
    // One lane: the values packed into one 4-lane vector and tested by two
    // compares, instead of a sign and exponent test per value through
    // integer registers (~10 instructions each, at the end of the lane's
    // longest chain). The test is "not in [0, FLT_MAX]": the vector form of
    // isNanInfOrNegative (unordered < 0 or = inf) is an fpclass test to
    // LLVM 19, which it expands into integer operations on 4-lane vectors.
    auto* quad = llvm::FixedVectorType::get(type_, 4);
    Value* v = llvm::Constant::getNullValue(quad);
    for (size_t i = 0; i < xs.size(); ++i) v = b.CreateInsertElement(v, xs[i], b.getInt32(uint32_t(i)));
    Value* bad = b.CreateNot(b.CreateAnd(b.CreateFCmpOGE(v, llvm::ConstantFP::get(quad, 0.0)),
                                         b.CreateFCmpOLE(v, llvm::ConstantFP::get(quad, FLT_MAX))));
    return b.CreateOrReduce(bad);
}

Value* MathEmitter::intrinsic(llvm::Intrinsic::ID id, Value* a) { return b.CreateIntrinsic(id, {type_}, {a}); }
Value* MathEmitter::intrinsic(llvm::Intrinsic::ID id, Value* a, Value* x) {
    return b.CreateIntrinsic(id, {type_}, {a, x});
}
Value* MathEmitter::abs(Value* a) { return intrinsic(llvm::Intrinsic::fabs, a); }
Value* MathEmitter::sqrt(Value* a) { return intrinsic(llvm::Intrinsic::sqrt, a); }
// One lane: two independent square roots queue on the one divide/square
// root unit; packed, they issue as one instruction.
std::pair<Value*, Value*> MathEmitter::sqrtBoth(Value* a, Value* x) {
    if (width() > 1) return {sqrt(a), sqrt(x)};
    auto* pair = llvm::FixedVectorType::get(type_, 2);
    Value* v = b.CreateInsertElement(llvm::PoisonValue::get(pair), a, b.getInt32(0));
    v = b.CreateInsertElement(v, x, b.getInt32(1));
    v = b.CreateIntrinsic(llvm::Intrinsic::sqrt, {pair}, {v});
    return {b.CreateExtractElement(v, b.getInt32(0)), b.CreateExtractElement(v, b.getInt32(1))};
}

Value* MathEmitter::minnum(Value* a, Value* x) { return intrinsic(llvm::Intrinsic::minnum, a, x); }
Value* MathEmitter::maxnum(Value* a, Value* x) { return intrinsic(llvm::Intrinsic::maxnum, a, x); }
Value* MathEmitter::min(Value* a, Value* x) { return intrinsic(llvm::Intrinsic::minimum, a, x); }
Value* MathEmitter::max(Value* a, Value* x) { return intrinsic(llvm::Intrinsic::maximum, a, x); }
Value* MathEmitter::rint(Value* a) { return intrinsic(llvm::Intrinsic::rint, a); }

Value* MathEmitter::poly(Value* x, std::initializer_list<double> coeffs) {
    // Horner from the highest coefficient down.
    auto it = coeffs.end();
    Value* acc = c(*--it);
    while (it != coeffs.begin()) acc = fma(acc, x, c(*--it));
    return acc;
}

Value* MathEmitter::polyEstrin(Value* x, std::initializer_list<double> coeffs) {
    const std::vector<double> k(coeffs);
    std::vector<Value*> terms;
    for (size_t i = 0; i < k.size(); i += 2) terms.push_back(i + 1 < k.size() ? fma(x, c(k[i + 1]), c(k[i])) : c(k[i]));
    // Each round halves the terms, t[2i] + x^(2^r) t[2i+1] in round r.
    Value* power = mul(x, x);
    while (terms.size() > 1) {
        std::vector<Value*> next;
        for (size_t i = 0; i < terms.size(); i += 2)
            next.push_back(i + 1 < terms.size() ? fma(power, terms[i + 1], terms[i]) : terms[i]);
        terms = std::move(next);
        if (terms.size() > 1) power = mul(power, power);
    }
    return terms.front();
}

Value* MathEmitter::convert(Value* v, llvm::Type* to) {
    if (v->getType() == to) return v;
    if (to->getScalarSizeInBits() > v->getType()->getScalarSizeInBits()) return b.CreateFPExt(v, to);
    return b.CreateFPTrunc(v, to);
}

Value* MathEmitter::exp2Int(Value* n) {
    // Build the IEEE bit pattern of 2^n directly.
    int mantissa = isDouble_ ? 52 : 23, bias = isDouble_ ? 1023 : 127;
    Value* i = b.CreateFPToSI(n, intType_);
    Value* bits = b.CreateShl(b.CreateAdd(i, ci(bias)), ci(mantissa));
    return b.CreateBitCast(bits, type_);
}

Value* MathEmitter::exp(Value* x) {
    const double hi = isDouble_ ? 709.782712893384 : 88.72283935546875;
    const double lo = isDouble_ ? -745.1332191019412 : -103.97208404541016;
    Value* xc = minnum(maxnum(x, c(lo)), c(hi));
    Value* n;
    Value* p = expReduced(xc, n);
    // Scale in two steps so that results in the subnormal range and up to
    // the largest finite value are both reachable.
    Value* n1 = intrinsic(llvm::Intrinsic::trunc, mul(n, c(0.5)));
    Value* n2 = sub(n, n1);
    Value* result = mul(mul(p, exp2Int(n1)), exp2Int(n2));
    result = select(gt(x, c(hi)), c(INFINITY), result);
    result = select(lt(x, c(lo)), c(0.0), result);
    return select(isNan(x), x, result);
}

Value* MathEmitter::expNormal(Value* x, bool floatResult) {
    // n in [-1010, 1010] (double) or [-123, 123] (float): 2^n is one
    // normal number, and p 2^n equals exp()'s p 2^n1 2^n2 exactly.
    Value* n;
    Value* p = expReduced(x, n, floatResult);
    return mul(p, exp2Int(n));
}

Value* MathEmitter::expReduced(Value* xc, Value*& n, bool floatResult) {
    // exp(x) = 2^n e^r, n = rint(x / ln 2), |r| <= ln2/2, r computed with a
    // two-part ln 2 so that n*C1 is exact. e^r by its Taylor series, one
    // degree past the type's precision (r^8/8! < 2^-28 for float).
    n = rint(mul(xc, c(1.4426950408889634)));
    Value *r;
    if (isDouble_) {
        r = fma(n, c(-6.93145751953125e-1), xc);
        r = fma(n, c(-1.42860682030941723212e-6), r);
    } else {
        r = fma(n, c(-0.693359375), xc);
        r = fma(n, c(2.12194440e-4), r);
    }
    Value* p;
    if (isDouble_ && floatResult)  // remainder ~ |r|^10/10! < 7e-12
        p = poly(r, {1, 1, 1 / 2.0, 1 / 6.0, 1 / 24.0, 1 / 120.0, 1 / 720.0, 1 / 5040.0, 1 / 40320.0,
                     1 / 362880.0});
    else if (isDouble_)
        p = poly(r, {1, 1, 1 / 2.0, 1 / 6.0, 1 / 24.0, 1 / 120.0, 1 / 720.0, 1 / 5040.0, 1 / 40320.0,
                     1 / 362880.0, 1 / 3628800.0, 1 / 39916800.0, 1 / 479001600.0, 1 / 6227020800.0});
    else if (fast_)  // degree 6: r^7/7! < 1.2e-7 relative
        p = poly(r, {1, 1, 1 / 2.0, 1 / 6.0, 1 / 24.0, 1 / 120.0, 1 / 720.0});
    else
        p = poly(r, {1, 1, 1 / 2.0, 1 / 6.0, 1 / 24.0, 1 / 120.0, 1 / 720.0, 1 / 5040.0, 1 / 40320.0});
    return p;
}

Value* MathEmitter::log(Value* x) {
    // x = m 2^e with m in [sqrt(1/2), sqrt(2)); log(1+f), f = m - 1, from the
    // series of 2 atanh(s), s = f/(2+f), arranged (as in fdlibm) so that the
    // exactly known f carries the leading term.
    int mantissa = isDouble_ ? 52 : 23, bias = isDouble_ ? 1023 : 127;
    double minNormal = isDouble_ ? 2.2250738585072014e-308 : 1.1754943508222875e-38;
    double denScale = isDouble_ ? 18014398509481984.0 /* 2^54 */ : 33554432.0 /* 2^25 */;
    int denShift = isDouble_ ? 54 : 25;
    Value* isDen = lt(x, c(minNormal));
    Value* xs = select(isDen, mul(x, c(denScale)), x);
    Value* bits = b.CreateBitCast(xs, intType_);
    int64_t mantMask = isDouble_ ? 0x000fffffffffffffLL : 0x7fffff;
    int64_t oneBits = isDouble_ ? 0x3ff0000000000000LL : 0x3f800000;
    Value* e = b.CreateSub(b.CreateLShr(bits, ci(mantissa)), ci(bias));
    Value* m = b.CreateBitCast(b.CreateOr(b.CreateAnd(bits, ci(mantMask)), ci(oneBits)), type_);
    Value* big = gt(m, c(1.4142135623730951));
    m = select(big, mul(m, c(0.5)), m);
    e = b.CreateAdd(e, b.CreateZExt(big, intType_));
    e = b.CreateSub(e, select(isDen, ci(denShift), ci(0)));
    Value* f = sub(m, c(1.0));
    Value* s = div(f, add(c(2.0), f));
    Value* z = mul(s, s);
    Value* R = isDouble_ ? mul(z, poly(z, {2 / 3.0, 2 / 5.0, 2 / 7.0, 2 / 9.0, 2 / 11.0, 2 / 13.0, 2 / 15.0,
                                         2 / 17.0, 2 / 19.0}))
               : fast_   ? mul(z, poly(z, {2 / 3.0, 2 / 5.0, 2 / 7.0}))  // z^4 term: < 2e-8
                         : mul(z, poly(z, {2 / 3.0, 2 / 5.0, 2 / 7.0, 2 / 9.0, 2 / 11.0}));
    Value* hfsq = mul(c(0.5), mul(f, f));
    Value* lf = sub(f, sub(hfsq, mul(s, add(hfsq, R))));
    Value* E = b.CreateSIToFP(e, type_);
    double ln2hi = isDouble_ ? 6.93147180369123816490e-01 : 0.693145751953125;
    double ln2lo = isDouble_ ? 1.90821492927058770002e-10 : 1.4286068203094172e-06;
    Value* result = fma(E, c(ln2hi), fma(E, c(ln2lo), lf));
    result = select(eq(x, c(0.0)), c(-INFINITY), result);
    result = select(eq(x, c(INFINITY)), x, result);
    // Negative or NaN input: NaN (the unordered compare catches NaN).
    return select(b.CreateFCmpULT(x, c(0.0)), c(NAN), result);
}

Value* MathEmitter::log1p(Value* x) {
    // log(u) * x / (u - 1) with u = 1 + x rounded: the quotient corrects the
    // rounding of u (Goldberg 1991), so small x keep full relative accuracy.
    Value* u = add(c(1.0), x);
    Value* d = sub(u, c(1.0));
    Value* r = mul(log(u), div(x, d));
    r = select(eq(d, c(0.0)), x, r);
    return select(eq(x, c(INFINITY)), x, r);
}

Value* MathEmitter::pow(Value* x, Value* y) {
    // exp(y log|x|) evaluated in double so that the product's rounding
    // (|y log x| up to ~100) does not cost float accuracy (fast: in float).
    llvm::Type* dty = type_->getScalarType()->isDoubleTy() || fast_
                          ? type_
                          : (width() > 1 ? (llvm::Type*)llvm::VectorType::get(b.getDoubleTy(), width(), false)
                                         : (llvm::Type*)b.getDoubleTy());
    MathEmitter d(b, dty, fast_);
    Value* X = d.convert(x, dty);
    Value* Y = d.convert(y, dty);
    Value* r = d.exp(d.mul(Y, d.log(d.abs(X))));
    Value* yInt = d.eq(d.rint(Y), Y);
    Value* yOdd = b.CreateAnd(yInt, b.CreateFCmpONE(d.mul(d.rint(d.mul(Y, d.c(0.5))), d.c(2.0)), Y));
    Value* neg = d.lt(X, d.c(0.0));
    r = d.select(b.CreateAnd(neg, yOdd), d.neg(r), r);
    r = d.select(b.CreateAnd(neg, b.CreateNot(yInt)), d.c(NAN), r);
    r = d.select(b.CreateOr(d.eq(Y, d.c(0.0)), d.eq(X, d.c(1.0))), d.c(1.0), r);
    return convert(r, type_);
}

Value* MathEmitter::erfcx(Value* x) {
    // exp(x^2) erfc(x) = t Q(t) on [0, 4], t = 1/(1 + x/2) in [1/3, 1]:
    // Q is smooth there, so a polynomial in u = 3t - 2 in [-1, 1] fits it
    // (Chebyshev interpolant of exp(a^2) erfc(a) / t, computed in double
    // from std::erfc: degree 9 within 1.0e-9, degree 7 (fast) within
    // 1.5e-7). Unlike erfc itself this needs no exp: callers that also
    // want exp(-x^2) (Beckmann's Lambda) compute that exp once.
    Value* t = div(c(1.0), fma(x, c(0.5), c(1.0)));
    Value* u = fma(t, c(3.0), c(-2.0));
    Value* q = fast_ ? poly(u, {0.64137541194314207, 0.29403933535157029, 0.066619300645764906,
                                0.00045436189384515102, -0.0026223273947471037, 2.0494742468568639e-05,
                                0.0001268485958774157, -1.3393034755893041e-05})
                     : poly(u, {0.64137536428934128, 0.29403935084782579, 0.066620824716861773,
                                0.00045387019687324057, -0.0026299444994267954, 2.2940722565634171e-05,
                                0.00013903213732131546, -1.7293292060038824e-05, -6.0903284747837466e-06,
                                1.9453809308345173e-06});
    return mul(t, q);
}

Value* MathEmitter::erfcxWide(Value* x) {
    // exp(x^2) erfc(x) = t Q(t), t = 1/(1 + x/4) in [1/3, 1] for x in [0, 8],
    // Q as a Chebyshev series in u = 3t - 2 in [-1, 1]. The 18 coefficients
    // are the Chebyshev interpolant of Q at 18 nodes, computed in
    // __float128 (erfcq); the truncation is below 1e-15 relative, and
    // Clenshaw's recurrence keeps the double rounding at a few ulps (a
    // monomial form of this degree would lose digits to cancellation).
    static const double kCheb[] = {
        0.48852333238058238,     0.36675797417450784,     0.11083299935000804,     0.027366874104304755,
        0.005512089060919048,    0.00088855482743268384,  0.00010912475423103769,  8.9020243263815163e-06,
        2.1037045046220292e-07,  -5.4477228202874779e-08, -6.6857616777708028e-09, 4.2354334600089629e-11,
        7.1580616906876796e-11,  3.0353875627949835e-12,  -6.9592001297247728e-13, -5.5312688443029196e-14,
        7.4856550041250511e-15,  7.8501817441494034e-16};
    constexpr int n = sizeof kCheb / sizeof kCheb[0];
    Value* t = div(c(1.0), fma(x, c(0.25), c(1.0)));
    Value* u = fma(t, c(3.0), c(-2.0));
    Value* twoU = add(u, u);
    Value *b1 = c(0.0), *b2 = c(0.0);
    for (int k = n - 1; k >= 1; --k) {
        Value* bk = add(fma(twoU, b1, neg(b2)), c(kCheb[k]));
        b2 = b1;
        b1 = bk;
    }
    return mul(t, add(fma(u, b1, neg(b2)), c(kCheb[0])));
}

Value* MathEmitter::gaussianQuantile(Value* u, double limit) {
    // By symmetry from the lower tail q = 2 min(u, 1 - u) (1 - u is exact),
    // where C(y) = erfc(-y)/2 = q/2, y <= 0. The start: Giles's
    // single-precision erfinv(q - 1) (GPU Computing Gems, 2010: a fit in w =
    // -ln(q (2 - q)), one polynomial below w = 5 and one in sqrt(w) above),
    // within 1.3e-7 relative of the root up to w = 16 (q down to 5.6e-8:
    // every float u from 2.8e-8 to 1 - 2^-24; measured against a 40-digit
    // bisection); beyond it, where the fit was not made, y^2 = L - ln(L)/2
    // with L = -ln(q sqrt(pi)) = w + ln 2 - ln(pi)/2 (from erfc(z) ~
    // exp(-z^2) / (z sqrt(pi))), within 2e-3. Then Halley's steps on C(y) =
    // q/2 with t = (C - q/2) / C' = sqrt(pi) (erfcx(-y)/2 - (q/2) exp(y^2)):
    // cubic convergence, one for the fitted lanes, two from the far tail's
    // start, 9e-16 from the worst (MathTests). The second runs only when a
    // lane of the vector needs it, and changes only such lanes: a lane's
    // value does not depend on its neighbours.
    internal_assert(isDouble_ && limit > 0 && limit <= 8) << "gaussianQuantile in float or beyond erfcxWide's [0, 8]";
    Value* upper = gt(u, c(0.5));
    Value* q = mul(select(upper, sub(c(1.0), u), u), c(2.0));
    q = maxnum(q, c(0x1p-1000));  // u = 0: a finite start, clamped below
    Value* w = neg(log(mul(q, sub(c(2.0), q))));
    Value* qm1 = sub(q, c(1.0));
    Value* central = mul(poly(sub(w, c(2.5)), {1.50140941, 0.246640727, -0.00417768164, -0.00125372503,
                                               0.00021858087, -4.39150654e-06, -3.5233877e-06, 3.43273939e-07,
                                               2.81022636e-08}),
                         qm1);
    Value* outer = mul(poly(sub(sqrt(w), c(3.0)), {2.83297682, 1.00167406, 0.00943887047, -0.0076224613,
                                                   0.00573950773, -0.00367342844, 0.00134934322, 0.000100950558,
                                                   -0.000200214257}),
                       qm1);
    Value* L = add(w, c(std::log(2.0) - 0.5 * std::log(M_PI)));
    Value* farTail = neg(sqrt(fma(log(maxnum(L, c(1.0))), c(-0.5), L)));
    Value* tail = ge(w, c(16.0));
    auto clamp = [&](Value* v) { return minnum(maxnum(v, c(-limit)), c(0.0)); };
    Value* halfQ = mul(q, c(0.5));
    auto halley = [&](Value* y) {
        y = clamp(y);
        Value* t = mul(c(std::sqrt(M_PI)), sub(mul(erfcxWide(neg(y)), c(0.5)), mul(halfQ, expNormal(mul(y, y)))));
        return clamp(sub(y, div(t, fma(y, t, c(1.0)))));
    };
    Value* once = halley(select(tail, farTail, select(lt(w, c(5.0)), central, outer)));

    llvm::BasicBlock* before = b.GetInsertBlock();
    llvm::Function* fn = before->getParent();
    auto* refine = llvm::BasicBlock::Create(b.getContext(), "quantile.tail", fn);
    auto* join = llvm::BasicBlock::Create(b.getContext(), "quantile.join", fn);
    b.CreateCondBr(anyLane(b, tail), refine, join);
    b.SetInsertPoint(refine);
    Value* twice = select(tail, halley(once), once);
    llvm::BasicBlock* refineEnd = b.GetInsertBlock();
    b.CreateBr(join);

    b.SetInsertPoint(join);
    llvm::PHINode* y = b.CreatePHI(type_, 2, "quantile.y");
    y->addIncoming(once, before);
    y->addIncoming(twice, refineEnd);
    return select(upper, neg(y), y);
}

Value* MathEmitter::atan2(Value* y, Value* x) {
    // Reduce to a = min/max in [0, 1], then to |t| <= tan(pi/8) with
    // atan(a) = pi/4 + atan((a-1)/(a+1)); odd Taylor series to t^21.
    Value* ax = abs(x);
    Value* mx = maxnum(ax, y);
    Value* mn = minnum(ax, y);
    Value* a = select(eq(mx, c(0.0)), c(0.0), div(mn, mx));
    Value* big = gt(a, c(0.41421356237309503));
    Value* t = select(big, div(sub(a, c(1.0)), add(a, c(1.0))), a);
    Value* z = mul(t, t);
    Value* series = fast_ ? poly(z, {-1 / 3.0, 1 / 5.0, -1 / 7.0, 1 / 9.0, -1 / 11.0, 1 / 13.0})  // t^15: < 2e-7
                          : poly(z, {-1 / 3.0, 1 / 5.0, -1 / 7.0, 1 / 9.0, -1 / 11.0, 1 / 13.0, -1 / 15.0, 1 / 17.0,
                                     -1 / 19.0, 1 / 21.0});
    Value* at = fma(mul(t, z), series, t);
    at = select(big, add(at, c(M_PI / 4)), at);
    Value* r = select(gt(y, ax), sub(c(M_PI / 2), at), at);
    return select(lt(x, c(0.0)), sub(c(M_PI), r), r);
}

std::pair<Value*, Value*> MathEmitter::sinCosTurns(Value* t) {
    // t = k/4 + f with k = rint(4 t) and |f| <= 1/8: t - k/4 is exact (k/4
    // has fewer significant bits than t), and r = 2 pi f is in [-pi/4, pi/4].
    Value* k = rint(mul(t, c(4.0)));
    Value* r = mul(fma(k, c(-0.25), t), c(2 * M_PI));
    Value* z = mul(r, r);
    Value *s, *co;
    if (isDouble_ && !fast_) {
        s = fma(mul(r, z), poly(z, {-1 / 6.0, 1 / 120.0, -1 / 5040.0, 1 / 362880.0, -1 / 39916800.0,
                                    1 / 6227020800.0, -1 / 1307674368000.0}), r);
        co = poly(z, {1.0, -1 / 2.0, 1 / 24.0, -1 / 720.0, 1 / 40320.0, -1 / 3628800.0, 1 / 479001600.0,
                      -1 / 87178291200.0, 1 / 20922789888000.0});
    } else {
        s = fma(mul(r, z), poly(z, {-1 / 6.0, 1 / 120.0, -1 / 5040.0, 1 / 362880.0}), r);
        co = poly(z, {1.0, -1 / 2.0, 1 / 24.0, -1 / 720.0, 1 / 40320.0, -1 / 3628800.0});
    }
    // The quadrant q = k mod 4 turns (cos, sin) by q quarter turns.
    Value* q = b.CreateAnd(b.CreateFPToSI(k, intType_), ci(3));
    Value* odd = b.CreateICmpEQ(b.CreateAnd(q, ci(1)), ci(1));
    Value* sinNeg = b.CreateICmpNE(b.CreateAnd(q, ci(2)), ci(0));                  // q = 2, 3
    Value* cosNeg = b.CreateICmpNE(b.CreateAnd(b.CreateAdd(q, ci(1)), ci(2)), ci(0));  // q = 1, 2
    Value* sinV = select(odd, co, s);
    Value* cosV = select(odd, s, co);
    return {select(sinNeg, neg(sinV), sinV), select(cosNeg, neg(cosV), cosV)};
}

Value* anyLane(llvm::IRBuilder<>& b, Value* mask) {
    auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(mask->getType());
    if (!vt) return mask;
    llvm::Type* bits = b.getIntNTy(unsigned(vt->getNumElements()));
    return b.CreateICmpNE(b.CreateBitCast(mask, bits), llvm::ConstantInt::get(bits, 0));
}

Value* allLanes(llvm::IRBuilder<>& b, Value* mask) {
    auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(mask->getType());
    if (!vt) return mask;
    llvm::Type* bits = b.getIntNTy(unsigned(vt->getNumElements()));
    return b.CreateICmpEQ(b.CreateBitCast(mask, bits), llvm::ConstantInt::getAllOnesValue(bits));
}

Value* dot(MathEmitter& m, const LaneVec3& a, const LaneVec3& b) {
    return m.fma(a[0], b[0], m.fma(a[1], b[1], m.mul(a[2], b[2])));
}

LaneVec3 selectVec(MathEmitter& m, Value* cond, const LaneVec3& a, const LaneVec3& b) {
    return {m.select(cond, a[0], b[0]), m.select(cond, a[1], b[1]), m.select(cond, a[2], b[2])};
}

LaneVec3 constantVec(MathEmitter& m, double x, double y, double z) { return {m.c(x), m.c(y), m.c(z)}; }

}  // namespace facet
