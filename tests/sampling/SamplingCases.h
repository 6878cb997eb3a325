// SamplingCases: the materials the sampling tests run on, generated from the
// model catalog: every NDF (isotropic, and 10:1 anisotropic where it has
// alpha_x and alpha_y) x every masking the checker accepts with it x
// diffuse none or lambert, at a given roughness; a model added to the
// catalog is covered without an edit here.
#pragma once

#include "Checker.h"
#include "Interpreter.h"

#include <memory>
#include <string>
#include <vector>

namespace sampling_test {

struct Combo {
    const facet::NdfEntry* ndf;
    const facet::MaskingEntry* masking;
    bool anisotropic;
    bool diffuse;      // lambert(0.5) base
    bool compensated;  // energy = kulla_conty
    std::string name() const;
};

// Every combination above, in catalog order (NDF, anisotropy, masking,
// diffuse), plus kulla_conty variants of the representative NDF with the
// representative maskings.
const std::vector<Combo>& combos();

// A parsed and checked material kept alive with its interpreter.
struct TestMaterial {
    std::string text;
    facet::CheckedProgram program;
    const facet::CheckedMaterial* material = nullptr;
    std::unique_ptr<facet::Interpreter<double>> interpreter;
    facet::ResolvedMaterial<double> resolved;  // at the default inputs
};

// The material of a combination at roughness alpha (alpha_y = alpha / 10
// when anisotropic; other NDFs through their argsAtAlpha, shape parameters
// at typical * {1, 0.75, 1.5}[variant % 3]). `fresnel` is the statement's
// right-hand side. Null if the checker rejects it (with the diagnostics in
// *error).
std::unique_ptr<TestMaterial> makeMaterial(const Combo& c, double alpha, int variant = 0,
                                           const std::string& fresnel = "schlick(0.5)", std::string* error = nullptr);

// Any material text (one material) with default inputs; null if rejected.
std::unique_ptr<TestMaterial> loadMaterial(const std::string& text, std::string* error = nullptr);

}  // namespace sampling_test
