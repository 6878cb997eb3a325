// DiffHarness: sampling and error statistics (see DiffHarness.h).
#include "DiffHarness.h"
#include "ReferenceComparison.h"

#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

namespace facet::test {

std::string readFile(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

namespace {
void addSlots(const CheckedMaterial& m, LaneBatch& s, std::mt19937_64& rng, size_t n) {
    s.slots.assign(m.slotCount, {});
    std::uniform_real_distribution<double> u(0, 1);
    for (const CheckedInput& in : m.inputs) {
        for (int c = 0; c < in.slotCount(); ++c) {
            std::vector<float>& col = s.slots[in.firstSlot + c];
            for (size_t i = 0; i < n; ++i) {
                double lo = in.hasRange ? in.lo : 0.0, hi = in.hasRange ? in.hi : 2 * in.defaultValue[c] + 0.1;
                double v = lo + (hi - lo) * u(rng);
                if (u(rng) < 0.05) v = in.hasRange ? (u(rng) < 0.5 ? lo - 0.5 : hi + 0.5) : in.defaultValue[c];
                col.push_back(float(v));
            }
        }
    }
}
}  // namespace

LaneBatch randomSample(const CheckedMaterial& m, size_t n, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    LaneBatch s;
    for (size_t i = 0; i < n; ++i) {
        double w[2][3];
        for (auto& v : w) {
            double z = u(rng), phi = 2 * M_PI * u(rng);
            if (u(rng) < 0.05) z = -z;  // below the horizon
            double r = std::sqrt(std::max(0.0, 1 - z * z));
            v[0] = r * std::cos(phi), v[1] = r * std::sin(phi), v[2] = z;
        }
        s.push(w[0], w[1], {});  // the slots are drawn afterwards
    }
    addSlots(m, s, rng, n);
    s.finish();
    return s;
}

LaneBatch hardSample(const CheckedMaterial& m) {
    LaneBatch s;
    auto push = [&](double ax, double ay, double az, double bx, double by, double bz) {
        double la = std::sqrt(ax * ax + ay * ay + az * az), lb = std::sqrt(bx * bx + by * by + bz * bz);
        double wi[3] = {ax / la, ay / la, az / la}, wo[3] = {bx / lb, by / lb, bz / lb};
        s.push(wi, wo, {});  // the slots are drawn afterwards
    };
    const double zs[] = {1.0, 0.5, 1e-2, 1e-4, 1e-7};
    for (double zi : zs)
        for (double zo : zs)
            for (double phi : {0.0, M_PI / 2, M_PI, M_PI - 1e-3, 1.0}) {
                double ri = std::sqrt(1 - zi * zi), ro = std::sqrt(1 - zo * zo);
                push(ri, 0, zi, ro * std::cos(phi), ro * std::sin(phi), zo);
                push(-ri, 0, zi, ro * std::cos(phi), ro * std::sin(phi), zo);  // mirror-ish pairs
            }
    push(0, 0, 1, 0, 0, 1);
    push(0.6, 0, 0.8, -0.6, 0, 0.8);                // exact mirror: n.h = 1
    push(0.6, 1e-7, 0.8, -0.6, 0, 0.8);             // n.h within 1e-7 of 1
    push(0.999999, 0, 1e-3, -0.999999, 1e-4, 1e-3);  // wi + wo nearly zero
    push(0.6, 0, -0.8, 0, 0, 1);                    // wi below the horizon
    std::mt19937_64 rng(7);
    addSlots(m, s, rng, s.size());
    s.finish();
    return s;
}

bool DiffStats::ok(std::string& why) const {
    if (nonFinite || negative) {
        why = fmt::format("{} non-finite and {} negative outputs", nonFinite, negative);
        return false;
    }
    if (beyond2e3) {
        why = fmt::format("{} values beyond 2e-3 relative; worst: {}", beyond2e3, worst);
        return false;
    }
    if (finiteRef && double(within1e5) < 0.999 * double(finiteRef)) {
        why = fmt::format("only {}/{} within 1e-5; worst: {}", within1e5, finiteRef, worst);
        return false;
    }
    if (ulpViolations) {
        why = fmt::format("{} lanes differ by more than 4 ulp between scalar and SIMD (max {})", ulpViolations,
                          maxUlpScalarSimd);
        return false;
    }
    return true;
}

void compare(const Kernel& kernel, const CheckedMaterial& reference, const LaneBatch& s, DiffStats& stats,
             std::optional<ReferenceValues>* shared) {
    size_t n = s.size();
    // Kernel slots are the reference slots minus bound inputs; map by name.
    std::vector<const float*> inputs(kernel.inputCount());
    for (int k = 0; k < kernel.inputCount(); ++k)
        for (int r = 0; r < reference.slotCount; ++r)
            if (reference.slotName(r) == kernel.inputName(k)) inputs[k] = s.slots[r].data();
    std::vector<float> out[3];
    for (auto& o : out) o.assign(n, -1.0f);
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    const float* const* wi = s.wi();
    const float* const* wo = s.wo();
    if (kernel.backend() == Backend::Scalar) {
        std::vector<float> in(kernel.inputCount());
        for (size_t i = 0; i < n; ++i) {
            float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, o[3];
            for (int k = 0; k < kernel.inputCount(); ++k) in[k] = inputs[k][i];
            kernel.eval(a, b, in.data(), o);
            for (int c = 0; c < 3; ++c) rgb[c][i] = o[c];
        }
    } else {
        kernel.evalBatch(int64_t(n), wi, wo, kernel.inputCount() ? inputs.data() : nullptr, rgb);
    }
    // The reference evaluates the kernel's own material, in which bound
    // inputs are folded, on the kernel's remaining inputs.
    std::optional<ReferenceValues> own;
    std::optional<ReferenceValues>& slot = shared ? *shared : own;
    if (!slot) slot = evaluateReference(kernel.material(), kernel.lobeEnergyTables(), n, wi, wo, inputs.data());
    const ReferenceValues& ref = *slot;
    const float* const written[3] = {rgb[0], rgb[1], rgb[2]};
    ReferenceComparison cmp = compareWithReference(ref, written);
    size_t compared = cmp.rel.size() - cmp.nonFinite;
    stats.compared += cmp.values;
    stats.nonFinite += cmp.nonFinite;
    stats.negative += cmp.negative;
    stats.finiteRef += compared;
    stats.within1e5 += cmp.countWithin(1e-5);
    stats.beyond2e3 += compared - (cmp.countWithin(2e-3));
    if (cmp.worst.present && cmp.maxRel > stats.maxRel) {
        stats.maxRel = cmp.maxRel;
        const WorstLane& w = cmp.worst;
        stats.worst = fmt::format("rel {:.3g} ch {} {} got {:.9g} want {:.17g}", w.rel, w.channel,
                                  describeLane(kernel.material(), wi, wo, inputs.data(), w.lane), w.got, w.want);
    }
}

void compareUlp(const Kernel& scalar, const Kernel& simd, const LaneBatch& s, DiffStats& stats) {
    size_t n = s.size();
    int slots = simd.inputCount();
    std::vector<const float*> inputs;
    for (int k = 0; k < slots; ++k) inputs.push_back(s.slots[k].data());
    std::vector<float> out[3];
    for (auto& o : out) o.assign(n, 0.0f);
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    const float* wi[3] = {s.dir[0].data(), s.dir[1].data(), s.dir[2].data()};
    const float* wo[3] = {s.dir[3].data(), s.dir[4].data(), s.dir[5].data()};
    simd.evalBatch(int64_t(n), wi, wo, slots ? inputs.data() : nullptr, rgb);
    for (size_t i = 0; i < n; ++i) {
        float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, o[3];
        std::vector<float> in(slots);
        for (int k = 0; k < slots; ++k) in[k] = inputs[k][i];
        scalar.eval(a, b, in.data(), o);
        for (int c = 0; c < 3; ++c) {
            double ulps = floatUlpDistance(o[c], rgb[c][i]);
            stats.maxUlpScalarSimd = std::max(stats.maxUlpScalarSimd, ulps);
            if (ulps > 4) ++stats.ulpViolations;
        }
    }
}

}  // namespace facet::test
