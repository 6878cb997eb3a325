// gaussian: the Gaussian NDF in theta as IR (the reference is
// Gaussian.cpp). Its normalization N(alpha) has no closed form: a constant
// alpha folds it at compile time, a per-lane alpha interpolates a table of
// ln N over ln alpha embedded in the kernel (both from the neutral
// numeric/GaussianNormalization.h).
#include "lowering/LaneEmitter.h"

#include "GaussianNormalization.h"
#include "Specialize.h"

#include <llvm/IR/Constants.h>

#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlpha = 0;
constexpr int kOwnNorm = 0;  // NdfParams::own: N(alpha), precise type

// N(alpha) per lane: 4-point Lagrange in double, entries fetched with gathers.
Value* normLookup(LaneEmitter& lane, Value* alpha) {
    const GaussianNormTable& t = gaussianNormTable();
    MathEmitter& dm = lane.doubleMath();
    llvm::IRBuilder<>& b = lane.builder;
    llvm::GlobalVariable* gv = lane.doubleTable(t.q, "facet_gaussian_norm_table");
    double h = (GaussianNormTable::kX1 - GaussianNormTable::kX0) / (GaussianNormTable::kSize - 1);
    Value* x = dm.log(dm.convert(alpha, dm.type()));
    Value* u = dm.div(dm.sub(x, dm.c(GaussianNormTable::kX0)), dm.c(h));
    // Alphas beyond the table use its ends (N is flat in log alpha there);
    // the 4-point stencil stays inside: i in [1, size - 3], and s = u - i in
    // [-1, 2] then interpolates (or reaches the end nodes).
    u = dm.minnum(dm.maxnum(u, dm.c(0.0)), dm.c(GaussianNormTable::kSize - 1.0));
    Value* fi = dm.minnum(dm.maxnum(lane.intrinsic(llvm::Intrinsic::floor, u), dm.c(1.0)),
                          dm.c(GaussianNormTable::kSize - 3.0));
    Value* s = dm.sub(u, fi);
    llvm::Type* i32 = b.getInt32Ty();
    llvm::Type* idxTy = dm.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(i32, dm.width()) : i32;
    Value* idx = b.CreateFPToSI(fi, idxTy);
    auto fetch = [&](int offset) -> Value* {
        Value* j = b.CreateAdd(idx, llvm::ConstantInt::get(idxTy, offset, true));
        Value* ptr = b.CreateGEP(b.getDoubleTy(), gv, j);
        if (dm.width() == 1) return b.CreateLoad(b.getDoubleTy(), ptr);
        return b.CreateMaskedGather(dm.type(), ptr, llvm::Align(8));
    };
    Value *p0 = fetch(-1), *p1 = fetch(0), *p2 = fetch(1), *p3 = fetch(2);
    // Lagrange weights at s for nodes -1, 0, 1, 2.
    Value* sm1 = dm.add(s, dm.c(1.0));
    Value* s1 = dm.sub(s, dm.c(1.0));
    Value* s2 = dm.sub(s, dm.c(2.0));
    Value* w0 = dm.mul(dm.mul(s, dm.mul(s1, s2)), dm.c(-1.0 / 6.0));
    Value* w1 = dm.mul(dm.mul(sm1, dm.mul(s1, s2)), dm.c(0.5));
    Value* w2 = dm.mul(dm.mul(sm1, dm.mul(s, s2)), dm.c(-0.5));
    Value* w3 = dm.mul(dm.mul(sm1, dm.mul(s, s1)), dm.c(1.0 / 6.0));
    Value* q = dm.fma(w0, p0, dm.fma(w1, p1, dm.fma(w2, p2, dm.mul(w3, p3))));
    return lane.preciseMath().convert(dm.exp(q), lane.preciseMath().type());
}

class GaussianEmitter final : public NdfEmitter {
public:
    GaussianEmitter() { traits.isotropicOnly = true; }

    NdfParams params(LaneEmitter& lane) const override {
        const ModelUse& use = lane.material.ndf;
        NdfParams n = lane.alphaParams(use, kAlpha, kAlpha, true);
        const Expr& arg = *use.args[kAlpha];
        if (isConstantExpr(arg)) {
            double alpha = std::max(constantValue(arg)[0], use.model->canonical[kAlpha].lo);
            n.own[kOwnNorm] = lane.preciseMath().c(gaussianNdfNorm<double>(alpha));
        } else {
            n.own[kOwnNorm] = normLookup(lane, n.axD);
        }
        lane.roundAlphas(n);
        return n;
    }

    // theta^2/alpha^2 is an exponent too: precise type.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& hD = geo.hD;
        Value* theta = pm.atan2(pm.sqrt(pm.fma(hD[0], hD[0], pm.mul(hD[1], hD[1]))), hD[2]);
        Value* e = pm.div(pm.mul(theta, theta), pm.mul(n.axD, n.axD));
        return pm.div(lane.expTail(e), n.own[kOwnNorm]);
    }
};

}  // namespace

std::vector<TermEmitterEntry> facetEmitters_ndf_GaussianEmitter() {
    static const GaussianEmitter emitter;
    // The normalization table only where alpha is known per lane (params()).
    auto tables = [](const CheckedMaterial& material) -> std::vector<EmbeddedTable> {
        if (isConstantExpr(*material.ndf.args[kAlpha])) return {};
        const std::vector<double>& q = gaussianNormTable().q;
        return {{"facet_gaussian_norm_table", q.data(), q.size() * sizeof(double)}};
    };
    return {{ModelSlot::Ndf, "gaussian", &emitter, tables}};
}

}  // namespace facet
