// Builtins: the tables themselves.
#include "Builtins.h"

#include "Diagnostics.h"

namespace facet {

const std::vector<BuiltinFunction>& builtinFunctions() {
    static const std::vector<BuiltinFunction> table = {
        {BuiltinFn::Rgb, "rgb", 3, true, "rgb(r, g, b)"},
        {BuiltinFn::Sqrt, "sqrt", 1, false, "sqrt(x)"},
        {BuiltinFn::Pow, "pow", 2, false, "pow(x, y)"},
        {BuiltinFn::Exp, "exp", 1, false, "exp(x)"},
        {BuiltinFn::Log, "log", 1, false, "log(x)"},
        {BuiltinFn::Abs, "abs", 1, false, "abs(x)"},
        {BuiltinFn::Min, "min", 2, false, "min(a, b)"},
        {BuiltinFn::Max, "max", 2, false, "max(a, b)"},
        {BuiltinFn::Clamp, "clamp", 3, false, "clamp(x, lo, hi)"},
        {BuiltinFn::Mix, "mix", 3, false, "mix(a, b, t)"},
        {BuiltinFn::PhongExponent, "phong_exponent", 1, false, "phong_exponent(roughness)"},
        {BuiltinFn::BeckmannToPhong, "beckmann_to_phong", 1, false, "beckmann_to_phong(alpha)"},
    };
    return table;
}

const BuiltinFunction* findBuiltinFunction(std::string_view name) {
    for (const BuiltinFunction& f : builtinFunctions())
        if (name == f.name) return &f;
    return nullptr;
}

namespace {
constexpr ValueType F = ValueType::Float;
constexpr ValueType C = ValueType::Rgb;  // "colour"

ModelInfo ndf(NdfModel id, const char* name, std::vector<const char*> aliases,
              std::vector<ModelParam> canonical, std::vector<ModelForm> forms, bool smith,
              const char* summary) {
    return {ModelSlot::Ndf, int(id), name, std::move(aliases), std::move(canonical), std::move(forms),
            smith, summary};
}
ModelInfo masking(MaskingModel id, const char* name, bool smith, const char* summary,
                  std::vector<ModelParam> canonical = {}, std::vector<ModelForm> forms = {ModelForm{}}) {
    return {ModelSlot::Masking, int(id), name, {}, std::move(canonical), std::move(forms), smith, summary};
}
// ggx(alpha) | ggx(alpha_x, alpha_y)
std::vector<ModelForm> alphaForms() {
    return {ModelForm{{{"alpha", F, {param::AlphaX, param::AlphaY}}}},
            ModelForm{{{"alpha_x", F, {param::AlphaX}}, {"alpha_y", F, {param::AlphaY}}}}};
}
}  // namespace

const std::vector<ModelInfo>& builtinModels() {
    static const std::vector<ModelInfo> table = [] {
        std::vector<ModelInfo> t;
        std::vector<ModelParam> alphaXY = {{"alpha_x", F}, {"alpha_y", F}};
        t.push_back(ndf(NdfModel::Ggx, "ggx", {"trowbridge_reitz"}, alphaXY, alphaForms(), true,
                        "GGX / Trowbridge-Reitz (Walter et al. 2007)"));
        t.push_back(ndf(NdfModel::Beckmann, "beckmann", {}, alphaXY, alphaForms(), true,
                        "Beckmann (Cook & Torrance 1982, Walter et al. 2007)"));
        t.push_back(ndf(NdfModel::BlinnPhong, "blinn_phong", {}, {{"exponent", F}},
                        {ModelForm{{{"exponent", F, {param::Exponent}}}}}, true,
                        "normalized Blinn-Phong NDF"));
        t.push_back(ndf(NdfModel::Gtr, "gtr", {}, {{"alpha", F}, {"gamma", F}},
                        {ModelForm{{{"alpha", F, {param::GtrAlpha}}, {"gamma", F, {param::GtrGamma}}}}},
                        false, "generalized Trowbridge-Reitz (Burley 2012)"));
        t.push_back(ndf(NdfModel::Gaussian, "gaussian", {}, {{"alpha", F}},
                        {ModelForm{{{"alpha", F, {param::GaussianAlpha}}}}}, false,
                        "Gaussian in the polar angle, normalized by quadrature"));
        t.push_back(ndf(NdfModel::Ward, "ward", {}, alphaXY, alphaForms(), false,
                        "whole anisotropic Ward (1992) lobe"));

        t.push_back(masking(MaskingModel::None, "none", false, "G = 1"));
        t.push_back(masking(MaskingModel::Implicit, "implicit", false, "G = (n.wi)(n.wo)"));
        t.push_back(masking(MaskingModel::CookTorrance, "cook_torrance", false, "V-cavity (Cook & Torrance 1982)"));
        t.push_back(masking(MaskingModel::Kelemen, "kelemen", false, "Kelemen & Szirmay-Kalos 2001"));
        t.push_back(masking(MaskingModel::Neumann, "neumann", false, "Neumann et al. 1999"));
        t.push_back(masking(MaskingModel::SchlickSmith, "schlick_smith", false, "Schlick 1994 approximation of Smith",
                            {{"k", F}}, {ModelForm{{{"k", F, {param::SchlickK}}}}}));
        t.push_back(masking(MaskingModel::SmithSeparable, "smith_separable", true, "uncorrelated Smith (Heitz 2014)"));
        t.push_back(masking(MaskingModel::SmithHeightCorrelated, "smith_height_correlated", true,
                            "height-correlated Smith (Heitz 2014)"));
        t.push_back(masking(MaskingModel::SmithDirectionCorrelated, "smith_direction_correlated", true,
                            "direction-correlated Smith (Heitz 2014, Ashikhmin et al.)"));
        t.push_back(masking(MaskingModel::SmithHeightDirectionCorrelated, "smith_height_direction_correlated",
                            true, "height-direction-correlated Smith (Heitz 2014)"));

        auto other = [&](ModelSlot slot, int id, const char* name, std::vector<ModelParam> canonical,
                         std::vector<ModelForm> forms, const char* summary) {
            t.push_back({slot, id, name, {}, std::move(canonical), std::move(forms), false, summary});
        };
        other(ModelSlot::Fresnel, int(FresnelModel::None), "none", {}, {ModelForm{}}, "F = 1");
        other(ModelSlot::Fresnel, int(FresnelModel::Schlick), "schlick", {{"f0", C}, {"eta", C}},
              {ModelForm{{{"f0", C, {param::F0}}}}, ModelForm{{{"eta", C, {param::SchlickEta}}}}},
              "Schlick 1994 approximation");
        other(ModelSlot::Fresnel, int(FresnelModel::Dielectric), "dielectric", {{"eta", C}},
              {ModelForm{{{"eta", C, {param::DielectricEta}}}}}, "exact dielectric Fresnel");
        other(ModelSlot::Fresnel, int(FresnelModel::Conductor), "conductor", {{"eta", C}, {"k", C}},
              {ModelForm{{{"eta", C, {param::ConductorEta}}, {"k", C, {param::ConductorK}}}}},
              "exact conductor Fresnel, complex index eta + ik");
        other(ModelSlot::Energy, int(EnergyModel::None), "none", {}, {ModelForm{}}, "no compensation");
        other(ModelSlot::Energy, int(EnergyModel::KullaConty), "kulla_conty", {}, {ModelForm{}},
              "Kulla & Conty 2017 multiple-scattering compensation");
        other(ModelSlot::Diffuse, int(DiffuseModel::None), "none", {}, {ModelForm{}}, "no diffuse base");
        other(ModelSlot::Diffuse, int(DiffuseModel::Lambert), "lambert", {{"albedo", C}},
              {ModelForm{{{"albedo", C, {param::Albedo}}}}}, "Lambertian base, albedo / pi");
        return t;
    }();
    return table;
}

const ModelInfo* findModel(ModelSlot slot, std::string_view name) {
    for (const ModelInfo& m : builtinModels()) {
        if (m.slot != slot) continue;
        if (name == m.name) return &m;
        for (const char* alias : m.aliases)
            if (name == alias) return &m;
    }
    return nullptr;
}

const ModelInfo& modelInfo(ModelSlot slot, int id) {
    for (const ModelInfo& m : builtinModels())
        if (m.slot == slot && m.id == id) return m;
    internal_error << "no model " << id << " in slot " << modelSlotName(slot);
}

}  // namespace facet
