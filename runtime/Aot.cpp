// Aot: the C entry points of an ahead-of-time object, and writing it out
// (see Aot.h; the target machine is AotTarget.cpp's).
#include "Aot.h"

#include "Diagnostics.h"
#include "Jit.h"

#include <llvm/Bitcode/BitcodeWriter.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LegacyPassManager.h>
#include <llvm/IR/Verifier.h>
#include <llvm/Support/raw_ostream.h>

#include <algorithm>
#include <vector>

namespace facet {

namespace {

// One family of kernel functions in the lowered module (eval, sample or
// pdf) as the C entry points call them. Every family reads two groups of
// three floats per lane (wi and wo, or wo and u) and the material's slots.
struct KernelFamily {
    llvm::Function* scalar = nullptr;  // int32 (in0, in1, inputs, outputs...): 1 for an invalid lane
    llvm::Function* batch = nullptr;   // int64 (n, in0[3], in1[3], inputs, outputs... [, status])
    bool batchStatus = false;          // the batch function takes a per-lane status array last (eval's)
    std::vector<int> outputs;          // floats per lane of each output group: 3 (an array of three
                                       // streams in the batch call) or 1 (one stream)
};

// Emits the C entry points of an ahead-of-time object over the families.
class EntryEmitter {
public:
    EntryEmitter(llvm::Module& module, const CheckedMaterial& material, const std::string& prefix)
        : module_(module), ctx_(module.getContext()), b_(ctx_), material_(material), prefix_(prefix),
          ptr_(b_.getPtrTy()), i64_(b_.getInt64Ty()), f32_(b_.getFloatTy()) {
        // The kernels load only the slots a model argument depends on
        // (LoweringPlan::reads); the entry points pass on only those, so a
        // material with thousands of unused inputs costs nothing per lane.
        slotRead_ = material.readByModels().slots;
    }

    // void PREFIX_eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]):
    // as facet_eval, a NULL direction gives rgb = 0 (if rgb is not NULL).
    void evalScalar(const KernelFamily& eval) {
        llvm::Function* fn = declare("_eval", b_.getVoidTy(), {ptr_, ptr_, ptr_, ptr_});
        llvm::Value *wi = fn->getArg(0), *wo = fn->getArg(1), *inputs = fn->getArg(2), *rgb = fn->getArg(3);
        auto* reject = llvm::BasicBlock::Create(ctx_, "reject", fn);
        auto* zero = llvm::BasicBlock::Create(ctx_, "zero", fn);
        auto* run = llvm::BasicBlock::Create(ctx_, "run", fn);
        auto* done = llvm::BasicBlock::Create(ctx_, "done", fn);
        b_.CreateCondBr(anyNull({wi, wo, rgb}), reject, run);
        b_.SetInsertPoint(reject);
        b_.CreateCondBr(b_.CreateIsNull(rgb), done, zero);
        b_.SetInsertPoint(zero);
        storeZeros(rgb, 3);
        b_.CreateBr(done);
        b_.SetInsertPoint(run);
        oneLane(eval, wi, wo, inputs, {rgb});
        b_.CreateBr(done);
        b_.SetInsertPoint(done);
        b_.CreateRetVoid();
    }

    // int32 PREFIX_sample(const float wo[3], const float u[3], const float* inputs,
    //                     float wi[3], float* pdf, float weight[3]):
    // as facet_sample, 1 for an invalid lane (a NULL wo or u is one: its
    // outputs are 0), else 0; a NULL output is not written.
    void sampleScalar(const KernelFamily& sample) {
        llvm::Function* fn = declare("_sample", b_.getInt32Ty(), {ptr_, ptr_, ptr_, ptr_, ptr_, ptr_});
        llvm::Value *wo = fn->getArg(0), *u = fn->getArg(1), *inputs = fn->getArg(2);
        // A NULL output writes to a scratch array instead.
        std::vector<llvm::Value*> out;
        for (unsigned g = 0; g < 3; ++g) {
            int count = sample.outputs[g];
            llvm::Value* scratch = b_.CreateAlloca(f32_, b_.getInt32(unsigned(count)), "scratch");
            llvm::Value* dst = fn->getArg(3 + g);
            out.push_back(b_.CreateSelect(b_.CreateIsNull(dst), scratch, dst));
        }
        auto* reject = llvm::BasicBlock::Create(ctx_, "reject", fn);
        auto* run = llvm::BasicBlock::Create(ctx_, "run", fn);
        b_.CreateCondBr(anyNull({wo, u}), reject, run);
        b_.SetInsertPoint(reject);
        for (unsigned g = 0; g < 3; ++g) storeZeros(out[g], sample.outputs[g]);
        b_.CreateRet(b_.getInt32(1));
        b_.SetInsertPoint(run);
        b_.CreateRet(b_.CreateZExt(oneLane(sample, wo, u, inputs, out), b_.getInt32Ty()));
    }

