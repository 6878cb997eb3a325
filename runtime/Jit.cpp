// Jit: the LLJIT instance, the middle-end pass list and object emission at
// two codegen levels (quick and optimized). Measurements behind the choices
// below, and the options tried and rejected, are in docs/perf-log.md.
//
// Middle end. The lowering emits straight-line, explicitly vectorized IR:
// one function per entry point, <W x float> / <W x double> operations,
// masked loads, stores and gathers, one loop over lanes plus a masked tail,
// and no calls but intrinsics. O3 spends most of its time on what such IR
// does not need (inlining, loop transforms, vectorizers, IPO) and its
// InstCombine/GVN runs repeat each other. optimize() runs three function
// passes instead, once each:
//
//   early-cse    the lowering emits the same subexpression more than once
//                (finiteness tests, clamps, fpext of one input per use).
//   reassociate  ranks and regroups integer and i1 chains: the lane-invalid
//                masks, or-ed together one by one as the lowering finds
//                them, become one chain at the end of the loop body, which
//                codegen schedules and allocates better. It rewrites a
//                floating-point operation only if it carries `reassoc` and
//                `nsz`, which the lowering never sets.
//   instcombine  folds fpext/fptrunc pairs, mask algebra and the constants
//                specialization leaves, cleans up after the two above and
//                deletes dead code; one iteration, as O3 runs it.
//
// The kernels' outputs are bit-identical to O3's. Not run, on purpose:
// SROA/mem2reg (the lowering allocates nothing), GVN (EarlyCSE finds the
// same redundancies in straight-line code), SimplifyCFG, LICM and the loop
// passes (the CFG is already entry/loop/tail/exit and codegen hoists the
// invariants), the vectorizers and the inliner.
//
// Object emission, 80-90% of a compile, costs time about linear in the IR's
// size. emitObject() saves what it can without changing the objects:
//
//   - the codegen pipeline (a legacy PassManager with the AsmPrinter and its
//     object streamer) is built once per level and run on every module.
//     AsmPrinter and MachineModuleInfo reset the MC streamer and context at
//     the end of each module, so the objects are byte-identical to a fresh
//     pipeline's.
//   - SkipPasses, an OptPassGate set on the module's own LLVMContext while it
//     is emitted (so no process-global cl::opt, nothing seen by other LLVM
//     users in the process), skips passes that have nothing to do in a
//     kernel: TLS, memcmp, libcall, GC, call-frame and Atom passes, the CFG
//     passes (the CFG is always entry/loop/stage/compute/unstage/latch) and a
//     few x86 peepholes that never fire here. The objects stay byte-identical;
//     a pass LLVM renames merely runs again.
//
// Two levels. Level::Optimized emits at CodeGenOptLevel::Aggressive (Default
// costs the same and differs only in late block placement). Level::Quick
// emits at CodeGenOptLevel::None (fast register allocation, no machine
// scheduler or peepholes) after EarlyCSE alone: 2.2-2.8x less emission
// time, for kernels that run 6-26% slower on the bench models. Kernel.h's
// tiered compile returns quick code first and swaps in optimized code from
// a background thread. The levels compute the same bits: codegen level
// does not change floating-point results, and without fast-math flags
// neither do Reassociate and InstCombine. With flags (fast kernels with
// estimates) both levels run the full middle end (see carriesFastMathFlags).
#include "Jit.h"

#include "Diagnostics.h"

#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Transforms/InstCombine/InstCombine.h>
#include <llvm/Transforms/Scalar/EarlyCSE.h>
#include <llvm/Transforms/Scalar/Reassociate.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/Target/TargetMachine.h>
#include <llvm/TargetParser/Host.h>

#include <algorithm>
#include <iterator>
#include <stdexcept>

namespace facet {

namespace {
template <typename T>
T unwrap(llvm::Expected<T> value, const char* what) {
    if (!value) throw std::runtime_error(std::string(what) + ": " + llvm::toString(value.takeError()));
    return std::move(*value);
}
template <typename T>
T& unwrap(llvm::Expected<T&> value, const char* what) {
    if (!value) throw std::runtime_error(std::string(what) + ": " + llvm::toString(value.takeError()));
    return *value;
}
}  // namespace

std::unique_ptr<FacetJit> FacetJit::Create() {
    static std::once_flag initOnce;  // LLVM's target registry is process-wide by design
    std::call_once(initOnce, [] {
        llvm::InitializeNativeTarget();
        llvm::InitializeNativeTargetAsmPrinter();
        llvm::InitializeNativeTargetAsmParser();
    });
    std::unique_ptr<FacetJit> jit(new FacetJit());
    auto jtmb = unwrap(llvm::orc::JITTargetMachineBuilder::detectHost(), "detecting the host CPU");
    jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::Aggressive);  // see the top of this file
    jit->cpu_ = jtmb.getCPU();
    jit->features_ = jtmb.getFeatures().getString();
    jit->optimized_.tm = unwrap(jtmb.createTargetMachine(), "creating the target machine");
    jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::None);
    jit->quick_.tm = unwrap(jtmb.createTargetMachine(), "creating the target machine");
    jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::Aggressive);
    jit->jit_ = unwrap(llvm::orc::LLJITBuilder().setJITTargetMachineBuilder(jtmb).create(), "creating the JIT");
    jit->warmUp();
    return jit;
}

