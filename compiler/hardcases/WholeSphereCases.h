// WholeSphereCases: the direction pairs SPEC 11 lists as hard for a lobe
// that scatters below the surface, added to hardCases() for a material with
// one: at the critical angle seen from inside (and 1e-12, 1e-6 either side
// of it), wi = -wo straight through (at 0, 30, 89 and 89.999999 degrees) and
// 1e-7 off it, a direction and its mirror image through the surface, and
// grazing pairs across the surface (n.w of 1e-7, 1e-15, 1e-300 on one side
// against the other). eta is the lobe's when it is a constant, else 1.5.
#pragma once

#include "Material.h"

#include <array>
#include <string>
#include <vector>

namespace facet {

struct DirectionPair {
    std::array<double, 3> wi, wo;
    std::string label;
};

// Empty for a material without a whole-sphere lobe.
std::vector<DirectionPair> wholeSphereDirectionPairs(const CheckedMaterial& material);

}  // namespace facet
