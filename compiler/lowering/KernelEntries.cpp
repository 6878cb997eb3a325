// KernelEntries: the scalar and batch entry points of a kernel module
// around the lane bodies (LaneEmitter), and lowerMaterial(), which emits
// both as its plan says.
//
// The batch entry loops over vectors of `width` lanes; the lane bodies are
// the plan's (LoweringPlan::batchBodies for eval, SamplingPlan::batchBodies
// for sample): one plain body, or a guarded first body and a cold fallback
// function for the lanes it distrusts.
#include "Lowering.h"
#include "Immortal.h"

#include "Diagnostics.h"
#include "CombinationEmitter.h"
#include "LaneEmitter.h"

#include <llvm/IR/Constants.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/MDBuilder.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Support/raw_ostream.h>

#include <algorithm>
#include <functional>
#include <optional>

namespace facet {
namespace {

// A module's lowering inputs: the material, its plan, the options.
struct KernelContext {
    const CheckedMaterial& material;
    const LoweringPlan& plan;
    const LoweringOptions& options;
    std::string symbolPrefix;
};


// Builds the constant global array of slot defaults, `count` copies of
// each slot's default (the batch kernel reads `width` lanes of a default
// with stride 0; the scalar kernel reads one).
llvm::GlobalVariable* defaultsArray(llvm::Module& module, const std::vector<float>& values, const std::string& name) {
    auto* arr = llvm::ConstantDataArray::get(module.getContext(), values);
    return new llvm::GlobalVariable(module, arr->getType(), true, llvm::GlobalValue::PrivateLinkage, arr, name);
}

void addKernelAttributes(llvm::Function* fn, int width, const BodyPlan& body) {
    if (body.estimates) fn->addFnAttr("reciprocal-estimates", "div:1,vec-div:1,sqrt:1,vec-sqrt:1");
    fn->addFnAttr(llvm::Attribute::NoUnwind);
    fn->addFnAttr(llvm::Attribute::NoFree);
    fn->addFnAttr(llvm::Attribute::WillReturn);
    // Explicit 512-bit vectors should stay in zmm registers even on CPUs
    // whose default preference is 256-bit.
    std::string bits = std::to_string(width * 32);
    fn->addFnAttr("min-legal-vector-width", bits);
    fn->addFnAttr("prefer-vector-width", bits);
}

// The lane body of an entry point: the values of its output streams and
// the invalid mask, from its input streams (float or <W x float> lanes) and
// the material's slots.
struct LaneOutputs {
    std::vector<llvm::Value*> values;
    llvm::Value* invalid;
};
// What one body computes for a vector of lanes: its output values, the
// invalid mask and (guarded body) the lanes to recompute in the other body.
struct BodyLanes {
    std::vector<llvm::Value*> values;
    llvm::Value* invalid;
    llvm::Value* untrusted;
};
using BodyEmit = std::function<BodyLanes(LaneEmitter& lanes, const std::vector<llvm::Value*>& in,
                                         const std::vector<llvm::Value*>& slots)>;

// The lanes of a batch entry, for lanes of type `laneTy` (<W x float>):
// `emitBody` in the body `first`, and, for a two-body entry (`fallback`
// set: a guarded float body of an exact kernel, or a guarded fast body),
// only if some lane of the vector is untrusted, `emitBody` again in the
// fallback body (a function named .precise in both cases), whose values
// the untrusted lanes keep. Each lane's value is decided by the lane alone,
// never by its neighbours in the vector, so a lane gives the same result in
// any batch.
// One body's lanes, emitted through the builder given (KernelEntries' own
// or the fallback function's).
using BodyFn = std::function<BodyLanes(llvm::IRBuilder<>& b, const std::vector<llvm::Value*>& in,
                                       const std::vector<llvm::Value*>& slots)>;

// The same for any pair of bodies (`fallback` null: `first` alone);
// `fallbackPlan` gives the fallback function its attributes.
LaneOutputs emitTwoBodies(llvm::IRBuilder<>& b, llvm::Type* laneTy, llvm::Module& module,
                          const std::vector<llvm::Value*>& in, const std::vector<llvm::Value*>& slots,
                          const BodyFn& first, const BodyFn* fallbackBody, const BodyPlan* fallback) {
    BodyLanes fl = first(b, in, slots);
    if (!fallbackBody) return {fl.values, fl.invalid};

    llvm::LLVMContext& ctx = module.getContext();
    llvm::Function* fn = b.GetInsertBlock()->getParent();
    llvm::Value* anyUntrusted = anyLane(b, fl.untrusted);
    // The fallback body is a cold function of its own, called only when
    // needed, so that its code does not take part in the hot loop's register
    // allocation and layout. It is optnone: our own pipeline still runs on
    // it, but codegen selects it at -O0 and skips the machine
    // optimizations, which shortens a cold compile by a few milliseconds
    // and leaves the outputs bit-identical and batches of untrusted lanes
    // as fast as before (docs/perf-log.md).
    const size_t outputs = fl.values.size();
    // Its arguments: the lane's inputs and the slots the material reads
    // (null in `slots` for the others).
    std::vector<size_t> passed;
    for (size_t s = 0; s < slots.size(); ++s)
        if (slots[s]) passed.push_back(s);
    std::vector<llvm::Type*> argTypes(in.size() + passed.size(), laneTy);
    llvm::Type* maskTy = fl.invalid->getType();
    std::vector<llvm::Type*> resultTypes(outputs, laneTy);
    resultTypes.push_back(maskTy);
    auto* resultTy = llvm::StructType::get(ctx, resultTypes);
    auto* preciseFn = llvm::Function::Create(llvm::FunctionType::get(resultTy, argTypes, false),
                                             llvm::Function::InternalLinkage, fn->getName() + ".precise", module);
    preciseFn->setCallingConv(llvm::CallingConv::Fast);
    addKernelAttributes(preciseFn, laneTy->isVectorTy() ? int(llvm::cast<llvm::FixedVectorType>(laneTy)->getNumElements()) : 1,
                        *fallback);
    preciseFn->addFnAttr(llvm::Attribute::NoInline);
    preciseFn->addFnAttr(llvm::Attribute::Cold);
    preciseFn->addFnAttr(llvm::Attribute::OptimizeNone);
    {
        llvm::IRBuilder<> pb(llvm::BasicBlock::Create(ctx, "entry", preciseFn));
        std::vector<llvm::Value*> pin, pslots(slots.size(), nullptr);
        for (size_t a = 0; a < in.size(); ++a) pin.push_back(preciseFn->getArg(unsigned(a)));
        for (size_t p = 0; p < passed.size(); ++p) pslots[passed[p]] = preciseFn->getArg(unsigned(in.size() + p));
        BodyLanes pr = (*fallbackBody)(pb, pin, pslots);
        llvm::Value* agg = llvm::UndefValue::get(resultTy);
        for (unsigned c = 0; c < outputs; ++c) agg = pb.CreateInsertValue(agg, pr.values[c], c);
        agg = pb.CreateInsertValue(agg, pr.invalid, unsigned(outputs));
        pb.CreateRet(agg);
    }
    auto* precise = llvm::BasicBlock::Create(ctx, "precise.lanes", fn);
    auto* done = llvm::BasicBlock::Create(ctx, "lanes.done", fn);
    llvm::BasicBlock* firstEnd = b.GetInsertBlock();
    // Untrusted lanes are rare in renderer batches.
    b.CreateCondBr(anyUntrusted, precise, done, llvm::MDBuilder(ctx).createBranchWeights(1, 1000));

    b.SetInsertPoint(precise);
    std::vector<llvm::Value*> args(in.begin(), in.end());
    for (size_t s : passed) args.push_back(slots[s]);
    llvm::CallInst* call = b.CreateCall(preciseFn, args);
    call->setCallingConv(llvm::CallingConv::Fast);
    std::vector<llvm::Value*> mixed;
    for (unsigned c = 0; c < outputs; ++c)
        mixed.push_back(b.CreateSelect(fl.untrusted, b.CreateExtractValue(call, c), fl.values[c]));
    // Invalid lanes are untrusted, so the precise body's mask is the whole answer.
    llvm::Value* mixedInvalid = b.CreateExtractValue(call, unsigned(outputs));
    b.CreateBr(done);

    b.SetInsertPoint(done);
    LaneOutputs out;
    for (unsigned c = 0; c < outputs; ++c) {
        llvm::PHINode* phi = b.CreatePHI(laneTy, 2, "lane.out");
        phi->addIncoming(fl.values[c], firstEnd);
        phi->addIncoming(mixed[c], precise);
        out.values.push_back(phi);
    }
    llvm::PHINode* inv = b.CreatePHI(maskTy, 2, "invalid");
    inv->addIncoming(fl.invalid, firstEnd);
    inv->addIncoming(mixedInvalid, precise);
    out.invalid = inv;
    return out;
}

LaneOutputs emitBodies(const KernelContext& k, llvm::IRBuilder<>& b, llvm::Type* laneTy, llvm::Module& module,
                       const std::vector<llvm::Value*>& in, const std::vector<llvm::Value*>& slots,
                       const BodyPlan& first, const BodyPlan* fallback, const BodyEmit& emitBody) {
    auto inBody = [&](const BodyPlan& body) {
        return BodyFn([&k, &module, &body, &emitBody, laneTy](llvm::IRBuilder<>& builder,
                                                              const std::vector<llvm::Value*>& lanesIn,
                                                              const std::vector<llvm::Value*>& lanesSlots) {
            LaneEmitter lanes(k.material, k.plan, body, k.options.energyTable, builder, laneTy, module,
                              k.options.energyTableInside);
            return emitBody(lanes, lanesIn, lanesSlots);
        });
    };
    BodyFn firstFn = inBody(first);
    std::optional<BodyFn> fallbackFn;
    if (fallback) fallbackFn = inBody(*fallback);
    return emitTwoBodies(b, laneTy, module, in, slots, firstFn, fallbackFn ? &*fallbackFn : nullptr, fallback);
}

using LaneBody = std::function<LaneOutputs(llvm::IRBuilder<>& b, llvm::Type* laneTy, const std::vector<llvm::Value*>& in,
                                           const std::vector<llvm::Value*>& slots)>;

// The argument groups of an entry point besides n and inputs: direction-like
// inputs (three floats per lane, read as three arrays with the padding
// value of each for masked-off lanes) and outputs (three arrays, or one).
struct EntryShape {
    std::vector<std::array<float, 3>> inputs;  // padding of each input group
    std::vector<int> outputs;                  // 3 or 1 streams per output group
    int inStreams() const { return 3 * int(inputs.size()); }
    int outStreams() const {
        int n = 0;
        for (int o : outputs) n += o;
        return n;
    }
};

// A scalar entry point: int32 name(const float* in0, ..., const float*
// inputs, float* out0, ...), returning 1 for an invalid lane. The argument
// order is the shape's: the input groups, the material's inputs, the
// output groups.
llvm::Function* emitScalarFunction(const KernelContext& k, llvm::Module& module, const std::string& name,
                                   const EntryShape& shape, const BodyPlan& body, const LaneBody& lanes) {
    const CheckedMaterial& mat = k.material;
    llvm::LLVMContext& ctx = module.getContext();
    llvm::IRBuilder<> b(ctx);
    llvm::Type* ptr = b.getPtrTy();
    llvm::Type* f32 = b.getFloatTy();
    const int groupsIn = int(shape.inputs.size()), groupsOut = int(shape.outputs.size());
    std::vector<llvm::Type*> argTypes(size_t(groupsIn + 1 + groupsOut), ptr);
    auto* fn = llvm::Function::Create(llvm::FunctionType::get(b.getInt32Ty(), argTypes, false),
                                      llvm::Function::ExternalLinkage, name, module);
    addKernelAttributes(fn, 1, body);
    b.SetInsertPoint(llvm::BasicBlock::Create(ctx, "entry", fn));
    std::vector<llvm::Value*> in;
    for (int g = 0; g < groupsIn; ++g)
        for (int i = 0; i < 3; ++i) in.push_back(b.CreateLoad(f32, b.CreateConstGEP1_32(f32, fn->getArg(unsigned(g)), i)));
    llvm::Value* inP = fn->getArg(unsigned(groupsIn));
    std::vector<llvm::Value*> slots;
    if (mat.slotCount > 0) {
        // inputs == NULL means all defaults: read from a constant array instead.
        std::vector<double> d = mat.defaultSlots();
        auto* defaults = defaultsArray(module, std::vector<float>(d.begin(), d.end()), name + ".defaults");
        llvm::Value* base = b.CreateSelect(b.CreateIsNull(inP), defaults, inP);
        for (int s = 0; s < mat.slotCount; ++s)
            slots.push_back(k.plan.slotRead(s) ? b.CreateLoad(f32, b.CreateConstGEP1_32(f32, base, s)) : nullptr);
    }
    LaneOutputs r = lanes(b, f32, in, slots);
    size_t next = 0;
    for (int g = 0; g < groupsOut; ++g)
        for (int i = 0; i < shape.outputs[g]; ++i)
            b.CreateStore(r.values[next++], b.CreateConstGEP1_32(f32, fn->getArg(unsigned(groupsIn + 1 + g)), i));
    // Under the host's promise (LoweringPlan::trustInputs) no lane is reported invalid.
    b.CreateRet(k.plan.trustInputs ? b.getInt32(0) : b.CreateZExt(r.invalid, b.getInt32Ty()));
    return fn;
}

// The lane body of an entry point computing `emit` in the body `first`
// and, where `fallback` is set, in that body for the lanes `first`
// distrusts (emitBodies).
LaneBody bodies(const KernelContext& k, llvm::Module& module, const BodyPlan& first, const BodyPlan* fallback,
                BodyEmit emit) {
    return [&k, &module, &first, fallback, emit](llvm::IRBuilder<>& b, llvm::Type* laneTy,
                                                  const std::vector<llvm::Value*>& in,
                                                  const std::vector<llvm::Value*>& slots) {
        return emitBodies(k, b, laneTy, module, in, slots, first, fallback, emit);
    };
}

// The lane body of a combination of lobes (CombinationEmitter.h): every
// lobe in its plain body; in a batch entry whose plan has two bodies, first
// every lobe in its batch body (guarded where the lobe's own kernel would
// guard it), and the lanes any of them distrusts again in the plain bodies.
LaneBody combinationBody(const KernelContext& k, llvm::Module& module, bool scalar) {
    return [&k, &module, scalar](llvm::IRBuilder<>& b, llvm::Type* laneTy, const std::vector<llvm::Value*>& in,
                                 const std::vector<llvm::Value*>& slots) {
        auto inBodies = [&k, &module, laneTy](bool guarded) {
            return BodyFn([&k, &module, laneTy, guarded](llvm::IRBuilder<>& builder,
                                                         const std::vector<llvm::Value*>& lanesIn,
                                                         const std::vector<llvm::Value*>& lanesSlots) {
                CombinationLanes c =
                    emitCombination(k.material, k.plan, k.options, guarded, builder, laneTy, module,
                                    {lanesIn[0], lanesIn[1], lanesIn[2]}, {lanesIn[3], lanesIn[4], lanesIn[5]},
                                    lanesSlots, k.symbolPrefix);
                return BodyLanes{{c.rgb.begin(), c.rgb.end()}, c.invalid, c.untrusted};
            });
        };
        const bool twoBodies = !scalar && k.plan.fallbackBody;
        BodyFn plain = inBodies(false);
        if (!twoBodies) return emitTwoBodies(b, laneTy, module, in, slots, plain, nullptr, nullptr);
        BodyFn guarded = inBodies(true);
        return emitTwoBodies(b, laneTy, module, in, slots, guarded, &plain, &*k.plan.fallbackBody);
    };
}

LaneBody combinationSampleBody(const KernelContext& k, llvm::Module& module) {
    return [&k, &module](llvm::IRBuilder<>& b, llvm::Type* laneTy, const std::vector<llvm::Value*>& in,
                                 const std::vector<llvm::Value*>& slots) {
        CombinationSampleLanes c = emitCombinationSample(k.material, k.plan, k.options, b, laneTy, module,
                                                         {in[0], in[1], in[2]}, {in[3], in[4], in[5]}, slots,
                                                         k.symbolPrefix);
        return LaneOutputs{{c.wi[0], c.wi[1], c.wi[2], c.pdf, c.weight[0], c.weight[1], c.weight[2]}, c.invalid};
    };
}

LaneBody combinationPdfBody(const KernelContext& k, llvm::Module& module) {
    return [&k, &module](llvm::IRBuilder<>& b, llvm::Type* laneTy, const std::vector<llvm::Value*>& in,
                                 const std::vector<llvm::Value*>& slots) {
        CombinationPdfLanes c = emitCombinationPdf(k.material, k.plan, k.options, b, laneTy, module,
                                                   {in[0], in[1], in[2]}, {in[3], in[4], in[5]}, slots,
                                                   k.symbolPrefix);
        return LaneOutputs{{c.pdf}, c.invalid};
    };
}

BodyLanes evalBody(LaneEmitter& lanes, const std::vector<llvm::Value*>& in, const std::vector<llvm::Value*>& slots) {
    LaneEmitter::Result r = lanes.emit({in[0], in[1], in[2]}, {in[3], in[4], in[5]}, slots);
    return {{r.rgb.begin(), r.rgb.end()}, r.invalid, r.untrusted};
}

// The scalar kernel: `<name>` computes one lane and returns 1 if it was
// invalid. Kernel::eval, the SPEC's void entry point, calls it and drops
// the status.
void emitScalarEntry(const KernelContext& k, llvm::Module& module, const std::string& name) {
    // The scalar kernel computes the precise body directly: per lane, float
    // arithmetic is no faster than double except for division and square
    // root, and the guards would cost more than they save (measured: GGX
    // 47 ns/eval precise, 56 ns float-first).
    EntryShape shape{{{0, 0, 1}, {0, 0, 1}}, {3}};
    emitScalarFunction(k, module, name, shape, k.plan.scalarBody,
                       k.plan.combines() ? combinationBody(k, module, true)
                                         : bodies(k, module, k.plan.scalarBody, nullptr, evalBody));
}

// A call of one lane (LoweringPlan::oneLaneBody): `oneLane`, the batch
// entry's lane body at one lane (oneLaneFunction), on the lane's values
// gathered into stack arrays, instead of a whole vector of `width` lanes
// for one (a one-lane vector call cost 1.0-3.5x a scalar call on the bench
// materials). Emitted at the insert point, which it leaves in the block
// where the vector loop goes on when n != 1. The call stays a call:
// inlined, the one-lane body would double the batch entry's compile time.
void emitOneLaneCall(const KernelContext& k, llvm::IRBuilder<>& b, const EntryShape& shape, llvm::Function* oneLane,
                     llvm::Value* n, const std::vector<llvm::Value*>& inP, const std::vector<llvm::Value*>& outP,
                     const std::vector<int>& readSlots, const std::vector<llvm::Value*>& slotBase,
                     llvm::Value* statusA) {
    llvm::LLVMContext& ctx = b.getContext();
    llvm::Function* fn = b.GetInsertBlock()->getParent();
    llvm::Type* f32 = b.getFloatTy();
    const int groupsIn = int(shape.inputs.size()), groupsOut = int(shape.outputs.size());
    std::vector<llvm::Value*> inArrays, outArrays;  // static allocas: still the entry block
    for (int g = 0; g < groupsIn; ++g) inArrays.push_back(b.CreateAlloca(f32, b.getInt32(3), "one.in"));
    for (int g = 0; g < groupsOut; ++g)
        outArrays.push_back(b.CreateAlloca(f32, b.getInt32(unsigned(shape.outputs[size_t(g)])), "one.out"));
    const int slotCount = k.material.slotCount;
    llvm::Value* slotArray = slotCount > 0 ? b.CreateAlloca(f32, b.getInt32(unsigned(slotCount)), "one.slots") : nullptr;
    auto* single = llvm::BasicBlock::Create(ctx, "one.lane", fn);
    auto* rest = llvm::BasicBlock::Create(ctx, "vectors.entry", fn);
    b.CreateCondBr(b.CreateICmpEQ(n, b.getInt64(1)), single, rest);

    b.SetInsertPoint(single);
    for (int g = 0; g < groupsIn; ++g)
        for (int c = 0; c < 3; ++c)
            b.CreateStore(b.CreateLoad(f32, inP[size_t(3 * g + c)]), b.CreateConstGEP1_32(f32, inArrays[size_t(g)], c));
    // Only the slots the body reads (plan.slotRead), from their stream or
    // its defaults (slotBase); the body never loads the others.
    for (size_t r = 0; r < readSlots.size(); ++r)
        b.CreateStore(b.CreateLoad(f32, slotBase[r]), b.CreateConstGEP1_32(f32, slotArray, readSlots[r]));
    std::vector<llvm::Value*> args(inArrays.begin(), inArrays.end());
    args.push_back(slotArray ? slotArray : llvm::ConstantPointerNull::get(b.getPtrTy()));
    args.insert(args.end(), outArrays.begin(), outArrays.end());
    llvm::CallInst* call = b.CreateCall(oneLane, args);
    call->addFnAttr(llvm::Attribute::NoInline);
    size_t stream = 0;
    for (int g = 0; g < groupsOut; ++g)
        for (int c = 0; c < shape.outputs[size_t(g)]; ++c)
            b.CreateStore(b.CreateLoad(f32, b.CreateConstGEP1_32(f32, outArrays[size_t(g)], c)), outP[stream++]);
    llvm::Value* status = b.CreateZExt(call, b.getInt64Ty());
    if (statusA) {
        auto* store = llvm::BasicBlock::Create(ctx, "one.status", fn);
        auto* done = llvm::BasicBlock::Create(ctx, "one.done", fn);
        b.CreateCondBr(b.CreateIsNull(statusA), done, store);
        b.SetInsertPoint(store);
        b.CreateStore(b.CreateTrunc(call, b.getInt8Ty()), statusA);
        b.CreateBr(done);
        b.SetInsertPoint(done);
    }
    b.CreateRet(status);
    b.SetInsertPoint(rest);
}

// The lane body of a batch entry at one lane, as a function of the scalar
// entries' form (emitScalarFunction) named `<batch>.one`, for its one-lane
// calls: the batch's bodies (its guarded first body and the fallback), so
// that a lane gets the same bits whether it is called alone or in a vector.
llvm::Function* oneLaneFunction(const KernelContext& k, llvm::Module& module, const std::string& batchName,
                                const EntryShape& shape, const BodyPlan& body, const LaneBody& lanes) {
    llvm::Function* fn = emitScalarFunction(k, module, batchName + ".one", shape, body, lanes);
    fn->setLinkage(llvm::GlobalValue::InternalLinkage);
    return fn;
}

// A batch entry point: int64 name(int64 n, const float* const in0[3], ...,
// const float* const* inputs, float* const out0[3] (or float* out0), ...
// [, uint8_t* status]), returning the number of invalid lanes (0, and a
// status of 0s, under the host's promise of valid inputs: the plan's
// trustInputs). It loops over vectors of `width` lanes.
void emitBatchFunction(const KernelContext& k, llvm::Module& module, const std::string& name, const EntryShape& shape,
                       bool withStatus, const BodyPlan& body, const LaneBody& lanes, llvm::Function* oneLane) {
    const CheckedMaterial& mat = k.material;
    llvm::LLVMContext& ctx = module.getContext();
    llvm::IRBuilder<> b(ctx);
    const int W = k.options.width;
    llvm::Type* ptr = b.getPtrTy();
    llvm::Type* i64 = b.getInt64Ty();
    llvm::Type* f32 = b.getFloatTy();
    auto* vecTy = llvm::FixedVectorType::get(f32, W);
    const int groupsIn = int(shape.inputs.size()), groupsOut = int(shape.outputs.size());
    std::vector<llvm::Type*> argTypes(size_t(1 + groupsIn + 1 + groupsOut + (withStatus ? 1 : 0)), ptr);
    argTypes[0] = i64;
    auto* fnTy = llvm::FunctionType::get(i64, argTypes, false);
    auto* fn = llvm::Function::Create(fnTy, llvm::Function::ExternalLinkage, name, module);
    addKernelAttributes(fn, W, body);
    llvm::Value *n = fn->getArg(0), *inA = fn->getArg(unsigned(1 + groupsIn));
    llvm::Value* statusA = withStatus ? fn->getArg(unsigned(2 + groupsIn + groupsOut)) : nullptr;
    auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
    auto* header = llvm::BasicBlock::Create(ctx, "loop.header", fn);
    auto* bodyBlock = llvm::BasicBlock::Create(ctx, "loop.body", fn);
    auto* exit = llvm::BasicBlock::Create(ctx, "exit", fn);

    b.SetInsertPoint(entry);
    // The slots the material reads: an unread one is never loaded, so that
    // a material's unused inputs cost nothing (no stream, no register).
    std::vector<int> readSlots;
    for (int s = 0; s < mat.slotCount; ++s)
        if (k.plan.slotRead(s)) readSlots.push_back(s);
    // The stage buffers of the partial chunk (below), in the entry block:
    // static allocas.
    const int streams = shape.inStreams() + int(readSlots.size());
    const int outStreams = shape.outStreams();
    llvm::Value* stageIn = b.CreateAlloca(vecTy, b.getInt32(streams), "stage.in");
    llvm::Value* stageOut = b.CreateAlloca(vecTy, b.getInt32(outStreams), "stage.out");
    std::vector<llvm::Value*> inP, outP;
    for (int g = 0; g < groupsIn; ++g)
        for (int i = 0; i < 3; ++i)
            inP.push_back(b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, fn->getArg(unsigned(1 + g)), i), "in.ptr"));
    for (int g = 0; g < groupsOut; ++g) {
        llvm::Value* arg = fn->getArg(unsigned(2 + groupsIn + g));
        if (shape.outputs[g] == 1) outP.push_back(arg);
        else
            for (int i = 0; i < shape.outputs[g]; ++i)
                outP.push_back(b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, arg, i), "out.ptr"));
    }
    // Per slot: a base pointer and a stride (1 for a caller array, 0 for the
    // constant array of defaults when inputs or inputs[s] is NULL).
    std::vector<llvm::Value*> slotBase, slotStep;
    std::vector<double> defaults = mat.defaultSlots();
    for (int s : readSlots) {
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

    if (oneLane) emitOneLaneCall(k, b, shape, oneLane, n, inP, outP, readSlots, slotBase, statusA);

    auto popcount = [&](llvm::Value* mask) {
        llvm::Value* bits = b.CreateBitCast(mask, b.getIntNTy(W));
        llvm::Value* cnt = b.CreateUnaryIntrinsic(llvm::Intrinsic::ctpop, bits);
        return b.CreateZExt(cnt, i64);
    };

    // The lane body is emitted once (it is most of the module: emitting it a
    // second time for the remainder doubled the compile time). The last,
    // partial chunk is staged through W-lane buffers on the stack: masked
    // loads fill them (masked-off lanes read the padding, a valid direction
    // such as (0,0,1), and the slot defaults), the body runs on the buffers,
    // and a loop over the valid lanes copies them back.
    llvm::BasicBlock* preheader = b.GetInsertBlock();
    b.CreateBr(header);

    b.SetInsertPoint(header);
    llvm::PHINode* i = b.CreatePHI(i64, 2, "i");
    llvm::PHINode* count = b.CreatePHI(i64, 2, "invalid");
    i->addIncoming(llvm::ConstantInt::get(i64, 0), preheader);
    count->addIncoming(llvm::ConstantInt::get(i64, 0), preheader);
    llvm::Value* remaining = b.CreateSub(n, i);
    b.CreateCondBr(b.CreateICmpSGT(remaining, llvm::ConstantInt::get(i64, 0)), bodyBlock, exit);

    b.SetInsertPoint(bodyBlock);
    llvm::Value* partial = b.CreateICmpSLT(remaining, llvm::ConstantInt::get(i64, W));
    // Source pointers of the chunk: the caller's arrays, or the stage
    // buffers on the partial chunk (filled below).
    std::vector<llvm::Value*> streamPtr;
    std::vector<float> padding;
    for (int g = 0; g < groupsIn; ++g)
        for (int c = 0; c < 3; ++c) {
            streamPtr.push_back(b.CreateGEP(f32, inP[size_t(3 * g + c)], i));
            padding.push_back(shape.inputs[g][c]);
        }
    for (size_t r = 0; r < readSlots.size(); ++r) {
        streamPtr.push_back(b.CreateGEP(f32, slotBase[r], b.CreateMul(i, slotStep[r])));
        padding.push_back(float(defaults[size_t(readSlots[r])]));
    }
    auto* stageBlock = llvm::BasicBlock::Create(ctx, "stage", fn);
    auto* compute = llvm::BasicBlock::Create(ctx, "compute", fn);
    llvm::BasicBlock* bodyEntry = b.GetInsertBlock();
    b.CreateCondBr(partial, stageBlock, compute);

    b.SetInsertPoint(stageBlock);
    // The first `remaining` lanes of the last chunk (computed there only: a
    // full chunk takes all lanes, without the two compares per vector).
    std::vector<llvm::Constant*> laneIds;
    for (int l = 0; l < W; ++l) laneIds.push_back(llvm::ConstantInt::get(i64, l));
    llvm::Value* partialMask = b.CreateICmpSLT(llvm::ConstantVector::get(laneIds), b.CreateVectorSplat(W, remaining));
    std::vector<llvm::Value*> stagePtr;
    for (int s = 0; s < streams; ++s) {
        llvm::Value* v = b.CreateMaskedLoad(vecTy, streamPtr[s], llvm::Align(4), partialMask,
                                            llvm::ConstantFP::get(vecTy, padding[s]));
        stagePtr.push_back(b.CreateConstGEP1_32(vecTy, stageIn, s));
        b.CreateAlignedStore(v, stagePtr.back(), llvm::Align(4));
    }
    b.CreateBr(compute);

    b.SetInsertPoint(compute);
    llvm::PHINode* mask = b.CreatePHI(partialMask->getType(), 2, "lanes");
    mask->addIncoming(llvm::Constant::getAllOnesValue(partialMask->getType()), bodyEntry);
    mask->addIncoming(partialMask, stageBlock);
    std::vector<llvm::PHINode*> src;
    for (int s = 0; s < streams; ++s) {
        src.push_back(b.CreatePHI(ptr, 2));
        src.back()->addIncoming(streamPtr[s], bodyEntry);
        src.back()->addIncoming(stagePtr[s], stageBlock);
    }
    std::vector<llvm::Value*> in, slots(size_t(mat.slotCount), nullptr), out;
    for (int s = 0; s < streams; ++s) {
        llvm::Value* v = b.CreateAlignedLoad(vecTy, src[s], llvm::Align(4));
        if (s < shape.inStreams()) in.push_back(v);
        else slots[size_t(readSlots[size_t(s - shape.inStreams())])] = v;
    }
    for (int c = 0; c < outStreams; ++c)
        out.push_back(b.CreateSelect(partial, b.CreateConstGEP1_32(vecTy, stageOut, c), b.CreateGEP(f32, outP[c], i)));
    LaneOutputs r = lanes(b, vecTy, in, slots);
    for (int c = 0; c < outStreams; ++c) b.CreateAlignedStore(r.values[c], out[c], llvm::Align(4));
    const bool counts = !k.plan.trustInputs;
    llvm::Value* bodyCount = counts ? b.CreateAdd(count, popcount(b.CreateAnd(r.invalid, mask))) : count;
    auto* unstage = llvm::BasicBlock::Create(ctx, "unstage", fn);
    auto* latch = llvm::BasicBlock::Create(ctx, "latch", fn);
    if (withStatus) {
        auto* statusBlock = llvm::BasicBlock::Create(ctx, "status", fn);
        auto* statusDone = llvm::BasicBlock::Create(ctx, "status.done", fn);
        b.CreateCondBr(b.CreateIsNull(statusA), statusDone, statusBlock,
                       llvm::MDBuilder(ctx).createBranchWeights(1, 1));

        b.SetInsertPoint(statusBlock);
        auto* statusTy = llvm::FixedVectorType::get(b.getInt8Ty(), W);
        b.CreateMaskedStore(counts ? b.CreateZExt(r.invalid, statusTy) : llvm::Constant::getNullValue(statusTy),
                            b.CreateGEP(b.getInt8Ty(), statusA, i), llvm::Align(1), mask);
        b.CreateBr(statusDone);

        b.SetInsertPoint(statusDone);
    }
    b.CreateCondBr(partial, unstage, latch);

    // The valid lanes go back in a loop of plain scalar stores, not masked
    // ones: a load that follows a masked store to an address equal in its
    // low 12 bits (columns of equal length are often page-aligned alike: the
    // next chunk's inputs) waits until that store retires on AMD cores,
    // which took a one-lane call of GGX from ~75 to ~200 ns.
    b.SetInsertPoint(unstage);
    auto* unstageLanes = llvm::BasicBlock::Create(ctx, "unstage.lanes", fn);
    b.CreateBr(unstageLanes);
    b.SetInsertPoint(unstageLanes);
    llvm::PHINode* lane = b.CreatePHI(i64, 2, "lane");
    lane->addIncoming(llvm::ConstantInt::get(i64, 0), unstage);
    for (int c = 0; c < outStreams; ++c) {
        llvm::Value* from = b.CreateGEP(f32, b.CreateConstGEP1_32(vecTy, stageOut, c), lane);
        b.CreateAlignedStore(b.CreateAlignedLoad(f32, from, llvm::Align(4)),
                             b.CreateGEP(f32, outP[c], b.CreateAdd(i, lane)), llvm::Align(4));
    }
    llvm::Value* nextLane = b.CreateAdd(lane, llvm::ConstantInt::get(i64, 1));
    lane->addIncoming(nextLane, unstageLanes);
    b.CreateCondBr(b.CreateICmpSLT(nextLane, remaining), unstageLanes, latch);

    b.SetInsertPoint(latch);
    i->addIncoming(b.CreateAdd(i, llvm::ConstantInt::get(i64, W)), latch);
    count->addIncoming(bodyCount, latch);
    b.CreateBr(header);

    b.SetInsertPoint(exit);
    b.CreateRet(count);
}

