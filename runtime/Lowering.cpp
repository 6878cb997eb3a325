// Lowering: per-lane BRDF formulas in IR, and the scalar and batch drivers
// around them (see Lowering.h).
#include "Lowering.h"

#include "Diagnostics.h"
#include "Interpreter.h"  // gaussianNdfNorm: the normalization table is filled from the reference quadrature
#include "KullaConty.h"
#include "Specialize.h"
#include "VectorMath.h"

#include <llvm/IR/Constants.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Support/raw_ostream.h>

#include <cmath>

namespace facet {

const char* mathModeName(MathMode m) { return m == MathMode::Exact ? "exact" : "fast"; }

std::string MathVariant::name() const {
    std::string s = precise && !estimates && !shortPolynomials ? "exact" : (!precise && estimates && shortPolynomials ? "fast" : "custom");
    if (walterLambda) s += "+walter";
    if (schlickDielectric) s += "+schlick";
    return s;
}

namespace {

using llvm::Value;
constexpr double kPi = 3.141592653589793238462643383279502884;

// A lowered expression value: one channel for float, three for rgb. When the
// three channel Values are the same pointer the rgb is gray and every
// operation on it is emitted once ("computed once" specialization).
struct LVal {
    std::array<Value*, 3> c{};
    bool rgb = false;
    bool gray() const { return c[0] == c[1] && c[1] == c[2]; }
    static LVal scalar(Value* v) { return {{v, v, v}, false}; }
};

// Gaussian NDF normalization N(alpha) tabulated as q(x) = ln N(e^x) over
// x = ln alpha in [ln 1e-4, ln 1e4], for alphas that are only known per lane.
// Cubic (4-point Lagrange) interpolation keeps the relative error < 1e-8.
struct GaussianNormTable {
    static constexpr int kSize = 1024;
    static constexpr double kX0 = -9.210340371976184;  // ln 1e-4
    static constexpr double kX1 = 9.210340371976184;   // ln 1e4
    std::vector<double> q;
    GaussianNormTable() : q(kSize) {
        for (int i = 0; i < kSize; ++i) {
            double x = kX0 + (kX1 - kX0) * i / (kSize - 1);
            q[i] = std::log(gaussianNdfNorm<double>(std::exp(x)));
        }
    }
    static const GaussianNormTable& get() {
        static const GaussianNormTable table;  // immutable data, built once per process
        return table;
    }
};

class LaneEmitter {
public:
    LaneEmitter(const CheckedMaterial& m, const LoweringOptions& opt, llvm::IRBuilder<>& b, llvm::Type* F,
                llvm::Module& module)
        : mat_(m), opt_(opt), b_(b), f_(b, F, opt.variant.shortPolynomials),
          d_(b, opt.variant.precise ? doubleOf(b, F) : F, opt.variant.shortPolynomials),
          wide_(b, doubleOf(b, F)), module_(module) {
        invalid_ = llvm::Constant::getNullValue(boolType());
        if (opt.variant.estimates) {
            // Lets the backend replace division and sqrt by rcp/rsqrt
            // estimates plus a Newton step ("reciprocal-estimates" below).
            // No nnan/ninf: the NaN and overflow checks must stay exact.
            llvm::FastMathFlags fmf;
            fmf.setAllowReciprocal();
            fmf.setApproxFunc();
            fmf.setAllowContract();
            b_.setFastMathFlags(fmf);
        }
    }

    struct Result {
        std::array<Value*, 3> rgb;
        Value* invalid;
    };

    Result emit(std::array<Value*, 3> wi, std::array<Value*, 3> wo, const std::vector<Value*>& slots) {
        MathEmitter& m = f_;
        MathEmitter& d = d_;
        // SPEC 2: non-finite or non-unit directions are invalid lanes; valid
        // ones are renormalized. Normalization and the half vector are
        // computed in double: wi + wo cancels when the directions are nearly
        // opposite, and the float rounding of the renormalization would then
        // decide h (and so D, G and F) by itself.
        std::array<Value*, 3> wiD, woD;
        auto direction = [&](const std::array<Value*, 3>& w, std::array<Value*, 3>& out) {
            Value* finite = b_.CreateAnd(b_.CreateAnd(m.isFinite(w[0]), m.isFinite(w[1])), m.isFinite(w[2]));
            for (int i = 0; i < 3; ++i) out[i] = d.convert(w[i], d.type());
            Value* len = d.sqrt(d.fma(out[0], out[0], d.fma(out[1], out[1], d.mul(out[2], out[2]))));
            Value* unit = d.le(d.abs(d.sub(len, d.c(1.0))), d.c(kUnitTolerance));
            markInvalid(b_.CreateNot(b_.CreateAnd(finite, unit)));
            Value* inv = d.div(d.c(1.0), len);
            for (Value*& x : out) x = d.mul(x, inv);
        };
        direction(wi, wiD);
        direction(wo, woD);
        std::array<Value*, 3> hD = {d.add(wiD[0], woD[0]), d.add(wiD[1], woD[1]), d.add(wiD[2], woD[2])};
        Value* hlen = d.sqrt(d.fma(hD[0], hD[0], d.fma(hD[1], hD[1], d.mul(hD[2], hD[2]))));
        Value* hinv = d.div(d.c(1.0), hlen);
        for (Value*& x : hD) x = d.mul(x, hinv);
        // wi.h = wo.h = |wi + wo| / 2 for unit vectors: one value for both
        // keeps f exactly reciprocal. 1 - cos = |wi - wo|^2 / (2 (2 + |wi + wo|))
        // (from |wi + wo|^2 + |wi - wo|^2 = 4) has no cancellation at wi = wo.
        Value* cosD = d.minnum(d.mul(hlen, d.c(0.5)), d.c(1.0));
        std::array<Value*, 3> diff = {d.sub(wiD[0], woD[0]), d.sub(wiD[1], woD[1]), d.sub(wiD[2], woD[2])};
        Value* diff2 = d.fma(diff[0], diff[0], d.fma(diff[1], diff[1], d.mul(diff[2], diff[2])));
        Value* oneMinusCos = d.div(diff2, d.mul(d.c(2.0), d.add(d.c(2.0), hlen)));
        Geometry g;
        for (int i = 0; i < 3; ++i) {
            g.wi[i] = m.convert(wiD[i], m.type());
            g.wo[i] = m.convert(woD[i], m.type());
            g.h[i] = m.convert(hD[i], m.type());
        }
        g.hD = hD;
        g.oh = m.convert(cosD, m.type());
        g.cosD = cosD;
        g.oneMinusCos = m.convert(d.minnum(oneMinusCos, d.c(1.0)), m.type());
        g.hNonZero = d.gt(hlen, d.c(0.0));
        // Inputs: non-finite values are invalid; in-range clamping. Inputs,
        // lets and model parameters are evaluated in double: a parameter
        // such as alpha enters exp() multiplied by tens in the NDF tails, and
        // the user's arithmetic must not lose accuracy the reference keeps.
        inputs_.clear();
        for (const CheckedInput& in : mat_.inputs) {
            LVal v;
            v.rgb = in.type == ValueType::Rgb;
            for (int ch = 0; ch < in.slotCount(); ++ch) {
                Value* x = slots.at(in.firstSlot + ch);
                markInvalid(b_.CreateNot(m.isFinite(x)));
                x = d.convert(x, d.type());
                if (in.hasRange) x = d.maxnum(d.minnum(x, d.c(in.hi)), d.c(in.lo));
                v.c[ch] = x;
            }
            if (!v.rgb) v.c[1] = v.c[2] = v.c[0];
            inputs_.push_back(v);
        }
        lets_.clear();
        for (const CheckedLet& let : mat_.lets) lets_.push_back(lower(*let.value));

        Result r;
        r.rgb = brdf(g);
        for (Value*& x : r.rgb) {
            // A value that overflows float is an invalid lane, never Inf/NaN.
            markInvalid(b_.CreateNot(b_.CreateAnd(m.isFinite(x), m.ge(x, m.c(0.0)))));
        }
        for (Value*& x : r.rgb) x = m.select(invalid_, m.c(0.0), x);
        r.invalid = invalid_;
        return r;
    }

private:
    static llvm::Type* doubleOf(llvm::IRBuilder<>& b, llvm::Type* F) {
        if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(F))
            return llvm::FixedVectorType::get(b.getDoubleTy(), vt->getNumElements());
        return b.getDoubleTy();
    }
    llvm::Type* boolType() {
        if (auto* vt = llvm::dyn_cast<llvm::FixedVectorType>(f_.type()))
            return llvm::FixedVectorType::get(b_.getInt1Ty(), vt->getNumElements());
        return b_.getInt1Ty();
    }
    void markInvalid(Value* cond) { invalid_ = b_.CreateOr(invalid_, cond); }

