// gaussian: an NDF Gaussian in the polar angle, exp(-theta^2/alpha^2) / N(alpha),
// normalized by quadrature (gaussianNdfNorm). No closed-form Smith Lambda.
#include "QuadMath.h"
#include "GaussianNormalization.h"

#include "models/ModelMath.h"

#include <fmt/format.h>

namespace facet::models {
namespace {

constexpr int kAlpha = 0;
constexpr int kNorm = 0;  // derived: N(alpha)

template <typename Real>
struct GaussianFormulas final : NdfFormulas<Real> {
    Real D(const ModelArgs<Real>& a, const Vec3<Real>& m) const override {
        using std::atan2; using std::exp; using std::sqrt;
        Real theta = atan2(sqrt(m.x * m.x + m.y * m.y), m.z);
        return exp(-theta * theta / sq(a[kAlpha])) / a.derived[kNorm];
    }
    void derive(ModelArgs<Real>& a) const override { a.derived[kNorm] = gaussianNdfNorm(a[kAlpha]); }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Gaussian() {
    static const NdfEntry entry = [] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 4, "gaussian", "Gaussian in the polar angle, normalized by quadrature");
        e.canonical = {{"alpha", ValueType::Float, kMinAlpha}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlpha}}}}};
        e.equivalentAlphas = [](const ModelArgs<double>& a) { return std::array<double, 2>{a[kAlpha], a[kAlpha]}; };
        e.argsAtAlpha = [](double alpha, const std::vector<double>&) {
            ModelArgs<double> a;
            a.set(kAlpha, alpha);
            return a;
        };
        e.describe = [](const ModelArgs<double>& a) { return fmt::format("alpha=({:.6g},{:.6g})", a[kAlpha], a[kAlpha]); };
        e.examples = {{"gaussian", "input alpha = 0.3;", "gaussian(alpha)"}};
        e.hardCases = {
            {"hcc_gaussian_alpha_min", "ndf = gaussian(1e-4); masking = cook_torrance;"},
            {"hcc_gaussian_alpha_2", "ndf = gaussian(2); masking = schlick_smith(0.5);"},
        };
        e.formulas = makeFormulas<NdfFormulas, GaussianFormulas>();
        return e;
    }();
    return {&entry};
}

}  // namespace facet::models
