// Jit: LLJIT setup, optimization pipeline and object emission.
#include "Jit.h"

#include "Diagnostics.h"

#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/ExecutionEngine/Orc/CompileUtils.h>
#include <llvm/Passes/PassBuilder.h>
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
    jtmb.setCodeGenOptLevel(llvm::CodeGenOptLevel::Aggressive);
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
    llvm::ModulePassManager mpm = pb.buildPerModuleDefaultPipeline(llvm::OptimizationLevel::O3);
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