    // Unit directions, half vector and wo.h of one lane, in float (computed in double).
    struct Geometry {
        std::array<Value*, 3> wi, wo, h;
        std::array<Value*, 3> hD;  // h in double, for NDFs whose exponent amplifies rounding
        Value* cosD;               // wo.h = wi.h in [0, 1], precise type (exact Fresnel near its critical angle)
        Value* oneMinusCos;        // 1 - wo.h = |wo - h|^2 / 2, float, without cancellation at wi = wo
        Value* oh;
        Value* hNonZero;
    };

    // ---- expressions ----

    // Applies `op` channel-wise, once for gray values.
    template <typename Op>
    LVal map(const std::vector<LVal>& args, bool rgb, Op op) {
        LVal out;
        out.rgb = rgb;
        bool gray = true;
        for (const LVal& a : args) gray &= a.gray();
        for (int ch = 0; ch < 3; ++ch) {
            if (gray && ch > 0) {
                out.c[ch] = out.c[0];
                continue;
            }
            std::vector<Value*> xs;
            for (const LVal& a : args) xs.push_back(a.c[ch]);
            out.c[ch] = op(xs);
        }
        return out;
    }

    // x^k for a small integer k, by repeated squaring (exact-ish and fast).
    Value* powInt(Value* x, long k) {
        MathEmitter& m = d_;
        bool negative = k < 0;
        unsigned long e = negative ? -k : k;
        Value* result = m.c(1.0);
        Value* base = x;
        bool first = true;
        while (e) {
            if (e & 1) {
                result = first ? base : m.mul(result, base);
                first = false;
            }
            e >>= 1;
            if (e) base = m.mul(base, base);
        }
        return negative ? m.div(m.c(1.0), result) : result;
    }

    std::optional<long> smallIntegerConstant(const Expr& e) {
        if (e.kind != ExprKind::Number) return std::nullopt;
        double v = static_cast<const NumberExpr&>(e).value;
        if (v != std::floor(v) || std::fabs(v) > 64) return std::nullopt;
        return long(v);
    }

    Value* applyBuiltin(BuiltinFn fn, const std::vector<Value*>& a) {
        MathEmitter& m = d_;
        switch (fn) {
            case BuiltinFn::Sqrt: return m.sqrt(a[0]);
            case BuiltinFn::Pow: return m.pow(a[0], a[1]);
            case BuiltinFn::Exp: return m.exp(a[0]);
            case BuiltinFn::Log: return m.log(a[0]);
            case BuiltinFn::Abs: return m.abs(a[0]);
            case BuiltinFn::Min: return m.min(a[0], a[1]);
            case BuiltinFn::Max: return m.max(a[0], a[1]);
            case BuiltinFn::Clamp: {
                // As the reference: NaN anywhere gives NaN; otherwise lo wins
                // over hi when the bounds are inverted.
                Value* nan = b_.CreateOr(b_.CreateOr(m.isNan(a[0]), m.isNan(a[1])), m.isNan(a[2]));
                Value* r = m.select(m.lt(a[0], a[1]), a[1], m.select(m.gt(a[0], a[2]), a[2], a[0]));
                return m.select(nan, m.c(NAN), r);
            }
            case BuiltinFn::Mix: return m.fma(m.sub(a[1], a[0]), a[2], a[0]);
            case BuiltinFn::PhongExponent: {
                Value* r2 = m.mul(a[0], a[0]);
                return m.sub(m.div(m.c(2.0), m.mul(r2, r2)), m.c(2.0));
            }
            case BuiltinFn::BeckmannToPhong: return m.sub(m.div(m.c(2.0), m.mul(a[0], a[0])), m.c(2.0));
            case BuiltinFn::Rgb: break;
        }
        internal_error << "builtin has no channel-wise lowering";
    }

    // Lowers an expression in double (see emit()).
    LVal lower(const Expr& e) {
        MathEmitter& m = d_;
        switch (e.kind) {
            case ExprKind::Number: return LVal::scalar(m.c(static_cast<const NumberExpr&>(e).value));
            case ExprKind::Name: {
                const auto& n = static_cast<const NameExpr&>(e);
                return n.binding == BindingKind::Input ? inputs_.at(n.index) : lets_.at(n.index);
            }
            case ExprKind::Unary: {
                LVal v = lower(*static_cast<const UnaryExpr&>(e).operand);
                return map({v}, v.rgb, [&](auto& x) { return m.neg(x[0]); });
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
                        case BinaryOp::Add: return m.add(x[0], x[1]);
                        case BinaryOp::Sub: return m.sub(x[0], x[1]);
                        case BinaryOp::Mul: return m.mul(x[0], x[1]);
                        case BinaryOp::Div: return m.div(x[0], x[1]);
                        case BinaryOp::Pow: return m.pow(x[0], x[1]);
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
                return map(args, e.type == ValueType::Rgb,
                           [&](auto& x) { return applyBuiltin(call.function->id, x); });
            }
        }
        internal_error << "unknown expression kind";
    }

    // Model parameter, clamped to [lo, hi]; NaN, or infinite after clamping,
    // marks the lane invalid (as in the reference).
    // Clamps a double parameter; the result is double (floatResult: float).
    Value* clampParam(Value* x, double lo, double hi, bool floatResult) {
        MathEmitter& d = d_;
        markInvalid(d.isNan(x));
        if (std::isfinite(hi)) x = d.minnum(x, d.c(hi));
        x = d.maxnum(x, d.c(lo));
        Value* xf = f_.convert(x, f_.type());
        // Finite in double but not in float is still an invalid lane: the
        // float formulas would overflow.
        markInvalid(b_.CreateNot(f_.isFinite(xf)));
        return floatResult ? xf : x;
    }
    Value* scalarParam(const ModelUse& use, int p, double lo, double hi, bool floatResult = true) {
        return clampParam(lower(*use.args.at(p)).c[0], lo, hi, floatResult);
    }
    LVal rgbParam(const ModelUse& use, int p, double lo, double hi, bool floatResult = true) {
        LVal v = lower(*use.args.at(p));
        return map({v}, true, [&](auto& x) { return clampParam(x[0], lo, hi, floatResult); });
    }

    // ---- model terms ----

    struct Ndf {
        Value *ax = nullptr, *ay = nullptr;  // ggx, beckmann, ward, gtr, gaussian (float)
        Value *axD = nullptr, *ayD = nullptr;  // the same in double
        bool isotropic = false;
        Value* exponent = nullptr;  // blinn_phong (double)
        Value* gamma = nullptr;     // gtr (double)
        Value* gaussianNorm = nullptr;
    };

