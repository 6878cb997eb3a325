// student_t: the Student's t-distribution of slopes as IR (the reference is
// StudentT.cpp), in log form in the precise type, from u = wi + wo (h up to
// scale): e is a ratio of u's components and mz^4 = uz^4 / |u|^4; its Smith
// Lambda from the tabulated one the plan carries (TabulatedLambdaEmitter.h,
// whose functions are written here); its visible normals, and
// the exact Lambda that normalizes them, from the Student-t slope
// distribution of StudentSlopeEmitter.h, stretched.
#include "StudentSlopeEmitter.h"
#include "Immortal.h"
#include "TabulatedLambdaEmitter.h"

#include "LambdaTable.h"

#include <cmath>

namespace facet {
namespace {

using llvm::Value;

constexpr int kAlphaX = 0, kAlphaY = 1, kGamma = 2;
constexpr int kOwnGamma = 0;  // NdfParams::own: the clamped gamma, precise type

class StudentTEmitter final : public NdfEmitter {
public:
    StudentTEmitter() {
        traits.dFromUnnormalizedHalf = true;
        traits.samplesNormals = true;
        traits.samplesVisibleNormals = true;
    }

    NdfParams params(LaneEmitter& lane) const override {
        return lane.roundedAlphaParams(lane.material.singleLobe().ndf, kAlphaX, kAlphaY, {kGamma});  // own[kOwnGamma]
    }

    // D = exp(-gamma log(1 + x) - 2 log mz^2) / (pi ax ay), x = s / ((gamma
    // - 1) uz^2), s = ux^2/ax^2 + uy^2/ay^2, mz^2 = uz^2 / |u|^2. For x > 1,
    // log(1 + x) = log(s / (gamma - 1)) - log uz^2 + log1p(1/x), and the
    // powers of uz combine to (gamma - 2) log uz^2: no overflow of x or of
    // the power toward the horizon (where D grows for gamma < 2). log uz^2
    // is 2 log|uz|, so that a float uz^2 cannot underflow.
    Value* D(LaneEmitter& lane, const NdfParams& n, const LaneGeometry& geo) const override {
        MathEmitter& pm = lane.preciseMath();
        const std::array<Value*, 3>& u = geo.slopeH;
        Value* G = n.own[kOwnGamma];
        Value* s = n.isotropic ? pm.div(pm.fma(u[0], u[0], pm.mul(u[1], u[1])), pm.mul(n.axD, n.axD))
                               : pm.add(pm.div(pm.mul(u[0], u[0]), pm.mul(n.axD, n.axD)),
                                        pm.div(pm.mul(u[1], u[1]), pm.mul(n.ayD, n.ayD)));
        Value* gm1 = pm.sub(G, pm.c(1.0));
        Value* x = pm.div(s, pm.mul(gm1, pm.mul(u[2], u[2])));
        Value* logUz2 = pm.mul(pm.log(pm.abs(u[2])), pm.c(2.0));
        Value* farTail = pm.fma(pm.sub(G, pm.c(2.0)), logUz2,
                                pm.neg(pm.mul(G, pm.add(pm.log(pm.div(s, gm1)), pm.log1p(pm.div(pm.c(1.0), x))))));
        Value* nearTail = pm.sub(pm.neg(pm.mul(G, pm.log1p(x))), pm.add(logUz2, logUz2));
        Value* logD = pm.select(pm.gt(x, pm.c(1.0)), farTail, nearTail);
        // |u|^2 (1 where slopeHLen2 is null, u = h): mz^-4 = |u|^4 / uz^4.
        if (geo.slopeHLen2) logD = pm.add(logD, pm.mul(pm.log(geo.slopeHLen2), pm.c(2.0)));
        // The normalization 1 / (pi ax ay) in the exponent too: ax ay may
        // leave float's range where D does not.
        Value* logNorm = n.isotropic ? pm.mul(pm.log(n.axD), pm.c(2.0)) : pm.add(pm.log(n.axD), pm.log(n.ayD));
        logNorm = pm.add(logNorm, pm.c(std::log(kPi)));
        return pm.exp(pm.sub(logD, logNorm));
    }

