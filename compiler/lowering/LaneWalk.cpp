// LaneWalk: the lane bodies of a lobe with `energy = random_walk` (SPEC 13,
// docs/sampling.md): Heitz et al. 2016's random walk on the Smith
// microsurface of the lobe's NDF, per lane, as a loop of the IR.
//
// - eval adds one walk's next-event estimate of the scattering orders >= 2
//   to the exact single scattering, the walk seeded by the directions;
// - sample walks from wo with the random numbers seeded by the bits of the
//   three uniforms, and returns the direction it leaves in with the product
//   of the Fresnel terms met as the weight;
// - pdf is the density multiple importance sampling gets.
// The random numbers are the counter stream of compiler/reference/
// MicrosurfaceWalk.h (WalkRandom::counterStream) in 32-bit integer lanes,
// and each order draws three of them (height, then the visible normal's
// two), so that a lane walks the reference's path number for number. The
// walk's steps are written here independently of the reference's
// (MicrosurfaceWalk.cpp, WalkLobe.cpp), from the NDF's and Fresnel term's
// emitters: Lambda (visibleCosLambda), D, the visible-normal sampler (which
// the catalog promises takes views below the horizon: NdfEntry::
// compiledWalk) and F.
#include "LaneEmitter.h"

#include <llvm/IR/Constants.h>

