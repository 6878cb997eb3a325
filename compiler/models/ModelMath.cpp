// ModelMath: the parameter tables shared by the alpha_x / alpha_y NDFs.
#include "ModelMath.h"

#include <fmt/format.h>

namespace facet::models {

namespace {

std::vector<ModelParam> alphaXYParams() {
    return {{"alpha_x", ValueType::Float, kMinAlpha}, {"alpha_y", ValueType::Float, kMinAlpha}};
}

// ndf(alpha) | ndf(alpha_x, alpha_y)
std::vector<ModelForm> alphaXYForms() {
    return {ModelForm{{{"alpha", ValueType::Float, {kAlphaX, kAlphaY}}}},
            ModelForm{{{"alpha_x", ValueType::Float, {kAlphaX}}, {"alpha_y", ValueType::Float, {kAlphaY}}}}};
}

std::array<double, 2> alphaXYOf(const ModelArgs<double>& a) { return {a[kAlphaX], a[kAlphaY]}; }

ModelArgs<double> alphaXYAt(double alpha, const std::vector<double>&) {
    ModelArgs<double> a;
    a.set(kAlphaX, alpha);
    a.set(kAlphaY, alpha);
    return a;
}

std::string describeAlphaXY(const ModelArgs<double>& a) {
    return fmt::format("alpha=({:.6g},{:.6g})", a[kAlphaX], a[kAlphaY]);
}

}  // namespace

NdfEntry alphaXYNdf(int id, const char* name, const char* summary) {
    NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, id, name, summary);
    e.canonical = alphaXYParams();
    e.forms = alphaXYForms();
    e.equivalentAlphas = alphaXYOf;
    e.argsAtAlpha = alphaXYAt;
    e.describe = describeAlphaXY;
    std::string n = name;
    e.examples = {{n, "input alpha = 0.3;", n + "(alpha)"},
                  {n + "_aniso", "input alpha_x = 0.05; input alpha_y = 0.5;",
                   n + "(alpha_x = alpha_x, alpha_y = alpha_y)"}};
    return e;
}

}  // namespace facet::models
