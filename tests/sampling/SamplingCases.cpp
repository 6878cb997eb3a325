// SamplingCases: see SamplingCases.h.
#include "SamplingCases.h"

#include "Diagnostics.h"
#include "KullaConty.h"

#include <fmt/format.h>

#include <map>

namespace sampling_test {

using namespace facet;

namespace {

bool hasAlphaXY(const NdfEntry& ndf) { return paramIndex(ndf, "alpha_x") >= 0 && paramIndex(ndf, "alpha_y") >= 0; }

// How the masking is written: its first catalog example (inputs and
// statement), e.g. schlick_smith(k) with `input k = 0.15;`.
std::string maskingStatement(const MaskingEntry& m, std::string& inputs) {
    if (m.examples.empty()) return m.name;
    inputs += m.examples[0].inputs + "\n" + m.examples[0].extra + "\n";
    return m.examples[0].stmt;
}

std::string ndfStatement(const Combo& c, double alpha, int variant) {
    const NdfEntry& ndf = *c.ndf;
    const double factors[3] = {1, 0.75, 1.5};
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) {
        const ModelParam& param = ndf.canonical[p];
        shape.push_back(std::clamp(param.typical * factors[variant % 3], param.lo, param.hi));
    }
    // Shape values without a Smith Lambda (student_t at gamma 1.5): halfway
    // back to the typical ones (student_t at 1.75, where D is singular at
    // the horizon and its visible normals crowd toward it).
    if (c.masking->smith && ndf.lambdaShapeError && !ndf.lambdaShapeError(shape).empty())
        for (size_t i = 0; i < shape.size(); ++i)
            shape[i] = (shape[i] + ndf.canonical[ndf.tableShapeParams[i]].typical) / 2;
    ModelArgs<double> args = ndf.argsAtAlpha(alpha, shape);
    if (c.anisotropic) {
        args.set(paramIndex(ndf, "alpha_x"), alpha);
        args.set(paramIndex(ndf, "alpha_y"), alpha / 10);
    }
    std::string out;
    for (size_t p = 0; p < ndf.canonical.size(); ++p)
        if (args.given[p]) out += fmt::format("{}{} = {:.17g}", out.empty() ? "" : ", ", ndf.canonical[p].name, args[int(p)]);
    return fmt::format("{}({})", ndf.name, out);
}

}  // namespace

std::string Combo::name() const {
    return fmt::format("{}{} / {} / {}{}", ndf->name, anisotropic ? " 10:1" : "", masking->name,
                       diffuse ? "lambert" : "no diffuse", compensated ? " / kulla_conty" : "");
}

std::unique_ptr<TestMaterial> loadMaterial(const std::string& text, std::string* error) {
    auto t = std::make_unique<TestMaterial>();
    t->text = text;
    DiagnosticEngine diags;
    t->program = loadProgramText(t->text, "sampling.mat", diags);
    if (diags.hasErrors() || t->program.materials.empty()) {
        if (error) *error = diags.str();
        return nullptr;
    }
    t->material = &t->program.materials.front();
    // One Kulla-Conty table per key for the whole run (each takes ~0.5 s).
    static std::map<EnergyTableKey, std::shared_ptr<const EnergyTable>> tables;
    std::shared_ptr<const EnergyTable> table;
    if (t->material->singleLobe().compensatesEnergy()) {
        EnergyTableKey key = energyTableKey(*t->material);
        std::shared_ptr<const EnergyTable>& slot = tables[key];
        if (!slot) slot = buildEnergyTable(key);
        table = slot;
    }
    t->interpreter = std::make_unique<Interpreter<double>>(*t->material, table);
    t->resolved = t->interpreter->resolve(nullptr);
    return t;
}

std::unique_ptr<TestMaterial> makeMaterial(const Combo& c, double alpha, int variant, const std::string& fresnel,
                                           std::string* error) {
    std::string inputs;
    std::string masking = maskingStatement(*c.masking, inputs);
    std::string text = fmt::format(
        "material t {{\n{}\n    ndf = {};\n    masking = {};\n    fresnel = {};\n    diffuse = {};\n    energy = {};\n}}\n",
        inputs, ndfStatement(c, alpha, variant), masking, fresnel, c.diffuse ? "lambert(0.5)" : "none",
        c.compensated ? "kulla_conty" : "none");
    return loadMaterial(text, error);
}

const std::vector<Combo>& combos() {
    static const std::vector<Combo> all = [] {
        // The NDF forms: each NDF isotropic, then anisotropic where it can be.
        std::vector<std::pair<const NdfEntry*, bool>> forms;
        for (const ModelInfo* n : catalogSlot(ModelSlot::Ndf)) {
            forms.push_back({&ndfEntry(*n), false});
            if (hasAlphaXY(ndfEntry(*n))) forms.push_back({&ndfEntry(*n), true});
        }
        std::vector<Combo> out;
        for (auto [ndf, aniso] : forms)
            for (const ModelInfo* m : catalogSlot(ModelSlot::Masking)) {
                const MaskingEntry* masking = &maskingEntry(*m);
                std::vector<Combo> variants = {{ndf, masking, aniso, false, false}, {ndf, masking, aniso, true, false}};
                if (ndf->representative && masking->representative && !aniso)
                    variants.push_back({ndf, masking, aniso, false, true});
                for (const Combo& c : variants)
                    if (makeMaterial(c, 0.5)) out.push_back(c);
            }
        return out;
    }();
    return all;
}

}  // namespace sampling_test