// The eval batch entry; the sixth argument is the optional per-lane status
// array (one byte per lane, 1 = invalid; null: not wanted).
void emitBatchEntry(const KernelContext& k, llvm::Module& module, const std::string& name, bool oneLane) {
    EntryShape shape{{{0, 0, 1}, {0, 0, 1}}, {3}};
    const BodyPlan* fallback = k.plan.fallbackBody ? &*k.plan.fallbackBody : nullptr;
    LaneBody lanes = k.plan.combines() ? combinationBody(k, module, false)
                                       : bodies(k, module, k.plan.batchBody, fallback, evalBody);
    emitBatchFunction(k, module, name, shape, true, k.plan.batchBody, lanes,
                      oneLane ? oneLaneFunction(k, module, name, shape, k.plan.batchBody, lanes) : nullptr);
}

// The sampler's entry points (SPEC 8), in the plan's sampling bodies:
//   sample: (wo[3], u[3], inputs) -> (wi[3], pdf, weight[3])
//   pdf:    (wi[3], wo[3], inputs) -> (pdf)
// Masked-off lanes of a partial chunk read wo = (0,0,1) and u = 0.
const EntryShape& kSampleShape = immortal<EntryShape>(EntryShape{{{0, 0, 1}, {0, 0, 0}}, {3, 1, 3}});
const EntryShape& kPdfShape = immortal<EntryShape>(EntryShape{{{0, 0, 1}, {0, 0, 1}}, {1}});

