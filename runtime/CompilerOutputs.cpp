// CompilerOutputs: what a Compiler makes besides JIT kernels, through the
// same pipeline: an ahead-of-time build of a material (Compiler::compileAot,
// `facet build`; the target machine and emission are Aot.h's) and the IR
// text of `facet ir` (Compiler::irText).
#include "Kernel.h"

#include "Pipeline.h"
#include "TableCache.h"

#include <fmt/format.h>

namespace facet {

std::optional<AotKernel> Compiler::compileAot(const CheckedMaterial& material, const CompileOptions& options,
                                              llvm::TargetMachine& target, int width, const std::string& prefix,
                                              AotOutput output, DiagnosticEngine& diags) {
    internal_assert(options.backend != Backend::Interp) << "an ahead-of-time build needs a compiled backend";
    PipelineTarget aotTarget;
    aotTarget.machine = &target;
    aotTarget.aotOutput = output;
    aotTarget.naturalWidth = width;
    PipelineRun run = PipelineRun::fromChecked(material, options);
    PipelineControl control;
    control.symbolPrefix = prefix;
    control.aotEntryPoints = true;
    control.stopAfter = PipelineStage::Planned;
    if (!runKernelPipeline(run, control, aotTarget, *tables_, diags)) return std::nullopt;
    AotKernel aot;
    aot.material = run.specialized;
    aot.width = run.simd ? run.lowering.width : 1;
    aot.variant = run.lowering.variant.name();
    // The eval kernel's lowering with the sampler's entry points in the same
    // module: lowering and the middle end work function by function, so
    // they are the code the JIT kernel compiles in a module of its own.
    LoweringOptions lowering = run.lowering;
    lowering.emitSampling = true;
    if (options.tolerance) {
        // The variant compileMaterial chooses for the host: the same search,
        // measuring JIT kernels of the host's width against the interpreter.
        LoweringOptions host = loweringOptionsFor(options, run.energyTable.get(), run.simd, resolveWidth(options));
        host.energyTableInside = run.energyTableInside.get();
        MathVariant chosen = host.variant;
        CachedKernel probe = searchVariants(run.specialized, host, *options.tolerance, "facet_aot_probe",
                                            FacetJit::Level::Quick, chosen);
        lowering.variant = chosen;
        aot.variant = probe.variant;
        aot.measuredError = probe.measuredError;
    }
    run.rewindTo(PipelineStage::Specialized);
    control.lowering = lowering;
    control.stopAfter = PipelineStage::Emitted;
    if (!runKernelPipeline(run, control, aotTarget, *tables_, diags)) return std::nullopt;
    aot.output = std::move(run.object);
    aot.hasSampler = !run.lowered.sampleScalarSymbol.empty() || !run.lowered.sampleBatchSymbol.empty();
    return aot;
}

std::string Compiler::irText(const std::string& path, const std::string& name, const CompileOptions& options,
                             bool simd, IrOutput output, DiagnosticEngine& diags) {
    PipelineRun run = PipelineRun::fromFile(path, name, options);
    run.simd = simd;
    PipelineControl control;
    control.stopAfter = output == IrOutput::Plan ? PipelineStage::Planned : PipelineStage::Optimized;
    std::string out;
    if (output == IrOutput::Stages) {
        control.afterStage = [&](PipelineStage stage, const PipelineRun& r) {
            std::string text = pipelineStageText(stage, r);
            switch (stage) {
                case PipelineStage::Checked: out += "; ==== stage 1: checked material\n"; break;
                case PipelineStage::Specialized:
                    out += fmt::format("; ==== stage 2: specialized material ({} inputs bound)\n",
                                       r.options.bindings.size());
                    break;
                case PipelineStage::Planned:
                    out += "; ==== stage 3: lowering plan\n";
                    // As IR comments, so that the whole dump stays one IR-like text.
                    for (size_t start = 0; start < text.size();) {
                        size_t end = text.find('\n', start);
                        out += "; " + text.substr(start, end - start) + "\n";
                        start = end == std::string::npos ? text.size() : end + 1;
                    }
                    return;
                case PipelineStage::Lowered: out += "; ==== stage 4: lowered IR (verified, unoptimized)\n"; break;
                case PipelineStage::Optimized: out += "; ==== stage 5: optimized IR\n"; break;
                default: return;
            }
            out += text;
        };
    }
    if (!runPipeline(run, control, FacetJit::Level::Optimized, diags)) return "";
    if (output == IrOutput::Plan) return pipelineStageText(PipelineStage::Planned, run);
    if (output == IrOutput::Optimized) return pipelineStageText(PipelineStage::Optimized, run);
    return out;
}

}  // namespace facet