void FacetJit::warmUp() {
    // A kernel-like loop body: a masked vector load, float and double
    // arithmetic, FMA, square root, division, conversions, a select.
    llvm::LLVMContext context;
    llvm::Module module("facet_warm_up", context);
    llvm::IRBuilder<> b(context);
    auto* f32 = llvm::FixedVectorType::get(b.getFloatTy(), 16);
    auto* f64 = llvm::FixedVectorType::get(b.getDoubleTy(), 16);
    auto* fn = llvm::Function::Create(llvm::FunctionType::get(b.getVoidTy(), {b.getPtrTy(), b.getPtrTy()}, false),
                                      llvm::Function::ExternalLinkage, "facet_warm_up", module);
    b.SetInsertPoint(llvm::BasicBlock::Create(context, "entry", fn));
    llvm::Value* mask = llvm::ConstantInt::getTrue(llvm::FixedVectorType::get(b.getInt1Ty(), 16));
    llvm::Value* x = b.CreateMaskedLoad(f32, fn->getArg(0), llvm::Align(4), mask);
    llvm::Value* d = b.CreateFPExt(x, f64);
    d = b.CreateIntrinsic(llvm::Intrinsic::fmuladd, {f64}, {d, d, d});
    llvm::Value* y = b.CreateFPTrunc(b.CreateFDiv(llvm::ConstantFP::get(f64, 1.0), d), f32);
    y = b.CreateIntrinsic(llvm::Intrinsic::sqrt, {f32}, {y});
    y = b.CreateSelect(b.CreateFCmpOLT(x, y), x, y);
    b.CreateStore(y, fn->getArg(1));
    b.CreateRetVoid();
    for (Level level : {Level::Quick, Level::Optimized}) {
        optimize(module, level);
        emitObject(module, level);
    }
}

FacetJit::~FacetJit() = default;

int FacetJit::hostVectorWidth() const {
    if (features_.find("+avx512f") != std::string::npos) return 16;
    if (features_.find("+avx2") != std::string::npos) return 8;
    return 4;
}

namespace {
// Whether any floating-point operation in `module` carries fast-math flags
// (the lowering sets arcp, afn and contract in fast variants that use
// estimates). Without them no pass and no codegen level changes a
// floating-point result. With them the IR codegen sees decides results:
// InstCombine may rewrite a division, and an fmul is contracted into an FMA
// only if it has one use, which dead code left by skipping Reassociate and
// InstCombine can spoil (plastic's fast kernel then differs in the last bit
// in 64% of its lanes).
bool carriesFastMathFlags(const llvm::Module& module) {
    for (const llvm::Function& f : module)
        for (const llvm::BasicBlock& block : f)
            for (const llvm::Instruction& inst : block)
                if (llvm::isa<llvm::FPMathOperator>(inst) && inst.getFastMathFlags().any()) return true;
    return false;
}
}  // namespace

void optimizeKernelModule(llvm::Module& module, llvm::TargetMachine& tm, FacetJit::Level level) {
    module.setDataLayout(tm.createDataLayout());
    module.setTargetTriple(tm.getTargetTriple().str());
    llvm::LoopAnalysisManager lam;
    llvm::FunctionAnalysisManager fam;
    llvm::CGSCCAnalysisManager cgam;
    llvm::ModuleAnalysisManager mam;
    llvm::PassBuilder pb(&tm);
    pb.registerModuleAnalyses(mam);
    pb.registerCGSCCAnalyses(cgam);
    pb.registerFunctionAnalyses(fam);
    pb.registerLoopAnalyses(lam);
    pb.crossRegisterProxies(lam, fam, cgam, mam);
    // See the top of this file for the choice of passes.
    llvm::FunctionPassManager fpm;
    fpm.addPass(llvm::EarlyCSEPass());
    if (level == FacetJit::Level::Optimized || carriesFastMathFlags(module)) {
        fpm.addPass(llvm::ReassociatePass());
        fpm.addPass(llvm::InstCombinePass());
    }
    llvm::ModulePassManager mpm;
    mpm.addPass(llvm::createModuleToFunctionPassAdaptor(std::move(fpm)));
    mpm.run(module, mam);
}