    // float PREFIX_pdf(const float wi[3], const float wo[3], const float* inputs):
    // as facet_pdf, 0 for an invalid lane or a NULL direction.
    void pdfScalar(const KernelFamily& pdf) {
        llvm::Function* fn = declare("_pdf", f32_, {ptr_, ptr_, ptr_});
        llvm::Value *wi = fn->getArg(0), *wo = fn->getArg(1), *inputs = fn->getArg(2);
        llvm::Value* value = b_.CreateAlloca(f32_, nullptr, "pdf");
        auto* reject = llvm::BasicBlock::Create(ctx_, "reject", fn);
        auto* run = llvm::BasicBlock::Create(ctx_, "run", fn);
        b_.CreateCondBr(anyNull({wi, wo}), reject, run);
        b_.SetInsertPoint(reject);
        b_.CreateRet(llvm::ConstantFP::get(f32_, 0.0));
        b_.SetInsertPoint(run);
        oneLane(pdf, wi, wo, inputs, {value});
        b_.CreateRet(b_.CreateLoad(f32_, value));
    }

    // int64_t PREFIX_<suffix>(int64_t n, const float* const in0[3], const float* const in1[3],
    //                         const float* const* inputs, outputs...):
    // an output group of three floats per lane is an array of three
    // streams (float* const out[3]), one of one float a stream (float* out).
    // -1 for n < 0, 0 for n = 0 whatever the pointers (as the C API: SPEC
    // section 4), -1 for a NULL array or array entry, else the number of
    // invalid lanes.
    void batch(const char* suffix, const KernelFamily& family) {
        const unsigned outGroups = unsigned(family.outputs.size());
        std::vector<llvm::Type*> args(4 + outGroups, ptr_);
        args[0] = i64_;
        llvm::Function* fn = declare(suffix, i64_, args);
        llvm::Value* n = fn->getArg(0);
        llvm::Value* inputs = fn->getArg(3);
        std::vector<llvm::Value*> in = {fn->getArg(1), fn->getArg(2)}, out, arrays = in, required = in;
        for (unsigned g = 0; g < outGroups; ++g) {
            out.push_back(fn->getArg(4 + g));
            required.push_back(out.back());
            if (family.outputs[g] == 3) arrays.push_back(out.back());
        }
        auto* reject = llvm::BasicBlock::Create(ctx_, "reject", fn);
        auto* checkEmpty = llvm::BasicBlock::Create(ctx_, "check.empty", fn);
        auto* empty = llvm::BasicBlock::Create(ctx_, "empty", fn);
        auto* arraysGiven = llvm::BasicBlock::Create(ctx_, "check.arrays", fn);
        auto* entries = llvm::BasicBlock::Create(ctx_, "check.entries", fn);
        auto* run = llvm::BasicBlock::Create(ctx_, "run", fn);
        b_.CreateCondBr(b_.CreateICmpSLT(n, llvm::ConstantInt::get(i64_, 0)), reject, checkEmpty);
        b_.SetInsertPoint(reject);
        b_.CreateRet(llvm::ConstantInt::get(i64_, -1));
        b_.SetInsertPoint(checkEmpty);
        b_.CreateCondBr(b_.CreateICmpEQ(n, llvm::ConstantInt::get(i64_, 0)), empty, arraysGiven);
        b_.SetInsertPoint(empty);
        b_.CreateRet(llvm::ConstantInt::get(i64_, 0));
        b_.SetInsertPoint(arraysGiven);
        b_.CreateCondBr(anyNull(required), reject, entries);
        b_.SetInsertPoint(entries);
        std::vector<llvm::Value*> streams;
        for (llvm::Value* array : arrays)
            for (unsigned c = 0; c < 3; ++c) streams.push_back(b_.CreateLoad(ptr_, b_.CreateConstGEP1_32(ptr_, array, c)));
        b_.CreateCondBr(anyNull(streams), reject, run);
        b_.SetInsertPoint(run);
        if (family.batch) {
            std::vector<llvm::Value*> callArgs = {n, in[0], in[1], inputs};
            callArgs.insert(callArgs.end(), out.begin(), out.end());
            if (family.batchStatus) callArgs.push_back(nullPtr());
            b_.CreateRet(b_.CreateCall(family.batch, callArgs));
        } else {
            b_.CreateRet(laneLoop(fn, family, n, in, inputs, out));
        }
    }

private:
    llvm::Function* declare(const char* suffix, llvm::Type* ret, const std::vector<llvm::Type*>& args) {
        auto* fn = llvm::Function::Create(llvm::FunctionType::get(ret, args, false), llvm::Function::ExternalLinkage,
                                          prefix_ + suffix, module_);
        fn->addFnAttr(llvm::Attribute::NoUnwind);
        b_.SetInsertPoint(llvm::BasicBlock::Create(ctx_, "entry", fn));
        return fn;
    }
    llvm::Value* nullPtr() { return llvm::ConstantPointerNull::get(llvm::PointerType::get(ctx_, 0)); }
    llvm::Value* anyNull(const std::vector<llvm::Value*>& ptrs) {
        llvm::Value* any = b_.getFalse();
        for (llvm::Value* p : ptrs) any = b_.CreateOr(any, b_.CreateIsNull(p));
        return any;
    }
    void storeZeros(llvm::Value* dst, int count) {
        for (int c = 0; c < count; ++c)
            b_.CreateStore(llvm::ConstantFP::get(f32_, 0.0), b_.CreateConstGEP1_32(f32_, dst, unsigned(c)));
    }
    // An array of `count` pointers on the stack, element k = base + k floats;
    // with `only`, the elements it marks (the others are never read).
    llvm::Value* pointerArray(llvm::Value* base, int count, const char* name, const std::vector<bool>* only = nullptr) {
        llvm::Value* array = b_.CreateAlloca(ptr_, b_.getInt32(unsigned(count)), name);
        for (int k = 0; k < count; ++k)
            if (!only || (*only)[size_t(k)])
                b_.CreateStore(b_.CreateConstGEP1_32(f32_, base, unsigned(k)), b_.CreateConstGEP1_32(ptr_, array, unsigned(k)));
        return array;
    }

