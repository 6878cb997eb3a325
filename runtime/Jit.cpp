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
#include "Jit.h"

#include "Diagnostics.h"

#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/CompileUtils.h>
#include <llvm/Passes/PassBuilder.h>
#include <llvm/Transforms/InstCombine/InstCombine.h>
#include <llvm/Transforms/Scalar/EarlyCSE.h>
#include <llvm/Transforms/Scalar/Reassociate.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/TargetParser/Host.h>

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
    jit->tm_ = unwrap(jtmb.createTargetMachine(), "creating the target machine");
    jit->jit_ = unwrap(llvm::orc::LLJITBuilder().setJITTargetMachineBuilder(jtmb).create(), "creating the JIT");
    return jit;
}

FacetJit::~FacetJit() = default;

int FacetJit::hostVectorWidth() const {
    if (features_.find("+avx512f") != std::string::npos) return 16;
    if (features_.find("+avx2") != std::string::npos) return 8;
    return 4;
}

void FacetJit::optimize(llvm::Module& module) {
    module.setDataLayout(tm_->createDataLayout());
    module.setTargetTriple(tm_->getTargetTriple().str());
    llvm::LoopAnalysisManager lam;
    llvm::FunctionAnalysisManager fam;
    llvm::CGSCCAnalysisManager cgam;
    llvm::ModuleAnalysisManager mam;
    llvm::PassBuilder pb(tm_.get());
    pb.registerModuleAnalyses(mam);
    pb.registerCGSCCAnalyses(cgam);
    pb.registerFunctionAnalyses(fam);
    pb.registerLoopAnalyses(lam);
    pb.crossRegisterProxies(lam, fam, cgam, mam);
    // See the top of this file for the choice of passes.
    llvm::FunctionPassManager fpm;
    fpm.addPass(llvm::EarlyCSEPass());
    fpm.addPass(llvm::ReassociatePass());
    fpm.addPass(llvm::InstCombinePass());
    llvm::ModulePassManager mpm;
    mpm.addPass(llvm::createModuleToFunctionPassAdaptor(std::move(fpm)));
    mpm.run(module, mam);
}

std::unique_ptr<llvm::MemoryBuffer> FacetJit::emitObject(llvm::Module& module) {
    std::lock_guard<std::mutex> lock(mutex_);
    llvm::orc::SimpleCompiler compiler(*tm_);
    return unwrap(compiler(module), "emitting object code");
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
