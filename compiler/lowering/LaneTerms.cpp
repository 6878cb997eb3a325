// LaneTerms: pieces several model emitters share (NDF tails, slope
// ratios, the Smith projection, the direction-correlation weight, the
// Fresnel cosine) and the constant tables kernels embed (Kulla-Conty,
// F_avg, the Gaussian normalization) with their lookups.
#include "LaneEmitter.h"

#include <llvm/IR/Constants.h>

namespace facet {

using llvm::Value;

NdfParams LaneEmitter::alphaParams(const ModelUse& use, int px, int py, bool isotropic) {
    NdfParams n;
    n.isotropic = isotropic;
    n.axD = scalarParam(use, px, false);
    n.ayD = isotropic ? n.axD : scalarParam(use, py, false);
    return n;
}

void LaneEmitter::roundAlphas(NdfParams& n) {
    n.ax = floatMath_.convert(n.axD, floatMath_.type());
    n.ay = n.isotropic ? n.ax : floatMath_.convert(n.ayD, floatMath_.type());
}

Value* LaneEmitter::intrinsic(llvm::Intrinsic::ID id, Value* a) {
    return builder.CreateIntrinsic(id, {a->getType()}, {a});
}

// Clamped to [-limit, limit], exp's argument is in expNormal's range, which
// leaves out exp()'s own clamping, selects and two-step scaling. e >= 0 up
// to rounding (blinn_phong's -E ln mz); a NaN e (an invalid lane) becomes
// limit. The argument is clamped first because a subnormal result costs a
// ~100-cycle microcode assist per operation, and random directions with
// small alpha hit it in most lanes. The tail only ever multiplies into the
// float BRDF value, so in double the shorter series (1e-11) serves.
Value* LaneEmitter::expTail(Value* e) {
    MathEmitter& pm = preciseMath_;
    const double limit = expTailLimit();
    Value* v = pm.expNormal(pm.neg(pm.maxnum(pm.minnum(e, pm.c(limit)), pm.c(-limit))), /*floatResult=*/true);
    return pm.select(pm.gt(e, pm.c(limit)), pm.c(0.0), v);
}

// The series where exp(y) - 1 would cancel (|y| < 1e-5 in double, < 1e-2
// in float), the quotient elsewhere.
Value* LaneEmitter::expm1OverX(Value* y) {
    MathEmitter& pm = preciseMath_;
    Value* series = pm.poly(y, {1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0});
    Value* direct = pm.div(pm.sub(pm.exp(y), pm.c(1.0)), y);
    return pm.select(pm.lt(pm.abs(y), pm.c(pm.isDouble() ? 1e-5 : 1e-2)), series, direct);
}

Value* LaneEmitter::slope2(const NdfParams& n, const std::array<Value*, 3>& h) {
    MathEmitter& fm = floatMath_;
    Value *x2 = fm.mul(h[0], h[0]), *y2 = fm.mul(h[1], h[1]);
    if (n.isotropic) return fm.div(fm.add(x2, y2), fm.mul(n.ax, n.ax));
    return fm.add(fm.div(x2, fm.mul(n.ax, n.ax)), fm.div(y2, fm.mul(n.ay, n.ay)));
}

// It is the argument of exp() for the exponent NDFs, where its rounding
// error is multiplied by its size (tens) in the result: precise type.
Value* LaneEmitter::slopeExponent(const NdfParams& n, const std::array<Value*, 3>& h) {
    MathEmitter& pm = preciseMath_;
    Value *ax = n.axD, *ay = n.ayD;
    Value *x2 = pm.mul(h[0], h[0]), *y2 = pm.mul(h[1], h[1]), *z2 = pm.mul(h[2], h[2]);
    Value* s = n.isotropic ? pm.div(pm.add(x2, y2), pm.mul(ax, ax))
                           : pm.add(pm.div(x2, pm.mul(ax, ax)), pm.div(y2, pm.mul(ay, ay)));
    return pm.div(s, z2);
}

Value* LaneEmitter::smithProjection(const NdfEmitter& ndf, const NdfParams& n, const std::array<Value*, 3>& v) {
    MathEmitter& fm = floatMath_;
    Value *ax = nullptr, *ay = nullptr;
    bool isotropic = false;
    ndf.smithAlphas(*this, n, ax, ay, isotropic);
    // Products with alpha first: alpha^2 may overflow float (alpha up to
    // FLT_MAX is a valid parameter), and Inf * 0 at v = n would be NaN.
    Value *px = fm.mul(v[0], ax), *py = fm.mul(v[1], isotropic ? ax : ay);
    return fm.fma(px, px, fm.mul(py, py));
}

Value* LaneEmitter::azimuthWeight(const LaneGeometry& geo) {
    MathEmitter& fm = floatMath_;
    const std::array<Value*, 3>&wi = geo.wi, &wo = geo.wo;
    Value* cross = fm.abs(fm.sub(fm.mul(wi[0], wo[1]), fm.mul(wi[1], wo[0])));
    Value* dot = fm.fma(wi[0], wo[0], fm.mul(wi[1], wo[1]));
    Value* phi = fm.mul(fm.c(4.41), fm.atan2(cross, dot));
    return preciseMath_.convert(fm.div(phi, fm.add(phi, fm.c(1.0))), preciseMath_.type());
}

Value* LaneEmitter::quarterDOver(Value* x, Value* y) {
    MathEmitter& pm = preciseMath_;
    if (quarterD_.value && x == quarterD_.value) return pm.div(quarterD_.num, pm.mul(quarterD_.den, y));
    return pm.div(x, y);
}

Value* LaneEmitter::overProduct(Value* x, Value* y, Value* z) {
    MathEmitter& pm = preciseMath_;
    return body.scaleMaskingSums ? pm.div(pm.div(x, y), z) : quarterDOver(x, pm.mul(y, z));
}

// Below 1e-18 F equals F(0) to float precision (its slope in c is O(|N|)),
// and float-subnormal cosines would lose their bits in c gp, c^2.
Value* LaneEmitter::fresnelCos(MathEmitter& math, const LaneGeometry& geo) {
    Value* c = math.convert(geo.cosD, math.type());
    return math.isDouble() ? c : math.maxnum(c, math.c(1e-18));
}

// ---- constant tables ----

namespace {

// The module's constant array `name`, made from `data` the first time.
template <typename T>
llvm::GlobalVariable* constantTable(llvm::Module& module, const std::vector<T>& data, const std::string& name) {
    if (llvm::GlobalVariable* gv = module.getNamedGlobal(name)) return gv;
    auto* arr = llvm::ConstantDataArray::get(module.getContext(), data);
    return new llvm::GlobalVariable(module, arr->getType(), true, llvm::GlobalValue::PrivateLinkage, arr, name);
}

}  // namespace

llvm::GlobalVariable* LaneEmitter::floatTable(const std::vector<float>& data, const std::string& name) {
    return constantTable(module_, data, name);
}

llvm::GlobalVariable* LaneEmitter::doubleTable(const std::vector<double>& data, const std::string& name) {
    return constantTable(module_, data, name);
}

llvm::GlobalVariable* LaneEmitter::uint64Table(const std::vector<uint64_t>& data, const std::string& name) {
    return constantTable(module_, data, name);
}

Value* LaneEmitter::fetch(llvm::GlobalVariable* table, Value* index, MathEmitter* math) {
    MathEmitter& pm = math ? *math : preciseMath_;
    llvm::Type* i32 = builder.getInt32Ty();
    llvm::Type* idxTy = pm.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, pm.width()) : i32;
    Value* ptr = builder.CreateGEP(builder.getFloatTy(), table, builder.CreateFPToSI(index, idxTy));
    Value* v = pm.width() == 1 ? (Value*)builder.CreateLoad(builder.getFloatTy(), ptr)
                               : (Value*)builder.CreateMaskedGather(floatMath_.type(), ptr, llvm::Align(4));
    return pm.convert(v, pm.type());
}

