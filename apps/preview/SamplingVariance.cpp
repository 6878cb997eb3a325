// SamplingVariance: the technique study (see SamplingVariance.h).
#include "SamplingVariance.h"

#include "SphereRender.h"

#include <fmt/format.h>

#include <chrono>
#include <iterator>
#include <cmath>
#include <stdexcept>

namespace facet::preview {

namespace {

std::string materialText(const std::string& ndf, double alpha) {
    // Blinn-Phong at the exponent whose Beckmann alpha matches (Walter et
    // al. 2007: n = 2 / alpha^2 - 2).
    std::string arg = ndf == "blinn_phong" ? fmt::format("beckmann_to_phong({})", alpha) : fmt::format("{}", alpha);
    return fmt::format("material lobe {{ ndf = {}({}); masking = smith_height_correlated; fresnel = schlick(0.9); }}",
                       ndf, arg);
}

// RMSE of `image` against `reference` over the pixels the sphere covers.
double rmse(const SphereImage& image, const SphereImage& reference, double& referenceMean) {
    double sum = 0, mean = 0;
    size_t count = 0;
    for (size_t p = 0; p < reference.coverage.size(); ++p) {
        if (reference.coverage[p] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            double d = double(image.radiance[p * 3 + c]) - reference.radiance[p * 3 + c];
            sum += d * d;
            mean += reference.radiance[p * 3 + c];
            ++count;
        }
    }
    referenceMean = count ? mean / double(count) : 0;
    return count ? std::sqrt(sum / double(count)) : 0;
}

}  // namespace

std::vector<VarianceRow> measureSamplingVariance(Compiler& compiler, const VarianceSettings& settings) {
    SphereScene scene;
    scene.size = settings.size;
    scene.lightIrradiance = 0;  // the sky alone: the light's lane has no variance
    scene.viewThetaDeg = 30;    // the view off the pole, so grazing directions are on screen
    scene.threads = settings.threads;
    std::vector<VarianceRow> rows;
    for (const char* ndf : {"ggx", "beckmann", "blinn_phong"})
        for (double alpha : {0.05, 0.3}) {
            auto start = std::chrono::steady_clock::now();
            VarianceRow row;
            row.ndf = ndf;
            row.alpha = alpha;
            row.material = materialText(ndf, alpha);
            CompileOptions options;
            options.cache = CompileOptions::Cache::Memory;
            DiagnosticEngine diags;
            std::unique_ptr<Kernel> kernel = compiler.compileText(row.material, "variance.mat", "", options, diags);
            if (!kernel) throw std::runtime_error("cannot compile " + row.material + ": " + diags.str());
            SphereScene referenceScene = scene;
            referenceScene.skySamples = settings.referenceSamples;
            SphereImage reference = renderSphere(*kernel, referenceScene);

            Interpreter<double> interp(kernel->material(), kernel->energyTable());
            const ResolvedMaterial<double> resolved = interp.resolve(nullptr);
            SphereScene noisy = scene;
            noisy.skySamples = settings.samples;
            for (SamplingTechnique technique : kVarianceTechniques) {
                if (technique == SamplingTechnique::VisibleNormals && !hasVisibleNormalSampler(resolved)) {
                    row.rmse.push_back(std::nullopt);
                    continue;
                }
                // The reference sampler with the technique forced, lane by
                // lane in double (the material has no inputs).
                SkySampler sampler = [&](int64_t n, const float* const wo[3], const float* const u[3],
                                         float* const wi[3], float* pdf, float* const weight[3]) {
                    for (int64_t i = 0; i < n; ++i) {
                        Vec3<double> o{wo[0][i], wo[1][i], wo[2][i]};
                        double len = std::sqrt(o.x * o.x + o.y * o.y + o.z * o.z);
                        o = {o.x / len, o.y / len, o.z / len};
                        SampleResult<double> s =
                            sampleBrdf(resolved, o, std::array<double, 3>{u[0][i], u[1][i], u[2][i]}, technique);
                        wi[0][i] = float(s.wi.x), wi[1][i] = float(s.wi.y), wi[2][i] = float(s.wi.z);
                        pdf[i] = float(s.pdf);
                        for (int c = 0; c < 3; ++c) weight[c][i] = float(s.weight[c]);
                    }
                    return int64_t(0);
                };
                SphereImage image = renderSphere(*kernel, noisy, sampler);
                row.rmse.push_back(rmse(image, reference, row.referenceMean));
            }
            row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            rows.push_back(std::move(row));
        }
    return rows;
}

std::string varianceTable(const std::vector<VarianceRow>& rows, const VarianceSettings& settings) {
    std::string md = fmt::format(
        "RMSE of the sky-lit sphere ({}x{} pixels, view 30 deg off the pole, no light) at {} samples per pixel "
        "against {} samples per pixel with the kernel's own sampler; Schlick F0 = 0.9, Smith height-correlated, "
        "no diffuse. Lower is better; the lowest per row is in bold.\n\n",
        settings.size, settings.size, settings.samples, settings.referenceSamples);
    md += "| NDF | alpha | mean radiance |";
    for (SamplingTechnique t : kVarianceTechniques) md += fmt::format(" {} |", samplingTechniqueName(t));
    md += " time |\n|---|--:|--:|";
    for (size_t i = 0; i < std::size(kVarianceTechniques); ++i) md += "--:|";
    md += "--:|\n";
    for (const VarianceRow& r : rows) {
        double best = INFINITY;
        for (const auto& v : r.rmse)
            if (v) best = std::min(best, *v);
        md += fmt::format("| {} | {} | {:.4f} |", r.ndf, r.alpha, r.referenceMean);
        for (const auto& v : r.rmse) {
            if (!v) md += " n/a |";
            else md += *v == best ? fmt::format(" **{:.4g}** |", *v) : fmt::format(" {:.4g} |", *v);
        }
        md += fmt::format(" {:.1f} s |\n", r.seconds);
    }
    return md;
}

}  // namespace facet::preview
