// ModelCatalog: the registry of entries and the lookups.
//
// The build generates ModelRegistry.inc with one line
// FACET_MODEL_FILE(<slot>, <Stem>) per file compiler/models/<slot>/<Stem>.cpp;
// each such file defines facetModels_<slot>_<Stem>(), returning its entries.
#include "models/ModelCatalog.h"
#include "Immortal.h"

#include "Diagnostics.h"

#include <algorithm>
#include <set>

namespace facet {

namespace models {
#define FACET_MODEL_FILE(slot, stem) std::vector<const ModelInfo*> facetModels_##slot##_##stem();
#include "ModelRegistry.inc"
#undef FACET_MODEL_FILE
}  // namespace models

template <typename Real>
Real NdfFormulas<Real>::cosLambda(const ModelArgs<Real>&, const Vec3<Real>&) const {
    internal_error << "Smith Lambda requested for an NDF without a closed form";
}
template <typename Real>
Real NdfFormulas<Real>::wholeLobe(const ModelArgs<Real>&, const Vec3<Real>&, Real, Real) const {
    internal_error << "whole lobe requested for a microfacet NDF";
}
template struct NdfFormulas<float>;
template struct NdfFormulas<double>;
template struct NdfFormulas<long double>;
template struct NdfFormulas<__float128>;

namespace {

// All entries in slot order, each slot in id order; the catalog's own
// consistency is checked once (an inconsistent entry is a bug in Facet, not
// in a material).
std::vector<const ModelInfo*> buildCatalog() {
    std::vector<const ModelInfo*> all;
#define FACET_MODEL_FILE(slot, stem) \
    for (const ModelInfo* m : models::facetModels_##slot##_##stem()) all.push_back(m);
#include "ModelRegistry.inc"
#undef FACET_MODEL_FILE
    std::stable_sort(all.begin(), all.end(), [](const ModelInfo* a, const ModelInfo* b) {
        return a->slot != b->slot ? a->slot < b->slot : a->id < b->id;
    });
    std::set<std::pair<int, std::string>> names;
    for (size_t i = 0; i < all.size(); ++i) {
        const ModelInfo& m = *all[i];
        int expectedId = i > 0 && all[i - 1]->slot == m.slot ? all[i - 1]->id + 1 : 0;
        internal_assert(m.id == expectedId) << modelSlotName(m.slot) << " model '" << m.name << "' has id " << m.id
                                            << ", expected " << expectedId << " (ids of a slot are 0..n-1)";
        internal_assert(m.canonical.size() <= size_t(kMaxModelParams)) << m.name << " has too many parameters";
        internal_assert(!m.forms.empty()) << m.name << " has no form";
        internal_assert(names.insert({int(m.slot), m.name}).second)
            << "two " << modelSlotName(m.slot) << " models named " << m.name;
        for (const char* alias : m.aliases)
            internal_assert(names.insert({int(m.slot), alias}).second) << "alias " << alias << " is taken";
    }
    return all;
}

}  // namespace
const std::vector<const ModelInfo*>& catalog() {
    static const std::vector<const ModelInfo*>& all = immortal<std::vector<const ModelInfo*>>(buildCatalog());
    return all;
}

std::vector<const ModelInfo*> catalogSlot(ModelSlot slot) {
    std::vector<const ModelInfo*> out;
    for (const ModelInfo* m : catalog())
        if (m->slot == slot) out.push_back(m);
    return out;
}

const ModelInfo* findModel(ModelSlot slot, std::string_view name) {
    for (const ModelInfo* m : catalog()) {
        if (m->slot != slot) continue;
        if (name == m->name) return m;
        for (const char* alias : m->aliases)
            if (name == alias) return m;
    }
    return nullptr;
}

const ModelInfo& modelInfo(ModelSlot slot, int id) {
    for (const ModelInfo* m : catalog())
        if (m->slot == slot && m->id == id) return *m;
    internal_error << "no model " << id << " in slot " << modelSlotName(slot);
}

const ModelInfo& modelNamed(ModelSlot slot, std::string_view name) {
    const ModelInfo* m = findModel(slot, name);
    internal_assert(m) << "no " << modelSlotName(slot) << " model named " << std::string(name);
    return *m;
}

int paramIndex(const ModelInfo& m, std::string_view name) {
    for (size_t p = 0; p < m.canonical.size(); ++p)
        if (name == m.canonical[p].name) return int(p);
    return -1;
}

namespace {
template <typename Entry>
const Entry& entryOf(const ModelInfo& m, ModelSlot slot) {
    internal_assert(m.slot == slot) << "model '" << m.name << "' is not a " << modelSlotName(slot) << " model";
    return static_cast<const Entry&>(m);
}
}  // namespace

const NdfEntry& ndfEntry(const ModelInfo& m) { return entryOf<NdfEntry>(m, ModelSlot::Ndf); }
const MaskingEntry& maskingEntry(const ModelInfo& m) { return entryOf<MaskingEntry>(m, ModelSlot::Masking); }
const FresnelEntry& fresnelEntry(const ModelInfo& m) { return entryOf<FresnelEntry>(m, ModelSlot::Fresnel); }
const EnergyEntry& energyEntry(const ModelInfo& m) { return entryOf<EnergyEntry>(m, ModelSlot::Energy); }
const DiffuseEntry& diffuseEntry(const ModelInfo& m) { return entryOf<DiffuseEntry>(m, ModelSlot::Diffuse); }

}  // namespace facet
