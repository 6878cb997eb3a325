// KernelEval: evaluating and sampling with a Kernel (Kernel.h): eval,
// evalBatch, sample, pdf and their batch forms.
//
// Each call takes the kernel's own entry point where it has one. Without
// it, the work goes one lane at a time: a SIMD kernel's one-lane call
// through its batch entry; a scalar kernel's batch through its scalar
// entry; an interpreter kernel (and a JIT kernel without a compiled
// sampler) through the double interpreter, whose results are brought to
// the compiled kernels' conventions so that a host sees one behaviour on
// every backend.
#include "Kernel.h"

#include "Interpreter.h"
#include "KernelCode.h"
#include "Sampling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

namespace facet {

namespace {

// A three-vector as the three columns of a one-lane batch.
std::array<const float*, 3> laneColumns(const float v[3]) { return {&v[0], &v[1], &v[2]}; }
std::array<float*, 3> laneColumns(float v[3]) { return {&v[0], &v[1], &v[2]}; }

// The column pointers of one lane's input slots, for a one-lane call of a
// batch entry. They live on the stack for the usual slot counts: a heap
// allocation would cost a sizeable part of the call.
class LaneInputColumns {
public:
    LaneInputColumns(const float* inputs, int slots) {
        if (!inputs) return;  // columns() stays null: every slot's default
        if (slots > kStackSlots) many_.resize(size_t(slots));
        const float** in = slots > kStackSlots ? many_.data() : few_;
        for (int s = 0; s < slots; ++s) in[s] = &inputs[s];
        columns_ = in;
    }
    LaneInputColumns(const LaneInputColumns&) = delete;  // columns_ may point into few_
    LaneInputColumns& operator=(const LaneInputColumns&) = delete;
    const float* const* columns() const { return columns_; }

private:
    static constexpr int kStackSlots = 32;
    const float* few_[kStackSlots];
    std::vector<const float*> many_;
    const float** columns_ = nullptr;
};

// Calls laneFn(i, slots, floatSlots) for each of n lanes, with the lane's
// inputs as evalBatch reads them (the caller's value, or the slot's default
// where inputs or inputs[s] is NULL) in double and in float; returns how
// many lanes it reported invalid.
template <typename LaneFn>
int64_t forEachLane(const CheckedMaterial& material, int64_t n, const float* const* inputs, LaneFn laneFn) {
    const int slots = material.slotCount;
    std::vector<double> defaults = material.defaultSlots(), lane(std::max(1, slots));
    std::vector<float> laneF(std::max(1, slots));
    int64_t invalid = 0;
    for (int64_t i = 0; i < n; ++i) {
        for (int s = 0; s < slots; ++s) {
            lane[s] = inputs && inputs[s] ? double(inputs[s][i]) : defaults[s];
            laneF[s] = float(lane[s]);
        }
        invalid += laneFn(i, lane.data(), laneF.data()) ? 0 : 1;
    }
    return invalid;
}

// The interpreter's value of one lane as a compiled kernel reports it:
// false, with rgb 0, for an invalid lane, and for a result float cannot
// hold (never Inf).
bool referenceEval(const Interpreter<double>& interp, const float wi[3], const float wo[3], const double* slots,
                   float rgb[3]) {
    double a[3] = {wi[0], wi[1], wi[2]}, b[3] = {wo[0], wo[1], wo[2]};
    EvalResult<double> r = interp.eval(a, b, slots);
    bool bad = !r.valid;
    for (int c = 0; c < 3; ++c) {
        rgb[c] = float(r.rgb[c]);
        bad |= !std::isfinite(rgb[c]);
    }
    if (bad) rgb[0] = rgb[1] = rgb[2] = 0.0f;
    return !bad;
}

// The interpreter's sample of one lane as a compiled sampler reports it
// (LaneSampling.cpp): a density that underflows float is no density a
// renderer can divide by, so pdf 0 means weight 0; false, with every output
// 0, for an invalid lane or a result float cannot hold.
bool referenceSample(const Interpreter<double>& interp, const float wo[3], const float u[3], const double* slots,
                     float wi[3], float& pdf, float weight[3]) {
    double od[3] = {wo[0], wo[1], wo[2]}, ud[3] = {u[0], u[1], u[2]};
    SampleResult<double> r = interp.sample(od, ud, slots);
    wi[0] = float(r.wi.x), wi[1] = float(r.wi.y), wi[2] = float(r.wi.z);
    pdf = float(r.pdf);
    for (int c = 0; c < 3; ++c) weight[c] = pdf > 0 ? float(r.weight[c]) : 0.0f;
    const bool bad = !r.valid || !std::isfinite(pdf) || !std::isfinite(weight[0]) || !std::isfinite(weight[1]) ||
                     !std::isfinite(weight[2]);
    if (bad) wi[0] = wi[1] = wi[2] = pdf = weight[0] = weight[1] = weight[2] = 0.0f;
    return !bad;
}

// The interpreter's density of one lane as a compiled sampler reports it:
// false, with pdf 0, for an invalid lane or a density float cannot hold.
bool referencePdf(const Interpreter<double>& interp, const float wi[3], const float wo[3], const double* slots,
                  float& pdf) {
    double a[3] = {wi[0], wi[1], wi[2]}, b[3] = {wo[0], wo[1], wo[2]};
    PdfResult<double> r = interp.pdf(a, b, slots);
    pdf = float(r.pdf);
    const bool bad = !r.valid || !std::isfinite(pdf);
    if (bad) pdf = 0;
    return !bad;
}

}  // namespace

void Kernel::eval(const float wi[3], const float wo[3], const float* inputs, float rgb[3]) const {
    if (ScalarStatusFn scalar = entryPoint(code_, &KernelCode::scalarStatus)) {
        scalar(wi, wo, inputs, rgb);
        return;
    }
    // A SIMD or interpreter kernel: one lane through evalBatch.
    LaneInputColumns in(inputs, inputCount());
    evalBatch(1, laneColumns(wi).data(), laneColumns(wo).data(), in.columns(), laneColumns(rgb).data());
}

int64_t Kernel::evalBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                          float* const rgb[3], uint8_t* status) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    if (BatchKernelFn batch = entryPoint(code_, &KernelCode::batch)) return batch(n, wi, wo, inputs, rgb, status);
    // Scalar and interpreter kernels: one lane at a time, same conventions.
    ScalarStatusFn scalar = entryPoint(code_, &KernelCode::scalarStatus);
    std::optional<Interpreter<double>> interp;
    if (!scalar) interp.emplace(material_, lobeEnergyTables_), interp->setTransport(transport_);
    return forEachLane(material_, n, inputs, [&](int64_t i, const double* lane, const float* laneF) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, out[3];
        const bool bad = scalar ? scalar(a, b, laneF, out) != 0 : !referenceEval(*interp, a, b, lane, out);
        if (status) status[i] = uint8_t(bad);
        for (int c = 0; c < 3; ++c) rgb[c][i] = out[c];
        return !bad;
    });
}

