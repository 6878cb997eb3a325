// Helpers the transmission tests share: a checked material with its
// reference interpreter, the material text of a rough interface, directions,
// and integration over the sphere.
#pragma once

#include "Checker.h"
#include "Interpreter.h"
#include "SamplingCheck.h"
#include "Specialize.h"

#include <doctest/doctest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <string>

namespace transmission_test {

using facet::Vec3;
using V3 = Vec3<double>;
constexpr double kPi = std::numbers::pi;

// The checked material of `text` and its interpreter (kept alive together).
struct Reference {
    facet::CheckedProgram program;
    std::unique_ptr<facet::Interpreter<double>> interp;
    facet::ResolvedMaterial<double> lobe;
    explicit Reference(const std::string& text, facet::Transport transport = facet::Transport::Radiance) {
        facet::DiagnosticEngine diags;
        program = facet::loadProgramText(text, "glass.mat", diags);
        INFO(text, "\n", diags.str());
        REQUIRE_FALSE(diags.hasErrors());
        interp = std::make_unique<facet::Interpreter<double>>(*program.find("t"));
        interp->setTransport(transport);
        lobe = interp->resolve(nullptr);
    }
    double f(const V3& wi, const V3& wo) const {
        double i[3] = {wi.x, wi.y, wi.z}, o[3] = {wo.x, wo.y, wo.z};
        facet::EvalResult<double> e = interp->eval(i, o, nullptr);
        REQUIRE(e.valid);
        return e.rgb[0];
    }
};

inline std::string glass(const std::string& ndf, double eta, const std::string& masking = "smith_height_correlated",
                  const std::string& scatter = "both") {
    return fmt::format("material t {{ ndf = {}; masking = {}; fresnel = dielectric({}); scatter = {}; }}\n", ndf,
                       masking, eta, scatter);
}

inline V3 direction(double thetaDeg, double phi) {
    double t = thetaDeg * kPi / 180;
    return {std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)};
}

inline V3 uniformSphere(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0, 1);
    double z = 1 - 2 * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u(rng);
    return {r * std::cos(phi), r * std::sin(phi), z};
}

inline double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

inline double relDiff(double a, double b) {
    double scale = std::max(std::abs(a), std::abs(b));
    return scale < 1e-300 ? 0 : std::abs(a - b) / scale;
}

// Int pdf over the sphere (or a part of it) by integrateCells on a fine grid.
inline double integrate(const facet::PdfFunction& fn, int rows = 48, int columns = 96) {
    facet::SphereGrid grid = facet::SphereGrid::equalArea(rows, columns);
    double sum = 0;
    for (double cell : facet::integrateCells(grid, fn, 1e-8)) sum += cell;
    return sum;
}

// A grid graded toward the refracted direction of wo about n (toward the
// mirror direction past the critical angle), with the edges at the horizon.
inline facet::SphereGrid transmissionGrid(const V3& wo, double alpha, double eta) {
    double thetaO = std::acos(std::clamp(wo.z, -1.0, 1.0)), phiO = std::atan2(wo.y, wo.x);
    double relative = wo.z > 0 ? eta : 1 / eta;
    double s = std::sin(thetaO) / relative;
    double peakTheta, spread;
    if (s < 1) {
        double t = std::asin(s);
        peakTheta = wo.z > 0 ? kPi - t : t;
        spread = std::min(alpha, 1.0) * std::abs(1 - 1 / relative) / 2;
    } else {
        peakTheta = kPi - thetaO;  // the mirror direction, on wo's side
        spread = std::min(alpha, 1.0) / 2;
    }
    double first = std::max(spread, 2e-3);
    return facet::SphereGrid::forLobe(thetaO, peakTheta, phiO + kPi, first, std::min(0.2, 4 * first));
}

}  // namespace transmission_test
