// SamplingCheck: see SamplingCheck.h.
#include "SamplingCheck.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <random>

namespace sampling_test {

std::string CheckOutcome::describe() const {
    return fmt::format("pdf integral {:.7f} (below the horizon {:.5f}), {} draws without a sample, {}", integral,
                       belowHorizon, noSample,
                       chi2.failure.empty() ? fmt::format("chi-square {:.1f}, dof {}, p = {:.3g}", chi2.statistic,
                                                          chi2.dof, chi2.pValue)
                                            : chi2.failure);
}

CheckOutcome checkSampler(const Sampler& sampler, const PdfFunction& pdf, const SphereGrid& grid,
                          const CheckSettings& s) {
    CellHistogram samples(grid);
    std::mt19937_64 rng(s.seed);
    std::uniform_real_distribution<double> uniform(0, 1);
    for (int i = 0; i < s.samples; ++i) {
        std::array<double, 3> u{uniform(rng), uniform(rng), uniform(rng)};
        facet::SampleResult<double> r = sampler(u);
        if (r.pdf > 0) samples.add(grid, r.wi);
        else samples.addNone();
    }
    FitSettings fit{s.normalizationTolerance / (10.0 * double(grid.cellCount())), s.level, s.minExpected,
                    s.renormalize};
    FitOutcome f = fitToPdf(grid, samples, pdf, fit);
    CheckOutcome out;
    out.integral = f.integral;
    out.belowHorizon = f.belowHorizon;
    out.noSample = int(samples.unbinned);
    out.chi2 = f.chi2;
    return out;
}

SphereGrid lobeGrid(const facet::ResolvedMaterial<double>& r, const V3& wo) {
    auto [ax, ay] = r.ndf->equivalentAlphas(r.ndfArgs);
    double first = std::min({ax, ay, 1.0}) / 2;
    double theta = std::atan2(std::sqrt(wo.x * wo.x + wo.y * wo.y), wo.z), phi = std::atan2(-wo.y, -wo.x);
    // Out of the plane of incidence, a tilt d of m turns wi by 2 (wo.m) d:
    // the lobe is 2 alpha cos(theta_o) wide there, alpha cot(theta_o) in azimuth.
    double firstPhi = std::min(0.2, first * std::max(wo.z, 1e-7) / std::max(std::sin(theta), 1e-7));
    return SphereGrid::forLobe(theta, theta, phi, first, firstPhi);
}

CheckOutcome checkMaterial(const facet::ResolvedMaterial<double>& r, const V3& wo, const CheckSettings& s,
                           const PdfFunction& pdf) {
    SphereGrid grid = lobeGrid(r, wo);
    return checkSampler([&](const std::array<double, 3>& u) { return facet::sampleBrdf(r, wo, u); },
                        pdf ? pdf : PdfFunction([&](const V3& wi) { return facet::brdfPdf(r, wi, wo); }), grid, s);
}

}  // namespace sampling_test
