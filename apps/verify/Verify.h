// Verify: the hard-case sample on the reference interpreter and on compiled
// kernels, with the statistics that `facet verify` prints and the hard-case
// tests assert (SPEC sections 2 and 7).
//
// Per lane of a backend:
//   - the output is finite and >= 0 (never NaN, Inf or negative);
//   - a case with a non-finite input or direction, or a non-unit direction,
//     gives f = 0 and is counted invalid; the batch call's return value is
//     the number of invalid lanes;
//   - a kernel may report further lanes invalid only where float cannot
//     hold the result or a model parameter (the reference's value or a
//     resolved parameter is beyond FLT_MAX), and then outputs 0;
//   - on lanes both sides find valid, the error against the double
//     interpreter (relativeError of ReferenceComparison.h) is within the
//     bound, or (for errors
//     above 8 u) the input is
//     ill-conditioned: the error is within 16 kappa u, kappa the condition
//     number of f at that input (QuadReference::condition, estimated in
//     __float128) and u the unit roundoff of the math mode (2^-24 exact,
//     1e-6 fast: its polynomials' stated accuracy). Such lanes are counted
//     and reported, not failed: float inputs cannot determine f better.
#pragma once

#include "HardCases.h"
#include "Interpreter.h"
#include "Kernel.h"
#include "ReferenceComparison.h"

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace facet {

// Error bounds of the JIT kernels against the double interpreter on the
// hard-case sample (valid, finite lanes), per math mode. Measured maxima
// are in docs/numerics.md; the bounds leave a margin over them.
constexpr double kHardCaseBoundExact = 1e-5;
constexpr double kHardCaseBoundFast = 1e-3;
inline double hardCaseBound(MathMode m) { return m == MathMode::Exact ? kHardCaseBoundExact : kHardCaseBoundFast; }
// Unit roundoff of a math mode for the ill-conditioning allowance.
inline double hardCaseRoundoff(MathMode m) { return m == MathMode::Exact ? 0x1p-24 : 1e-6; }
constexpr double kConditionAllowance = 16;  // error within 16 kappa u

// The double interpreter on a sample.
struct HardCaseReference {
    std::vector<EvalResult<double>> results;
    // The result or a resolved model parameter is beyond float range: a
    // float kernel may report the lane invalid.
    std::vector<char> floatOverflow;
};
HardCaseReference evaluateHardCaseReference(const Interpreter<double>& interp, const std::vector<HardCase>& cases);

// A kernel on a sample (its slots must be the material's: compiled without
// bindings). SIMD kernels run the whole sample in one batch call; scalar
// kernels through the scalar entry point, lane by lane. The per-lane
// invalid status is exact: lanes whose output is all zero are re-run alone
// through the batch entry (whose return value is then that lane's status).
struct KernelRun {
    std::vector<std::array<float, 3>> rgb;
    std::vector<char> invalid;
    int64_t batchCount = 0;  // the batch call's return value over the whole sample
    int64_t laneCount = 0;   // number of lanes found invalid one by one
};
KernelRun runKernel(const Kernel& kernel, const std::vector<HardCase>& cases);

struct SampleStats {
    std::string backend;
    size_t cases = 0;
    size_t nan = 0, inf = 0, negative = 0;
    size_t invalid = 0;            // lanes reported invalid
    size_t expectedInvalid = 0;    // cases with a non-finite or non-unit input
    size_t missedInvalid = 0;      // such a case not reported invalid, or with a non-zero output
    size_t unexpectedInvalid = 0;  // reported invalid where the reference is valid and float can hold it
    size_t invalidNonZero = 0;     // reported invalid with a non-zero output
    size_t validityMismatch = 0;   // valid here but invalid in the reference
    bool countMismatch = false;    // batch return value != number of invalid lanes
    size_t compared = 0, beyondBound = 0;
    size_t illConditioned = 0;  // values with an error above 8 u but within 16 kappa u
    double maxKappa = 0;        // of those
    double bound = 0, maxRel = 0;  // maxRel: over the values not explained by conditioning (failures included)
    double maxRelWithin = 0;       // the same over the values within the bound (the accuracy where it passes)
    double maxRelNormal = 0;       // maxRelWithin over cases without a float-subnormal direction component
    size_t worstCase = SIZE_MAX;
    int worstChannel = 0;
    double worstGot = 0, worstWant = 0;
    // Cases that failed, with the reason (the first few of each kind).
    std::vector<std::pair<size_t, std::string>> failures;

    // Whether the accuracy (bound, validity of valid lanes) is a pass/fail
    // criterion: exact mode. Fast mode computes in float throughout and
    // its hard-case accuracy is reported, not enforced (docs/numerics.md).
    bool accuracyEnforced = true;

    // Outputs finite and >= 0; invalid inputs give 0 and are counted.
    bool safe() const {
        return nan == 0 && inf == 0 && negative == 0 && missedInvalid == 0 && invalidNonZero == 0 && !countMismatch;
    }
    bool accurate() const { return unexpectedInvalid == 0 && validityMismatch == 0 && beyondBound == 0; }
    bool ok() const { return safe() && (accurate() || !accuracyEnforced); }
    std::string summary() const;  // one line
};

// The reference itself: finite, >= 0, the SPEC 2 invalid cases counted.
SampleStats checkReference(const std::vector<HardCase>& cases, const HardCaseReference& ref);
// A kernel run against the reference. `condition(i)` (optional) gives the
// condition number of case i; `roundoff` is the math mode's unit roundoff.
SampleStats checkKernel(const std::string& backend, const KernelRun& run, const std::vector<HardCase>& cases,
                        const HardCaseReference& ref, double bound, const std::function<double(size_t)>& condition = {},
                        double roundoff = 0x1p-24);

}  // namespace facet
