// HardCases: the hard-case sample of SPEC section 7, shared by the
// hard-case tests, `facet verify` and `facet bench`.
//
// hardCases(material) lists (wi, wo, input slot values, label) for one
// checked material:
//   - directions: grazing n.wi and n.wo in {0, float denormal, double
//     denormal, 1e-7, 1e-4, 1e-2} against each other and against 0.5 and 1,
//     at several azimuths; wi = wo = n; n.h = 1 exactly (mirror pairs);
//     n.h within 1e-7 of 1 and h tilted by 1e-7; wi + wo nearly zero; one or
//     both directions below the horizon (also -0 and a negative denormal);
//     nearly-unit directions (valid), non-unit, zero, NaN and infinite
//     components (invalid); for a lobe that scatters below the surface,
//     SPEC 11's pairs across it (WholeSphereCases.h);
//   - inputs: every float slot swept over range ends, values outside the
//     range, 0, denormal, tiny, the roughness ladder {1e-5 (below the 1e-4
//     clamp), 1e-4, 1e-3, 0.01, 1, 2}, 1 +- 1e-6 (GTR neighbourhoods, eta = 1),
//     exponents up to 2e8 and beyond, huge, FLT_MAX, negative values, NaN and
//     +-Inf; rgb inputs with all three channels together and one channel at
//     a time; pairs of float inputs at opposite ends (anisotropy 1e4); the
//     roughness ladder crossed with the grazing directions.
// Model-parameter hard cases need materials that expose those parameters:
// hardCaseMaterials() generates one material per NDF form x masking x
// Fresnel combination the checker accepts, with every model parameter an
// unranged per-evaluation input (so the input sweep drives alpha, the
// exponent, gamma, eta, k, f0 and schlick k anywhere), plus materials with
// constant extreme parameters (which the JIT folds, so they exercise other
// code) and range-clamped variants.
//
// Values are rounded to float by default: the JIT kernels take float, and
// the reference must see the very same inputs to be comparable.
//
// The module also holds the reference-side analysis: the double interpreter
// against the __float128 one, with a componentwise condition number of f
// estimated in __float128 (compareWithQuad).
#pragma once

#include "KullaConty.h"
#include "Material.h"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace facet {

struct HardCase {
    std::array<double, 3> wi{}, wo{};
    std::vector<double> slots;  // material.slotCount values
    std::string label;
    // SPEC 2: a non-finite input or direction, or a direction whose length is
    // not 1 within 1e-3, must give f = 0 and be counted invalid.
    bool invalidInput = false;
};

struct HardCaseOptions {
    bool roundToFloat = true;  // round every value to float (what kernels see)
    bool inputSweeps = true;   // the per-input value sweeps (else directions only)
};

std::vector<HardCase> hardCases(const CheckedMaterial& material, const HardCaseOptions& options = {});

// The slot values of a case as text: "roughness=0.5 tint.r=1 ...".
std::string describeSlots(const CheckedMaterial& material, const std::vector<double>& slots);
// "wi=(x,y,z) wo=(x,y,z) roughness=... [label]", full precision.
std::string describeCase(const CheckedMaterial& material, const HardCase& c);

// A generated material: its name, source text and what it is for.
struct HardCaseMaterial {
    std::string name;
    std::string text;
    std::string ndf, masking, fresnel;  // model names, for grouping reports
};

// Every example (ModelExample) of every NDF x masking x Fresnel model of
// the catalog that can be combined (a Smith masking only with an NDF that
// has a Smith Lambda, a whole-lobe NDF only with masking = none, a sparse
// example only with the representative models), model parameters as
// unranged inputs; then every model's own hard cases (ModelHardCase). Only
// texts the checker accepts are returned; `rejected` (if given) receives the
// generated texts it refused, which should be none.
std::vector<HardCaseMaterial> hardCaseMaterials(std::vector<std::string>* rejected = nullptr);

// ---- the double reference against __float128 --------------------------------

struct QuadComparison {
    bool doubleValid = true, quadValid = true;
    std::array<double, 3> d{};      // double interpreter
    std::array<double, 3> q{};      // __float128 interpreter, rounded to double
    double relError = 0;            // max over channels of |d - q| / max(|q|, 2^-900)
    int channel = 0;                // channel of relError
    bool validMismatch = false;     // valid flags differ (and the quad value is not at double's range limit)
};

// The double reference interpreter and the __float128 one for one material
// (both built once: a kulla_conty material shares one energy table, the
// caller's `table` when it has one, else one built here).
class QuadReference {
public:
    explicit QuadReference(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> table = nullptr);
    ~QuadReference();
    QuadReference(const QuadReference&) = delete;
    QuadReference& operator=(const QuadReference&) = delete;

    // Evaluates `c` in double and in __float128. The relative error of a
    // channel is |d - q| / max(|q|, 2^-900): results near double's subnormal
    // range (whose factors may be subnormal) compare absolutely. A quad value beyond DBL_MAX counts as
    // invalid for double (SPEC 2: overflow is an invalid lane); validity is
    // not a mismatch when the quad value is within a factor 16 of DBL_MAX
    // (where an intermediate product may overflow first).
    QuadComparison compare(const HardCase& c) const;

    // True if a direction component is a double subnormal: the half vector
    // then has a subnormal component and double cannot hold f to 1e-12
    // (only float-range inputs reach the kernels; see docs/numerics.md).
    static bool subnormalDirection(const HardCase& c);

    // The componentwise relative condition number of f at this input,
    // estimated in __float128:
    //   kappa = max over channels of sum_j |f(x with x_j (1 + u)) - f(x)| / (u |f(x)|)
    // over every input component x_j (the six direction components and each
    // slot), u = 2^-53: the relative change of f under a 1-ulp relative
    // perturbation of each input in double (componentwise: a grazing n.w =
    // 1e-7 is perturbed by 1e-23, not by 1e-16; the evaluators keep the
    // relative accuracy of small components). A backward-stable double
    // evaluation has an error of at most a small multiple of kappa * u. Inf
    // where a perturbation flips a branch (horizon, TIR, clamp, validity) or
    // f = 0 but not f(x + dx); 0 where f = 0 at every perturbation.
    double condition(const HardCase& c) const;

    // __float128 evaluation rounded to double (valid = false: invalid lane).
    bool evalQuad(const HardCase& c, std::array<double, 3>& rgb) const;

private:
    struct Impl;
    Impl* impl_;
};

}  // namespace facet
