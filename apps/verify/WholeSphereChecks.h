// WholeSphereChecks: the physics checks of `facet verify` for a lobe that
// scatters over the whole sphere (SPEC 11), on the reference interpreter:
//   white furnace   R + T = Int f |n.wi| dwi (importance transport: the
//                   power scattered) from outside and from inside, per alpha
//                   at the material's eta, without and with energy
//                   compensation (the material's own tables, or tables built
//                   for it when it has none): <= 1 without, within 1% of 1
//                   with (SPEC 11's bound);
//   reciprocity     f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2 on random pairs
//                   over the sphere (radiance transport).
// Integration: integrateCells (ChiSquare.h) on an equal-area grid, adaptive.
#pragma once

#include "Interpreter.h"
#include "PhysicsChecks.h"

#include <string>
#include <vector>

namespace facet {

struct FurnaceRow {
    double alpha = 0, eta = 0;
    bool inside = false;
    // Over the view angles: the least and largest R + T.
    double plainMin = 0, plainMax = 0;
    double compensatedMin = 0, compensatedMax = 0;
    bool compensated = false;  // the columns with compensation were computed
};

struct WholeSphereReport {
    std::vector<FurnaceRow> furnace;
    std::string compensationNote;      // why there are no compensated columns ("" when there are)
    std::vector<PhysicsCheck> checks;  // the enforced bounds, and reciprocity
};

// `interp` is the material's (a single whole-sphere lobe), with its tables.
WholeSphereReport wholeSphereChecks(const CheckedMaterial& material, const Interpreter<double>& interp);

}  // namespace facet
