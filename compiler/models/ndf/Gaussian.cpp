// gaussian: an NDF Gaussian in the polar angle, exp(-theta^2/alpha^2) / N(alpha),
// normalized by quadrature (gaussianNdfNorm). No closed-form Smith Lambda and
// not shape-invariant: Lambda is tabulated in (a, alpha).
#include "QuadMath.h"
#include "Immortal.h"
#include "GaussianNormalization.h"
#include "LambdaTable.h"

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
    // The tabulated (n.v) Lambda(v) at the material's alpha.
    Real cosLambda(const ModelArgs<Real>& a, const Vec3<Real>& v) const override {
        static const NdfEntry& self = ndfEntry(modelNamed(ModelSlot::Ndf, "gaussian"));
        return Real(tabulatedCosLambda(self, {}, double(smithProjection(a[kAlpha], a[kAlpha], v)), double(v.z),
                                       double(a[kAlpha])));
    }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_ndf_Gaussian() {
    static const NdfEntry& entry = immortal<NdfEntry>([] {
        NdfEntry e = makeEntry<NdfEntry>(ModelSlot::Ndf, 4, "gaussian", "Gaussian in the polar angle, normalized by quadrature");
        e.canonical = {{"alpha", ValueType::Float, kMinAlpha}};
        e.forms = {ModelForm{{{"alpha", ValueType::Float, {kAlpha}}}}};
        e.tabulatedLambda = true;
        // Lambda's tail toward the normal falls like exp(-c / alpha^2) and
        // so changes faster across rows than the shape-invariant NDFs':
        // steps of 1/16 (1/32 in log alpha) keep it within 1e-6 (1/8 left
        // 1.1e-6 near alpha = 0.4). Beyond alpha = 1, alpha = 1's.
        e.lambdaRows = [](const std::vector<double>&) { return LambdaRows{kMinAlpha, 1, 4, 1.0 / 16}; };
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
            {"hcc_gaussian_smith_alpha_min", "ndf = gaussian(1e-4); masking = smith_height_correlated;"},
            {"hcc_gaussian_smith_ranged", "input alpha = 0.5 in 0 .. 3; ndf = gaussian(alpha); "
                                          "masking = smith_separable; fresnel = conductor(eta = 0.2, k = 3);"},
        };
        e.formulas = makeFormulas<NdfFormulas, GaussianFormulas>();
        return e;
    }());
    return {&entry};
}

}  // namespace facet::models
