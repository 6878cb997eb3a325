// WholeSphereCases: SPEC 11's hard direction pairs (see WholeSphereCases.h).
#include "WholeSphereCases.h"

#include "KullaConty.h"  // inputUsed, constantOf

#include <fmt/format.h>

#include <cmath>

namespace facet {
namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;
using Dir = std::array<double, 3>;

Dir polar(double thetaDeg, double phi) {
    double t = thetaDeg * kPi / 180;
    return {std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)};
}

// The lobe's eta where it is a constant (the critical angle depends on it).
double lobeEta(const CheckedMaterial& m, const CheckedLobe& lobe) {
    int p = fresnelEntry(*lobe.fresnel.model).refractiveIndexParam;
    if (p < 0 || !lobe.fresnel.has(p) || inputUsed(*lobe.fresnel.args[size_t(p)], m)) return 1.5;
    double eta = constantOf(*lobe.fresnel.args[size_t(p)], m);
    return std::isfinite(eta) && eta > 0 ? eta : 1.5;
}

}  // namespace

std::vector<DirectionPair> wholeSphereDirectionPairs(const CheckedMaterial& m) {
    std::vector<DirectionPair> out;
    const CheckedLobe* lobe = nullptr;
    for (const CheckedLobe& l : m.lobes)
        if (l.wholeSphere()) lobe = &l;
    if (!lobe) return out;
    auto add = [&](Dir wi, Dir wo, const std::string& label) {
        out.push_back({wi, wo, label});
        out.push_back({wo, wi, label + " (swapped)"});
    };
    // The critical angle, seen from the denser side.
    double eta = lobeEta(m, *lobe);
    double dense = eta > 1 ? -1 : 1;  // the denser side's sign of z
    double ratio = eta > 1 ? 1 / eta : eta;
    if (ratio < 1) {
        double critical = std::asin(ratio) * 180 / kPi;
        for (double d : {-1e-6, -1e-12, 0.0, 1e-12, 1e-6}) {
            Dir inside = polar(critical + d * 180 / kPi, 0.2);
            inside[2] *= dense;
            Dir far = polar(89.9999, 0.2 + kPi), mirror = {-inside[0], -inside[1], inside[2]};
            far[2] *= -dense;
            std::string at = fmt::format("critical angle {:+g}", d);
            add(far, inside, at + ", out grazing");
            add(mirror, inside, at + ", its mirror");
        }
    }
    // Straight through, and just off it.
    for (double theta : {0.0, 30.0, 89.0, 89.999999}) {
        Dir wo = polar(theta, 1.1);
        add({-wo[0], -wo[1], -wo[2]}, wo, fmt::format("wi = -wo at {} deg", theta));
        add(polar(180 - theta - 1e-7, 1.1 + kPi), wo, fmt::format("wi 1e-7 off -wo at {} deg", theta));
        add({wo[0], wo[1], -wo[2]}, wo, fmt::format("mirror through the surface at {} deg", theta));
    }
    // Grazing on both sides.
    for (double z : {1e-7, 1e-15, 1e-300}) {
        double s = std::sqrt(1 - z * z);
        add({s, 0, -z}, {0.3, 0.1, std::sqrt(0.9)}, fmt::format("wi grazing {:g} below", z));
        add({s, 0, -z}, {-s, 0, z}, fmt::format("both grazing {:g}, across", z));
        add({s, 0, z}, {-s, 0, -z}, fmt::format("both grazing {:g}, across, mirrored", z));
    }
    return out;
}

}  // namespace facet