    // One lane: in0 and in1 point to three floats each, inputs to one
    // value per slot (or is NULL: the defaults), out[g] to the group's
    // floats. Returns whether the lane was invalid. A SIMD kernel runs a
    // one-lane batch, as Kernel::eval, Kernel::sample and Kernel::pdf do.
    llvm::Value* oneLane(const KernelFamily& family, llvm::Value* in0, llvm::Value* in1, llvm::Value* inputs,
                         const std::vector<llvm::Value*>& out) {
        if (family.scalar) {
            std::vector<llvm::Value*> args = {in0, in1, inputs};
            args.insert(args.end(), out.begin(), out.end());
            return b_.CreateICmpNE(b_.CreateCall(family.scalar, args), b_.getInt32(0));
        }
        llvm::Value* slotsArg = nullPtr();
        if (material_.slotCount > 0)
            slotsArg = b_.CreateSelect(b_.CreateIsNull(inputs), slotsArg,
                                       pointerArray(inputs, material_.slotCount, "input.lanes", &slotRead_));
        std::vector<llvm::Value*> args = {llvm::ConstantInt::get(i64_, 1), pointerArray(in0, 3, "in0.lanes"),
                                          pointerArray(in1, 3, "in1.lanes"), slotsArg};
        for (size_t g = 0; g < out.size(); ++g)
            args.push_back(family.outputs[g] == 3 ? pointerArray(out[g], 3, "out.lanes") : out[g]);
        if (family.batchStatus) args.push_back(nullPtr());  // no per-lane status
        return b_.CreateICmpNE(b_.CreateCall(family.batch, args), llvm::ConstantInt::get(i64_, 0));
    }

