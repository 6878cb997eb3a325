// The model catalog checks itself: every entry has what every consumer reads
// (forms that reach each parameter, domains, the hooks of its slot, finite
// reference values in all three reference types) and is covered by the
// generated hard-case sample. A new entry that misses any of it fails here.
#include "QuadMath.h"

#include "HardCases.h"
#include "Interpreter.h"
#include "models/ModelCatalog.h"

#include <doctest/doctest.h>

#include <cmath>
#include <set>
#include <string>

using namespace facet;

namespace {

template <typename Real>
bool finiteReal(Real x) {
    using std::isfinite;
    return isfinite(x);
}

// The reference formulas of an NDF at roughness 0.3 (typical shape), at the
// normal and at a grazing direction, in one real type.
template <typename Real>
void checkNdfFormulas(const NdfEntry& ndf) {
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) shape.push_back(ndf.canonical[p].typical);
    ModelArgs<double> a = ndf.argsAtAlpha(0.3, shape);
    ModelArgs<Real> args = convertArgs<Real>(a);
    const NdfFormulas<Real>& f = ndf.formulas.template get<Real>();
    f.derive(args);
    Vec3<Real> n{0, 0, 1}, grazing{Real(0.9999995), 0, Real(0.001)};
    if (ndf.wholeLobe) {
        Real lobe = f.wholeLobe(args, n, Real(0.5), Real(0.5));
        CHECK((finiteReal(lobe) && lobe > 0));
    } else {
        Real d = f.D(args, n);
        CHECK((finiteReal(d) && d > 0));
    }
    if (ndf.smith) {
        Real cl = f.cosLambda(args, grazing);
        CHECK((finiteReal(cl) && cl >= 0));
        CHECK(f.cosLambda(args, n) == 0);  // nothing is masked at the normal
    }
}

}  // namespace