BodyLanes sampleBody(LaneEmitter& lanes, const std::vector<llvm::Value*>& in, const std::vector<llvm::Value*>& slots) {
    LaneEmitter::SampleResult r = lanes.emitSample({in[0], in[1], in[2]}, {in[3], in[4], in[5]}, slots);
    return {{r.wi[0], r.wi[1], r.wi[2], r.pdf, r.weight[0], r.weight[1], r.weight[2]}, r.invalid, r.untrusted};
}

BodyLanes pdfBody(LaneEmitter& lanes, const std::vector<llvm::Value*>& in, const std::vector<llvm::Value*>& slots) {
    LaneEmitter::PdfResult r = lanes.emitPdf({in[0], in[1], in[2]}, {in[3], in[4], in[5]}, slots);
    return {{r.pdf}, r.invalid, r.invalid};
}

}  // namespace

LoweredModule lowerMaterial(const CheckedMaterial& material, const LoweringPlan& plan, const LoweringOptions& options,
                            llvm::LLVMContext& context, const std::string& symbolPrefix) {
    internal_assert(options.width == 4 || options.width == 8 || options.width == 16)
        << "unsupported vector width " << options.width;
    LoweredModule out;
    out.plan = plan;
    const KernelContext k{material, out.plan, options, symbolPrefix};
    out.module = std::make_unique<llvm::Module>(symbolPrefix, context);
    const bool sampling = options.emitSampling && plan.sampling.compiled;
    if (options.emitScalar) {
        if (options.emitEval) {
            out.scalarSymbol = symbolPrefix + "_scalar_status";
            emitScalarEntry(k, *out.module, out.scalarSymbol);
        }
        if (sampling) {
            out.sampleScalarSymbol = symbolPrefix + "_sample_scalar";
            out.pdfScalarSymbol = symbolPrefix + "_pdf_scalar";
            const BodyPlan& body = out.plan.sampling.body;
            const bool mixture = plan.combines();
            emitScalarFunction(k, *out.module, out.sampleScalarSymbol, kSampleShape, body,
                               mixture ? combinationSampleBody(k, *out.module)
                                       : bodies(k, *out.module, body, nullptr, sampleBody));
            emitScalarFunction(k, *out.module, out.pdfScalarSymbol, kPdfShape, body,
                               mixture ? combinationPdfBody(k, *out.module)
                                       : bodies(k, *out.module, body, nullptr, pdfBody));
        }
    }
    const bool oneLane = plan.oneLaneBody && options.oneLaneBodies;
    if (options.emitBatch) {
        if (options.emitEval) {
            out.batchSymbol = symbolPrefix + "_batch";
            emitBatchEntry(k, *out.module, out.batchSymbol, oneLane);
        }
        if (sampling) {
            out.sampleBatchSymbol = symbolPrefix + "_sample_batch";
            out.pdfBatchSymbol = symbolPrefix + "_pdf_batch";
            const SamplingPlan& sp = out.plan.sampling;
            const bool floatFirst = sp.batchBodies == BatchBodies::FloatFirst;
            const bool mixture = plan.combines();
            LaneBody sampleLanes = mixture ? combinationSampleBody(k, *out.module)
                                           : bodies(k, *out.module, sp.batchBody, floatFirst ? &sp.body : nullptr,
                                                    sampleBody);
            emitBatchFunction(k, *out.module, out.sampleBatchSymbol, kSampleShape, false, sp.batchBody, sampleLanes,
                              oneLane ? oneLaneFunction(k, *out.module, out.sampleBatchSymbol, kSampleShape,
                                                        sp.batchBody, sampleLanes)
                                      : nullptr);
            LaneBody pdfLanes = mixture ? combinationPdfBody(k, *out.module)
                                        : bodies(k, *out.module, sp.body, nullptr, pdfBody);
            emitBatchFunction(k, *out.module, out.pdfBatchSymbol, kPdfShape, false, sp.body, pdfLanes,
                              oneLane ? oneLaneFunction(k, *out.module, out.pdfBatchSymbol, kPdfShape, sp.body, pdfLanes)
                                      : nullptr);
        }
    }
    // Every constant table in the module is part of the cache key: the
    // energy tables through their own key (runtime/KernelCache.h), the others
    // through embeddedTables(), whose per-material hooks must agree with
    // what the emitters embedded.
    std::vector<EmbeddedTable> keyed = embeddedTables(material);
    for (const llvm::GlobalVariable& gv : out.module->globals()) {
        std::string name = gv.getName().str();
        if (name.rfind(symbolPrefix, 0) == 0 || name.rfind("facet_energy_", 0) == 0) continue;  // defaults, E tables
        bool inKey = std::any_of(keyed.begin(), keyed.end(), [&](const EmbeddedTable& t) { return t.name == name; });
        internal_assert(inKey) << "table '" << name << "' is embedded but not hashed into the cache key "
                               << "(TermEmitterEntry::tables of its model)";
    }
    std::string errors;
    llvm::raw_string_ostream os(errors);
    for (llvm::Function& fn : *out.module)
        if (!fn.isDeclaration() && llvm::verifyFunction(fn, &os)) internal_error << "invalid IR for " << fn.getName().str() << ": " << os.str();
    if (llvm::verifyModule(*out.module, &os)) internal_error << "invalid module: " << os.str();
    return out;
}

}  // namespace facet

