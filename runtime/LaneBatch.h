// LaneBatch: evaluation lanes (wi, wo and the input slots of a material) in
// the structure-of-arrays float layout of Kernel::evalBatch.
//
// The one container for the samples that `facet bench`, the differential
// tests and the JIT tests feed to kernels and, widened to double, to the
// reference interpreter: every caller sees the very same floats. Columns may
// be filled with push() or written directly; finish() (and every copy)
// points wi(), wo() and inputs() at the columns.
#pragma once

#include <cstddef>
#include <vector>

namespace facet {

struct LaneBatch {
    std::vector<float> dir[6];              // wi_x, wi_y, wi_z, wo_x, wo_y, wo_z
    std::vector<std::vector<float>> slots;  // one column per input slot of the material

    LaneBatch() = default;
    LaneBatch(const LaneBatch& other) : slots(other.slots) {
        for (int d = 0; d < 6; ++d) dir[d] = other.dir[d];
        finish();
    }
    LaneBatch& operator=(const LaneBatch& other) {
        if (this != &other) {
            for (int d = 0; d < 6; ++d) dir[d] = other.dir[d];
            slots = other.slots;
            finish();
        }
        return *this;
    }
    // Moving a vector keeps its buffer, but the pointers are refreshed anyway
    // so that a moved-to batch never depends on that.
    LaneBatch(LaneBatch&& other) noexcept : slots(std::move(other.slots)) {
        for (int d = 0; d < 6; ++d) dir[d] = std::move(other.dir[d]);
        finish();
    }
    LaneBatch& operator=(LaneBatch&& other) noexcept {
        for (int d = 0; d < 6; ++d) dir[d] = std::move(other.dir[d]);
        slots = std::move(other.slots);
        finish();
        return *this;
    }

    size_t size() const { return dir[0].size(); }

    // Appends one lane (slots.size() values in `inputs`).
    void push(const double wi[3], const double wo[3], const std::vector<double>& inputs) {
        for (int d = 0; d < 3; ++d) {
            dir[d].push_back(float(wi[d]));
            dir[3 + d].push_back(float(wo[d]));
        }
        for (size_t s = 0; s < slots.size(); ++s) slots[s].push_back(float(inputs[s]));
    }

    // Pointers in the layout of Kernel::evalBatch: wi[3], wo[3], inputs[slots]
    // (nullptr without slots). Valid until the columns change size.
    const float* const* wi() const { return wiPtr_; }
    const float* const* wo() const { return woPtr_; }
    const float* const* inputs() const { return inPtr_.empty() ? nullptr : inPtr_.data(); }
    // Refreshes the pointers once the columns are complete.
    void finish() {
        for (int d = 0; d < 3; ++d) {
            wiPtr_[d] = dir[d].data();
            woPtr_[d] = dir[3 + d].data();
        }
        inPtr_.clear();
        for (const auto& column : slots) inPtr_.push_back(column.data());
    }

private:
    const float* wiPtr_[3] = {};
    const float* woPtr_[3] = {};
    std::vector<const float*> inPtr_;
};

}  // namespace facet