    // The scalar kernel over n >= 1 lanes, one at a time, with the
    // conventions of Kernel::evalBatch / sampleBatch / pdfBatch for scalar
    // kernels: a NULL inputs or inputs[s] reads the slot's default. Returns
    // the number of invalid lanes.
    llvm::Value* laneLoop(llvm::Function* fn, const KernelFamily& family, llvm::Value* n,
                          const std::vector<llvm::Value*>& in, llvm::Value* inputs, const std::vector<llvm::Value*>& out) {
        llvm::BasicBlock* start = b_.GetInsertBlock();
        std::vector<llvm::Value*> inStreams, outStreams;  // three per input group; per output group, its count
        for (llvm::Value* array : in)
            for (unsigned c = 0; c < 3; ++c) inStreams.push_back(b_.CreateLoad(ptr_, b_.CreateConstGEP1_32(ptr_, array, c)));
        for (size_t g = 0; g < out.size(); ++g) {
            if (family.outputs[g] == 1) outStreams.push_back(out[g]);
            else
                for (unsigned c = 0; c < 3; ++c)
                    outStreams.push_back(b_.CreateLoad(ptr_, b_.CreateConstGEP1_32(ptr_, out[g], c)));
        }
        const int slots = material_.slotCount;
        llvm::Value* nullSlot = b_.CreateAlloca(ptr_, nullptr, "null.slot");
        b_.CreateStore(nullPtr(), nullSlot);
        std::vector<double> defaults = material_.defaultSlots();
        std::vector<llvm::Value*> slotBase, slotDefault;
        slotBase.resize(size_t(slots));
        slotDefault.resize(size_t(slots));
        for (int s = 0; s < slots; ++s) {
            if (!slotRead_[size_t(s)]) continue;
            llvm::Value* addr = b_.CreateSelect(b_.CreateIsNull(inputs), nullSlot,
                                                b_.CreateConstGEP1_32(ptr_, inputs, unsigned(s)));
            slotBase[size_t(s)] = b_.CreateLoad(ptr_, addr);
            std::string name = prefix_ + ".aot.default" + std::to_string(s);
            llvm::GlobalVariable* global = module_.getGlobalVariable(name, true);
            if (!global)
                global = new llvm::GlobalVariable(module_, f32_, true, llvm::GlobalValue::PrivateLinkage,
                                                  llvm::ConstantFP::get(f32_, double(float(defaults[s]))), name);
            slotDefault[size_t(s)] = global;
        }
        std::vector<llvm::Value*> inLane, outLane;
        for (size_t g = 0; g < in.size(); ++g) inLane.push_back(b_.CreateAlloca(f32_, b_.getInt32(3), "in.lane"));
        for (int count : family.outputs) outLane.push_back(b_.CreateAlloca(f32_, b_.getInt32(unsigned(count)), "out.lane"));
        llvm::Value* lane = b_.CreateAlloca(f32_, b_.getInt32(unsigned(std::max(1, slots))), "inputs.lane");
        auto* loop = llvm::BasicBlock::Create(ctx_, "lane", fn);
        auto* exit = llvm::BasicBlock::Create(ctx_, "exit", fn);
        b_.CreateBr(loop);
        b_.SetInsertPoint(loop);
        llvm::PHINode* i = b_.CreatePHI(i64_, 2, "i");
        llvm::PHINode* count = b_.CreatePHI(i64_, 2, "invalid");
        i->addIncoming(llvm::ConstantInt::get(i64_, 0), start);
        count->addIncoming(llvm::ConstantInt::get(i64_, 0), start);
        for (size_t g = 0; g < in.size(); ++g)
            for (unsigned c = 0; c < 3; ++c)
                b_.CreateStore(b_.CreateLoad(f32_, b_.CreateGEP(f32_, inStreams[3 * g + c], i)),
                               b_.CreateConstGEP1_32(f32_, inLane[g], c));
        for (int s = 0; s < slots; ++s) {
            if (!slotRead_[size_t(s)]) continue;
            llvm::Value* src = b_.CreateSelect(b_.CreateIsNull(slotBase[s]), slotDefault[s],
                                               b_.CreateGEP(f32_, slotBase[s], i));
            b_.CreateStore(b_.CreateLoad(f32_, src), b_.CreateConstGEP1_32(f32_, lane, unsigned(s)));
        }
        std::vector<llvm::Value*> args = inLane;
        args.push_back(lane);
        args.insert(args.end(), outLane.begin(), outLane.end());
        llvm::Value* invalid = b_.CreateICmpNE(b_.CreateCall(family.scalar, args), b_.getInt32(0));
        llvm::Value* next = b_.CreateAdd(count, b_.CreateZExt(invalid, i64_));
        size_t stream = 0;
        for (size_t g = 0; g < out.size(); ++g)
            for (unsigned c = 0; c < unsigned(family.outputs[g]); ++c)
                b_.CreateStore(b_.CreateLoad(f32_, b_.CreateConstGEP1_32(f32_, outLane[g], c)),
                               b_.CreateGEP(f32_, outStreams[stream++], i));
        llvm::Value* iNext = b_.CreateAdd(i, llvm::ConstantInt::get(i64_, 1));
        i->addIncoming(iNext, loop);
        count->addIncoming(next, loop);
        b_.CreateCondBr(b_.CreateICmpSLT(iNext, n), loop, exit);
        b_.SetInsertPoint(exit);
        return next;
    }

