// Pipeline: runs the stages of a kernel compile in order (Pipeline.h).
#include "Pipeline.h"

#include "CompileStack.h"

#include "Checker.h"
#include "Diagnostics.h"
#include "Specialize.h"
#include "TableCache.h"
#include "reference/DielectricEnergy.h"

#include <llvm/IR/LLVMContext.h>
#include <llvm/Support/raw_ostream.h>

#include <fmt/format.h>

namespace facet {

PipelineTarget PipelineTarget::forJit(FacetJit& jit, FacetJit::Level level) {
    PipelineTarget target;
    target.jit = &jit;
    target.level = level;
    target.naturalWidth = jit.hostVectorWidth();
    return target;
}

const char* pipelineStageName(PipelineStage stage) {
    switch (stage) {
        case PipelineStage::Source: return "source";
        case PipelineStage::Checked: return "checked";
        case PipelineStage::Specialized: return "specialized";
        case PipelineStage::Planned: return "planned";
        case PipelineStage::Lowered: return "lowered";
        case PipelineStage::Optimized: return "optimized";
        case PipelineStage::Emitted: return "emitted";
    }
    return "?";
}

PipelineRun::PipelineRun() = default;
PipelineRun::~PipelineRun() {
    // The module belongs to the context: release it first.
    lowered.module.reset();
}
PipelineRun::PipelineRun(PipelineRun&&) noexcept = default;

PipelineRun PipelineRun::fromFile(std::string path, std::string name, const CompileOptions& options) {
    PipelineRun run;
    run.path = std::move(path), run.name = std::move(name), run.readFile = true;
    run.options = options;
    run.simd = options.backend == Backend::Simd;
    return run;
}

PipelineRun PipelineRun::fromText(std::string text, std::string path, std::string name, const CompileOptions& options) {
    PipelineRun run = fromFile(std::move(path), std::move(name), options);
    run.text = std::move(text), run.readFile = false;
    return run;
}

PipelineRun PipelineRun::fromChecked(const CheckedMaterial& material, const CompileOptions& options) {
    PipelineRun run = fromFile("", material.name, options);
    run.readFile = false;
    run.checked = material;
    run.reached = PipelineStage::Checked;
    return run;
}

PipelineRun PipelineRun::fromSpecialized(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> table) {
    PipelineRun run = fromChecked(material, CompileOptions{});
    run.specialized = material;
    run.energyTable = std::move(table);
    run.reached = PipelineStage::Specialized;
    return run;
}

void PipelineRun::rewindTo(PipelineStage stage) {
    if (stage >= reached) return;
    if (stage < PipelineStage::Emitted) object.clear();
    if (stage < PipelineStage::Lowered) {
        lowered = LoweredModule{};
        context.reset();
    }
    if (stage < PipelineStage::Planned) lowering = LoweringOptions{}, plan = LoweringPlan{};
    if (stage < PipelineStage::Specialized)
        specialized = CheckedMaterial{}, energyTable.reset(), energyTableInside.reset(), lambdaTable.reset(),
        lobeEnergyTables.clear(),
        lobeLambdaTables.clear();
    internal_assert(stage >= PipelineStage::Checked || readFile || !text.empty())
        << "a pipeline run given a checked material cannot rewind to its source";
    reached = stage;
}

namespace {

// One stage's work; false on a user error.
bool check(PipelineRun& run, DiagnosticEngine& diags) {
    CheckedProgram program =
        run.readFile ? loadProgramFile(run.path, diags) : loadProgramText(run.text, run.path, diags);
    if (diags.hasErrors()) return false;
    const CheckedMaterial* material = program.find(run.name);
    if (!material) {
        diags.error({std::make_shared<const std::string>(run.path), 0, 0},
                    fmt::format("no material named '{}'", run.name));
        return false;
    }
    run.checked = *material;
    return true;
}

// A combination's lobes each have their tables (the one-lobe view of each).
void lobeTables(PipelineRun& run, TableCache& tables) {
    if (!run.specialized.combinesLobes() || !run.lobeEnergyTables.empty()) return;
    for (size_t l = 0; l < run.specialized.lobes.size(); ++l) {
        CheckedMaterial view = lobeView(run.specialized, int(l));
        const CheckedLobe& lobe = view.singleLobe();
        run.lobeEnergyTables.push_back(lobe.compensatesEnergy() ? tables.getFor(view) : nullptr);
        if (lobe.hasNdf() && usesTabulatedLambda(view)) run.lobeLambdaTables.push_back(tables.lambdaFor(view));
    }
}

bool specialize(PipelineRun& run, TableCache& tables, DiagnosticEngine& diags) {
    // After the bindings: a bound input can make a layer's tables constant.
    run.specialized = specializeMaterial(run.checked, run.options.bindings, diags);
    if (diags.hasErrors()) return false;
    const bool compiled = run.options.backend != Backend::Interp;
    if (std::string why = compiled ? compiledBackendsRefuse(run.specialized) : ""; !why.empty()) {
        diags.error(run.specialized.loc, why);
        return false;
    }
    if (!run.specialized.combinesLobes()) {
        if (run.specialized.singleLobe().compensatesEnergy()) run.energyTable = tables.getFor(run.specialized);
        if (usesTabulatedLambda(run.specialized)) run.lambdaTable = tables.lambdaFor(run.specialized);
    }
    lobeTables(run, tables);
    return true;
}

// A lobe over the whole sphere compensates from both sides: the table from
// inside too (DielectricEnergy.h; a thin sheet's sides share one).
void insideTable(PipelineRun& run, TableCache& tables) {
    if (run.energyTableInside || !run.energyTable || run.specialized.combinesLobes()) return;
    const CheckedLobe& lobe = run.specialized.singleLobe();
    if (!lobe.wholeSphere()) return;
    run.energyTableInside = lobe.thin ? run.energyTable : tables.get(insideTableKey(run.energyTable->key));
}

void plan(PipelineRun& run, const PipelineControl& control, const PipelineTarget& target, TableCache& tables) {
    lobeTables(run, tables);
    insideTable(run, tables);
    if (control.lowering) {
        run.lowering = *control.lowering;
    } else {
        int width = run.options.width ? run.options.width : target.naturalWidth;
        run.lowering = loweringOptionsFor(run.options, run.energyTable.get(), run.simd, width);
    }
    // A run that starts specialized from a caller's lowering (the kernel's
    // object, its tier-up) keeps the caller's inside table.
    if (run.energyTableInside) run.lowering.energyTableInside = run.energyTableInside.get();
    run.lowering.lobeEnergyTables.clear();
    for (const auto& t : run.lobeEnergyTables) run.lowering.lobeEnergyTables.push_back(t.get());
    internal_assert(run.specialized.combinesLobes() || !run.specialized.singleLobe().compensatesEnergy() ||
                    run.lowering.energyTable)
        << "energy compensation planned without its table";
    // The sampler's tables only for a run that emits the sampler.
    run.plan = planLowering(run.specialized, run.lowering.variant, run.lowering.trustInputs, run.lobeEnergyTables,
                            run.lowering.emitSampling, run.lowering.transport);
}

void lower(PipelineRun& run, const PipelineControl& control, const PipelineTarget& target) {
    run.context = std::make_unique<llvm::LLVMContext>();
    const std::string prefix = control.symbolPrefix.empty() ? "facet_" + run.specialized.name : control.symbolPrefix;
    // Optimized batch code has one-lane bodies for its one-lane calls
    // (LoweringOptions::oneLaneBodies); quick code, which lives until its
    // tier-up, does not pay for their compile.
    LoweringOptions lowering = run.lowering;
    lowering.oneLaneBodies = target.level == FacetJit::Level::Optimized;
    run.lowered = lowerMaterial(run.specialized, run.plan, lowering, *run.context, prefix);
    if (control.aotEntryPoints) addAotEntryPoints(run.lowered, run.specialized, prefix);
}

void optimize(PipelineRun& run, const PipelineTarget& target) {
    if (target.jit)
        target.jit->optimize(*run.lowered.module, target.level);
    else
        optimizeKernelModule(*run.lowered.module, *target.machine, target.level);
}

void emit(PipelineRun& run, const PipelineTarget& target) {
    run.object = target.jit ? target.jit->emitObject(*run.lowered.module, target.level)->getBuffer().str()
                            : writeAotOutput(*run.lowered.module, *target.machine, target.aotOutput);
}

}  // namespace

bool runKernelPipeline(PipelineRun& run, const PipelineControl& control, const PipelineTarget& target,
                       TableCache& tables, DiagnosticEngine& diags) {
    internal_assert(target.jit || target.machine) << "a pipeline run needs a JIT or a target machine";
    while (run.reached < control.stopAfter) {
        auto next = PipelineStage(int(run.reached) + 1);
        switch (next) {
            case PipelineStage::Source: break;
            case PipelineStage::Checked:
                if (!check(run, diags)) return false;
                break;
            case PipelineStage::Specialized:
                if (!specialize(run, tables, diags)) return false;
                break;
            case PipelineStage::Planned: plan(run, control, target, tables); break;
            // LLVM's stages recurse as deep as the material is long: on a
            // stack of known size, whatever thread the host calls from.
            case PipelineStage::Lowered: onCompileStack([&] { lower(run, control, target); }); break;
            case PipelineStage::Optimized: onCompileStack([&] { optimize(run, target); }); break;
            case PipelineStage::Emitted: onCompileStack([&] { emit(run, target); }); break;
        }
        run.reached = next;
        if (control.afterStage) control.afterStage(next, run);
    }
    return true;
}

std::string pipelineStageText(PipelineStage stage, const PipelineRun& run) {
    switch (stage) {
        case PipelineStage::Checked: return printMaterial(run.checked);
        case PipelineStage::Specialized: return printMaterial(run.specialized);
        case PipelineStage::Planned: return printPlan(run.specialized, run.plan);
        case PipelineStage::Lowered:
        case PipelineStage::Optimized: {
            std::string out;
            llvm::raw_string_ostream os(out);
            os << *run.lowered.module;
            return os.str();
        }
        case PipelineStage::Source:
        case PipelineStage::Emitted: return "";
    }
    return "";
}

}  // namespace facet