    Value* cosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        return tabulatedCosLambda(lane, *this, n, v);
    }

    // The standard slope radius has the CDF 1 - (1 + r^2 / (gamma - 1))^(1 -
    // gamma): r^2 = (gamma - 1) expm1(log1p(-u) / (1 - gamma)).
    std::array<Value*, 3> sampleNormal(LaneEmitter& lane, const NdfParams& n, Value* u1, Value* u2) const override {
        MathEmitter& pm = lane.preciseMath();
        Value* gm1 = pm.sub(n.own[kOwnGamma], pm.c(1.0));
        Value* r2 = pm.mul(gm1, lane.expm1(pm.div(pm.log1p(pm.neg(u1)), pm.neg(gm1))));
        return lane.stretchedSlopeNormal(n, r2, u2);
    }

    // The slopes of D are those of P22 (StudentSlopeEmitter.h) with nu = 2
    // gamma - 2 stretched by k = sqrt(gamma - 1) (alpha_x, alpha_y): v maps
    // to (kx vx, ky vy, vz) in P22's frame, and (n.v) Lambda(v) is that
    // vector's length times P22's at its unit direction. Exact (the
    // masking's is the table's): the visible density integrates to 1.
    Value* visibleCosLambda(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        SlopeFrame f = slopeFrame(lane, n, v);
        return pm.convert(dm.mul(f.length, studentSlopeCosLambda(dm, f.nu, f.v)), pm.type());
    }

    // P22's visible normal m' for the view in its frame; m is (kx m'x, ky
    // m'y, m'z) normalized (the slopes scale by k).
    std::array<Value*, 3> sampleVisibleNormal(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& wo,
                                              Value* u1, Value* u2) const override {
        MathEmitter& dm = lane.doubleMath();
        MathEmitter& pm = lane.preciseMath();
        SlopeFrame f = slopeFrame(lane, n, wo);
        std::array<Value*, 3> m =
            studentSlopeVisibleNormal(lane, f.nu, f.v, dm.convert(u1, dm.type()), dm.convert(u2, dm.type()));
        Value* mx = dm.mul(f.kx, m[0]);
        Value* my = dm.mul(f.ky, m[1]);
        Value* inv = dm.div(dm.c(1.0), dm.sqrt(dm.fma(mx, mx, dm.fma(my, my, dm.mul(m[2], m[2])))));
        return {pm.convert(dm.mul(mx, inv), pm.type()), pm.convert(dm.mul(my, inv), pm.type()),
                pm.convert(dm.mul(m[2], inv), pm.type())};
    }

private:
    // A direction in P22's frame, in double: the stretch k (alpha_x, alpha_y),
    // nu, the unit direction and the length it had.
    struct SlopeFrame {
        Value *kx, *ky, *nu, *length;
        std::array<Value*, 3> v;
    };
    static SlopeFrame slopeFrame(LaneEmitter& lane, const NdfParams& n, const std::array<Value*, 3>& v) {
        MathEmitter& dm = lane.doubleMath();
        SlopeFrame f;
        Value* g = dm.convert(n.own[kOwnGamma], dm.type());
        Value* k = dm.sqrt(dm.sub(g, dm.c(1.0)));
        f.kx = dm.mul(k, dm.convert(n.axD, dm.type()));
        f.ky = dm.mul(k, dm.convert(n.ayD, dm.type()));
        f.nu = dm.fma(g, dm.c(2.0), dm.c(-2.0));
        Value* x = dm.mul(f.kx, dm.convert(v[0], dm.type()));
        Value* y = dm.mul(f.ky, dm.convert(v[1], dm.type()));
        Value* z = dm.convert(v[2], dm.type());
        f.length = dm.sqrt(dm.fma(x, x, dm.fma(y, y, dm.mul(z, z))));
        Value* inv = dm.div(dm.c(1.0), f.length);
        f.v = {dm.mul(x, inv), dm.mul(y, inv), dm.mul(z, inv)};
        return f;
    }
};

}  // namespace

