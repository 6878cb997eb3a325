// CosineAlbedo: the directional albedo Int f(wi) (n.wi) dwi by Monte Carlo
// with wi drawn from the cosine lobe, one draw per path from WalkRandom(seed,
// path): the next-event albedo the walk tests set against the walks' exits.
#pragma once

#include "MicrosurfaceWalk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace stochastic {

// `fCos(wi, random)` returns an estimate of f(wi) (n.wi) per channel; the
// result is the mean of fCos / pdf, pdf = (n.wi) / pi, with its standard error.
template <typename FCos>
facet::WalkEstimate cosineAlbedo(int64_t paths, uint64_t seed, const FCos& fCos) {
    constexpr double kPi = std::numbers::pi;
    facet::WalkAccumulator acc;
    for (int64_t k = 0; k < paths; ++k) {
        facet::WalkRandom random(seed, uint64_t(k));
        double r = std::sqrt(random.next()), phi = 2 * kPi * random.next();
        facet::Vec3<double> wi{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - r * r))};
        std::array<double, 3> x = fCos(wi, random);
        for (double& v : x) v = wi.z > 0 ? v * kPi / wi.z : 0.0;
        acc.add(x);
    }
    return acc.estimate();
}

}  // namespace stochastic