    Ndf ndfParams() {
        MathEmitter& m = f_;
        Ndf n;
        const ModelUse& use = mat_.ndf;
        switch (mat_.ndfModel()) {
            case NdfModel::Ggx:
            case NdfModel::Beckmann:
            case NdfModel::Ward:
                n.axD = scalarParam(use, param::AlphaX, kMinAlpha, INFINITY, false);
                n.isotropic = use.args[param::AlphaX] == use.args[param::AlphaY];
                n.ayD = n.isotropic ? n.axD : scalarParam(use, param::AlphaY, kMinAlpha, INFINITY, false);
                break;
            case NdfModel::BlinnPhong: n.exponent = scalarParam(use, param::Exponent, 0, kMaxPhongExponent, false); break;
            case NdfModel::Gtr:
                n.axD = n.ayD = scalarParam(use, param::GtrAlpha, kMinAlpha, INFINITY, false);
                n.gamma = scalarParam(use, param::GtrGamma, 0, INFINITY, false);
                n.isotropic = true;
                break;
            case NdfModel::Gaussian: {
                n.axD = n.ayD = scalarParam(use, param::GaussianAlpha, kMinAlpha, INFINITY, false);
                n.isotropic = true;
                const Expr& arg = *use.args[param::GaussianAlpha];
                if (isConstantExpr(arg)) {
                    double alpha = std::max(constantValue(arg)[0], kMinAlpha);
                    n.gaussianNorm = m.c(gaussianNdfNorm<double>(alpha));
                } else {
                    n.gaussianNorm = gaussianNormLookup(n.axD);
                }
                break;
            }
        }
        if (n.axD) {
            n.ax = m.convert(n.axD, m.type());
            n.ay = n.isotropic ? n.ax : m.convert(n.ayD, m.type());
        }
        return n;
    }

    // N(alpha) per lane from GaussianNormTable: 4-point Lagrange in double,
    // table entries fetched with gathers.
    Value* gaussianNormLookup(Value* alpha) {
        const GaussianNormTable& t = GaussianNormTable::get();
        MathEmitter& d = wide_;
        llvm::LLVMContext& ctx = module_.getContext();
        auto* arrTy = llvm::ArrayType::get(b_.getDoubleTy(), t.q.size());
        llvm::GlobalVariable* gv = module_.getNamedGlobal("facet_gaussian_norm_table");
        if (!gv) {
            gv = new llvm::GlobalVariable(module_, arrTy, true, llvm::GlobalValue::PrivateLinkage,
                                          llvm::ConstantDataArray::get(ctx, t.q), "facet_gaussian_norm_table");
        }
        double h = (GaussianNormTable::kX1 - GaussianNormTable::kX0) / (GaussianNormTable::kSize - 1);
        Value* x = d.log(d.convert(alpha, d.type()));
        Value* u = d.div(d.sub(x, d.c(GaussianNormTable::kX0)), d.c(h));
        // Alphas beyond the table use its ends (N is flat in log alpha
        // there); the 4-point stencil stays inside: i in [1, size - 3], and
        // s = u - i in [-1, 2] then interpolates (or reaches the end nodes).
        u = d.minnum(d.maxnum(u, d.c(0.0)), d.c(GaussianNormTable::kSize - 1.0));
        Value* fi = d.minnum(d.maxnum(intrinsic(llvm::Intrinsic::floor, u), d.c(1.0)),
                             d.c(GaussianNormTable::kSize - 3.0));
        Value* s = d.sub(u, fi);
        llvm::Type* i32 = b_.getInt32Ty();
        llvm::Type* idxTy = d.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, d.width()) : i32;
        Value* idx = b_.CreateFPToSI(fi, idxTy);
        auto fetch = [&](int offset) -> Value* {
            Value* j = b_.CreateAdd(idx, llvm::ConstantInt::get(idxTy, offset, true));
            Value* ptr = b_.CreateGEP(b_.getDoubleTy(), gv, j);
            if (d.width() == 1) return b_.CreateLoad(b_.getDoubleTy(), ptr);
            return b_.CreateMaskedGather(d.type(), ptr, llvm::Align(8));
        };
        Value *p0 = fetch(-1), *p1 = fetch(0), *p2 = fetch(1), *p3 = fetch(2);
        // Lagrange weights at s for nodes -1, 0, 1, 2.
        Value* sm1 = d.add(s, d.c(1.0));
        Value* s1 = d.sub(s, d.c(1.0));
        Value* s2 = d.sub(s, d.c(2.0));
        Value* w0 = d.mul(d.mul(s, d.mul(s1, s2)), d.c(-1.0 / 6.0));
        Value* w1 = d.mul(d.mul(sm1, d.mul(s1, s2)), d.c(0.5));
        Value* w2 = d.mul(d.mul(sm1, d.mul(s, s2)), d.c(-0.5));
        Value* w3 = d.mul(d.mul(sm1, d.mul(s, s1)), d.c(1.0 / 6.0));
        Value* q = d.fma(w0, p0, d.fma(w1, p1, d.fma(w2, p2, d.mul(w3, p3))));
        return f_.convert(d.exp(q), f_.type());
    }

    Value* intrinsic(llvm::Intrinsic::ID id, Value* a) { return b_.CreateIntrinsic(id, {a->getType()}, {a}); }

    // expm1(y)/y, continuous at 0: the series where exp(y) - 1 would cancel
    // (|y| < 1e-5 in double, < 1e-2 in float), the quotient elsewhere.
    Value* expm1OverX(Value* y) {
        MathEmitter& d = d_;
        Value* series = d.poly(y, {1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0});
        Value* direct = d.div(d.sub(d.exp(y), d.c(1.0)), y);
        return d.select(d.lt(d.abs(y), d.c(d.isDouble() ? 1e-5 : 1e-2)), series, direct);
    }

    // mx^2/ax^2 + my^2/ay^2 (one division when isotropic).
    Value* slope2(const Ndf& n, const std::array<Value*, 3>& h) {
        MathEmitter& m = f_;
        Value *x2 = m.mul(h[0], h[0]), *y2 = m.mul(h[1], h[1]);
        if (n.isotropic) return m.div(m.add(x2, y2), m.mul(n.ax, n.ax));
        return m.add(m.div(x2, m.mul(n.ax, n.ax)), m.div(y2, m.mul(n.ay, n.ay)));
    }

    // tan^2-weighted slope (mx^2/ax^2 + my^2/ay^2)/mz^2 in double: it is
    // the argument of exp() for beckmann and ward, where its rounding error
    // is multiplied by its size (tens) in the result.
    Value* slopeExponentD(const Ndf& n, const std::array<Value*, 3>& hD) {
        MathEmitter& d = d_;
        Value *ax = n.axD, *ay = n.ayD;
        Value *x2 = d.mul(hD[0], hD[0]), *y2 = d.mul(hD[1], hD[1]), *z2 = d.mul(hD[2], hD[2]);
        Value* s = n.isotropic ? d.div(d.add(x2, y2), d.mul(ax, ax))
                               : d.add(d.div(x2, d.mul(ax, ax)), d.div(y2, d.mul(ay, ay)));
        return d.div(s, z2);
    }

