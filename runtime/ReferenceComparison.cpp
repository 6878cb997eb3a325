// ReferenceComparison: kernel outputs against Interpreter<double> on the same
// float inputs (see the header for the conventions).
#include "ReferenceComparison.h"

#include "Interpreter.h"

#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace facet {

double relativeError(double got, double want) {
    if (!std::isfinite(got)) return INFINITY;
    double err = std::fabs(got - want);
    if (err <= kAbsoluteErrorFloor) return 0.0;
    return err / std::max(std::fabs(want), double(FLT_MIN));
}

double floatUlpDistance(float a, float b) {
    // Float bits mapped to a monotonic integer line.
    auto ordered = [](float f) {
        int32_t i;
        std::memcpy(&i, &f, 4);
        return i < 0 ? int64_t(INT32_MIN) - i : int64_t(i);
    };
    return std::fabs(double(ordered(a) - ordered(b)));
}

bool beyondFloatRange(double want) { return std::fabs(want) > double(FLT_MAX); }

ReferenceValues evaluateReference(const CheckedMaterial& material,
                                  const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables, size_t n,
                                  const float* const wi[3], const float* const wo[3], const float* const* slots) {
    Interpreter<double> interp(material, lobeTables);
    ReferenceValues ref;
    for (auto& c : ref.rgb) c.resize(n);
    ref.valid.resize(n);
    std::vector<double> laneSlots(std::max(1, material.slotCount));
    for (size_t i = 0; i < n; ++i) {
        double a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]};
        for (int k = 0; k < material.slotCount; ++k) laneSlots[k] = slots[k][i];
        EvalResult<double> r = interp.eval(a, b, laneSlots.data());
        ref.valid[i] = r.valid;
        for (int c = 0; c < 3; ++c) ref.rgb[c][i] = r.valid ? r.rgb[c] : 0.0;
    }
    return ref;
}

ReferenceValues evaluateReference(const CheckedMaterial& material, const LaneBatch& batch,
                                  const std::vector<std::shared_ptr<const EnergyTable>>& lobeTables) {
    return evaluateReference(material, lobeTables, batch.size(), batch.wi(), batch.wo(), batch.inputs());
}

size_t ReferenceComparison::countWithin(double bound) const {
    return size_t(std::count_if(rel.begin(), rel.end(), [bound](double r) { return r <= bound; }));
}

double ReferenceComparison::quantile(double fraction) const {
    if (rel.empty()) return 0;
    std::vector<double> sorted = rel;
    size_t rank = size_t(std::ceil(fraction * double(sorted.size())));
    rank = std::clamp<size_t>(rank, 1, sorted.size()) - 1;
    std::nth_element(sorted.begin(), sorted.begin() + ptrdiff_t(rank), sorted.end());
    return sorted[rank];
}

ReferenceComparison compareWithReference(const ReferenceValues& reference, const float* const rgb[3]) {
    ReferenceComparison cmp;
    size_t n = reference.size();
    cmp.rel.reserve(3 * n);
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            double got = rgb[c][i], want = reference.rgb[c][i];
            ++cmp.values;
            if (beyondFloatRange(want)) {
                ++cmp.skipped;
                continue;
            }
            if (!std::isfinite(got)) {
                ++cmp.nonFinite;
            } else {
                if (got < 0) ++cmp.negative;
                cmp.maxUlp = std::max(cmp.maxUlp, floatUlpDistance(float(got), float(want)));
            }
            double rel = relativeError(got, want);
            cmp.rel.push_back(rel);
            if (!cmp.worst.present || rel > cmp.maxRel) {
                cmp.maxRel = rel;
                cmp.worst = {true, i, c, got, want, rel};
            }
        }
    return cmp;
}

std::string describeLane(const CheckedMaterial& material, const float* const wi[3], const float* const wo[3],
                         const float* const* slots, size_t lane) {
    std::string s = fmt::format("wi=({:.9g},{:.9g},{:.9g}) wo=({:.9g},{:.9g},{:.9g})", wi[0][lane], wi[1][lane],
                                wi[2][lane], wo[0][lane], wo[1][lane], wo[2][lane]);
    for (int k = 0; k < material.slotCount; ++k) s += fmt::format(" {}={:.9g}", material.slotName(k), slots[k][lane]);
    return s;
}

}  // namespace facet
