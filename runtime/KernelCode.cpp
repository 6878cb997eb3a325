// KernelCode: loading a kernel's code and reporting its tier (KernelCode.h,
// and the Kernel methods that read the tier: codeTier, waitOptimized,
// tierUpError, tierUpMillis).
#include "KernelCode.h"

#include <llvm/Support/MemoryBuffer.h>

namespace facet {

KernelCode::~KernelCode() {
    for (llvm::orc::JITDylib* d : dylibs) jit->release(*d);
}

void KernelCode::settle(std::string error, double millis) {
    std::lock_guard<std::mutex> lock(mutex);
    optimized = error.empty();
    tierUpError = std::move(error);
    tierUpMillis = millis;
    tierUpPending = false;
    settled.notify_all();
}

llvm::orc::JITDylib& KernelCode::addObject(const std::string& object, const std::string& name) {
    llvm::orc::JITDylib& dylib = jit->addObject(llvm::MemoryBuffer::getMemBufferCopy(object, name));
    std::lock_guard<std::mutex> lock(mutex);
    dylibs.push_back(&dylib);
    return dylib;
}

Kernel::~Kernel() = default;

std::string Kernel::codeTier() const {
    if (!code_) return "interpreter";
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->optimized ? "optimized" : "quick";
}

void Kernel::waitOptimized() const {
    if (!code_) return;
    std::unique_lock<std::mutex> lock(code_->mutex);
    code_->settled.wait(lock, [this] { return !code_->tierUpPending; });
}

std::string Kernel::tierUpError() const {
    if (!code_) return "";
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->tierUpError;
}

double Kernel::tierUpMillis() const {
    if (!code_) return 0;
    std::lock_guard<std::mutex> lock(code_->mutex);
    return code_->tierUpMillis;
}

}  // namespace facet