    Value* D(const Ndf& n, const std::array<Value*, 3>& h, const std::array<Value*, 3>& hD) {
        MathEmitter& m = f_;
        Value *x2 = m.mul(h[0], h[0]), *y2 = m.mul(h[1], h[1]), *z2 = m.mul(h[2], h[2]);
        auto slope2 = [&]() { return this->slope2(n, h); };
        switch (mat_.ndfModel()) {
            case NdfModel::Ggx: {
                Value* t = m.add(slope2(), z2);
                return m.div(m.c(1.0 / kPi), m.mul(m.mul(n.ax, n.ay), m.mul(t, t)));
            }
            case NdfModel::Beckmann: {
                MathEmitter& d = d_;
                Value* e = slopeExponentD(n, hD);
                Value* z2d = d.mul(hD[2], hD[2]);
                Value* axy = d.mul(n.axD, n.ayD);
                Value* D = d.div(d.exp(d.neg(e)), d.mul(d.mul(d.c(kPi), axy), d.mul(z2d, z2d)));
                // exp underflowed: 0, not 0/0 when mz^4 underflows too.
                D = d.select(d.gt(e, d.c(d.isDouble() ? 700.0 : 85.0)), d.c(0.0), D);
                return m.convert(D, m.type());
            }
            case NdfModel::BlinnPhong: {
                // mz^e = exp(e/2 log1p(-(mx^2 + my^2))) in double: mz itself
                // is too coarse in float once e is large (1e6).
                MathEmitter& d = d_;
                // ln mz: near the pole from sin^2 (log1p(-s2)/2 keeps the
                // small angle exact), near the horizon from mz itself (where
                // 1 - s2 would cancel).
                Value* s2 = d.minnum(d.fma(hD[0], hD[0], d.mul(hD[1], hD[1])), d.c(1.0));
                Value* lnz = d.select(d.lt(s2, d.c(0.5)), d.mul(d.c(0.5), d.log1p(d.neg(s2))), d.log(hD[2]));
                Value* E = d.convert(n.exponent, d.type());
                Value* p = d.exp(d.mul(E, lnz));
                p = d.select(d.eq(E, d.c(0.0)), d.c(1.0), p);
                Value* norm = d.mul(d.add(E, d.c(2.0)), d.c(1.0 / (2 * kPi)));
                return f_.convert(d.mul(norm, p), f_.type());
            }
            case NdfModel::Gtr: {
                // c / t^gamma, c = phi(L) / (pi phi((1 - gamma) L)), L = ln a^2,
                // t = a^2 mz^2 + mx^2 + my^2; all in double.
                MathEmitter& d = d_;
                Value* A2 = d.mul(n.axD, n.axD);
                Value* L = d.log(A2);
                Value* G = n.gamma;
                Value* c = d.div(expm1OverX(L), d.mul(d.c(kPi), expm1OverX(d.mul(d.sub(d.c(1.0), G), L))));
                Value* t = d.fma(A2, d.mul(hD[2], hD[2]), d.fma(hD[0], hD[0], d.mul(hD[1], hD[1])));
                return f_.convert(d.mul(c, d.exp(d.neg(d.mul(G, d.log(t))))), f_.type());
            }
            case NdfModel::Gaussian: {
                // theta^2/alpha^2 is an exponent too: double.
                MathEmitter& d = d_;
                Value* theta = d.atan2(d.sqrt(d.fma(hD[0], hD[0], d.mul(hD[1], hD[1]))), hD[2]);
                Value* e = d.div(d.mul(theta, theta), d.mul(n.axD, n.axD));
                return m.div(m.convert(d.exp(d.neg(e)), m.type()), n.gaussianNorm);
            }
            case NdfModel::Ward: break;
        }
        internal_error << "D for ward";
    }

    // Smith Lambda(v) for ggx, beckmann and blinn_phong.
    Value* lambda(const Ndf& n, const std::array<Value*, 3>& v) {
        MathEmitter& m = f_;
        Value *ax = n.ax, *ay = n.ay;
        bool iso = n.isotropic;
        if (mat_.ndfModel() == NdfModel::BlinnPhong) {
            ax = ay = m.convert(d_.sqrt(d_.div(d_.c(2.0), d_.add(n.exponent, d_.c(2.0)))), m.type());
            iso = true;
        }
        Value* proj = iso ? m.mul(m.mul(ax, ax), m.fma(v[0], v[0], m.mul(v[1], v[1])))
                          : m.fma(m.mul(v[0], ax), m.mul(v[0], ax), m.mul(m.mul(v[1], ay), m.mul(v[1], ay)));
        if (mat_.ndfModel() == NdfModel::Ggx) {
            // t = alpha tan(theta); Lambda = (sqrt(1 + t^2) - 1)/2 written as
            // t^2 / (2 (1 + sqrt(1 + t^2))), and (t - 1)/2 once t^2 would overflow.
            Value* t = m.div(m.sqrt(proj), v[2]);
            Value* t2 = m.mul(t, t);
            Value* small = m.div(t2, m.mul(m.c(2.0), m.add(m.c(1.0), m.sqrt(m.add(m.c(1.0), t2)))));
            return m.select(m.gt(t, m.c(1e7)), m.mul(m.sub(t, m.c(1.0)), m.c(0.5)), small);
        }
        Value* a = m.div(v[2], m.sqrt(proj));
        if (opt_.variant.walterLambda) {
            // Walter et al. 2007, eq. 27 (as Lambda = 1/G1 - 1): rational in a,
            // 0 for a >= 1.6. Relative error in G1 below about 0.4%.
            Value* num = m.poly(a, {1.0, -1.259, 0.396});
            Value* den = m.mul(a, m.poly(a, {3.535, 2.181}));
            Value* l = m.select(m.lt(a, m.c(1.6)), m.div(num, den), m.c(0.0));
            return m.select(m.eq(proj, m.c(0.0)), m.c(0.0), l);
        }
        // Beckmann: a = cot / alpha; Lambda = (exp(-a^2)/(a sqrt(pi)) - erfc(a)) / 2.
        Value* l = m.mul(m.c(0.5), m.sub(m.div(m.exp(m.neg(m.mul(a, a))), m.mul(a, m.c(std::sqrt(kPi)))), m.erfc(a)));
        l = m.maxnum(l, m.c(0.0));
        return m.select(m.eq(proj, m.c(0.0)), m.c(0.0), l);
    }

    Value* G(const Ndf& n, const std::array<Value*, 3>& wi, const std::array<Value*, 3>& wo,
             const std::array<Value*, 3>& h, Value* ci, Value* co, Value* oh) {
        MathEmitter& m = f_;
        Value* nh = h[2];
        Value* one = m.c(1.0);
        auto azimuthWeight = [&] {
            Value* cross = m.abs(m.sub(m.mul(wi[0], wo[1]), m.mul(wi[1], wo[0])));
            Value* dot = m.fma(wi[0], wo[0], m.mul(wi[1], wo[1]));
            Value* phi = m.mul(m.c(4.41), m.atan2(cross, dot));
            return m.div(phi, m.add(phi, one));
        };
        switch (mat_.maskingModel()) {
            case MaskingModel::None: return one;
            case MaskingModel::Implicit: return m.mul(ci, co);
            case MaskingModel::CookTorrance: {
                Value* k = m.div(m.mul(m.c(2.0), nh), oh);
                return m.minnum(one, m.mul(k, m.minnum(ci, co)));
            }
            case MaskingModel::Kelemen: return m.div(m.mul(ci, co), m.mul(oh, oh));
            case MaskingModel::Neumann: return m.div(m.mul(ci, co), m.maxnum(ci, co));
            case MaskingModel::SchlickSmith: {
                Value* k = scalarParam(mat_.masking, param::SchlickK, 0, 1);
                Value* omk = m.sub(one, k);
                auto g1 = [&](Value* c) { return m.div(c, m.fma(c, omk, k)); };
                return m.mul(g1(ci), g1(co));
            }
            case MaskingModel::SmithSeparable:
                return m.div(one, m.mul(m.add(one, lambda(n, wi)), m.add(one, lambda(n, wo))));
            case MaskingModel::SmithHeightCorrelated:
                return m.div(one, m.add(one, m.add(lambda(n, wi), lambda(n, wo))));
            case MaskingModel::SmithDirectionCorrelated: {
                Value* g1i = m.div(one, m.add(one, lambda(n, wi)));
                Value* g1o = m.div(one, m.add(one, lambda(n, wo)));
                Value* w = azimuthWeight();
                return m.fma(w, m.mul(g1i, g1o), m.mul(m.sub(one, w), m.minnum(g1i, g1o)));
            }
            case MaskingModel::SmithHeightDirectionCorrelated: {
                Value *li = lambda(n, wi), *lo = lambda(n, wo);
                return m.div(one, m.add(one, m.fma(azimuthWeight(), m.minnum(li, lo), m.maxnum(li, lo))));
            }
        }
        internal_error << "unknown masking";
    }

