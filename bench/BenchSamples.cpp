// BenchSamples: regular and hard-case samples (see BenchSamples.h).
#include "BenchSamples.h"

#include "HardCases.h"

#include <cmath>
#include <random>

namespace facet::bench {

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

// The range an input is drawn from: its declared range, else [0, 2 default]
// (a scale around the author's value), per channel.
void inputRange(const CheckedInput& in, int channel, double& lo, double& hi) {
    if (in.hasRange) {
        lo = in.lo;
        hi = in.hi;
    } else {
        lo = 0;
        hi = 2 * std::fabs(in.defaultValue[channel]) + 0.1;
    }
}

}  // namespace

LaneBatch regularSample(const CheckedMaterial& material, size_t n, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    LaneBatch s;
    s.slots.assign(material.slotCount, {});
    for (auto& d : s.dir) d.reserve(n);
    for (auto& c : s.slots) c.reserve(n);
    std::vector<double> inputs(material.slotCount);
    // A lobe that scatters below the surface (SPEC 11) is defined over the
    // whole sphere: both directions uniform on it.
    const bool wholeSphere = !material.combinesLobes() && material.singleLobe().wholeSphere();
    for (size_t i = 0; i < n; ++i) {
        double w[2][3];
        for (auto& v : w) {
            // Uniform on the hemisphere: z uniform in [0, 1]. 5% are mirrored
            // below the horizon, which the kernels must return as 0.
            double z = u(rng), phi = 2 * kPi * u(rng);
            if (u(rng) < (wholeSphere ? 0.5 : 0.05)) z = -z;
            double r = std::sqrt(std::max(0.0, 1 - z * z));
            v[0] = r * std::cos(phi), v[1] = r * std::sin(phi), v[2] = z;
        }
        for (const CheckedInput& in : material.inputs)
            for (int c = 0; c < in.slotCount(); ++c) {
                double lo, hi;
                inputRange(in, c, lo, hi);
                inputs[in.firstSlot + c] = lo + (hi - lo) * u(rng);
            }
        s.push(w[0], w[1], inputs);
    }
    s.finish();
    return s;
}

namespace {

// The shared generator of compiler/hardcases/HardCases.h, as a lane batch.
LaneBatch fromHardCases(const CheckedMaterial& m, const std::vector<HardCase>& cases) {
    LaneBatch s;
    s.slots.assign(m.slotCount, {});
    for (const HardCase& c : cases) s.push(c.wi.data(), c.wo.data(), c.slots);
    s.finish();
    return s;
}

}  // namespace

// The one place that chooses the hard-case generator.
LaneBatch hardCaseSample(const CheckedMaterial& material) { return fromHardCases(material, hardCases(material)); }

std::string hardCaseSampleDescription() {
    return "compiler/hardcases/HardCases.h hardCases(): SPEC 7 grazing/mirror/retro/opposite/below-horizon directions, "
           "input sweeps (range ends, outside the range, denormal, roughness ladder 1e-5..2, anisotropy 1e4, "
           "NaN/Inf), and invalid lanes";
}

}  // namespace facet::bench
