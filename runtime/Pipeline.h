// Pipeline: the one path from material source to object code.
//
//   source -> checked -> specialized -> planned -> lowered -> optimized -> emitted
//
// runKernelPipeline() advances a PipelineRun from the stage it has reached
// to the stage asked for, and calls an observer after each stage, so that a
// caller can print (`facet ir --stages`), time (facet_compile_timing) or
// inspect (tests) any intermediate result. Every compile takes this path:
// JIT kernels (Compiler::compileMaterial, its tier-up and tolerance search),
// ahead-of-time objects, `facet ir` and the timing tool. A compile that may
// be served from a cache stops after `planned` (the key needs the
// specialized material and the lowering options) and resumes the same run
// on a miss.
//
// Each stage reads what the previous ones wrote and nothing else; the
// decisions of the lowering are made once, in the plan, by planLowering().
#pragma once

#include "Aot.h"
#include "Jit.h"
#include "Kernel.h"
#include "Lowering.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace llvm {
class LLVMContext;
class TargetMachine;
}  // namespace llvm

namespace facet {

class TableCache;

enum class PipelineStage { Source, Checked, Specialized, Planned, Lowered, Optimized, Emitted };
const char* pipelineStageName(PipelineStage stage);

// Where object code is made: for the JIT's host at one codegen level, or
// for an ahead-of-time target machine (in the form `aotOutput` names).
struct PipelineTarget {
    FacetJit* jit = nullptr;
    llvm::TargetMachine* machine = nullptr;  // ahead of time, when jit is null
    AotOutput aotOutput = AotOutput::Object;
    FacetJit::Level level = FacetJit::Level::Optimized;
    int naturalWidth = 8;  // SIMD lanes where the options name no width

    // The JIT's host at `level`, with the host's natural width.
    static PipelineTarget forJit(FacetJit& jit, FacetJit::Level level);
};

// One run's state: each stage fills its part, in order.
struct PipelineRun {
    // source: a file (read at the `checked` stage) or text, and the
    // material's name ("" = the first).
    std::string path, text, name;
    bool readFile = false;
    CompileOptions options;
    bool simd = true;  // a batch entry (else the scalar one); from options.backend
    // checked / specialized (with its Kulla-Conty table, if it compensates
    // energy, and its NDF's Lambda table, if its masking needs one: loaded
    // through the TableCache, which puts it where the plan finds it)
    CheckedMaterial checked, specialized;
    std::shared_ptr<const EnergyTable> energyTable;
    // and, a lobe over the whole sphere, its table from inside (loaded at
    // the planned stage; the same table for a thin sheet)
    std::shared_ptr<const EnergyTable> energyTableInside;
    std::shared_ptr<const LambdaTable> lambdaTable;
    // A combination of lobes: the same per lobe (Kulla-Conty tables in
    // CheckedMaterial::lobes order, null for a lobe without; the Lambda
    // tables held for the plan to find), loaded at the planned stage.
    std::vector<std::shared_ptr<const EnergyTable>> lobeEnergyTables;
    std::vector<std::shared_ptr<const LambdaTable>> lobeLambdaTables;
    // planned
    LoweringOptions lowering;
    LoweringPlan plan;
    // lowered / optimized (the module lives in the run's own context)
    std::unique_ptr<llvm::LLVMContext> context;
    LoweredModule lowered;
    // emitted
    std::string object;
    PipelineStage reached = PipelineStage::Source;

    static PipelineRun fromFile(std::string path, std::string name, const CompileOptions& options);
    static PipelineRun fromText(std::string text, std::string path, std::string name, const CompileOptions& options);
    static PipelineRun fromChecked(const CheckedMaterial& material, const CompileOptions& options);
    // A material specialized already (with its table, if it compensates
    // energy), for runs that resume at `planned` with their own lowering
    // options.
    static PipelineRun fromSpecialized(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> table);
    // Drops what the stages after `stage` made, so that they run again
    // (another math variant, another codegen level).
    void rewindTo(PipelineStage stage);

    PipelineRun();
    ~PipelineRun();
    // Movable, not assignable: the module must die before its context,
    // which a member-wise assignment would not ensure.
    PipelineRun(PipelineRun&&) noexcept;
    PipelineRun& operator=(PipelineRun&&) = delete;
};

struct PipelineControl {
    PipelineStage stopAfter = PipelineStage::Emitted;
    std::string symbolPrefix;  // of the entry points; "" = "facet_" + the material's name
    // The lowering options to plan with, instead of the ones the compile
    // options map to (loweringOptionsFor): a tolerance search's variant, a
    // tier-up repeating a quick compile, a test's single-body kernel.
    std::optional<LoweringOptions> lowering;
    // Adds the C entry points of an ahead-of-time object after lowering.
    bool aotEntryPoints = false;
    std::function<void(PipelineStage, const PipelineRun&)> afterStage;
};

// Advances `run` to control.stopAfter (or leaves it where it is, if it is
// there already). Returns false on a user error (a missing file or
// material, a parse, type or binding error), which `diags` reports; throws
// InternalError on a Facet bug.
bool runKernelPipeline(PipelineRun& run, const PipelineControl& control, const PipelineTarget& target,
                       TableCache& tables, DiagnosticEngine& diags);

// The result of `stage` as text: the material as Facet prints it, the plan,
// or the module's IR. Empty for `source` and `emitted`.
std::string pipelineStageText(PipelineStage stage, const PipelineRun& run);

}  // namespace facet