Value* LaneEmitter::lagrangeFetch(llvm::GlobalVariable* table, int size, Value* u) {
    MathEmitter& dm = doubleMath_;
    // The 4-point stencil stays inside: i in [1, size - 3], and s = u - i in
    // [-1, 2] then interpolates (or reaches the end nodes).
    Value* fi = dm.minnum(dm.maxnum(intrinsic(llvm::Intrinsic::floor, u), dm.c(1.0)), dm.c(size - 3.0));
    Value* s = dm.sub(u, fi);
    llvm::Type* i32 = builder.getInt32Ty();
    llvm::Type* idxTy = dm.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, dm.width()) : i32;
    Value* idx = builder.CreateFPToSI(fi, idxTy);
    auto node = [&](int offset) -> Value* {
        Value* j = builder.CreateAdd(idx, llvm::ConstantInt::get(idxTy, offset, true));
        Value* ptr = builder.CreateGEP(builder.getDoubleTy(), table, j);
        if (dm.width() == 1) return builder.CreateLoad(builder.getDoubleTy(), ptr);
        return builder.CreateMaskedGather(dm.type(), ptr, llvm::Align(8));
    };
    Value *p0 = node(-1), *p1 = node(0), *p2 = node(1), *p3 = node(2);
    // Lagrange weights at s for nodes -1, 0, 1, 2.
    Value* sm1 = dm.add(s, dm.c(1.0));
    Value* s1 = dm.sub(s, dm.c(1.0));
    Value* s2 = dm.sub(s, dm.c(2.0));
    Value* w0 = dm.mul(dm.mul(s, dm.mul(s1, s2)), dm.c(-1.0 / 6.0));
    Value* w1 = dm.mul(dm.mul(sm1, dm.mul(s1, s2)), dm.c(0.5));
    Value* w2 = dm.mul(dm.mul(sm1, dm.mul(s, s2)), dm.c(-0.5));
    Value* w3 = dm.mul(dm.mul(sm1, dm.mul(s, s1)), dm.c(1.0 / 6.0));
    return dm.fma(w0, p0, dm.fma(w1, p1, dm.fma(w2, p2, dm.mul(w3, p3))));
}

