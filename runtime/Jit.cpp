// Jit: LLJIT setup, optimization pipeline and object emission.
//
// The optimization pipeline (issue 4: cold compile time)
// ------------------------------------------------------
// The lowering emits straight-line, explicitly vectorized IR: one function
// per entry point, <W x float> / <W x double> operations, masked loads,
// stores and gathers, one loop over lanes plus a masked tail, and no calls
// but intrinsics. O3 spends most of its time on what such IR does not need
// (inlining, loop rotation/unswitching/unrolling, loop and SLP vectorization,
// IPO) and its InstCombine/GVN runs repeat each other. optimize() runs three
// function passes instead, once each:
//
//   early-cse    the lowering emits the same subexpression more than once
//                (finiteness tests, clamps, fpext of one input per use);
//                without it beckmann_conductor runs 30% slower.
//   reassociate  ranks and regroups integer and i1 chains: the lane-invalid
//                masks, or-ed together one by one as the lowering finds
//                them, become one chain at the end of the loop body, which
//                codegen schedules and allocates better (satin_gaussian
//                exact: 9% slower than O3 without it, 4% with it). It
//                rewrites a floating-point operation only if it carries
//                `reassoc` and `nsz`, which the lowering never sets.
//   instcombine  folds fpext/fptrunc pairs, mask algebra and the constants
//                specialization leaves, cleans up after the two above and
//                deletes dead code; one iteration, as O3 runs it.
//
// The kernels' outputs are bit-identical to O3's: all 54 kernels (simd
// exact, simd fast, scalar exact of materials/*.mat and bench/models/*.mat)
// on the bench's regular sample and on the hard-case sample
// (facet_compile_timing --dump, compared with cmp). Not run, on purpose:
// SROA/mem2reg (the lowering allocates nothing), GVN (EarlyCSE finds the
// same redundancies in straight-line code), SimplifyCFG, LICM and the loop
// passes (the CFG is already entry/loop/tail/exit and codegen hoists the
// invariants), the vectorizers and the inliner.
//
// Object emission stays at CodeGenOptLevel::Aggressive: Default costs the
// same here and differs only in late block placement. None (fast register
// allocation, no load folding) halves emission time but makes scalar
// kernels 10-70% and some SIMD kernels up to 23% slower (clearcoat_gtr).
//
// Measured with bench/CompileTiming.cpp (facet_compile_timing: median of 11
// cold compiles, cache off, thread CPU time, best of 3 interleaved runs) on a
// 2-core share of a Xeon (Sapphire Rapids, AVX-512: width 16), 54 kernels:
//                                  O3 (before)          this pipeline
//   middle end, ms                 3.1-32.7             0.5-5.2
//   cold compile, ms, median       34.6 (8.5-84.8)      18.1 (5.7-50.9)
//     simd exact / fast / scalar   42.6 / 36.6 / 13.0   26.2 / 19.5 / 8.5
//   SIMD ns/eval                   1                    geomean 0.98; bench
//                                                       models -3.5%..+0.1%;
//                                                       worst +4.6% (ward_brushed
//                                                       exact), best -14%
// The rest is object emission (80-90% of a compile), proportional to the
// IR's size: the masked tail, a second copy of the loop body, is about 40%
// of it (beckmann_conductor exact: llc 36 ms, 21 ms without the tail).
//
// Object emission (issue 4, continued)
// ------------------------------------
// Emission costs 25-40 us per IR instruction of the kernel, about linearly
// (fit over the 54 kernels: time ~ n^1.1): instruction selection ~35% (half
// of it the DAG combiner), greedy register allocation ~20%, the machine
// scheduler ~9%, the remaining third spread over ~80 small passes. What
// emitObject() saves without changing the kernels:
//
//   - the codegen pipeline (a legacy PassManager with the AsmPrinter and its
//     object streamer) is built once and run on every module. AsmPrinter and
//     MachineModuleInfo reset the MC streamer and context at the end of each
//     module, so the objects are byte-identical to a fresh pipeline's (all 54
//     kernels, compiled over and over in any order). Saves ~1 ms per compile
//     (emission -9%).
//   - SkipPasses, an OptPassGate set on the module's own LLVMContext while it
//     is emitted (so no process-global cl::opt, nothing seen by other LLVM
//     users in the process), skips passes that have nothing to do in a
//     kernel: TLS, memcmp, libcall, GC, call-frame and Atom passes, the CFG
//     passes (the CFG is always entry/loop/stage/compute/unstage/latch) and a
//     few x86 peepholes that never fire here. Each of them, and all of them
//     together, leave all 54 objects byte-identical; a pass LLVM renames
//     merely runs again. Emission -3%.
//
// Together (facet_compile_timing, 14 interleaved runs, 54 kernels): emission
// -12.6%, cold compile -10.5% (geomean; median over the rows 17.1 -> 15.3 ms,
// bench/models 13.9 -> 12.6 ms), the kernels unchanged byte for byte.
//
// Tried and rejected (facet_compile_timing, 3-8 interleaved runs, 54 kernels):
// skipping Loop Strength Reduction (-2% emission, -4% with -disable-lsr,
// which also drops IVUsers/SCEV but is a process-global cl::opt; the 36 SIMD
// objects change and the fastest ones run 1.5-2% slower),
// -enable-misched=false (-9% cold, kernels up to +30%: gold fast, clearcoat),
// -misched-regpressure=false (-5%, up to +24%), -misched=ilpmax/ilpmin (no
// faster), -regalloc=basic (-5%, up to +19%), -disable-machine-cse / -licm,
// -x86-machine-combiner=false, -disable-cgp (-1..-3% each; they change the
// code, some kernels up to 6-10% slower, others faster), -fast-isel (no faster: vector code falls back to the DAG),
// CodeGenOptLevel::None with -optimize-regalloc (-20% cold, kernels up to
// +30%), width 8 (no faster to compile). Splitting the loop body into its
// own function saves at most what the loop costs (0-25% of llc time on the
// body alone, before the call) and compile time is near linear in size, so
// splitting the body further buys little.
//
// Two codegen levels (issue 4: tiered compile)
// --------------------------------------------
// Level::Quick emits with CodeGenOptLevel::None (fast register allocation,
// no machine scheduler or peepholes) after EarlyCSE alone: 2.2-2.8x less
// emission time and half a middle end. Kernel.h's tiered compile returns
// such code first and swaps in Level::Optimized code from a background
// thread. The levels compute the same bits (all 54 kernels on the regular
// and hard-case samples, dump cmp; JitTests checks it): codegen level does
// not change floating-point results, and without fast-math flags neither do
// Reassociate and InstCombine. With flags (fast kernels with estimates)
// both levels run the full middle end, because dead code that those passes
// remove keeps an fmul from contracting into an FMA (plastic fast differed
// in a fifth of its output values). facet_compile_timing --runs 5,
// bench/models (ms, cold compile / ns per eval):
//                      optimized       quick
//   GGX exact          14.6 / 2.7      8.1 / 3.3
//   Beckmann exact     19.4 / 10.4     10.0 / 11.5
//   aniso GGX exact    18.2 / 4.9      10.3 / 5.2
//   Beckmann scalar    11.5 / 87       6.2 / 110
//   median, 9 rows     11.9            6.3
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
