// ReferenceComparison: the one definition of how far a kernel's output is from
// the double reference interpreter.
//
// `facet bench`, `facet verify`, the tolerance search (ToleranceSearch.cpp), the
// differential tests and the ahead-of-time tests all compare float kernel
// outputs with Interpreter<double> evaluated on the very same float inputs.
// They differ in what they report (a maximum, a p99.9, counts within a bound,
// a conditioning allowance), not in what an error is; this file fixes the
// latter once:
//   - the reference of a lane it reports invalid is 0 on every channel (the
//     value the contract asks an evaluator to write there);
//   - a reference beyond float range cannot be represented, so that value is
//     skipped (the kernel may report the lane invalid);
//   - relative error is |got - want| / max(|want|, FLT_MIN), and a difference
//     of at most kAbsoluteErrorFloor counts as 0 (float denormals and below);
//     a NaN or Inf output has infinite error.
#pragma once

#include "Checker.h"
#include "LaneBatch.h"

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace facet {

class EnergyTable;

// Differences up to this are below float's normal range and count as exact.
constexpr double kAbsoluteErrorFloor = 1e-30;

// Relative error of one output channel against its reference (see above).
double relativeError(double got, double want);

// Distance between two floats in units in the last place (0 for equal values,
// 1 for neighbours; +0 and -0 are the same point).
double floatUlpDistance(float a, float b);

// True when `want` cannot be represented as a float (such values are skipped).
bool beyondFloatRange(double want);

// The reference interpreter's values for every lane of a batch.
struct ReferenceValues {
    std::vector<double> rgb[3];  // 0 where the lane is invalid
    std::vector<char> valid;
    size_t size() const { return valid.size(); }
};

// Evaluates Interpreter<double> of `material` on n lanes: wi[3], wo[3] and
// one column per slot of `material`, in its slot order (nullptr when it has
// none). `lobeTables` holds, per lobe, the Kulla-Conty E table of a lobe that
// compensates energy (Kernel::lobeEnergyTables: the tables a kernel was built
// with); a missing or null entry is built here, as the interpreter does,
// which for a combination of several compensated lobes costs seconds.
ReferenceValues evaluateReference(const CheckedMaterial& material,
                                  const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables, size_t n,
                                  const float* const wi[3], const float* const wo[3], const float* const* slots);
// The same for a batch whose slot columns are those of `material`.
ReferenceValues evaluateReference(const CheckedMaterial& material, const LaneBatch& batch,
                                  const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables = {});

// The largest error of one comparison and where it happened.
struct WorstLane {
    bool present = false;
    size_t lane = 0;
    int channel = 0;
    double got = 0, want = 0, rel = 0;
};

// A kernel's outputs against the reference values of the same lanes.
struct ReferenceComparison {
    size_t values = 0;     // channel values looked at
    size_t skipped = 0;    // reference beyond float range
    size_t nonFinite = 0;  // NaN or Inf outputs (relative error infinite)
    size_t negative = 0;   // negative outputs
    double maxRel = 0;
    double maxUlp = 0;     // over finite outputs, against the reference rounded to float
    WorstLane worst;
    std::vector<double> rel;  // per compared value (lane-major, channel-minor), skipped values left out

    // Values whose relative error is at most `bound`.
    size_t countWithin(double bound) const;
    // The smallest error that a `fraction` of the compared values do not exceed.
    double quantile(double fraction) const;
};

ReferenceComparison compareWithReference(const ReferenceValues& reference, const float* const rgb[3]);

// "wi=(..) wo=(..) name=value .." of one lane, for messages: directions and
// one column per slot of `material`, in its slot order.
std::string describeLane(const CheckedMaterial& material, const float* const wi[3], const float* const wo[3],
                         const float* const* slots, size_t lane);

}  // namespace facet