    LVal fresnel(const Geometry& geo) {
        MathEmitter& m = f_;
        MathEmitter& d = d_;
        Value* one = m.c(1.0);
        Value* dOne = d.c(1.0);
        Value* c = geo.cosD;  // double
        const ModelUse& use = mat_.fresnel;
        switch (mat_.fresnelModel()) {
            case FresnelModel::None: return LVal::scalar(one);
            case FresnelModel::Schlick: {
                Value* q = geo.oneMinusCos;
                Value* q2 = m.mul(q, q);
                Value* q5 = m.mul(m.mul(q2, q2), q);
                LVal f0;
                if (use.has(param::F0)) {
                    f0 = rgbParam(use, param::F0, 0, 1);
                } else {
                    LVal eta = rgbParam(use, param::SchlickEta, kMinEta, INFINITY);
                    f0 = map({eta}, true, [&](auto& x) {
                        Value* r = m.div(m.sub(x[0], one), m.add(x[0], one));
                        return m.mul(r, r);
                    });
                }
                return map({f0}, true, [&](auto& x) { return m.fma(m.sub(one, x[0]), q5, x[0]); });
            }
            case FresnelModel::Dielectric: {
                if (opt_.variant.schlickDielectric) {
                    // Schlick with f0 = ((eta - 1)/(eta + 1))^2: only chosen by a
                    // tolerance that its measured error meets.
                    LVal eta = rgbParam(use, param::DielectricEta, kMinEta, INFINITY);
                    Value* q = geo.oneMinusCos;
                    Value* q2 = m.mul(q, q);
                    Value* q5 = m.mul(m.mul(q2, q2), q);
                    return map({eta}, true, [&](auto& x) {
                        Value* r = m.div(m.sub(x[0], one), m.add(x[0], one));
                        Value* f0 = m.mul(r, r);
                        return m.fma(m.sub(one, f0), q5, f0);
                    });
                }
                // In double: near the critical angle F depends on sqrt(g^2)
                // with g^2 -> 0, which turns float rounding of cos into
                // visible error.
                LVal eta = rgbParam(use, param::DielectricEta, kMinEta, INFINITY, false);
                Value* c2 = d.mul(c, c);
                return map({eta}, true, [&](auto& x) {
                    // g^2 = eta^2 - sin^2; g - c = (eta^2 - 1)/(g + c) without cancellation.
                    Value* n = x[0];
                    Value* e2m1 = d.mul(d.sub(n, dOne), d.add(n, dOne));
                    Value* g2 = d.add(e2m1, c2);
                    Value* g = d.sqrt(d.maxnum(g2, d.c(0.0)));
                    Value* gp = d.add(g, c);
                    Value* gm = d.div(e2m1, gp);
                    Value* A = d.div(gm, gp);
                    Value* B = d.div(d.fma(c, gp, d.c(-1.0)), d.fma(c, gm, dOne));
                    Value* F = d.mul(d.mul(d.c(0.5), d.mul(A, A)), d.fma(B, B, dOne));
                    Value* tir = b_.CreateOr(d.le(g2, d.c(0.0)), d.eq(gp, d.c(0.0)));
                    return m.convert(d.select(tir, dOne, F), m.type());
                });
            }
            case FresnelModel::Conductor: {
                LVal eta = rgbParam(use, param::ConductorEta, kMinEta, INFINITY, false);
                LVal k = rgbParam(use, param::ConductorK, 0, INFINITY, false);
                Value* c2 = d.mul(c, c);
                Value* s2 = d.mul(d.sub(dOne, c), d.add(dOne, c));
                return map({eta, k}, true, [&](auto& x) {
                    // |N cos_t|^2 = a^2 + b^2 with N = eta + ik (Born & Wolf):
                    // t0 = eta^2 - k^2 - sin^2, a2b2 = sqrt(t0^2 + 4 eta^2 k^2).
                    Value *n = x[0], *kk = x[1];
                    Value* n2 = d.mul(n, n);
                    Value* k2 = d.mul(kk, kk);
                    Value* t0 = d.sub(d.sub(n2, k2), s2);
                    Value* a2b2 = d.sqrt(d.fma(t0, t0, d.mul(d.c(4.0), d.mul(n2, k2))));
                    Value* a = d.sqrt(d.maxnum(d.mul(d.c(0.5), d.add(a2b2, t0)), d.c(0.0)));
                    Value* t1 = d.add(a2b2, c2);
                    Value* t2 = d.mul(d.mul(d.c(2.0), c), a);
                    Value* Rs = d.div(d.sub(t1, t2), d.add(t1, t2));
                    Value* t3 = d.fma(c2, a2b2, d.mul(s2, s2));
                    Value* t4 = d.mul(t2, s2);
                    Value* Rp = d.mul(Rs, d.div(d.sub(t3, t4), d.add(t3, t4)));
                    return m.convert(d.mul(d.c(0.5), d.add(Rs, Rp)), m.type());
                });
            }
        }
        internal_error << "unknown fresnel";
    }

    // ---- Kulla-Conty energy compensation (KullaConty.h gives the recipe) ----