namespace {

// Below the grid (a < a0): z on the chord in a from the grazing node zg =
// ln f(0) to z = ln f(a0) (LambdaTable.h), z + (1 - a / a0)(zg - z), with a /
// a0 = vz / (root a0) (1 at and above the grid, where the sum is z exactly).
Value* belowGrid(MathEmitter& dm, Value* vz, Value* root, double a0, Value* z, Value* zg) {
    Value* ratio = dm.minnum(dm.div(vz, dm.mul(root, dm.c(a0))), dm.c(1.0));
    return dm.fma(dm.sub(dm.c(1.0), ratio), dm.sub(zg, z), z);
}

}  // namespace

// (n.v) Lambda(v) = sqrt(proj) f(a), a = vz / sqrt(proj), from the plan's
// table of z = log f at u = (log a - x0) / h (LambdaTable.h): 4-point
// Lagrange up to the last node, linear in u beyond it, the chord to the
// grazing node f(0) below the grid; in double (z reaches -690). A
// SlopeAlpha table interpolates with kAlphaOrder points along u and across
// its rows at v = LambdaGrid::rowOf(alpha), alpha clamped to the rows'
// range (proj rescaled to the clamped alpha).
Value* tabulatedCosLambda(LaneEmitter& lane, const NdfEmitter& ndf, const NdfParams& n,
                          const std::array<Value*, 3>& v) {
    internal_assert(lane.plan.lambda == LambdaForm::Table && lane.plan.lambdaTable)
        << "a tabulated Smith Lambda without its table in the plan";
    const LambdaTable& table = *lane.plan.lambdaTable;
    MathEmitter& fm = lane.floatMath();
    MathEmitter& dm = lane.doubleMath();
    llvm::GlobalVariable* gv = lane.doubleTable(table.z, "facet_lambda_" + table.name());  // as lambdaTableEmbedding
    if (table.axes == LambdaAxes::Slope) {
        Value* proj = lane.smithProjection(ndf, n, v);
        Value* projD = dm.convert(proj, dm.type());
        Value* logRoot = dm.mul(dm.log(projD), dm.c(0.5));
        Value* vz = dm.convert(v[2], dm.type());
        Value* x = dm.sub(dm.log(vz), logRoot);
        Value* u = dm.maxnum(dm.div(dm.sub(x, dm.c(LambdaTable::kX0)), dm.c(LambdaTable::kStep)), dm.c(0.0));
        Value* uc = dm.minnum(u, dm.c(LambdaTable::kSize - 1.0));
        Value* z = lane.lagrangeFetch(gv, LambdaTable::kSize, uc);
        if (table.endSlope() != 0) z = dm.fma(dm.sub(u, uc), dm.c(table.endSlope()), z);
        z = belowGrid(dm, vz, dm.sqrt(projD), std::exp(LambdaTable::kX0), z,
                      dm.c(table.z[table.grid.grazingNode(0)]));
        Value* cl = dm.exp(dm.add(z, logRoot));
        return fm.select(fm.gt(proj, fm.c(0.0)), fm.convert(cl, fm.type()), fm.c(0.0));
    }
    // Isotropic: at the clamped alpha c the projection is c^2 (vx^2 + vy^2),
    // formed in double from v (alpha^2 in float overflows for a huge alpha).
    // alpha is the NDF's equivalent roughness (energyAlpha, the catalog's
    // equivalentAlphas), the one the rows are laid out in.
    internal_assert(n.isotropic) << "a Lambda table in (a, alpha) for an anisotropic lobe";
    const LambdaGrid& g = table.grid;
    const int size = g.size, rows = g.rows;
    Value* clamped = dm.minnum(dm.maxnum(dm.convert(ndf.energyAlpha(lane, n), dm.type()), dm.c(g.alphaLo)),
                               dm.c(g.alphaHi));
    Value* logClamped = dm.log(clamped);
    Value* vx = dm.convert(v[0], dm.type());
    Value* vy = dm.convert(v[1], dm.type());
    Value* side2 = dm.fma(vx, vx, dm.mul(vy, vy));
    Value* logRoot = dm.add(dm.mul(dm.log(side2), dm.c(0.5)), logClamped);
    Value* vz = dm.convert(v[2], dm.type());
    Value* x = dm.sub(dm.log(vz), logRoot);
    Value* u = dm.maxnum(dm.div(dm.sub(x, dm.c(g.x0)), dm.c(g.step)), dm.c(0.0));
    Value* uc = dm.minnum(u, dm.c(size - 1.0));
    // The row: asinh(s b), b = (1 - c)(1 + c) / c^2 (LambdaGrid::rowOf), as
    // sign(t) log1p(|t| + t^2 / (1 + sqrt(1 + t^2))), accurate at small |t|.
    Value* b = dm.div(dm.mul(dm.sub(dm.c(1.0), clamped), dm.add(dm.c(1.0), clamped)), dm.mul(clamped, clamped));
    Value* t = dm.mul(b, dm.c(g.rowScale));
    Value* at = dm.abs(t);
    Value* t2 = dm.mul(t, t);
    Value* asinhAbs = dm.log1p(dm.add(at, dm.div(t2, dm.add(dm.c(1.0), dm.sqrt(dm.add(dm.c(1.0), t2))))));
    Value* y = dm.select(dm.lt(t, dm.c(0.0)), dm.neg(asinhAbs), asinhAbs);
    Value* w = dm.minnum(dm.maxnum(dm.div(dm.sub(y, dm.c(g.y0)), dm.c(g.yStep)), dm.c(0.0)), dm.c(rows - 1.0));
    LaneEmitter::LagrangeStencil sx = lane.lagrangeStencil(size, LambdaTable::kAlphaOrder, uc);
    LaneEmitter::LagrangeStencil sy = lane.lagrangeStencil(rows, LambdaTable::kAlphaOrder, w);
    // Each row's slope per node past its last node (the linear tail in u):
    // its last node minus the one before.
    LaneEmitter::LagrangeStencil lastTwo{dm.c(size - 2.0), {dm.c(-1.0), dm.c(1.0)}};
    Value* rowStart = dm.mul(sy.first, dm.c(double(size)));
    Value *z = nullptr, *slope = nullptr;
    for (size_t r = 0; r < sy.w.size(); ++r) {
        Value* base = dm.add(rowStart, dm.c(double(r * size)));
        Value* zr = lane.stencilFetch(gv, sx, base);
        Value* sr = lane.stencilFetch(gv, lastTwo, base);
        z = z ? dm.fma(sy.w[r], zr, z) : dm.mul(sy.w[r], zr);
        slope = slope ? dm.fma(sy.w[r], sr, slope) : dm.mul(sy.w[r], sr);
    }
    z = dm.fma(dm.sub(u, uc), slope, z);
    // The rows' grazing nodes, across the rows with the same weights.
    Value* zGrazing = lane.stencilFetch(gv, sy, dm.c(double(g.grazingNode(0))));
    z = belowGrid(dm, vz, dm.mul(dm.sqrt(side2), clamped), std::exp(g.x0), z, zGrazing);
    Value* cl = dm.exp(dm.add(z, logRoot));
    return fm.select(dm.gt(side2, dm.c(0.0)), fm.convert(cl, fm.type()), fm.c(0.0));
}

std::vector<EmbeddedTable> lambdaTableEmbedding(const CheckedMaterial& material) {
    if (!material.singleLobe().masking.model || !material.singleLobe().masking.model->smith) return {};
    const NdfEntry& ndf = ndfEntry(*material.singleLobe().ndf.model);
    std::shared_ptr<const LambdaTable> t = lambdaTable(ndf, tabulatedLambdaShape(material));
    return {{"facet_lambda_" + t->name(), t->z.data(), t->z.size() * sizeof(double)}};  // kept by lambdaTable()
}

std::vector<TermEmitterEntry> facetEmitters_ndf_StudentTEmitter() {
    static const StudentTEmitter& emitter = immortal<StudentTEmitter>();
    return {{ModelSlot::Ndf, "student_t", &emitter, lambdaTableEmbedding}};
}

}  // namespace facet