void FacetJit::optimize(llvm::Module& module, Level level) {
    Codegen& codegen = codegenAt(level);
    std::lock_guard<std::mutex> lock(codegen.mutex);
    optimizeKernelModule(module, *codegen.tm, level);
}

namespace {
// Skips the codegen passes that have nothing to do in a kernel (see the top
// of this file); set on the module's own LLVMContext only while it is emitted.
struct SkipPasses : llvm::OptPassGate {
    bool isEnabled() const override { return true; }
    bool shouldRunPass(llvm::StringRef pass, llvm::StringRef) override;
};

bool SkipPasses::shouldRunPass(llvm::StringRef pass, llvm::StringRef) {
    // Legacy pass names (getPassName()) of LLVM 19; see the top of this file.
    static const llvm::StringRef skipped[] = {
        "Add __emutls_[vt]. variables for emultated TLS model",
        "TLS Variable Hoist",
        "Local Dynamic TLS Access Clean-up",
        "Merge contiguous icmps into a memcmp",
        "Expand memcmp() to load/stores",
        "Partially inline calls to library functions",
        "X86 Partial Reduction",
        "Canonicalize Freeze Instructions in Loops",
        "Early If-Conversion",
        "Early Tail Duplication",
        "Optimize machine instruction PHIs",
        "Remove dead machine instructions",
        "X86 Domain Reassignment Pass",
        "X86 cmov Conversion",
        "X86 LEA Optimize",
        "X86 Optimize Call Frame",
        "X86 Avoid Store Forwarding Blocks",
        "Fixup Statepoint Caller Saved",
        "Control Flow Optimizer",
        "Post RA top-down list latency scheduler",
        "X86 Atom pad short functions",
    };
    return std::find(std::begin(skipped), std::end(skipped), pass) == std::end(skipped);
}
}  // namespace

void runKernelCodegen(llvm::legacy::PassManager& passes, llvm::Module& module) {
    SkipPasses skipPasses;
    llvm::LLVMContext& context = module.getContext();
    llvm::OptPassGate& previousGate = context.getOptPassGate();
    context.setOptPassGate(skipPasses);
    passes.run(module);
    context.setOptPassGate(previousGate);
}

std::unique_ptr<llvm::MemoryBuffer> FacetJit::emitObject(llvm::Module& module, Level level) {
    Codegen& codegen = codegenAt(level);
    std::lock_guard<std::mutex> lock(codegen.mutex);
    if (!codegen.passes) {
        auto passes = std::make_unique<llvm::legacy::PassManager>();
        codegen.stream = std::make_unique<llvm::raw_svector_ostream>(codegen.object);
        llvm::MCContext* mc = nullptr;
        if (static_cast<llvm::LLVMTargetMachine&>(*codegen.tm).addPassesToEmitMC(*passes, mc, *codegen.stream))
            throw std::runtime_error("emitting object code: the target cannot emit object files");
        codegen.passes = std::move(passes);
    }
    codegen.object.clear();
    runKernelCodegen(*codegen.passes, module);
    return llvm::MemoryBuffer::getMemBufferCopy(llvm::StringRef(codegen.object.data(), codegen.object.size()),
                                                module.getModuleIdentifier() + "-jitted-objectbuffer");
}

llvm::orc::JITDylib& FacetJit::addObject(std::unique_ptr<llvm::MemoryBuffer> object) {
    std::lock_guard<std::mutex> lock(mutex_);
    llvm::orc::JITDylib& dylib = unwrap(jit_->createJITDylib("facet_kernel_" + std::to_string(dylibCounter_++)),
                                        "creating a JIT dylib");
    // Kernels call nothing outside themselves, but LLVM may emit memset and
    // friends: resolve those from the process.
    dylib.addToLinkOrder(jit_->getMainJITDylib());
    if (llvm::Error err = jit_->addObjectFile(dylib, std::move(object)))
        throw std::runtime_error("loading kernel object: " + llvm::toString(std::move(err)));
    return dylib;
}

void* FacetJit::lookup(llvm::orc::JITDylib& dylib, const std::string& symbol) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto addr = jit_->lookup(dylib, symbol);
    if (!addr) throw std::runtime_error("looking up " + symbol + ": " + llvm::toString(addr.takeError()));
    return addr->toPtr<void*>();
}

void FacetJit::release(llvm::orc::JITDylib& dylib) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (llvm::Error err = jit_->getExecutionSession().removeJITDylib(dylib))
        llvm::consumeError(std::move(err));  // nothing useful to do while releasing
}

}  // namespace facet