    llvm::GlobalVariable* floatTable(const std::vector<float>& data, const std::string& name) {
        if (llvm::GlobalVariable* gv = module_.getNamedGlobal(name)) return gv;
        auto* arr = llvm::ConstantDataArray::get(module_.getContext(), data);
        return new llvm::GlobalVariable(module_, arr->getType(), true, llvm::GlobalValue::PrivateLinkage, arr, name);
    }
    // table[index] for an integer-valued index in the precise type (a
    // gather across lanes), returned in the precise type.
    Value* fetch(llvm::GlobalVariable* table, Value* index) {
        MathEmitter& d = d_;
        llvm::Type* i32 = b_.getInt32Ty();
        llvm::Type* idxTy = d.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, d.width()) : i32;
        Value* ptr = b_.CreateGEP(b_.getFloatTy(), table, b_.CreateFPToSI(index, idxTy));
        llvm::Type* fty = f_.type();
        Value* v = d.width() == 1 ? (Value*)b_.CreateLoad(b_.getFloatTy(), ptr)
                                  : (Value*)b_.CreateMaskedGather(fty, ptr, llvm::Align(4));
        return d.convert(v, d.type());
    }
    // The roughness the E table is looked up with (KullaConty.h, energyAlpha).
    Value* energyAlpha(const Ndf& n) {
        MathEmitter& d = d_;
        switch (mat_.ndfModel()) {
            case NdfModel::BlinnPhong: return d.sqrt(d.div(d.c(2.0), d.add(d.convert(n.exponent, d.type()), d.c(2.0))));
            case NdfModel::Ggx:
            case NdfModel::Beckmann: return n.isotropic ? n.axD : d.sqrt(d.mul(n.axD, n.ayD));
            default: return n.axD;
        }
    }
    // F_avg of one channel: closed form for Schlick, folded quadrature for
    // constant dielectric/conductor parameters, the tables otherwise.
    Value* fresnelAverage(const std::array<Value*, 3>& f0, const std::array<Value*, 3>& eta,
                          const std::array<Value*, 3>& k, const std::array<const Expr*, 2>& constArgs, int ch) {
        MathEmitter& d = d_;
        switch (mat_.fresnelModel()) {
            case FresnelModel::None: return d.c(1.0);
            case FresnelModel::Schlick: return d.mul(d.fma(d.c(20.0), d.convert(f0[ch], d.type()), d.c(1.0)), d.c(1.0 / 21));
            case FresnelModel::Dielectric: {
                if (constArgs[0]) {
                    double e = std::max(constantValue(*constArgs[0])[ch], kMinEta);
                    return d.c(fresnelAverageDielectric(e));
                }
                // Table over s = (eta - 1)/(eta + 1) for eta >= 1; eta < 1 by
                // the reciprocity F_avg(eta) = 1 - eta^2 (1 - F_avg(1/eta)).
                const FresnelAverageTables& t = fresnelAverageTables();
                auto* gv = floatTable(t.dielectric, "facet_favg_dielectric");
                Value* n = d.convert(eta[ch], d.type());
                Value* below = d.lt(n, d.c(1.0));
                Value* m = d.select(below, d.div(d.c(1.0), n), n);
                Value* sPos = d.div(d.sub(m, d.c(1.0)), d.add(m, d.c(1.0)));
                const double last = FresnelAverageTables::kDielectricCount - 1;
                Value* u = d.minnum(d.maxnum(d.mul(sPos, d.c(last)), d.c(0.0)), d.c(last));
                Value* j = d.minnum(intrinsic(llvm::Intrinsic::floor, u), d.c(last - 1));
                Value* tu = d.sub(u, j);
                Value* a = fetch(gv, j);
                Value* fa = d.fma(tu, d.sub(fetch(gv, d.add(j, d.c(1.0))), a), a);
                return d.select(below, d.sub(d.c(1.0), d.mul(d.mul(n, n), d.sub(d.c(1.0), fa))), fa);
            }
            case FresnelModel::Conductor: {
                if (constArgs[0] && constArgs[1]) {
                    double e = std::max(constantValue(*constArgs[0])[ch], kMinEta);
                    double kk = std::max(constantValue(*constArgs[1])[ch], 0.0);
                    return d.c(fresnelAverageConductor(e, kk));
                }
                // Schlick's average at the conductor's F0 plus a tabulated
                // residual over (eta/(eta+1), sqrt(k)/(sqrt(k)+1)), bilinear.
                const FresnelAverageTables& t = fresnelAverageTables();
                auto* gv = floatTable(t.conductor, "facet_favg_conductor");
                Value* n = d.convert(eta[ch], d.type());
                Value* kk = d.convert(k[ch], d.type());
                Value* nm = d.sub(n, d.c(1.0)), *np = d.add(n, d.c(1.0)), *k2 = d.mul(kk, kk);
                Value* F0 = d.div(d.fma(nm, nm, k2), d.fma(np, np, k2));
                Value* base = d.mul(d.fma(d.c(20.0), F0, d.c(1.0)), d.c(1.0 / 21));
                const int N = FresnelAverageTables::kConductorCount;
                const double last = N - 1;
                Value* sk = d.sqrt(kk);
                Value* ua = d.minnum(d.mul(d.div(n, np), d.c(last)), d.c(last));
                Value* ub = d.minnum(d.mul(d.div(sk, d.add(sk, d.c(1.0))), d.c(last)), d.c(last));
                Value* ia = d.minnum(intrinsic(llvm::Intrinsic::floor, ua), d.c(last - 1));
                Value* ib = d.minnum(intrinsic(llvm::Intrinsic::floor, ub), d.c(last - 1));
                Value *ta = d.sub(ua, ia), *tb = d.sub(ub, ib);
                Value* row0 = d.fma(ib, d.c(double(N)), ia);
                Value* row1 = d.add(row0, d.c(double(N)));
                Value *a00 = fetch(gv, row0), *a01 = fetch(gv, d.add(row0, d.c(1.0)));
                Value *a10 = fetch(gv, row1), *a11 = fetch(gv, d.add(row1, d.c(1.0)));
                Value* r0 = d.fma(ta, d.sub(a01, a00), a00);
                Value* r1 = d.fma(ta, d.sub(a11, a10), a10);
                return d.add(base, d.fma(tb, d.sub(r1, r0), r0));
            }
        }
        internal_error << "unknown fresnel";
    }

    // f_ms per channel (KullaConty.h): bilinear Ec(mu_i), Ec(mu_o), linear
    // EcAvg in the sqrt-spaced table, then the lobe and the Fresnel term.
    std::array<Value*, 3> energyCompensation(const Ndf& n, Value* ci, Value* co) {
        MathEmitter& d = d_;
        const EnergyTable* table = opt_.energyTable;
        internal_assert(table) << "energy = kulla_conty lowered without its E table";
        auto* ecGv = floatTable(table->ec, "facet_energy_ec");
        auto* avgGv = floatTable(table->ecAvg, "facet_energy_ecavg");
        const int M = table->muCount;
        Value* alpha = d.minnum(d.maxnum(energyAlpha(n), d.c(table->alphaMin)), d.c(table->alphaMax));
        Value* v = d.fma(d.sqrt(alpha), d.c(table->alphaScale()), d.c(table->alphaOffset()));
        v = d.minnum(d.maxnum(v, d.c(0.0)), d.c(table->alphaCount - 1.0));
        Value* i = d.minnum(intrinsic(llvm::Intrinsic::floor, v), d.c(table->alphaCount - 2.0));
        Value* tv = d.sub(v, i);
        auto ec = [&](Value* c) {
            Value* cc = d.minnum(d.maxnum(d.convert(c, d.type()), d.c(0.0)), d.c(1.0));
            Value* u = d.mul(d.sqrt(cc), d.c(M - 1.0));
            Value* j = d.minnum(intrinsic(llvm::Intrinsic::floor, u), d.c(M - 2.0));
            Value* tu = d.sub(u, j);
            Value* r0 = d.fma(i, d.c(double(M)), j);
            Value* r1 = d.add(r0, d.c(double(M)));
            Value *a00 = fetch(ecGv, r0), *a01 = fetch(ecGv, d.add(r0, d.c(1.0)));
            Value *a10 = fetch(ecGv, r1), *a11 = fetch(ecGv, d.add(r1, d.c(1.0)));
            Value* lo = d.fma(tu, d.sub(a01, a00), a00);
            Value* hi = d.fma(tu, d.sub(a11, a10), a10);
            return d.fma(tv, d.sub(hi, lo), lo);
        };
        Value* avg0 = fetch(avgGv, i);
        Value* ecAvg = d.fma(tv, d.sub(fetch(avgGv, d.add(i, d.c(1.0))), avg0), avg0);
        Value* lobe = d.div(d.mul(ec(ci), ec(co)), d.mul(d.c(kPi), ecAvg));
        lobe = d.select(d.gt(ecAvg, d.c(0.0)), lobe, d.c(0.0));

        // Fresnel parameters (again: the lowering's CSE merges them with fresnel()).
        const ModelUse& use = mat_.fresnel;
        std::array<Value*, 3> f0{}, eta{}, k{};
        std::array<const Expr*, 2> constArgs{};
        switch (mat_.fresnelModel()) {
            case FresnelModel::Schlick: {
                if (use.has(param::F0)) {
                    f0 = rgbParam(use, param::F0, 0, 1, false).c;
                } else {
                    LVal e = rgbParam(use, param::SchlickEta, kMinEta, INFINITY, false);
                    f0 = map({e}, true, [&](auto& x) {
                             Value* r = d.div(d.sub(x[0], d.c(1.0)), d.add(x[0], d.c(1.0)));
                             return d.mul(r, r);
                         }).c;
                }
                break;
            }
            case FresnelModel::Dielectric:
                if (isConstantExpr(*use.args[param::DielectricEta])) constArgs[0] = use.args[param::DielectricEta].get();
                else eta = rgbParam(use, param::DielectricEta, kMinEta, INFINITY, false).c;
                break;
            case FresnelModel::Conductor:
                if (isConstantExpr(*use.args[param::ConductorEta]) && isConstantExpr(*use.args[param::ConductorK])) {
                    constArgs = {use.args[param::ConductorEta].get(), use.args[param::ConductorK].get()};
                } else {
                    eta = rgbParam(use, param::ConductorEta, kMinEta, INFINITY, false).c;
                    k = rgbParam(use, param::ConductorK, 0, INFINITY, false).c;
                }
                break;
            case FresnelModel::None: break;
        }
        std::array<Value*, 3> out;
        for (int ch = 0; ch < 3; ++ch) {
            Value* favg = fresnelAverage(f0, eta, k, constArgs, ch);
            Value* den = d.sub(d.c(1.0), d.mul(favg, ecAvg));
            Value* term = d.div(d.mul(d.mul(favg, favg), d.sub(d.c(1.0), ecAvg)), den);
            term = d.select(d.gt(den, d.c(0.0)), term, d.c(0.0));
            out[ch] = f_.convert(d.mul(lobe, term), f_.type());
        }
        return out;
    }

    std::array<Value*, 3> brdf(const Geometry& geo) {
        MathEmitter& m = f_;
        const std::array<Value*, 3>&wi = geo.wi, &wo = geo.wo, &h = geo.h;
        Value *ci = wi[2], *co = wo[2], *oh = geo.oh;
        Value* above = b_.CreateAnd(m.gt(ci, m.c(0.0)), m.gt(co, m.c(0.0)));

        Ndf n = ndfParams();
        Value* spec;
        if (mat_.ndfModel() == NdfModel::Ward) {
            MathEmitter& d = d_;
            Value* e = slopeExponentD(n, geo.hD);
            Value* lobe = m.div(m.convert(d.exp(d.neg(e)), m.type()),
                                m.mul(m.mul(m.c(4 * kPi), m.mul(n.ax, n.ay)), m.sqrt(m.mul(ci, co))));
            spec = lobe;
        } else {
            Value* dv = D(n, h, geo.hD);
            Value* g = G(n, wi, wo, h, ci, co, oh);
            spec = m.div(m.mul(dv, g), m.mul(m.mul(m.c(4.0), ci), co));
        }
        LVal F = fresnel(geo);
        LVal diffuse = LVal::scalar(m.c(0.0));
        bool hasDiffuse = mat_.diffuseModel() == DiffuseModel::Lambert;
        if (hasDiffuse) {
            LVal albedo = rgbParam(mat_.diffuse, param::Albedo, 0, INFINITY);
            diffuse = map({albedo}, true, [&](auto& x) { return m.mul(x[0], m.c(1.0 / kPi)); });
        }
        LVal specV = LVal::scalar(spec);
        LVal total = map({F, specV, diffuse}, true, [&](auto& x) {
            Value* s = m.mul(x[0], x[1]);
            return hasDiffuse ? m.add(s, x[2]) : s;
        });
        if (mat_.energyModel() == EnergyModel::KullaConty) {
            std::array<Value*, 3> ms = energyCompensation(n, ci, co);
            for (int ch = 0; ch < 3; ++ch) total.c[ch] = m.add(total.c[ch], ms[ch]);
        }
        // Below the horizon (or wi + wo = 0): f = 0, a valid lane.
        Value* valid = b_.CreateAnd(above, geo.hNonZero);
        return map({total}, true, [&](auto& x) { return m.select(valid, x[0], m.c(0.0)); }).c;
    }

    const CheckedMaterial& mat_;
    const LoweringOptions& opt_;
    llvm::IRBuilder<>& b_;
    MathEmitter f_;     // float lanes
    MathEmitter d_;     // "precise" lanes: double in exact mode, float in fast mode
    MathEmitter wide_;  // always double (the Gaussian normalization table is double)
    llvm::Module& module_;
    Value* invalid_;
    std::vector<LVal> inputs_, lets_;
};

