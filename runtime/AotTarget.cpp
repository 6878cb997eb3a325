// AotTarget: the target machine of an ahead-of-time build, from LLVM's
// registry, limited to what Facet builds for and checked before any code is
// generated (see Aot.h: createAotTarget).
#include "Aot.h"

#include <llvm/ExecutionEngine/Orc/JITTargetMachineBuilder.h>
#include <llvm/MC/MCSubtargetInfo.h>
#include <llvm/MC/TargetRegistry.h>
#include <llvm/Support/TargetSelect.h>
#include <llvm/TargetParser/Triple.h>

#include <algorithm>
#include <fmt/format.h>
#include <mutex>
#include <optional>
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

// The architectures Facet writes objects for: the ones its tests link and
// run objects of (x86_64 on the host, aarch64 under qemu-user), both
// little-endian with 64-bit pointers. LLVM's other backends are refused up
// front: several abort or emit nothing usable for the kernels' IR.
constexpr const char* kArchitectures = "x86_64 and aarch64 (little-endian, 64-bit pointers)";

bool servedArchitecture(const llvm::Triple& triple) {
    return triple.getArch() == llvm::Triple::x86_64 || triple.getArch() == llvm::Triple::aarch64;
}

// Why the kernels cannot be built or run on this CPU with these features,
// or "". Checked on the subtarget LLVM derives from the CPU and features
// (implied features included: -sse turns sse2 off too), before any code is
// generated, since LLVM reports these cases by aborting or with raw errors.
std::string subtargetProblem(const llvm::Triple& triple, const llvm::MCSubtargetInfo& sti, const AotTarget& target,
                             const std::string& requestedFeatures) {
    const std::string arch = triple.getArchName().str();
    const std::string cpu = fmt::format("CPU '{}' for {}{}", target.cpu, arch,
                                        requestedFeatures.empty() ? "" : " with features '" + requestedFeatures + "'");
    if (triple.isX86()) {
        if (!sti.checkFeatures("+64bit") || !sti.checkFeatures("+64bit-mode"))
            return cpu + " cannot run 64-bit code (features 64bit and 64bit-mode), which an x86_64 object is";
        if (!sti.checkFeatures("+sse2"))
            return cpu + " has no SSE2 (feature sse2), the registers x86_64 passes floats in";
        if (sti.checkFeatures("+soft-float"))
            return cpu + " uses soft-float, which passes floats in integer registers where C callers of the object "
                         "do not";
        // AVX-512F with neither 512-bit vectors nor VL leaves the kernels'
        // vector compares without instructions (LLVM aborts).
        if (sti.checkFeatures("+avx512f") && !sti.checkFeatures("+evex512") && !sti.checkFeatures("+avx512vl"))
            return cpu + " has avx512f without evex512 or avx512vl, for which LLVM cannot compile the kernels";
    } else if (triple.isAArch64()) {
        if (!sti.checkFeatures("+fp-armv8"))
            return cpu + " has no floating point (feature fp-armv8), which the kernels and the AArch64 calling "
                         "convention need";
        // The entry points call the kernels; LLVM cannot pass arguments
        // with an argument register reserved.
        for (int r = 1; r <= 7; ++r)
            if (sti.checkFeatures(fmt::format("+reserve-x{}", r)))
                return cpu + fmt::format(" reserves x{} (feature reserve-x{}), an argument register the object's "
                                         "internal calls need",
                                         r, r);
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
    // The host as the JIT sees it: the default target, and what --cpu
    // native means.
    const bool native = request.cpu == "native";
    std::optional<llvm::orc::JITTargetMachineBuilder> host;
    if (request.triple.empty() || native) {
        auto detected = llvm::orc::JITTargetMachineBuilder::detectHost();
        if (!detected) {
            error = "cannot detect the host: " + llvm::toString(detected.takeError());
            return target;
        }
        host = std::move(*detected);
    }
    target.triple = request.triple.empty() ? host->getTargetTriple().str() : llvm::Triple::normalize(request.triple);
    const llvm::Triple triple(target.triple);
    std::string lookupError;
    const llvm::Target* backend = llvm::TargetRegistry::lookupTarget(target.triple, lookupError);
    if (!backend || triple.getArch() == llvm::Triple::UnknownArch) {
        std::vector<std::string> names;
        for (const llvm::Target& t : llvm::TargetRegistry::targets()) names.push_back(t.getName());
        error = fmt::format("unknown target '{}' (this LLVM has: {}; e.g. aarch64-linux-gnu, x86_64-linux-gnu)",
                            request.triple, joined(names));
        return target;
    }
    if (!servedArchitecture(triple)) {
        error = fmt::format("target '{}' ({}) is not one Facet builds for; it builds for {}", request.triple,
                            triple.getArchName().str(), kArchitectures);
        return target;
    }
    if (native && triple.getArch() != host->getTargetTriple().getArch()) {
        error = fmt::format("--cpu native means this machine's CPU ({}), and target '{}' is another architecture; "
                            "name one of its CPUs",
                            host->getTargetTriple().getArchName().str(), request.triple);
        return target;
    }
    if (request.cpu.empty() ? request.triple.empty() : native) {
        // The JIT's CPU and features, so that the object runs the JIT's code.
        target.cpu = host->getCPU();
        target.features = host->getFeatures().getString();
    } else {
        target.cpu = request.cpu.empty() ? "generic" : request.cpu;
    }
    if (!request.features.empty()) target.features += (target.features.empty() ? "" : ",") + request.features;
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
    // The subtarget LLVM derives from the CPU and features, checked before
    // any code is generated.
    std::unique_ptr<llvm::MCSubtargetInfo> sti(
        backend->createMCSubtargetInfo(target.triple, target.cpu, target.features));
    // x86: the MC layer turns evex512 on beside any avx512 feature unless the
    // string names it, codegen only for the generic CPUs; for, say, znver3
    // with +avx512f the two disagree and codegen aborts. Name it, as the
    // MC layer (and clang) would.
    const std::string list = "," + target.features + ",";
    if (triple.isX86() && sti->checkFeatures("+avx512f") && list.find(",+evex512,") == std::string::npos &&
        list.find(",-evex512,") == std::string::npos) {
        target.features += ",+evex512";
        sti.reset(backend->createMCSubtargetInfo(target.triple, target.cpu, target.features));
    }
    if (std::string problem = subtargetProblem(triple, *sti, target, request.features); !problem.empty()) {
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
    if (target.machine->createDataLayout().getPointerSizeInBits() != 64) {
        error = fmt::format("target '{}' has 32-bit pointers; Facet builds for {}", request.triple, kArchitectures);
        target.machine.reset();
        return target;
    }
    // The width the JIT picks for the same features (FacetJit::hostVectorWidth).
    target.width = !triple.isX86()                  ? 4
                   : sti->checkFeatures("+avx512f") ? 16
                   : sti->checkFeatures("+avx2")    ? 8
                                                    : 4;
    return target;
}

}  // namespace facet
