// Verify: kernels and the reference on the hard-case sample (see Verify.h).
#include "Verify.h"

#include <cfloat>
#include <cmath>
#include <fmt/format.h>

namespace facet {

namespace {

bool beyondFloat(double x) { return std::isfinite(x) && std::fabs(x) > double(FLT_MAX); }

bool parametersBeyondFloat(const ResolvedMaterial<double>& r) {
    bool out = false;
    for (const ModelArgs<double>* args : {&r.ndfArgs, &r.maskingArgs, &r.fresnelArgs, &r.diffuseArgs})
        for (const std::array<double, 3>& param : args->value)
            for (double x : param) out |= beyondFloat(x);
    return out;
}

// Keeps the first 16 failures of each kind (the reason up to its first ':' or number).
void addFailure(SampleStats& s, size_t i, std::string why) {
    std::string kind = why.substr(0, why.find_first_of(":0123456789"));
    size_t same = 0;
    for (const auto& f : s.failures)
        if (f.second.compare(0, kind.size(), kind) == 0) ++same;
    if (same < 16) s.failures.push_back({i, std::move(why)});
}

}  // namespace

HardCaseReference evaluateHardCaseReference(const Interpreter<double>& interp, const std::vector<HardCase>& cases) {
    HardCaseReference ref;
    ref.results.reserve(cases.size());
    ref.floatOverflow.reserve(cases.size());
    for (const HardCase& c : cases) {
        const double* slots = c.slots.empty() ? nullptr : c.slots.data();
        EvalResult<double> r = interp.eval(c.wi.data(), c.wo.data(), slots);
        bool over = false;
        for (double v : r.rgb) over |= beyondFloat(v);
        if (!c.invalidInput)
            for (const ResolvedMaterial<double>& lobe : interp.resolveAll(slots).lobes) over |= parametersBeyondFloat(lobe);
        ref.results.push_back(r);
        ref.floatOverflow.push_back(over);
    }
    return ref;
}

KernelRun runKernel(const Kernel& kernel, const std::vector<HardCase>& cases) {
    size_t n = cases.size();
    int slots = kernel.inputCount();
    KernelRun run;
    run.rgb.assign(n, {0, 0, 0});
    run.invalid.assign(n, 0);
    std::vector<float> dir[6], out[3];
    std::vector<std::vector<float>> in(slots);
    for (auto& d : dir) d.resize(n);
    for (auto& o : out) o.assign(n, -1.0f);
    for (auto& s : in) s.resize(n);
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            dir[k][i] = float(cases[i].wi[k]);
            dir[3 + k][i] = float(cases[i].wo[k]);
        }
        for (int s = 0; s < slots; ++s) in[s][i] = float(cases[i].slots.at(s));
    }
    const float* wi[3] = {dir[0].data(), dir[1].data(), dir[2].data()};
    const float* wo[3] = {dir[3].data(), dir[4].data(), dir[5].data()};
    std::vector<const float*> inPtr;
    for (auto& s : in) inPtr.push_back(s.data());
    float* rgb[3] = {out[0].data(), out[1].data(), out[2].data()};
    run.batchCount = kernel.evalBatch(int64_t(n), wi, wo, slots ? inPtr.data() : nullptr, rgb);
    for (size_t i = 0; i < n; ++i) run.rgb[i] = {out[0][i], out[1][i], out[2][i]};
    if (kernel.backend() == Backend::Scalar) {
        // The SPEC's scalar entry point (the batch path above went through its status twin).
        std::vector<float> lane(std::max(1, slots));
        for (size_t i = 0; i < n; ++i) {
            float a[3] = {wi[0][i], wi[1][i], wi[2][i]}, b[3] = {wo[0][i], wo[1][i], wo[2][i]}, o[3];
            for (int s = 0; s < slots; ++s) lane[s] = in[s][i];
            kernel.eval(a, b, lane.data(), o);
            run.rgb[i] = {o[0], o[1], o[2]};
        }
    }
    // Exact per-lane status: only lanes with an all-zero output can be invalid.
    std::vector<float> one(std::max(1, slots));
    for (size_t i = 0; i < n; ++i) {
        const std::array<float, 3>& o = run.rgb[i];
        if (!(o[0] == 0 && o[1] == 0 && o[2] == 0)) continue;
        const float* a[3] = {&dir[0][i], &dir[1][i], &dir[2][i]};
        const float* b[3] = {&dir[3][i], &dir[4][i], &dir[5][i]};
        std::vector<const float*> ip;
        for (int s = 0; s < slots; ++s) ip.push_back(&in[s][i]);
        float r[3] = {-1, -1, -1};
        float* rp[3] = {&r[0], &r[1], &r[2]};
        int64_t bad = kernel.evalBatch(1, a, b, slots ? ip.data() : nullptr, rp);
        run.invalid[i] = bad != 0;
        run.laneCount += bad != 0;
    }
    return run;
}

std::string SampleStats::summary() const {
    std::string s = fmt::format("{}: {} cases, {} invalid ({} by input), NaN {}, Inf {}, negative {}", backend, cases,
                                invalid, expectedInvalid, nan, inf, negative);
    if (missedInvalid) s += fmt::format(", {} invalid inputs not reported", missedInvalid);
    if (unexpectedInvalid) s += fmt::format(", {} valid lanes reported invalid", unexpectedInvalid);
    if (invalidNonZero) s += fmt::format(", {} invalid lanes with non-zero output", invalidNonZero);
    if (validityMismatch) s += fmt::format(", {} lanes valid here but invalid in the reference", validityMismatch);
    if (countMismatch) s += ", batch count != invalid lanes";
    if (bound > 0) s += fmt::format(", max rel err {:.3g} (bound {:.0e}, {} beyond)", maxRel, bound, beyondBound);
    if (illConditioned) s += fmt::format(", {} ill-conditioned (max kappa {:.3g})", illConditioned, maxKappa);
    return s;
}

