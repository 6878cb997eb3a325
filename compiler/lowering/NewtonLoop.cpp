// NewtonLoop: the bracketed Newton (or Halley) iteration the samplers invert
// their CDFs with, as a loop of the IR (see NewtonLoop.h).
#include "NewtonLoop.h"

#include <llvm/IR/Constants.h>
#include <llvm/IR/Metadata.h>

namespace facet {

using llvm::Value;

Value* emitBracketedNewton(llvm::IRBuilder<>& b, MathEmitter& pm, const std::function<NewtonTerms(Value*)>& eval,
                           Value* v0, Value* lo0, Value* hi0, int steps, double settledStep, double settledFloor) {
    llvm::Function* fn = b.GetInsertBlock()->getParent();
    llvm::BasicBlock* pre = b.GetInsertBlock();
    auto* loop = llvm::BasicBlock::Create(b.getContext(), "newton.step", fn);
    auto* done = llvm::BasicBlock::Create(b.getContext(), "newton.done", fn);
    b.CreateBr(loop);

    b.SetInsertPoint(loop);
    llvm::PHINode* k = b.CreatePHI(b.getInt32Ty(), 2, "newton.k");
    llvm::PHINode* v = b.CreatePHI(pm.type(), 2, "newton.v");
    llvm::PHINode* lo = b.CreatePHI(pm.type(), 2, "newton.lo");
    llvm::PHINode* hi = b.CreatePHI(pm.type(), 2, "newton.hi");
    llvm::Type* maskType = pm.width() > 1 ? (llvm::Type*)llvm::FixedVectorType::get(b.getInt1Ty(), pm.width())
                                          : b.getInt1Ty();
    llvm::PHINode* stopped = b.CreatePHI(maskType, 2, "newton.stopped");
    k->addIncoming(b.getInt32(0), pre);
    v->addIncoming(v0, pre);
    lo->addIncoming(lo0, pre);
    hi->addIncoming(hi0, pre);
    stopped->addIncoming(llvm::Constant::getNullValue(maskType), pre);
    NewtonTerms t = eval(v);
    // phi(v) > 0: the root is below v. (phi = 0 keeps v: the step is 0.)
    Value* above = pm.gt(t.phi, pm.c(0.0));
    Value* nextHi = pm.select(above, v, hi);
    Value* nextLo = pm.select(above, lo, v);
    Value* step = pm.div(t.phi, t.slope);
    if (t.curvature) {
        // Halley: the Newton step over 1 - L/2, L = phi phi'' / phi'^2,
        // where |L| < 1 (near the root L -> 0; farther, Newton's step and
        // the bracket).
        Value* L = pm.div(pm.mul(step, t.curvature), t.slope);
        step = pm.select(pm.lt(pm.abs(L), pm.c(1.0)), pm.div(step, pm.fma(L, pm.c(-0.5), pm.c(1.0))), step);
    }
    Value* newton = pm.sub(v, step);
    Value* inside = b.CreateAnd(pm.ge(newton, nextLo), pm.le(newton, nextHi));  // ordered: false for NaN
    Value* next = pm.select(inside, newton, pm.mul(pm.add(nextLo, nextHi), pm.c(0.5)));
    // A lane stops once a Newton (or Halley) step moved v by at most
    // settledStep max(|v|, settledFloor) (by default 2^-40 |v| in double,
    // 2^-20 |v| in float: Newton's error is then of the order of that step
    // squared), or v is NaN (and stays NaN); a short bisection does not stop
    // it, since it leaves a bracket that wide. It keeps the value that step
    // gave it: more steps for its neighbours do not move it, so a lane's
    // result is the same in any batch. Waiting for next == v exactly would
    // run all `steps` on most vectors: some lane's last bits keep moving by
    // an ulp. Without a floor, a root at 0 never settles early and runs
    // every step.
    if (settledStep == 0) settledStep = pm.type()->getScalarType()->isFloatTy() ? 0x1p-20 : 0x1p-40;
    Value* scale = settledFloor > 0 ? pm.maxnum(pm.abs(v), pm.c(settledFloor)) : pm.abs(v);
    Value* settles = b.CreateOr(b.CreateFCmpUNO(next, v),
                                b.CreateAnd(inside, pm.le(pm.abs(pm.sub(next, v)), pm.mul(pm.c(settledStep), scale))));
    Value* out = pm.select(stopped, v, next);
    Value* nowStopped = b.CreateOr(stopped, settles);
    Value* k1 = b.CreateAdd(k, b.getInt32(1));
    llvm::BasicBlock* latch = b.GetInsertBlock();
    k->addIncoming(k1, latch);
    v->addIncoming(out, latch);
    lo->addIncoming(nextLo, latch);
    hi->addIncoming(nextHi, latch);
    stopped->addIncoming(nowStopped, latch);
    Value* more = b.CreateAnd(b.CreateICmpSLT(k1, b.getInt32(steps)), b.CreateNot(allLanes(b, nowStopped)));
    keepLoopRolled(b.CreateCondBr(more, loop, done));

    b.SetInsertPoint(done);
    return out;
}

void keepLoopRolled(llvm::BranchInst* back) {
    llvm::LLVMContext& ctx = back->getContext();
    llvm::MDNode* disable = llvm::MDNode::get(ctx, llvm::MDString::get(ctx, "llvm.loop.unroll.disable"));
    llvm::MDNode* self = llvm::MDNode::getDistinct(ctx, {nullptr, disable});
    self->replaceOperandWith(0, self);
    back->setMetadata(llvm::LLVMContext::MD_loop, self);
}

}  // namespace facet