// Builds the constant global array of slot defaults, `count` copies of
// each slot's default (the batch kernel reads `width` lanes of a default
// with stride 0; the scalar kernel reads one).
llvm::GlobalVariable* defaultsArray(llvm::Module& module, const std::vector<float>& values, const std::string& name) {
    auto* arr = llvm::ConstantDataArray::get(module.getContext(), values);
    return new llvm::GlobalVariable(module, arr->getType(), true, llvm::GlobalValue::PrivateLinkage, arr, name);
}

void addKernelAttributes(llvm::Function* fn, int width, const MathVariant& variant) {
    if (variant.estimates) fn->addFnAttr("reciprocal-estimates", "div:1,vec-div:1,sqrt:1,vec-sqrt:1");
    fn->addFnAttr(llvm::Attribute::NoUnwind);
    fn->addFnAttr(llvm::Attribute::NoFree);
    fn->addFnAttr(llvm::Attribute::WillReturn);
    // Explicit 512-bit vectors should stay in zmm registers even on CPUs
    // whose default preference is 256-bit.
    std::string bits = std::to_string(width * 32);
    fn->addFnAttr("min-legal-vector-width", bits);
    fn->addFnAttr("prefer-vector-width", bits);
}

// The scalar kernel: `<name>_status` computes one lane and returns 1 if it
// was invalid; `<name>` is the SPEC's void entry point, a thin wrapper.
void emitScalarEntry(const CheckedMaterial& mat, const LoweringOptions& opt, llvm::Module& module,
                     const std::string& name) {
    llvm::LLVMContext& ctx = module.getContext();
    llvm::IRBuilder<> b(ctx);
    llvm::Type* ptr = b.getPtrTy();
    auto* statusTy = llvm::FunctionType::get(b.getInt32Ty(), {ptr, ptr, ptr, ptr}, false);
    auto* fn = llvm::Function::Create(statusTy, llvm::Function::ExternalLinkage, name + "_status", module);
    addKernelAttributes(fn, 1, opt.variant);
    b.SetInsertPoint(llvm::BasicBlock::Create(ctx, "entry", fn));
    llvm::Value *wiP = fn->getArg(0), *woP = fn->getArg(1), *inP = fn->getArg(2), *outP = fn->getArg(3);
    llvm::Type* f32 = b.getFloatTy();
    std::array<llvm::Value*, 3> wi, wo;
    for (int i = 0; i < 3; ++i) {
        wi[i] = b.CreateLoad(f32, b.CreateConstGEP1_32(f32, wiP, i));
        wo[i] = b.CreateLoad(f32, b.CreateConstGEP1_32(f32, woP, i));
    }
    std::vector<llvm::Value*> slots;
    if (mat.slotCount > 0) {
        // inputs == NULL means all defaults: read from a constant array instead.
        std::vector<double> d = mat.defaultSlots();
        auto* defaults = defaultsArray(module, std::vector<float>(d.begin(), d.end()), name + ".defaults");
        llvm::Value* base = b.CreateSelect(b.CreateIsNull(inP), defaults, inP);
        for (int s = 0; s < mat.slotCount; ++s) slots.push_back(b.CreateLoad(f32, b.CreateConstGEP1_32(f32, base, s)));
    }
    LaneEmitter lanes(mat, opt, b, f32, module);
    LaneEmitter::Result r = lanes.emit(wi, wo, slots);
    for (int i = 0; i < 3; ++i) b.CreateStore(r.rgb[i], b.CreateConstGEP1_32(f32, outP, i));
    b.CreateRet(b.CreateZExt(r.invalid, b.getInt32Ty()));

    auto* voidTy = llvm::FunctionType::get(b.getVoidTy(), {ptr, ptr, ptr, ptr}, false);
    auto* entry = llvm::Function::Create(voidTy, llvm::Function::ExternalLinkage, name, module);
    addKernelAttributes(entry, 1, opt.variant);
    b.SetInsertPoint(llvm::BasicBlock::Create(ctx, "entry", entry));
    b.CreateCall(fn, {entry->getArg(0), entry->getArg(1), entry->getArg(2), entry->getArg(3)});
    b.CreateRetVoid();
}

