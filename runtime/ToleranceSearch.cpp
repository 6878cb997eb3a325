// ToleranceSearch: the candidates of a tolerance search, the error
// measurement that decides between them, and the search itself
// (ToleranceSearch.h).
#include "ToleranceSearch.h"

#include "KernelCode.h"
#include "LaneBatch.h"
#include "ReferenceComparison.h"
#include "TableCache.h"

#include <cmath>
#include <random>
#include <vector>

namespace facet {

namespace {

// Candidate variants for a tolerance, fastest first. The model
// substitutions only appear where they apply to the material.
std::vector<MathVariant> toleranceCandidates(const CheckedMaterial& m) {
    bool smithBeckmann = walterLambdaApplies(m);
    bool dielectric = schlickDielectricApplies(m);
    std::vector<MathVariant> out;
    for (bool walter : {true, false})
        for (bool schlick : {true, false}) {
            if ((walter && !smithBeckmann) || (schlick && !dielectric)) continue;
            MathVariant v = MathVariant::fast();
            v.walterLambda = walter;
            v.schlickDielectric = schlick;
            out.push_back(v);
        }
    out.push_back(MathVariant::exact());
    return out;
}

}  // namespace

std::optional<MathVariant> cachedVariant(const CheckedMaterial& material, const MathVariant& variant, bool tolerance,
                                         const std::string& name) {
    if (!tolerance) return name == variant.name() ? std::optional<MathVariant>(variant) : std::nullopt;
    for (MathVariant v : toleranceCandidates(material))
        if (v.name() == name) {
            v.floatFirst = variant.floatFirst;
            return v;
        }
    return std::nullopt;
}

double measureKernelError(const Kernel& kernel, const CheckedMaterial& material, size_t samples) {
    // Directions cosine-uniform over the hemisphere (where a renderer
    // evaluates), inputs uniform over their ranges; fixed seed so a
    // tolerance choice is reproducible.
    std::mt19937_64 rng(0x5eed);
    std::uniform_real_distribution<double> u(0, 1);
    LaneBatch batch;
    batch.slots.resize(size_t(material.slotCount));
    std::vector<double> laneSlots(size_t(material.slotCount));
    for (size_t i = 0; i < samples; ++i) {
        double w[2][3];
        for (auto& d : w) {
            double z = std::sqrt(u(rng)), phi = 2 * M_PI * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
            d[0] = r * std::cos(phi), d[1] = r * std::sin(phi), d[2] = z;
        }
        for (const CheckedInput& in : material.inputs)
            for (int c = 0; c < in.slotCount(); ++c) {
                double lo = in.hasRange ? in.lo : 0.0, hi = in.hasRange ? in.hi : 2 * in.defaultValue[c];
                laneSlots[size_t(in.firstSlot + c)] = lo + (hi - lo) * u(rng);
            }
        batch.push(w[0], w[1], laneSlots);
    }
    batch.finish();
    std::vector<float> out[3];
    for (auto& o : out) o.assign(samples, 0.0f);
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    kernel.evalBatch(int64_t(samples), batch.wi(), batch.wo(), batch.inputs(), rgb);
    const float* const written[3] = {rgb[0], rgb[1], rgb[2]};
    return compareWithReference(evaluateReference(material, batch, kernel.lobeEnergyTables()), written).maxRel;
}

CachedKernel Compiler::searchVariants(const CheckedMaterial& material, LoweringOptions lowering, double tolerance,
                                      const std::string& prefix, FacetJit::Level level, MathVariant& chosen) {
    const bool floatFirst = lowering.variant.floatFirst;
    // Fastest first; the first whose measured error meets the tolerance wins.
    // Exact is always last: if even it does not meet the tolerance, it is
    // returned with its (larger) measured error for the caller to report.
    CachedKernel best;
    for (const MathVariant& v : toleranceCandidates(material)) {
        lowering.variant = v;
        lowering.variant.floatFirst = floatFirst;
        // Both codegen levels compute the same bits, so a quick candidate
        // measures the error of its optimized code too.
        CachedKernel candidate{compileObject(material, lowering, prefix, level), v.name(), 0.0};
        Kernel probe;
        probe.material_ = material;
        if (lowering.energyTable) probe.energyTable_ = tables_->getFor(material);
        probe.lobeEnergyTables_ = {probe.energyTable_};
        if (material.combinesLobes()) {
            probe.lobeEnergyTables_.clear();
            for (size_t l = 0; l < material.lobes.size(); ++l) {
                CheckedMaterial view = lobeView(material, int(l));
                probe.lobeEnergyTables_.push_back(view.singleLobe().compensatesEnergy() ? tables_->getFor(view) : nullptr);
            }
        }
        probe.backend_ = lowering.emitBatch ? Backend::Simd : Backend::Scalar;
        probe.code_ = std::make_shared<KernelCode>();
        probe.code_->jit = jit_;
        link(*probe.code_, candidate.object, prefix, lowering);
        candidate.measuredError = measureKernelError(probe, material);
        best = std::move(candidate);
        chosen = lowering.variant;
        if (best.measuredError <= tolerance) break;
    }
    return best;
}

}  // namespace facet