SampleStats checkReference(const std::vector<HardCase>& cases, const HardCaseReference& ref) {
    SampleStats s;
    s.backend = "interp";
    s.cases = cases.size();
    for (size_t i = 0; i < cases.size(); ++i) {
        const EvalResult<double>& r = ref.results[i];
        const HardCase& c = cases[i];
        s.expectedInvalid += c.invalidInput;
        s.invalid += !r.valid;
        for (double v : r.rgb) {
            if (std::isnan(v)) ++s.nan, addFailure(s, i, "NaN");
            else if (std::isinf(v)) ++s.inf, addFailure(s, i, "Inf");
            else if (v < 0) ++s.negative, addFailure(s, i, "negative");
        }
        if (c.invalidInput && (r.valid || r.rgb[0] != 0 || r.rgb[1] != 0 || r.rgb[2] != 0)) {
            ++s.missedInvalid;
            addFailure(s, i, "invalid input not reported");
        }
        if (!r.valid && (r.rgb[0] != 0 || r.rgb[1] != 0 || r.rgb[2] != 0)) {
            ++s.invalidNonZero;
            addFailure(s, i, "invalid lane with non-zero output");
        }
    }
    return s;
}

SampleStats checkKernel(const std::string& backend, const KernelRun& run, const std::vector<HardCase>& cases,
                        const HardCaseReference& ref, double bound, const std::function<double(size_t)>& condition,
                        double roundoff) {
    SampleStats s;
    s.backend = backend;
    s.cases = cases.size();
    s.bound = bound;
    s.countMismatch = run.batchCount != run.laneCount;
    for (size_t i = 0; i < cases.size(); ++i) {
        const HardCase& c = cases[i];
        const EvalResult<double>& r = ref.results[i];
        const std::array<float, 3>& got = run.rgb[i];
        bool invalid = run.invalid[i];
        s.expectedInvalid += c.invalidInput;
        s.invalid += invalid;
        bool zero = got[0] == 0 && got[1] == 0 && got[2] == 0;
        for (float v : got) {
            if (std::isnan(v)) ++s.nan, addFailure(s, i, "NaN");
            else if (std::isinf(v)) ++s.inf, addFailure(s, i, "Inf");
            else if (v < 0) ++s.negative, addFailure(s, i, fmt::format("negative {:.9g}", v));
        }
        if (c.invalidInput) {
            if (!invalid || !zero) {
                ++s.missedInvalid;
                addFailure(s, i, fmt::format("invalid input: lane {} with output ({:.9g},{:.9g},{:.9g})",
                                             invalid ? "counted" : "not counted", got[0], got[1], got[2]));
            }
            continue;
        }
        if (invalid) {
            if (!zero) ++s.invalidNonZero, addFailure(s, i, "invalid lane with non-zero output");
            if (r.valid && !ref.floatOverflow[i]) {
                ++s.unexpectedInvalid;
                addFailure(s, i,
                           fmt::format("reported invalid; reference ({:.17g},{:.17g},{:.17g}) is valid and within "
                                       "float range",
                                       r.rgb[0], r.rgb[1], r.rgb[2]));
            }
            continue;
        }
        if (!r.valid) {
            if (!zero) {
                ++s.validityMismatch;
                addFailure(s, i, fmt::format("valid ({:.9g},{:.9g},{:.9g}) but the reference is invalid", got[0],
                                             got[1], got[2]));
            }
            continue;
        }
        double kappa = -1;  // computed once per lane, when needed
        bool subnormal = false;
        for (const auto* w : {&c.wi, &c.wo})
            for (double x : *w) subnormal |= x != 0 && std::fabs(x) < double(FLT_MIN);
        for (int ch = 0; ch < 3; ++ch) {
            double g = got[ch], w = r.rgb[ch];
            if (!std::isfinite(g) || beyondFloatRange(w)) continue;
            ++s.compared;
            double rel = relativeError(g, w);
            // Beyond a few roundoffs, ask whether the input explains the error.
            if (rel > 8 * roundoff) {
                if (kappa < 0 && condition) kappa = condition(i);
                if (kappa >= 0 && rel <= kConditionAllowance * kappa * roundoff) {
                    ++s.illConditioned;
                    s.maxKappa = std::max(s.maxKappa, kappa);
                    continue;
                }
            }
            // The largest error not explained by conditioning, failures included (SampleStats::maxRel).
            if (rel > s.maxRel) {
                s.maxRel = rel;
                s.worstCase = i;
                s.worstChannel = ch;
                s.worstGot = g;
                s.worstWant = w;
            }
            if (rel > bound) {
                ++s.beyondBound;
                addFailure(s, i,
                           fmt::format("rel err {:.3g} ch {}: got {:.9g} want {:.17g}{}", rel, ch, g, w,
                                       kappa >= 0 ? fmt::format(" (kappa {:.3g})", kappa) : std::string()));
                continue;
            }
            s.maxRelWithin = std::max(s.maxRelWithin, rel);
            if (!subnormal) s.maxRelNormal = std::max(s.maxRelNormal, rel);
        }
    }
    return s;
}

}  // namespace facet