void emitBatchEntry(const CheckedMaterial& mat, const LoweringOptions& opt, llvm::Module& module,
                    const std::string& name) {
    llvm::LLVMContext& ctx = module.getContext();
    llvm::IRBuilder<> b(ctx);
    const int W = opt.width;
    llvm::Type* ptr = b.getPtrTy();
    llvm::Type* i64 = b.getInt64Ty();
    llvm::Type* f32 = b.getFloatTy();
    auto* vecTy = llvm::FixedVectorType::get(f32, W);
    auto* fnTy = llvm::FunctionType::get(i64, {i64, ptr, ptr, ptr, ptr}, false);
    auto* fn = llvm::Function::Create(fnTy, llvm::Function::ExternalLinkage, name, module);
    addKernelAttributes(fn, W, opt.variant);
    llvm::Value *n = fn->getArg(0), *wiA = fn->getArg(1), *woA = fn->getArg(2), *inA = fn->getArg(3),
                *outA = fn->getArg(4);
    auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
    auto* header = llvm::BasicBlock::Create(ctx, "loop.header", fn);
    auto* body = llvm::BasicBlock::Create(ctx, "loop.body", fn);
    auto* tailCheck = llvm::BasicBlock::Create(ctx, "tail.check", fn);
    auto* tail = llvm::BasicBlock::Create(ctx, "tail", fn);
    auto* exit = llvm::BasicBlock::Create(ctx, "exit", fn);

    b.SetInsertPoint(entry);
    std::array<llvm::Value*, 3> wiP, woP, outP;
    for (int i = 0; i < 3; ++i) {
        wiP[i] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, wiA, i), "wi.ptr");
        woP[i] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, woA, i), "wo.ptr");
        outP[i] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, outA, i), "rgb.ptr");
    }
    // Per slot: a base pointer and a stride (1 for a caller array, 0 for the
    // constant array of defaults when inputs or inputs[s] is NULL).
    std::vector<llvm::Value*> slotBase, slotStep;
    std::vector<double> defaults = mat.defaultSlots();
    for (int s = 0; s < mat.slotCount; ++s) {
        auto* dflt = defaultsArray(module, std::vector<float>(W, float(defaults[s])), name + ".default" + std::to_string(s));
        llvm::Value* inputsNull = b.CreateIsNull(inA);
        llvm::Value* slotPtrAddr = b.CreateSelect(inputsNull, dflt, b.CreateConstGEP1_32(ptr, inA, s));
        // When inputs is NULL, slotPtrAddr points at the defaults (non-null
        // data), and the loaded "pointer" is discarded below.
        llvm::Value* loaded = b.CreateLoad(ptr, slotPtrAddr);
        llvm::Value* useDefault = b.CreateOr(inputsNull, b.CreateIsNull(loaded));
        slotBase.push_back(b.CreateSelect(useDefault, dflt, loaded));
        slotStep.push_back(b.CreateSelect(useDefault, llvm::ConstantInt::get(i64, 0), llvm::ConstantInt::get(i64, 1)));
    }
    b.CreateBr(header);

    auto popcount = [&](llvm::Value* mask) {
        llvm::Value* bits = b.CreateBitCast(mask, b.getIntNTy(W));
        llvm::Value* cnt = b.CreateUnaryIntrinsic(llvm::Intrinsic::ctpop, bits);
        return b.CreateZExt(cnt, i64);
    };
    auto emitStep = [&](llvm::Value* i, llvm::Value* mask /* null = all lanes */) {
        auto load = [&](llvm::Value* base, llvm::Value* index, float passthru) -> llvm::Value* {
            llvm::Value* p = b.CreateGEP(f32, base, index);
            if (!mask) return b.CreateAlignedLoad(vecTy, p, llvm::Align(4));
            return b.CreateMaskedLoad(vecTy, p, llvm::Align(4), mask, llvm::ConstantFP::get(vecTy, passthru));
        };
        std::array<llvm::Value*, 3> wi, wo;
        for (int c = 0; c < 3; ++c) {
            // Masked-off lanes read a valid direction (0,0,1) so they cost nothing.
            wi[c] = load(wiP[c], i, c == 2 ? 1.0f : 0.0f);
            wo[c] = load(woP[c], i, c == 2 ? 1.0f : 0.0f);
        }
        std::vector<llvm::Value*> slots;
        for (int s = 0; s < mat.slotCount; ++s)
            slots.push_back(load(slotBase[s], b.CreateMul(i, slotStep[s]), float(defaults[s])));
        LaneEmitter lanes(mat, opt, b, vecTy, module);
        LaneEmitter::Result r = lanes.emit(wi, wo, slots);
        for (int c = 0; c < 3; ++c) {
            llvm::Value* p = b.CreateGEP(f32, outP[c], i);
            if (mask) b.CreateMaskedStore(r.rgb[c], p, llvm::Align(4), mask);
            else b.CreateAlignedStore(r.rgb[c], p, llvm::Align(4));
        }
        return popcount(mask ? b.CreateAnd(r.invalid, mask) : r.invalid);
    };

    b.SetInsertPoint(header);
    llvm::PHINode* i = b.CreatePHI(i64, 2, "i");
    llvm::PHINode* count = b.CreatePHI(i64, 2, "invalid");
    i->addIncoming(llvm::ConstantInt::get(i64, 0), entry);
    count->addIncoming(llvm::ConstantInt::get(i64, 0), entry);
    llvm::Value* next = b.CreateAdd(i, llvm::ConstantInt::get(i64, W));
    b.CreateCondBr(b.CreateICmpSLE(next, n), body, tailCheck);

    b.SetInsertPoint(body);
    llvm::Value* bodyCount = b.CreateAdd(count, emitStep(i, nullptr));
    i->addIncoming(next, b.GetInsertBlock());
    count->addIncoming(bodyCount, b.GetInsertBlock());
    b.CreateBr(header);

    b.SetInsertPoint(tailCheck);
    llvm::Value* remaining = b.CreateSub(n, i);
    b.CreateCondBr(b.CreateICmpSGT(remaining, llvm::ConstantInt::get(i64, 0)), tail, exit);

    b.SetInsertPoint(tail);
    std::vector<llvm::Constant*> laneIds;
    for (int l = 0; l < W; ++l) laneIds.push_back(llvm::ConstantInt::get(i64, l));
    llvm::Value* mask = b.CreateICmpSLT(llvm::ConstantVector::get(laneIds), b.CreateVectorSplat(W, remaining));
    llvm::Value* tailCount = b.CreateAdd(count, emitStep(i, mask));
    llvm::BasicBlock* tailEnd = b.GetInsertBlock();
    b.CreateBr(exit);

    b.SetInsertPoint(exit);
    llvm::PHINode* result = b.CreatePHI(i64, 2, "result");
    result->addIncoming(count, tailCheck);
    result->addIncoming(tailCount, tailEnd);
    b.CreateRet(result);
}

}  // namespace

LoweredModule lowerMaterial(const CheckedMaterial& material, const LoweringOptions& options,
                            llvm::LLVMContext& context, const std::string& symbolPrefix) {
    internal_assert(options.width == 4 || options.width == 8 || options.width == 16)
        << "unsupported vector width " << options.width;
    LoweredModule out;
    out.module = std::make_unique<llvm::Module>(symbolPrefix, context);
    if (options.emitScalar) {
        out.scalarSymbol = symbolPrefix + "_scalar";
        emitScalarEntry(material, options, *out.module, out.scalarSymbol);
    }
    if (options.emitBatch) {
        out.batchSymbol = symbolPrefix + "_batch";
        emitBatchEntry(material, options, *out.module, out.batchSymbol);
    }
    std::string errors;
    llvm::raw_string_ostream os(errors);
    for (llvm::Function& fn : *out.module)
        if (!fn.isDeclaration() && llvm::verifyFunction(fn, &os)) internal_error << "invalid IR for " << fn.getName().str() << ": " << os.str();
    if (llvm::verifyModule(*out.module, &os)) internal_error << "invalid module: " << os.str();
    return out;
}

}  // namespace facet

namespace facet {
extern const char* const kLoweringBuildStamp = __DATE__ " " __TIME__ " lowering";
}
