// EnergyTestUtil: helpers shared by the Kulla-Conty tests.
//
// Materials go through the real parser, checker and interpreter. Tables come
// from one memory-only TableCache per test process (built once per pair).
// The albedo quadrature is the physics tests' (PhysicsUtil.h): graded
// Gauss-Legendre panels over the half vector, written independently of the
// table code in compiler/reference/KullaConty.cpp.
#pragma once

#include "Checker.h"
#include "Interpreter.h"
#include "KullaContyEval.h"
#include "PhysicsUtil.h"
#include "TableCache.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace energy {

using physics::kPi;
using facet::Vec3;

// Runs fn(i) for i in [0, n) on all cores (at most 8 threads).
template <typename F>
void parallelFor(size_t n, const F& fn) {
    unsigned nt = std::clamp(std::thread::hardware_concurrency(), 1u, 8u);
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < nt; ++t)
        pool.emplace_back([&, t] {
            for (size_t i = t; i < n; i += nt) fn(i);
        });
    for (auto& th : pool) th.join();
}

inline facet::TableCache& memoryTables() {
    static facet::TableCache cache("");
    return cache;
}

// One checked material (`material t { body }`) with an interpreter that uses
// the shared table cache.
struct TestMaterial {
    facet::CheckedProgram program;
    const facet::CheckedMaterial* material = nullptr;
    std::unique_ptr<facet::Interpreter<double>> interp;

    explicit TestMaterial(const std::string& body) {
        facet::DiagnosticEngine diags;
        std::string text = "material t {\n" + body + "\n}\n";
        program = facet::loadProgramText(text, "energy.mat", diags);
        INFO("material source:\n", text, "\ndiagnostics:\n", diags.str());
        REQUIRE_FALSE(diags.hasErrors());
        material = program.find("t");
        REQUIRE(material != nullptr);
        std::shared_ptr<const facet::EnergyTable> table;
        if (material->singleLobe().compensatesEnergy()) table = memoryTables().getFor(*material);
        interp = std::make_unique<facet::Interpreter<double>>(*material, table);
    }
    // Resolved with the given slot values (null: defaults).
    facet::ResolvedMaterial<double> resolve(const std::vector<double>& slots = {}) const {
        facet::ResolvedMaterial<double> r = interp->resolve(slots.empty() ? nullptr : slots.data());
        REQUIRE(r.valid);
        return r;
    }
};

// Directional albedo A(wo) = Int f(wi, wo) (n.wi) dwi per channel, wo at
// polar angle thetaO (azimuth 0), integrated over the half vector h
// (dwi = 4 (wo.h) dwh) like tests/physics/AlbedoTests.cpp: theta_h on panels
// graded toward 0 (scale: the lobe width) and toward the two square-root kinks
// of the azimuthal cut; the azimuth covers exactly the h whose wi is above
// the horizon.
inline std::array<double, 3> albedoRgb(const facet::ResolvedMaterial<double>& m, double scale, double thetaO) {
    using namespace physics;
    Vec3<double> wo = dir(thetaO, 0);
    double thetaFull = (kPi / 2 - thetaO) / 2, thetaEnd = (kPi / 2 + thetaO) / 2;
    Hemisphere h;
    h.thetaBreaks = gradedBreaks(0, thetaEnd, {{0, scale / 8}, {thetaFull, 1e-4}, {thetaEnd, 1e-4}}, 0.08);
    h.center = 0;
    h.phiPanels = 8;
    auto hw = [&](double th) {
        return halfWidth(-std::cos(thetaO) * std::cos(2 * th), std::sin(thetaO) * std::sin(2 * th));
    };
    std::array<double, 3> out{};
    for (int ch = 0; ch < 3; ++ch) {
        auto f = [&](const Vec3<double>& hv) {
            double oh = dot(wo, hv);
            Vec3<double> wi{2 * oh * hv.x - wo.x, 2 * oh * hv.y - wo.y, 2 * oh * hv.z - wo.z};
            if (wi.z <= 0) return 0.0;
            return m.brdf(wi, wo)[ch] * wi.z * 4 * oh;
        };
        out[ch] = integrateHemisphere(f, hw, h);
        if (std::string_view(m.fresnel->name) == "none") {
            out[1] = out[2] = out[0];
            break;
        }
    }
    return out;
}

inline double albedo(const facet::ResolvedMaterial<double>& m, double scale, double thetaO) {
    return albedoRgb(m, scale, thetaO)[0];
}

}  // namespace energy