bool Kernel::sample(const float wo[3], const float u[3], const float* inputs, float wi[3], float* pdf,
                    float weight[3]) const {
    ensureSampler();
    if (SampleScalarFn fn = entryPoint(code_, &KernelCode::sampleScalar)) return fn(wo, u, inputs, wi, pdf, weight) == 0;
    // One lane through the batch entry (or the reference).
    LaneInputColumns in(inputs, inputCount());
    return sampleBatch(1, laneColumns(wo).data(), laneColumns(u).data(), in.columns(), laneColumns(wi).data(), pdf,
                       laneColumns(weight).data()) == 0;
}

float Kernel::pdf(const float wi[3], const float wo[3], const float* inputs) const {
    ensureSampler();
    float out = 0;
    if (PdfScalarFn fn = entryPoint(code_, &KernelCode::pdfScalar)) {
        fn(wi, wo, inputs, &out);
        return out;
    }
    LaneInputColumns in(inputs, inputCount());
    pdfBatch(1, laneColumns(wi).data(), laneColumns(wo).data(), in.columns(), &out);
    return out;
}

int64_t Kernel::sampleBatch(int64_t n, const float* const wo[3], const float* const u[3], const float* const* inputs,
                            float* const wi[3], float* pdf, float* const weight[3]) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    ensureSampler();
    if (SampleBatchFn fn = entryPoint(code_, &KernelCode::sampleBatch)) return fn(n, wo, u, inputs, wi, pdf, weight);
    SampleScalarFn scalar = entryPoint(code_, &KernelCode::sampleScalar);
    std::optional<Interpreter<double>> interp;
    if (!scalar) interp.emplace(material_, lobeEnergyTables_), interp->setTransport(transport_);
    return forEachLane(material_, n, inputs, [&](int64_t i, const double* lane, const float* laneF) {
        float o[3] = {wo[0][i], wo[1][i], wo[2][i]}, uu[3] = {u[0][i], u[1][i], u[2][i]};
        float w[3] = {0, 0, 0}, p = 0, wt[3] = {0, 0, 0};
        const bool bad =
            scalar ? scalar(o, uu, laneF, w, &p, wt) != 0 : !referenceSample(*interp, o, uu, lane, w, p, wt);
        for (int c = 0; c < 3; ++c) wi[c][i] = w[c], weight[c][i] = wt[c];
        pdf[i] = p;
        return !bad;
    });
}

int64_t Kernel::pdfBatch(int64_t n, const float* const wi[3], const float* const wo[3], const float* const* inputs,
                         float* pdf) const {
    if (n <= 0) return n == 0 ? 0 : -1;
    ensureSampler();
    if (PdfBatchFn fn = entryPoint(code_, &KernelCode::pdfBatch)) return fn(n, wi, wo, inputs, pdf);
    PdfScalarFn scalar = entryPoint(code_, &KernelCode::pdfScalar);
    std::optional<Interpreter<double>> interp;
    if (!scalar) interp.emplace(material_, lobeEnergyTables_), interp->setTransport(transport_);
    return forEachLane(material_, n, inputs, [&](int64_t i, const double* lane, const float* laneF) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, p = 0;
        const bool bad = scalar ? scalar(a, b, laneF, &p) != 0 : !referencePdf(*interp, a, b, lane, p);
        pdf[i] = p;
        return !bad;
    });
}

}  // namespace facet