    llvm::Module& module_;
    llvm::LLVMContext& ctx_;
    llvm::IRBuilder<> b_;
    const CheckedMaterial& material_;
    std::string prefix_;
    llvm::Type *ptr_, *i64_, *f32_;
    std::vector<bool> slotRead_;  // per slot: does a kernel load it?
};

}  // namespace

void addAotEntryPoints(LoweredModule& lowered, const CheckedMaterial& material, const std::string& prefix) {
    llvm::Module& module = *lowered.module;
    for (llvm::Function& fn : module)
        if (!fn.isDeclaration()) fn.setLinkage(llvm::GlobalValue::InternalLinkage);
    auto find = [&](const std::string& symbol) { return symbol.empty() ? nullptr : module.getFunction(symbol); };
    KernelFamily eval{find(lowered.scalarSymbol),
                      find(lowered.batchSymbol), true, {3}};
    KernelFamily sample{find(lowered.sampleScalarSymbol), find(lowered.sampleBatchSymbol), false, {3, 1, 3}};
    KernelFamily pdf{find(lowered.pdfScalarSymbol), find(lowered.pdfBatchSymbol), false, {1}};
    internal_assert(eval.batch || eval.scalar) << "AOT module without eval entry points";
    // The lowered sampler's names are the C entry points' (PREFIX_sample_batch, ...): free them.
    for (llvm::Function* fn : {sample.scalar, sample.batch, pdf.scalar, pdf.batch})
        if (fn) fn->setName(fn->getName() + ".kernel");
    EntryEmitter entries(module, material, prefix);
    entries.evalScalar(eval);
    entries.batch("_eval_batch", eval);
    // Where the plan has no compiled sampler, the object has no sampler
    // symbols (the header says so: PREFIX_HAS_SAMPLER 0).
    if (sample.scalar || sample.batch) {
        entries.sampleScalar(sample);
        entries.batch("_sample_batch", sample);
        entries.pdfScalar(pdf);
        entries.batch("_pdf_batch", pdf);
    }
    std::string errors;
    llvm::raw_string_ostream os(errors);
    if (llvm::verifyModule(module, &os)) internal_error << "invalid AOT entry points: " << os.str();
}

std::string writeAotOutput(llvm::Module& module, llvm::TargetMachine& machine, AotOutput output) {
    llvm::SmallVector<char, 0> buffer;
    llvm::raw_svector_ostream os(buffer);
    switch (output) {
        case AotOutput::LlvmIr: module.print(os, nullptr); break;
        case AotOutput::Bitcode: llvm::WriteBitcodeToFile(module, os); break;
        case AotOutput::Object:
        case AotOutput::Assembly: {
            llvm::legacy::PassManager passes;
            auto kind = output == AotOutput::Object ? llvm::CodeGenFileType::ObjectFile
                                                    : llvm::CodeGenFileType::AssemblyFile;
            if (machine.addPassesToEmitFile(passes, os, nullptr, kind))
                internal_error << "target " << machine.getTargetTriple().str() << " cannot emit this file type";
            runKernelCodegen(passes, module);
            break;
        }
    }
    return std::string(buffer.data(), buffer.size());
}

}  // namespace facet
