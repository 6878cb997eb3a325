// The diffuse base: none, or Lambert's albedo / pi.
#include "QuadMath.h"
#include "Immortal.h"
#include "models/ModelMath.h"

namespace facet::models {
namespace {

constexpr int kAlbedo = 0;

template <typename Real>
struct LambertDiffuse final : DiffuseFormulas<Real> {
    Real value(const ModelArgs<Real>& a, int ch) const override { return a.channel(kAlbedo, ch) / kPi<Real>; }
};

}  // namespace

std::vector<const ModelInfo*> facetModels_diffuse_Diffuse() {
    static const DiffuseEntry& none = immortal<DiffuseEntry>(makeEntry<DiffuseEntry>(ModelSlot::Diffuse, 0, "none", "no diffuse base"));
    static const DiffuseEntry& lambert = immortal<DiffuseEntry>([] {
        DiffuseEntry e = makeEntry<DiffuseEntry>(ModelSlot::Diffuse, 1, "lambert", "Lambertian base, albedo / pi");
        e.canonical = {{"albedo", ValueType::Rgb, 0}};
        e.forms = {ModelForm{{{"albedo", ValueType::Rgb, {kAlbedo}}}}};
        e.present = true;
        e.formulas = makeFormulas<DiffuseFormulas, LambertDiffuse>();
        return e;
    }());
    return {&none, &lambert};
}

}  // namespace facet::models
