// The energy slot: none; Kulla & Conty 2017 multiple-scattering
// compensation from the tabulated albedo of the material's NDF and masking
// (compiler/reference/KullaConty.h builds the tables); or random_walk, the
// multiple scattering of Heitz et al. 2016 by a random walk on the Smith
// microsurface (compiler/reference/MicrosurfaceWalk.h is its reference),
// which the kernels walk per lane (compiler/lowering/WalkEmitter.h).
#include "models/ModelMath.h"
#include "Immortal.h"

namespace facet::models {

std::vector<const ModelInfo*> facetModels_energy_Energy() {
    auto entry = [](int id, const char* name, const char* summary, bool compensates) {
        EnergyEntry e = makeEntry<EnergyEntry>(ModelSlot::Energy, id, name, summary);
        e.compensates = compensates;
        return e;
    };
    static const EnergyEntry& none = immortal<EnergyEntry>(entry(0, "none", "no compensation", false));
    static const EnergyEntry& kullaConty = immortal<EnergyEntry>([&] {
        EnergyEntry e = entry(1, "kulla_conty", "Kulla & Conty 2017 multiple-scattering compensation", true);
        // f_ms on the hard cases (its tables need constant shape parameters).
        e.hardCases = {
            {"hcc_kc_ggx_conductor",
             "input alpha = 0.3; ndf = ggx(alpha); masking = smith_height_correlated; "
             "fresnel = conductor(eta = rgb(0.14, 1, 1.38), k = rgb(3.7, 0, 1.9)); energy = kulla_conty;"},
            {"hcc_kc_beckmann_dielectric",
             "input alpha = 0.3; input eta = rgb(1.5, 1, 0.7); ndf = beckmann(alpha); masking = smith_separable; "
             "fresnel = dielectric(eta); energy = kulla_conty;"},
            {"hcc_kc_ggx_aniso_schlick",
             "input alpha_x = 0.05; input alpha_y = 0.5; input f0 = rgb(0.04, 0.5, 0.9); "
             "ndf = ggx(alpha_x = alpha_x, alpha_y = alpha_y); masking = smith_height_direction_correlated; "
             "fresnel = schlick(f0 = f0); energy = kulla_conty;"},
        };
        return e;
    }());
    static const EnergyEntry& randomWalk = immortal<EnergyEntry>([&] {
        EnergyEntry e = entry(2, "random_walk", "Heitz et al. 2016 multiple scattering by a random walk", false);
        e.walks = true;
        // The walk from grazing and normal views, alpha per lane up to 1.
        e.hardCases = {
            {"hcc_rw_ggx_conductor",
             "input alpha = 0.6 in 0.001 .. 1; ndf = ggx(alpha); masking = smith_height_correlated; "
             "fresnel = conductor(eta = rgb(0.2, 0.9, 1.1), k = rgb(3.9, 2.4, 2.2)); energy = random_walk;"},
        };
        return e;
    }());
    return {&none, &kullaConty, &randomWalk};
}

}  // namespace facet::models