TEST_SUITE("catalog") {

TEST_CASE("every slot has models, ids 0..n-1, and a 'none' where a slot may be left out") {
    for (ModelSlot slot : {ModelSlot::Ndf, ModelSlot::Masking, ModelSlot::Fresnel, ModelSlot::Energy, ModelSlot::Diffuse}) {
        std::vector<const ModelInfo*> models = catalogSlot(slot);
        REQUIRE(!models.empty());
        for (size_t i = 0; i < models.size(); ++i) CHECK(models[i]->id == int(i));
        if (slot != ModelSlot::Ndf) CHECK(findModel(slot, "none") != nullptr);
    }
    CHECK(findModel(ModelSlot::Ndf, "none") == nullptr);  // ndf is required
}

TEST_CASE("every entry is complete") {
    for (const ModelInfo* m : catalog()) {
        CAPTURE(modelSlotName(m->slot));
        CAPTURE(m->name);
        CHECK(std::string(m->summary).size() > 0);
        REQUIRE(!m->forms.empty());
        // Every form fills valid canonical parameters, and every canonical
        // parameter is filled by some form.
        std::set<int> reached;
        for (const ModelForm& form : m->forms)
            for (const ModelForm::Param& p : form.params)
                for (int t : p.targets) {
                    REQUIRE(t >= 0);
                    REQUIRE(t < int(m->canonical.size()));
                    CHECK(m->canonical[t].type == p.type);
                    reached.insert(t);
                }
        CHECK(reached.size() == m->canonical.size());
        for (const ModelParam& p : m->canonical) CHECK(p.lo <= p.hi);
        for (int p : m->tableShapeParams) {
            REQUIRE(p < int(m->canonical.size()));
            CHECK(std::string(m->canonical[p].tableTag).size() > 0);
            CHECK(m->canonical[p].typical >= m->canonical[p].lo);
            CHECK(m->canonical[p].typical <= m->canonical[p].hi);
        }
        switch (m->slot) {
            case ModelSlot::Ndf: {
                const NdfEntry& ndf = ndfEntry(*m);
                REQUIRE(ndf.formulas.d != nullptr);
                REQUIRE(ndf.formulas.ld != nullptr);
                REQUIRE(ndf.formulas.q != nullptr);
                REQUIRE((ndf.equivalentAlphas != nullptr));
                REQUIRE((ndf.argsAtAlpha != nullptr));
                REQUIRE((ndf.describe != nullptr));
                // argsAtAlpha and equivalentAlphas are inverse.
                std::vector<double> shape;
                for (int p : ndf.tableShapeParams) shape.push_back(ndf.canonical[p].typical);
                for (double alpha : {0.05, 0.3, 0.8}) {
                    std::array<double, 2> back = ndf.equivalentAlphas(ndf.argsAtAlpha(alpha, shape));
                    CHECK(back[0] == doctest::Approx(alpha).epsilon(1e-12));
                    CHECK(back[1] == doctest::Approx(alpha).epsilon(1e-12));
                }
                checkNdfFormulas<double>(ndf);
                checkNdfFormulas<long double>(ndf);
                checkNdfFormulas<__float128>(ndf);
                break;
            }
            case ModelSlot::Masking: {
                const MaskingEntry& masking = maskingEntry(*m);
                REQUIRE(masking.formulas.d != nullptr);
                REQUIRE(masking.formulas.ld != nullptr);
                REQUIRE(masking.formulas.q != nullptr);
                break;
            }
            case ModelSlot::Fresnel: {
                const FresnelEntry& fresnel = fresnelEntry(*m);
                REQUIRE(fresnel.formulas.d != nullptr);
                REQUIRE(fresnel.formulas.ld != nullptr);
                REQUIRE(fresnel.formulas.q != nullptr);
                // F of every form, parameters at 1.5 clamped to the domain, is in [0, 1].
                for (const ModelForm& form : m->forms) {
                    ModelArgs<double> a;
                    for (const ModelForm::Param& p : form.params)
                        for (int t : p.targets) a.set(t, std::clamp(1.5, m->canonical[t].lo, m->canonical[t].hi));
                    for (double c : {1.0, 0.5, 1e-3}) {
                        double F = fresnel.formulas.d->F(a, c, (1 - c) * (1 + c), 0);
                        CHECK(F >= 0);
                        CHECK(F <= 1);
                    }
                }
                break;
            }
            case ModelSlot::Diffuse: {
                const DiffuseEntry& diffuse = diffuseEntry(*m);
                if (diffuse.present) {
                    REQUIRE(diffuse.formulas.d != nullptr);
                    REQUIRE(diffuse.formulas.ld != nullptr);
                    REQUIRE(diffuse.formulas.q != nullptr);
                }
                break;
            }
            case ModelSlot::Energy: break;
        }
    }
}

TEST_CASE("every model is covered by the generated hard-case sample") {
    std::vector<std::string> rejected;
    std::vector<HardCaseMaterial> materials = hardCaseMaterials(&rejected);
    CHECK(rejected.empty());
    std::set<std::string> ndfs, maskings, fresnels;
    std::string texts;
    for (const HardCaseMaterial& h : materials) {
        ndfs.insert(h.ndf);
        maskings.insert(h.masking);
        fresnels.insert(h.fresnel);
        texts += h.text;
    }
    for (const ModelInfo* m : catalog()) {
        CAPTURE(modelSlotName(m->slot));
        CAPTURE(m->name);
        switch (m->slot) {
            case ModelSlot::Ndf:
                CHECK(!m->examples.empty());
                CHECK(ndfs.count(m->name) == 1);
                break;
            case ModelSlot::Masking:
                CHECK(!m->examples.empty());
                CHECK(maskings.count(m->name) == 1);
                break;
            case ModelSlot::Fresnel:
                CHECK(!m->examples.empty());
                CHECK(fresnels.count(m->name) == 1);
                break;
            case ModelSlot::Energy:
            case ModelSlot::Diffuse:
                // Used by some hard-case material, unless it is the default.
                if (std::string_view(m->name) != "none")
                    CHECK(texts.find(std::string(modelSlotName(m->slot)) + " = " + m->name) != std::string::npos);
                break;
        }
    }
    // Every entry's own hard cases are in the sample.
    std::set<std::string> names;
    for (const HardCaseMaterial& h : materials) names.insert(h.name);
    for (const ModelInfo* m : catalog())
        for (const ModelHardCase& c : m->hardCases) {
            CAPTURE(c.name);
            CHECK(names.count(c.name) == 1);
        }
}

}  // TEST_SUITE
