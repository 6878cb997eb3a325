// Aot: target machines from LLVM's registry, the C entry points of an
// ahead-of-time object, and writing it out (see Aot.h).
#include "Aot.h"

#include "Diagnostics.h"
#include "Jit.h"

#include <llvm/Bitcode/BitcodeWriter.h>
#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LegacyPassManager.h>
#include <llvm/IR/Verifier.h>
#include <llvm/MC/MCSubtargetInfo.h>
#include <llvm/MC/TargetRegistry.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Support/raw_ostream.h>
#include <llvm/TargetParser/Triple.h>

#include <algorithm>
#include <array>
#include <fmt/format.h>
#include <mutex>
#include <vector>

namespace facet {

namespace {

std::string joined(std::vector<std::string> names) {
    std::sort(names.begin(), names.end());
    names.erase(std::unique(names.begin(), names.end()), names.end());
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

// Every feature of `request` ("+name" or "-name", comma-separated) must be
// one the target knows.
std::string checkFeatures(const llvm::MCSubtargetInfo& info, const std::string& features) {
    std::vector<std::string> known;
    for (const llvm::SubtargetFeatureKV& f : info.getAllProcessorFeatures()) known.push_back(f.Key);
    size_t start = 0;
    while (start <= features.size()) {
        size_t comma = features.find(',', start);
        std::string item = features.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        start = comma == std::string::npos ? features.size() + 1 : comma + 1;
        if (item.empty()) continue;
        std::string name = item.substr(1);
        if ((item[0] != '+' && item[0] != '-') || std::find(known.begin(), known.end(), name) == known.end())
            return fmt::format("unknown feature '{}' for {} (write +NAME or -NAME; features: {})", item,
                               info.getTargetTriple().getArchName().str(), joined(known));
    }
    return "";
}

}  // namespace

AotTarget createAotTarget(const AotTargetRequest& request, std::string& error) {
    static std::once_flag initOnce;  // LLVM's target registry is process-wide by design
    std::call_once(initOnce, [] {
        llvm::InitializeAllTargetInfos();
        llvm::InitializeAllTargets();
        llvm::InitializeAllTargetMCs();
        llvm::InitializeAllAsmPrinters();
    });
    AotTarget target;
    error.clear();
    if (request.triple.empty()) {
        // The host as the JIT sees it, so that the object runs the JIT's code.
        auto host = llvm::orc::JITTargetMachineBuilder::detectHost();
        if (!host) {
            error = "cannot detect the host: " + llvm::toString(host.takeError());
            return target;
        }
        target.triple = host->getTargetTriple().str();
        target.cpu = request.cpu.empty() ? host->getCPU() : request.cpu;
        target.features = request.cpu.empty() ? host->getFeatures().getString() : "";
    } else {
        target.triple = llvm::Triple::normalize(request.triple);
        target.cpu = request.cpu.empty() ? "generic" : request.cpu;
    }
    if (!request.features.empty()) target.features += (target.features.empty() ? "" : ",") + request.features;

    std::string lookupError;
    const llvm::Target* backend = llvm::TargetRegistry::lookupTarget(target.triple, lookupError);
    llvm::Triple triple(target.triple);
    if (!backend || triple.getArch() == llvm::Triple::UnknownArch) {
        std::vector<std::string> names;
        for (const llvm::Target& t : llvm::TargetRegistry::targets()) names.push_back(t.getName());
        error = fmt::format("unknown target '{}' (this LLVM has: {}; e.g. aarch64-linux-gnu, x86_64-linux-gnu)",
                            request.triple, joined(names));
        return target;
    }
    std::unique_ptr<llvm::MCSubtargetInfo> info(backend->createMCSubtargetInfo(target.triple, "", ""));
    if (!info) {
        error = fmt::format("target '{}' has no subtarget information", target.triple);
        return target;
    }
    if (!info->isCPUStringValid(target.cpu)) {
        std::vector<std::string> cpus;
        for (const llvm::SubtargetSubTypeKV& c : info->getAllProcessorDescriptions()) cpus.push_back(c.Key);
        error = fmt::format("unknown CPU '{}' for {} (CPUs: {})", target.cpu, triple.getArchName().str(), joined(cpus));
        return target;
    }
    if (std::string problem = checkFeatures(*info, request.features); !problem.empty()) {
        error = problem;
        return target;
    }
    // Position-independent (links into PIE executables and shared
    // libraries) with the default code model; the JIT's in-process code
    // differs only in how it addresses its constants.
    target.machine.reset(backend->createTargetMachine(target.triple, target.cpu, target.features, llvm::TargetOptions(),
                                                      llvm::Reloc::PIC_, std::nullopt,
                                                      llvm::CodeGenOptLevel::Aggressive));
    if (!target.machine) {
        error = fmt::format("LLVM cannot create a target machine for {} ({})", target.triple, target.cpu);
        return target;
    }
    // The width the JIT picks for the same features (FacetJit::hostVectorWidth).
    const llvm::MCSubtargetInfo* sti = target.machine->getMCSubtargetInfo();
    target.width = !triple.isX86()                  ? 4
                   : sti->checkFeatures("+avx512f") ? 16
                   : sti->checkFeatures("+avx2")    ? 8
                                                    : 4;
    return target;
}

void addAotEntryPoints(LoweredModule& lowered, const CheckedMaterial& material, const std::string& prefix) {
    llvm::Module& module = *lowered.module;
    for (llvm::Function& fn : module)
        if (!fn.isDeclaration()) fn.setLinkage(llvm::GlobalValue::InternalLinkage);
    llvm::LLVMContext& ctx = module.getContext();
    llvm::IRBuilder<> b(ctx);
    llvm::Type* ptr = b.getPtrTy();
    llvm::Type* i64 = b.getInt64Ty();
    llvm::Type* f32 = b.getFloatTy();
    llvm::Function* batch = lowered.batchSymbol.empty() ? nullptr : module.getFunction(lowered.batchSymbol);
    llvm::Function* scalar = lowered.scalarSymbol.empty() ? nullptr : module.getFunction(lowered.scalarSymbol);
    llvm::Function* status = scalar ? module.getFunction(lowered.scalarSymbol + "_status") : nullptr;
    internal_assert(batch || (scalar && status)) << "AOT module without entry points";
    auto nullAny = [&](std::initializer_list<llvm::Value*> ptrs) {
        llvm::Value* any = b.getFalse();
        for (llvm::Value* p : ptrs) any = b.CreateOr(any, b.CreateIsNull(p));
        return any;
    };
    // An array of `count` pointers on the stack, element k = base + k floats.
    auto pointerArray = [&](llvm::Value* base, int count, const char* name) {
        llvm::Value* array = b.CreateAlloca(ptr, b.getInt32(unsigned(count)), name);
        for (int k = 0; k < count; ++k)
            b.CreateStore(b.CreateConstGEP1_32(f32, base, unsigned(k)), b.CreateConstGEP1_32(ptr, array, unsigned(k)));
        return array;
    };

    // void PREFIX_eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]):
    // as facet_eval, a NULL direction gives rgb = 0 (if rgb is not NULL).
    {
        auto* fn = llvm::Function::Create(llvm::FunctionType::get(b.getVoidTy(), {ptr, ptr, ptr, ptr}, false),
                                          llvm::Function::ExternalLinkage, prefix + "_eval", module);
        fn->addFnAttr(llvm::Attribute::NoUnwind);
        llvm::Value *wi = fn->getArg(0), *wo = fn->getArg(1), *inputs = fn->getArg(2), *rgb = fn->getArg(3);
        auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
        auto* reject = llvm::BasicBlock::Create(ctx, "reject", fn);
        auto* zero = llvm::BasicBlock::Create(ctx, "zero", fn);
        auto* run = llvm::BasicBlock::Create(ctx, "run", fn);
        auto* done = llvm::BasicBlock::Create(ctx, "done", fn);
        b.SetInsertPoint(entry);
        b.CreateCondBr(nullAny({wi, wo, rgb}), reject, run);
        b.SetInsertPoint(reject);
        b.CreateCondBr(b.CreateIsNull(rgb), done, zero);
        b.SetInsertPoint(zero);
        for (unsigned c = 0; c < 3; ++c) b.CreateStore(llvm::ConstantFP::get(f32, 0.0), b.CreateConstGEP1_32(f32, rgb, c));
        b.CreateBr(done);
        b.SetInsertPoint(run);
        if (scalar) {
            b.CreateCall(scalar, {wi, wo, inputs, rgb});
        } else {
            // A SIMD kernel evaluates one lane through its batch entry, as Kernel::eval does.
            llvm::Value* wiP = pointerArray(wi, 3, "wi.lanes");
            llvm::Value* woP = pointerArray(wo, 3, "wo.lanes");
            llvm::Value* outP = pointerArray(rgb, 3, "rgb.lanes");
            llvm::Value* slotsArg = llvm::ConstantPointerNull::get(llvm::PointerType::get(ctx, 0));
            if (material.slotCount > 0)
                slotsArg = b.CreateSelect(b.CreateIsNull(inputs), slotsArg,
                                          pointerArray(inputs, material.slotCount, "input.lanes"));
            // (no per-lane status: the batch entry's sixth argument is null)
            b.CreateCall(batch, {llvm::ConstantInt::get(i64, 1), wiP, woP, slotsArg, outP,
                                 llvm::ConstantPointerNull::get(llvm::PointerType::get(ctx, 0))});
        }
        b.CreateBr(done);
        b.SetInsertPoint(done);
        b.CreateRetVoid();
    }

    // int64_t PREFIX_eval_batch(int64_t n, const float* const wi[3], const float* const wo[3],
    //                           const float* const* inputs, float* const rgb[3]):
    // -1 for n < 0 or a NULL direction or output array (SPEC section 4), 0 for n = 0.
    {
        auto* fn = llvm::Function::Create(llvm::FunctionType::get(i64, {i64, ptr, ptr, ptr, ptr}, false),
                                          llvm::Function::ExternalLinkage, prefix + "_eval_batch", module);
        fn->addFnAttr(llvm::Attribute::NoUnwind);
        llvm::Value *n = fn->getArg(0), *wi = fn->getArg(1), *wo = fn->getArg(2), *inputs = fn->getArg(3),
                    *rgb = fn->getArg(4);
        auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
        auto* reject = llvm::BasicBlock::Create(ctx, "reject", fn);
        auto* checkEmpty = llvm::BasicBlock::Create(ctx, "check.empty", fn);
        auto* empty = llvm::BasicBlock::Create(ctx, "empty", fn);
        auto* run = llvm::BasicBlock::Create(ctx, "run", fn);
        b.SetInsertPoint(entry);
        llvm::Value* bad = b.CreateOr(b.CreateICmpSLT(n, llvm::ConstantInt::get(i64, 0)), nullAny({wi, wo, rgb}));
        b.CreateCondBr(bad, reject, checkEmpty);
        b.SetInsertPoint(reject);
        b.CreateRet(llvm::ConstantInt::get(i64, -1));
        b.SetInsertPoint(checkEmpty);
        b.CreateCondBr(b.CreateICmpEQ(n, llvm::ConstantInt::get(i64, 0)), empty, run);
        b.SetInsertPoint(empty);
        b.CreateRet(llvm::ConstantInt::get(i64, 0));
        b.SetInsertPoint(run);
        if (batch) {
            b.CreateRet(b.CreateCall(batch, {n, wi, wo, inputs, rgb,
                                              llvm::ConstantPointerNull::get(llvm::PointerType::get(ctx, 0))}));
        } else {
            // The scalar kernel one lane at a time through its status twin,
            // with the conventions of Kernel::evalBatch for scalar kernels:
            // a NULL inputs or inputs[s] reads the slot's default.
            std::array<llvm::Value*, 3> wiC, woC, outC;
            for (unsigned c = 0; c < 3; ++c) {
                wiC[c] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, wi, c));
                woC[c] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, wo, c));
                outC[c] = b.CreateLoad(ptr, b.CreateConstGEP1_32(ptr, rgb, c));
            }
            const int slots = material.slotCount;
            llvm::Value* nullSlot = b.CreateAlloca(ptr, nullptr, "null.slot");
            b.CreateStore(llvm::ConstantPointerNull::get(llvm::PointerType::get(ctx, 0)), nullSlot);
            std::vector<double> defaults = material.defaultSlots();
            std::vector<llvm::Value*> slotBase, slotDefault;
            for (int s = 0; s < slots; ++s) {
                llvm::Value* addr = b.CreateSelect(b.CreateIsNull(inputs), nullSlot,
                                                   b.CreateConstGEP1_32(ptr, inputs, unsigned(s)));
                slotBase.push_back(b.CreateLoad(ptr, addr));
                auto* value = llvm::ConstantFP::get(f32, double(float(defaults[s])));
                slotDefault.push_back(new llvm::GlobalVariable(module, f32, true, llvm::GlobalValue::PrivateLinkage,
                                                               value, prefix + ".aot.default" + std::to_string(s)));
            }
            llvm::Value* a = b.CreateAlloca(f32, b.getInt32(3), "wi.lane");
            llvm::Value* o = b.CreateAlloca(f32, b.getInt32(3), "wo.lane");
            llvm::Value* lane = b.CreateAlloca(f32, b.getInt32(unsigned(std::max(1, slots))), "inputs.lane");
            llvm::Value* out = b.CreateAlloca(f32, b.getInt32(3), "rgb.lane");
            auto* loop = llvm::BasicBlock::Create(ctx, "lane", fn);
            auto* exit = llvm::BasicBlock::Create(ctx, "exit", fn);
            b.CreateBr(loop);
            b.SetInsertPoint(loop);
            llvm::PHINode* i = b.CreatePHI(i64, 2, "i");
            llvm::PHINode* count = b.CreatePHI(i64, 2, "invalid");
            i->addIncoming(llvm::ConstantInt::get(i64, 0), run);
            count->addIncoming(llvm::ConstantInt::get(i64, 0), run);
            for (unsigned c = 0; c < 3; ++c) {
                b.CreateStore(b.CreateLoad(f32, b.CreateGEP(f32, wiC[c], i)), b.CreateConstGEP1_32(f32, a, c));
                b.CreateStore(b.CreateLoad(f32, b.CreateGEP(f32, woC[c], i)), b.CreateConstGEP1_32(f32, o, c));
            }
            for (int s = 0; s < slots; ++s) {
                llvm::Value* src = b.CreateSelect(b.CreateIsNull(slotBase[s]), slotDefault[s],
                                                  b.CreateGEP(f32, slotBase[s], i));
                b.CreateStore(b.CreateLoad(f32, src), b.CreateConstGEP1_32(f32, lane, unsigned(s)));
            }
            llvm::Value* invalid = b.CreateCall(status, {a, o, lane, out});
            llvm::Value* next = b.CreateAdd(count, b.CreateZExt(invalid, i64));
            for (unsigned c = 0; c < 3; ++c)
                b.CreateStore(b.CreateLoad(f32, b.CreateConstGEP1_32(f32, out, c)), b.CreateGEP(f32, outC[c], i));
            llvm::Value* iNext = b.CreateAdd(i, llvm::ConstantInt::get(i64, 1));
            i->addIncoming(iNext, loop);
            count->addIncoming(next, loop);
            b.CreateCondBr(b.CreateICmpSLT(iNext, n), loop, exit);
            b.SetInsertPoint(exit);
            b.CreateRet(next);
        }
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