namespace facet {

using llvm::Value;
using Vec = std::array<Value*, 3>;

namespace {

// As compiler/reference/WalkLobe.h: walks cut after this many reflections,
// and the seed grid of eval.
constexpr int kMaxOrder = 256;
constexpr double kSeedGrid = 65536.0, kSeedOffset = 0.3183;
constexpr uint32_t kGolden = 0x9e3779b9u, kEvalSalt = 0x5bd1e995u;

// The random numbers of one lane as 32-bit words.
class LaneRandomWords {
public:
    LaneRandomWords(llvm::IRBuilder<>& b, int width) : b_(b) {
        type_ = width > 1 ? (llvm::Type*)llvm::FixedVectorType::get(b.getInt32Ty(), width) : b.getInt32Ty();
    }
    llvm::Type* type() const { return type_; }
    Value* splat(uint32_t v) { return llvm::ConstantInt::get(type_, v); }
    // Wellons's lowbias32.
    Value* hash(Value* x) {
        x = b_.CreateXor(x, b_.CreateLShr(x, splat(16)));
        x = b_.CreateMul(x, splat(0x7feb352du));
        x = b_.CreateXor(x, b_.CreateLShr(x, splat(15)));
        x = b_.CreateMul(x, splat(0x846ca68bu));
        return b_.CreateXor(x, b_.CreateLShr(x, splat(16)));
    }
    Value* mixIn(Value* seed, Value* word) { return hash(b_.CreateXor(seed, word)); }
    // Number `index` (a scalar i32) of the stream of `seed`, in [0, 1) in pm's type.
    Value* uniform(MathEmitter& pm, Value* seed, Value* index) {
        Value* offset = b_.CreateMul(index, b_.getInt32(kGolden));
        if (type_->isVectorTy()) offset = b_.CreateVectorSplat(llvm::cast<llvm::FixedVectorType>(type_)->getNumElements(), offset);
        Value* bits = b_.CreateLShr(hash(b_.CreateAdd(seed, offset)), splat(8));
        return pm.mul(b_.CreateUIToFP(bits, pm.type()), pm.c(0x1p-24));
    }

private:
    llvm::IRBuilder<>& b_;
    llvm::Type* type_;
};

}  // namespace

// What one walk keeps from order to order.
struct LaneEmitter::WalkState {
    Vec w;                        // the ray's direction of travel (unit)
    Value* logC;                  // log of its height as the height CDF (0: above everything)
    std::array<Value*, 3> weight; // the product of the Fresnel terms met
    Value* walking;               // lanes still on the surface
};

// The walk of every lane from wo (unit, n.wo > 0 in the lanes of
// walking0), with values of the caller's carried from order to order:
// `step` gets the walk at each order (order >= 1) after the height test,
// the lanes that met a facet there and those that left, and returns the
// carried values' next values. The loop runs until every lane has left or
// after kMaxOrder orders; the carried values after it are returned.
std::vector<Value*> LaneEmitter::emitWalk(const Vec& wo, Value* seed, Value* walking0,
                                          const std::vector<Value*>& carriedInit, const WalkStep& step) {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const NdfEmitter& ndf = emitters_.ndf;
    NdfParams n = ndf.params(*this);
    LaneRandomWords words(b, pm.width());
    Vec start = {pm.neg(wo[0]), pm.neg(wo[1]), pm.neg(wo[2])};  // the first ray goes down along -wo
    llvm::Function* fn = b.GetInsertBlock()->getParent();
    llvm::BasicBlock* pre = b.GetInsertBlock();
    auto* loop = llvm::BasicBlock::Create(b.getContext(), "walk.order", fn);
    auto* done = llvm::BasicBlock::Create(b.getContext(), "walk.done", fn);
    b.CreateBr(loop);

    b.SetInsertPoint(loop);
    auto phi = [&](llvm::Type* t, const char* name, Value* init) {
        llvm::PHINode* p = b.CreatePHI(t, 2, name);
        p->addIncoming(init, pre);
        return p;
    };
    llvm::PHINode* order = phi(b.getInt32Ty(), "walk.k", b.getInt32(1));
    std::array<llvm::PHINode*, 3> w, weight;
    for (int i = 0; i < 3; ++i) w[i] = phi(pm.type(), "walk.w", start[i]);
    llvm::PHINode* logC = phi(pm.type(), "walk.logc", pm.c(0.0));
    for (int ch = 0; ch < 3; ++ch) weight[ch] = phi(pm.type(), "walk.weight", pm.c(1.0));
    llvm::PHINode* walking = phi(walking0->getType(), "walk.walking", walking0);
    std::vector<llvm::PHINode*> carried;
    std::vector<Value*> carriedNow;
    for (Value* init : carriedInit) carried.push_back(phi(init->getType(), "walk.carried", init));
    for (llvm::PHINode* c : carried) carriedNow.push_back(c);
    Vec dir = {w[0], w[1], w[2]};

    // The next height: with v = 1 - u in (0, 1], upward the ray leaves when
    // log v < Lambda(w) log c and otherwise meets the surface at log c' =
    // log c - log v / Lambda(w) (at most 0); downward it meets it at log c +
    // log v / (1 + Lambda(-w)); exactly grazing, at once. Lambda of the
    // direction's upper-hemisphere twin, one call for both cases.
    Value* index = b.CreateMul(order, b.getInt32(3));
    Value* u = words.uniform(pm, seed, b.CreateSub(index, b.getInt32(3)));
    Value* logV = pm.log(pm.sub(pm.c(1.0), u));
    Value* up = pm.gt(dir[2], pm.c(0.0));
    Value* down = pm.lt(dir[2], pm.c(0.0));
    const Vec back = {pm.neg(dir[0]), pm.neg(dir[1]), pm.neg(dir[2])};  // v = -w, toward where the ray came from
    Vec above = selectVec(pm, up, dir, back);
    // (A lane that has left or never walked computes from a valid direction.)
    Value* usable = b.CreateAnd(walking, b.CreateOr(up, down));
    above = selectVec(pm, usable, above, constantVec(pm, 0, 0, 1));
    Value* cosLambda = ndf.visibleCosLambda(*this, n, above);
    Value* lambda = pm.div(cosLambda, above[2]);
    Value* leaves = b.CreateAnd(up, b.CreateOr(pm.eq(cosLambda, pm.c(0.0)), pm.lt(logV, pm.mul(lambda, logC))));
    Value* logUp = pm.minnum(pm.sub(logC, pm.div(logV, lambda)), pm.c(0.0));
    Value* logDown = pm.add(logC, pm.div(logV, pm.add(pm.c(1.0), lambda)));
    Value* nextLogC = pm.select(up, logUp, pm.select(down, logDown, logC));
    Value* left = b.CreateAnd(walking, leaves);
    Value* met = b.CreateAnd(walking, b.CreateNot(leaves));

    WalkState state{dir, pm.select(met, nextLogC, logC), {weight[0], weight[1], weight[2]}, walking};
    std::vector<Value*> carriedNext = step(state, order, met, left, carriedNow);
    internal_assert(carriedNext.size() == carried.size()) << "walk step changed its carried values";

    // The facet met: a visible normal of v = -w, reflected about; F at v.m.
    Vec v = selectVec(pm, met, back, constantVec(pm, 0, 0, 1));
    Value* u1 = words.uniform(pm, seed, b.CreateSub(index, b.getInt32(2)));
    Value* u2 = words.uniform(pm, seed, b.CreateSub(index, b.getInt32(1)));
    Vec m = ndf.sampleVisibleNormal(*this, n, v, u1, u2);
    Value* vm = dot(pm, v, m);
    LVal F = walkFresnel(vm);
    // The mirror direction w - 2 (w.m) m, with w.m = -v.m.
    Value* twoVm = pm.add(vm, vm);
    Vec r = {pm.fma(twoVm, m[0], dir[0]), pm.fma(twoVm, m[1], dir[1]), pm.fma(twoVm, m[2], dir[2])};
    Value* inv = pm.div(pm.c(1.0), pm.sqrt(dot(pm, r, r)));
    Value* k1 = b.CreateAdd(order, b.getInt32(1));
    llvm::BasicBlock* latch = b.GetInsertBlock();
    order->addIncoming(k1, latch);
    for (int i = 0; i < 3; ++i) w[i]->addIncoming(pm.select(met, pm.mul(r[i], inv), dir[i]), latch);
    logC->addIncoming(state.logC, latch);
    for (int ch = 0; ch < 3; ++ch) weight[ch]->addIncoming(pm.select(met, pm.mul(weight[ch], F.c[ch]), weight[ch]), latch);
    walking->addIncoming(met, latch);
    for (size_t i = 0; i < carried.size(); ++i) carried[i]->addIncoming(carriedNext[i], latch);
    Value* more = b.CreateAnd(b.CreateICmpSLE(k1, b.getInt32(kMaxOrder)), anyLane(b, met));
    keepLoopRolled(b.CreateCondBr(more, loop, done));
    b.SetInsertPoint(done);
    return carriedNext;
}

// F of the lobe at a facet seen at cos c = v.m, per channel (precise type).
LVal LaneEmitter::walkFresnel(Value* c) {
    MathEmitter& pm = preciseMath_;
    LaneGeometry at{};
    at.cosD = pm.minnum(pm.maxnum(c, pm.c(0.0)), pm.c(1.0));
    at.oneMinusCosD = pm.sub(pm.c(1.0), at.cosD);
    at.sin2D = pm.mul(at.oneMinusCosD, pm.add(pm.c(1.0), at.cosD));
    LVal F = emitters_.fresnel.F(*this, at);
    for (int ch = 0; ch < 3; ++ch) F.c[ch] = pm.convert(F.c[ch], pm.type());
    return F;
}

// Eval's term: the next-event estimate toward wi at every facet of order
// >= 2 of one walk from wo, D(h) F(v.h) / (4 A(v)) c^Lambda(wi) with h the
// half vector of v = -w and wi and A(v) the projected area, over n.wi.
// `above`: the lanes whose directions are both above the horizon.
std::array<Value*, 3> LaneEmitter::walkScattering(const LaneGeometry& geo, Value* above) {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    const NdfEmitter& ndf = emitters_.ndf;
    NdfParams n = ndf.params(*this);
    LaneRandomWords words(b, pm.width());
    // Lanes below the horizon walk from n toward n (their f is 0 anyway).
    const Vec normal = constantVec(pm, 0, 0, 1);
    const Vec wi = selectVec(pm, above, geo.wiD, normal), wo = selectVec(pm, above, geo.woD, normal);
    Value* seed = words.splat(kEvalSalt);
    for (Value* x : {wi[0], wi[1], wi[2], wo[0], wo[1], wo[2]}) {
        Value* cell = intrinsic(llvm::Intrinsic::floor, pm.fma(x, pm.c(kSeedGrid), pm.c(kSeedOffset)));
        seed = words.mixIn(seed, b.CreateFPToSI(cell, words.type()));
    }
    Value* lambdaI = pm.div(ndf.visibleCosLambda(*this, n, wi), wi[2]);
    auto step = [&](const WalkState& s, Value* order, Value* met, Value*, const std::vector<Value*>& sum) {
        Vec v = {pm.neg(s.w[0]), pm.neg(s.w[1]), pm.neg(s.w[2])};
        Vec h = {pm.add(v[0], wi[0]), pm.add(v[1], wi[1]), pm.add(v[2], wi[2])};
        Value* len2 = dot(pm, h, h);
        Value* inv = pm.div(pm.c(1.0), pm.sqrt(len2));
        h = {pm.mul(h[0], inv), pm.mul(h[1], inv), pm.mul(h[2], inv)};
        Value* vh = dot(pm, v, h);
        Value* geometric = b.CreateAnd(pm.gt(len2, pm.c(0.0)), b.CreateAnd(pm.gt(h[2], pm.c(0.0)), pm.gt(vh, pm.c(0.0))));
        Value* higher = b.CreateICmpSGE(order, b.getInt32(2));  // one value for every lane
        if (pm.width() > 1) higher = b.CreateVectorSplat(pm.width(), higher);
        Value* counts = b.CreateAnd(b.CreateAnd(met, higher), geometric);
        auto safe = [&](const Vec& x) { return selectVec(pm, counts, x, normal); };
        // A(v): (n.v)(1 + Lambda(v)) for v above, (n.-v) Lambda(-v) below.
        Value* vUp = pm.gt(v[2], pm.c(0.0));
        Vec vAbove = safe(selectVec(pm, vUp, v, s.w));
        Value* area = pm.add(ndf.visibleCosLambda(*this, n, vAbove), pm.select(vUp, v[2], pm.c(0.0)));
        LaneGeometry atH{};
        Vec hSafe = safe(h);
        for (int i = 0; i < 3; ++i) atH.h[i] = floatMath_.convert(hSafe[i], floatMath_.type());
        atH.hD = hSafe;
        atH.slopeH = hSafe;
        Value* phase = pm.div(ndf.D(*this, n, atH), pm.mul(pm.c(4.0), area));
        Value* unshadowed = pm.select(pm.eq(lambdaI, pm.c(0.0)), pm.c(1.0), pm.exp(pm.mul(lambdaI, s.logC)));
        LVal F = walkFresnel(vh);
        std::vector<Value*> next(3);
        for (int ch = 0; ch < 3; ++ch) {
            Value* term = pm.mul(pm.mul(s.weight[ch], F.c[ch]), pm.mul(phase, unshadowed));
            next[ch] = pm.select(counts, pm.add(sum[ch], term), sum[ch]);
        }
        return next;
    };
    std::vector<Value*> sum = emitWalk(wo, seed, above, {pm.c(0.0), pm.c(0.0), pm.c(0.0)}, step);
    return {pm.div(sum[0], wi[2]), pm.div(sum[1], wi[2]), pm.div(sum[2], wi[2])};
}

// The sampler's walk from wo (unit; lanes of `walking` only), its random
// numbers seeded by the bits of the uniforms u (float lanes): the direction
// it leaves in (0 for a walk cut at kMaxOrder) and the product of the
// Fresnel terms met (0 likewise).
LaneEmitter::WalkExit LaneEmitter::walkFromView(const Vec& wo, Value* walking, const Vec& u) {
    MathEmitter& pm = preciseMath_;
    llvm::IRBuilder<>& b = builder;
    LaneRandomWords words(b, pm.width());
    Value* seed = words.hash(b.CreateBitCast(u[0], words.type()));
    seed = words.mixIn(seed, b.CreateBitCast(u[1], words.type()));
    seed = words.mixIn(seed, b.CreateBitCast(u[2], words.type()));
    auto step = [&](const WalkState& s, Value*, Value*, Value* left, const std::vector<Value*>& exit) {
        std::vector<Value*> next(6);
        for (int i = 0; i < 3; ++i) next[i] = pm.select(left, s.w[i], exit[i]);
        for (int ch = 0; ch < 3; ++ch) next[3 + ch] = pm.select(left, s.weight[ch], exit[3 + ch]);
        return next;
    };
    std::vector<Value*> exit = emitWalk(wo, seed, walking, std::vector<Value*>(6, pm.c(0.0)), step);
    return {{exit[0], exit[1], exit[2]}, {exit[3], exit[4], exit[5]}};
}

}  // namespace facet