Value* LaneEmitter::lerpFetch(llvm::GlobalVariable* table, Value* index, Value* t, MathEmitter* math) {
    MathEmitter& pm = math ? *math : preciseMath_;
    Value* a = fetch(table, index, &pm);
    return pm.fma(t, pm.sub(fetch(table, pm.add(index, pm.c(1.0)), &pm), a), a);
}

LaneEmitter::LagrangeStencil LaneEmitter::lagrangeStencil(int size, int n, Value* u) {
    MathEmitter& dm = doubleMath_;
    // Nodes first .. first + n - 1 around u, kept inside [0, size - 1]; the
    // weight of node first + k at s = u - first is prod_{m != k} (s - m) / (k - m).
    int half = n / 2;
    Value* fi = dm.minnum(dm.maxnum(intrinsic(llvm::Intrinsic::floor, u), dm.c(half - 1.0)), dm.c(size - 1.0 - half));
    LagrangeStencil st{dm.sub(fi, dm.c(half - 1.0)), {}};
    Value* s = dm.sub(u, st.first);
    std::vector<Value*> diff(n);
    for (int m = 0; m < n; ++m) diff[m] = dm.sub(s, dm.c(double(m)));
    for (int k = 0; k < n; ++k) {
        double denom = 1;
        Value* w = nullptr;
        for (int m = 0; m < n; ++m) {
            if (m == k) continue;
            denom *= k - m;
            w = w ? dm.mul(w, diff[m]) : diff[m];
        }
        st.w.push_back(dm.mul(w, dm.c(1.0 / denom)));
    }
    return st;
}

Value* LaneEmitter::stencilFetch(llvm::GlobalVariable* table, const LagrangeStencil& st, Value* base) {
    MathEmitter& dm = doubleMath_;
    llvm::Type* i32 = builder.getInt32Ty();
    llvm::Type* idxTy = dm.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, dm.width()) : i32;
    Value* idx = builder.CreateFPToSI(dm.add(base, st.first), idxTy);
    Value* sum = nullptr;
    for (size_t k = 0; k < st.w.size(); ++k) {
        Value* ptr = builder.CreateGEP(builder.getDoubleTy(), table, builder.CreateAdd(idx, llvm::ConstantInt::get(idxTy, k)));
        Value* node = dm.width() == 1 ? (Value*)builder.CreateLoad(builder.getDoubleTy(), ptr)
                                      : (Value*)builder.CreateMaskedGather(dm.type(), ptr, llvm::Align(8));
        sum = sum ? dm.fma(st.w[k], node, sum) : dm.mul(st.w[k], node);
    }
    return sum;
}

Value* LaneEmitter::bilerpFetch(llvm::GlobalVariable* table, int stride, Value* row, Value* col, Value* tRow,
                                Value* tCol, MathEmitter* math) {
    MathEmitter& pm = math ? *math : preciseMath_;
    Value* r0 = pm.fma(row, pm.c(double(stride)), col);
    Value* lo = lerpFetch(table, r0, tCol, &pm);
    Value* hi = lerpFetch(table, pm.add(r0, pm.c(double(stride))), tCol, &pm);
    return pm.fma(tRow, pm.sub(hi, lo), lo);
}

}  // namespace facet
