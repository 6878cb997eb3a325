// facet render: pictures of a material (apps/preview/).
//
//   facet render FILE -o OUT.png|OUT.exr [--material NAME] [--size N]
//                [--light THETA,PHI] [--view THETA,PHI] [--irradiance E]
//                [--sky gradient|constant|none] [--sky-radiance L] [--samples N]
//                [--exposure EV] [--threads N] [--backend simd|scalar|interp]
//                [--math exact|fast] [--set NAME=VALUE]...
//       a lit sphere, shaded by the compiled kernel (SphereRender.h); a
//       material that scatters below its surface is lit through it, from
//       behind unless --light says otherwise
//   facet render FILE --plot lobe -o lobe.png [--theta-i A,B,...] [--size W]
//       the BRDF in the plane of incidence, one polar curve per theta_i
//       (the whole circle, theta_i up to 180, for a lobe that scatters below)
//   facet render FILE --plot ndf -o ndf.png [--alpha A,B,...] [--size W]
//       D(theta_m) of the material's NDF at several roughnesses
//   facet render --plot ndf --compare ggx,beckmann,student_t:gamma=3 [--alpha A,...] -o ndf.png
//       several NDFs at matched roughness (no material file needed), each
//       with its shape parameters' typical values or those given
//   facet render FILE --plot pdf --wo X,Y,Z -o pdf.png [-n N] [--seed S] [--size W]
//       the histogram of N importance samples of wi beside the pdf integrated
//       over the same cells (PdfPlot.h), and their chi-square test
//   facet render FILE --plot walk -o walk.png [--theta-i A] [-n WALKS] [--seed S] [--size W]
//       the first lobe the random walk supports in the plane of incidence:
//       single scattering, with its energy compensation, and the random walk
//       on its microsurface (WalkPlot.h); WALKS per outgoing angle
//
// Angles are in degrees. Exit codes as everywhere: 0 ok, 1 a check failed
// (invalid lanes, or the image could not be written), 2 usage, 65 a
// material file error.
#include "Commands.h"

#include "Checker.h"
#include "CsvTable.h"
#include "ChiSquare.h"
#include "Kernel.h"
#include "MaterialFile.h"
#include "OutputFile.h"
#include "PdfPlot.h"
#include "Plots.h"
#include "MicrosurfaceWalk.h"
#include "Sampling.h"
#include "SamplingSetup.h"
#include "SphereRender.h"
#include "WalkPlot.h"

#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <optional>

namespace facet {

namespace {

constexpr const char* kRenderUsage =
    "usage: facet render FILE -o OUT.png|OUT.exr [--material NAME] [--size N] [--light THETA,PHI]\n"
    "                    [--view THETA,PHI] [--irradiance E] [--sky gradient|constant|none]\n"
    "                    [--sky-radiance L] [--samples N] [--exposure EV] [--threads N]\n"
    "                    [--backend simd|scalar|interp] [--math exact|fast] [--set NAME=VALUE]...\n"
    "       facet render FILE --plot lobe -o lobe.png [--theta-i A,B,...] [--size WIDTH]\n"
    "       facet render FILE --plot ndf -o ndf.png [--alpha A,B,...] [--size WIDTH]\n"
    "       facet render --plot ndf --compare NDF[:PARAM=VALUE],... [--alpha A,...] -o ndf.png\n"
    "       facet render FILE --plot pdf --wo X,Y,Z -o pdf.png [-n N] [--seed S] [--size WIDTH]\n"
    "       facet render FILE --plot walk -o walk.png [--theta-i A] [-n WALKS] [--seed S] [--size WIDTH]\n"
    "angles in degrees: THETA from the view axis +Z, PHI from +X towards +Y (world up)\n";

struct RenderUsageError {
    std::string message;
};

std::vector<double> parseNumberList(const std::string& option, const std::string& text) {
    std::vector<double> values;
    for (const std::string& field : splitFields(text)) {
        std::optional<double> v = parseNumber(field);
        if (!v || !std::isfinite(*v))
            throw RenderUsageError{fmt::format("{}: '{}' is not a finite number", option, field)};
        values.push_back(*v);
    }
    return values;
}

double parseOneNumber(const std::string& option, const std::string& text) {
    std::vector<double> v = parseNumberList(option, text);
    if (v.size() != 1) throw RenderUsageError{fmt::format("{} expects one number, got '{}'", option, text)};
    return v[0];
}

int parseInteger(const std::string& option, const std::string& text, int lo, int hi) {
    double v = parseOneNumber(option, text);
    if (v != std::floor(v) || v < lo || v > hi)
        throw RenderUsageError{fmt::format("{} expects an integer in {} .. {}, got '{}'", option, lo, hi, text)};
    return int(v);
}

std::pair<double, double> parseAngles(const std::string& option, const std::string& text) {
    std::vector<double> v = parseNumberList(option, text);
    if (v.size() != 2) throw RenderUsageError{fmt::format("{} expects THETA,PHI in degrees, got '{}'", option, text)};
    if (v[0] < 0 || v[0] > 180) throw RenderUsageError{fmt::format("{}: theta {} is outside 0 .. 180", option, v[0])};
    return {v[0], v[1]};
}

struct RenderArgs {
    std::string file, material, out, plot, compare;
    std::string options = "";  // compile-option string (backend, math, set.NAME)
    std::string backend = "simd", math = "exact";
    std::vector<double> thetaI, alphas;
    std::optional<int> size;
    std::string wo;                // --plot pdf: the view direction
    bool lightGiven = false;       // --light was given
    long samples = 1000000;        // --plot pdf: -n (--plot walk: walks per angle, when given)
    bool samplesGiven = false;
    uint64_t seed = 1;             // --plot pdf: --seed
    preview::SphereScene scene;
};

RenderArgs parseRenderArgs(const std::vector<std::string>& args) {
    RenderArgs r;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) throw RenderUsageError{fmt::format("{} needs a value", a)};
            return args[++i];
        };
        if (a == "-o" || a == "--out") r.out = value();
        else if (a == "--material") r.material = value();
        else if (a == "--plot") {
            r.plot = value();
            if (r.plot != "lobe" && r.plot != "ndf" && r.plot != "pdf" && r.plot != "walk")
                throw RenderUsageError{fmt::format("--plot expects lobe, ndf, pdf or walk, got '{}'", r.plot)};
        } else if (a == "--compare") r.compare = value();
        else if (a == "--size") r.size = parseInteger(a, value(), 8, 16384);
        else if (a == "--light") {
            std::tie(r.scene.lightThetaDeg, r.scene.lightPhiDeg) = parseAngles(a, value());
            r.lightGiven = true;
        }
        else if (a == "--view") std::tie(r.scene.viewThetaDeg, r.scene.viewPhiDeg) = parseAngles(a, value());
        else if (a == "--irradiance") r.scene.lightIrradiance = parseOneNumber(a, value());
        else if (a == "--sky") {
            const std::string& v = value();
            if (v == "gradient") r.scene.sky = preview::SkyModel::Gradient;
            else if (v == "constant") r.scene.sky = preview::SkyModel::Constant;
            else if (v == "none") r.scene.sky = preview::SkyModel::None;
            else throw RenderUsageError{fmt::format("--sky expects gradient, constant or none, got '{}'", v)};
        } else if (a == "--sky-radiance") r.scene.skyRadiance = parseOneNumber(a, value());
        else if (a == "--samples") r.scene.skySamples = parseInteger(a, value(), 0, 65536);
        else if (a == "--exposure") r.scene.exposureEv = parseOneNumber(a, value());
        else if (a == "--threads") r.scene.threads = parseInteger(a, value(), 1, 1024);
        else if (a == "--backend") r.backend = value();
        else if (a == "--math") r.math = value();
        else if (a == "--set") r.options += ";set." + value();
        else if (a == "--theta-i") r.thetaI = parseNumberList(a, value());
        else if (a == "--alpha") r.alphas = parseNumberList(a, value());
        else if (a == "--wo") r.wo = value();
        else if (a == "-n") r.samples = parseInteger(a, value(), 1, 100000000), r.samplesGiven = true;
        else if (a == "--seed") {
            if (std::string why = parseSeed(a, value(), r.seed); !why.empty()) throw RenderUsageError{why};
        }
        else if (!a.empty() && a[0] == '-') throw RenderUsageError{fmt::format("unknown option '{}'", a)};
        else if (r.file.empty()) r.file = a;
        else throw RenderUsageError{fmt::format("more than one material file ('{}' and '{}')", r.file, a)};
    }
    if (r.out.empty()) throw RenderUsageError{"-o OUT is required"};
    if (std::string why = sameFileProblem("facet render", r.out,
                                          {{r.file, "the material file"}, {r.compare, "the --compare file"}});
        !why.empty())
        throw RenderUsageError{why};
    if (!r.compare.empty() && r.plot != "ndf") throw RenderUsageError{"--compare goes with --plot ndf"};
    if (r.file.empty() && r.compare.empty()) throw RenderUsageError{"no material file given"};
    if (!r.thetaI.empty() && r.plot != "lobe" && r.plot != "walk")
        throw RenderUsageError{"--theta-i goes with --plot lobe or walk"};
    if (r.plot == "walk" && r.thetaI.size() > 1) throw RenderUsageError{"--plot walk takes one --theta-i"};
    if (r.plot == "walk" && !r.options.empty())
        throw RenderUsageError{"--set does not apply to --plot walk (it plots the material at its default inputs)"};
    if (!r.alphas.empty() && r.plot != "ndf") throw RenderUsageError{"--alpha goes with --plot ndf"};
    if (!r.wo.empty() && r.plot != "pdf") throw RenderUsageError{"--wo goes with --plot pdf"};
    if (r.plot == "pdf" && r.wo.empty()) throw RenderUsageError{"--plot pdf needs --wo X,Y,Z"};
    if (r.plot == "pdf" && !r.options.empty())
        throw RenderUsageError{"--set does not apply to --plot pdf (it samples the material at its default inputs)"};
    for (double a : r.alphas)
        if (!(a > 0 && a <= 4)) throw RenderUsageError{fmt::format("--alpha: {} is outside (0, 4]", a)};
    if (r.size) r.scene.size = *r.size;
    if (std::string why = preview::validateScene(r.scene); !why.empty()) throw RenderUsageError{why};
    r.options = fmt::format("backend={};math={}", r.backend, r.math) + r.options;
    return r;
}

// Compiles the material; on failure prints the diagnostics and returns null.
std::unique_ptr<Kernel> compileForRender(Compiler& compiler, const RenderArgs& r, int& exitCode) {
    CompileOptions options;
    if (std::string err = CompileOptions::parse(r.options, options); !err.empty()) throw RenderUsageError{err};
    DiagnosticEngine diags;
    // --set names an input of the material: a usage error (exit 2) otherwise,
    // as in eval and ir.
    CheckedProgram program = loadProgramFile(r.file, diags);
    if (const CheckedMaterial* m = diags.hasErrors() ? nullptr : program.find(r.material))
        for (const auto& [name, values] : options.bindings)
            if (!m->findInput(name))
                throw RenderUsageError{fmt::format("--set: material '{}' has no input '{}'", m->name, name)};
    diags.clear();
    std::unique_ptr<Kernel> kernel = compiler.compileFile(r.file, r.material, options, diags);
    if (!kernel) {
        std::fputs(diags.str().c_str(), stderr);
        exitCode = kExitMaterialError;
    }
    return kernel;
}

// The default light of a material that scatters below its surface: behind
// the sphere, up and to the left, so that the rim shows what comes through.
constexpr double kLightBehindThetaDeg = 135;

int renderSphereCommand(const RenderArgs& r) {
    Compiler compiler;
    int exitCode = kExitOk;
    std::unique_ptr<Kernel> kernel = compileForRender(compiler, r, exitCode);
    if (!kernel) return exitCode;
    preview::SphereScene scene = r.scene;
    const CheckedMaterial& m = kernel->material();
    if (scattersBelowSurface(m)) {
        // What comes through: the light behind the sphere unless placed.
        scene.lightThrough = true;
        if (!r.lightGiven) scene.lightThetaDeg = kLightBehindThetaDeg;
        std::printf("material %s scatters below its surface: the sphere is that one surface, lit through it from "
                    "(theta %g, phi %g)\n",
                    m.name.c_str(), scene.lightThetaDeg, scene.lightPhiDeg);
    }
    preview::SphereImage image = preview::renderSphere(*kernel, scene);
    const preview::RenderStats& s = image.stats;
    std::printf("material %s: %s %s kernel (%s, %d lanes), compiled in %.1f ms (%s)\n", kernel->material().name.c_str(),
                backendName(kernel->backend()), kernel->variant().c_str(), r.math.c_str(), kernel->width(),
                kernel->compileMillis(), kernel->origin().c_str());
    int skySamples = r.scene.sky == preview::SkyModel::None ? 0 : r.scene.skySamples;
    double lanes = double(s.evaluations + s.samples);
    std::printf("rendered %dx%d: %lld pixels x (1 light evaluation + %d sky samples from the kernel's sampler) = "
                "%.2fM kernel lanes in %.3f s on %d threads (%.1fM lanes/s; %.3f s of thread time in the kernel, "
                "sampler %s)\n",
                r.scene.size, r.scene.size, (long long)s.pixels, skySamples, lanes / 1e6, s.seconds, s.threads,
                lanes / 1e6 / std::max(s.seconds, 1e-9), s.kernelSeconds, kernel->samplerTier().c_str());
    if (std::string err = preview::writeSphereImage(image, scene, r.out); !err.empty()) {
        std::fprintf(stderr, "facet: render: %s\n", err.c_str());
        return kExitFailed;
    }
    std::printf("wrote %s\n", r.out.c_str());
    if (s.invalidLanes) {
        std::fprintf(stderr, "facet: render: %lld of %lld kernel lanes were invalid (shaded black): the material's "
                     "parameters are not finite at these inputs\n", (long long)s.invalidLanes,
                     (long long)(s.evaluations + s.samples));
        return kExitFailed;
    }
    return kExitOk;
}

// Loads r.file and finds its material r.material (null in `material`
// after a material file error). A missing material is a usage error.
NamedMaterial loadRenderMaterial(const RenderArgs& r) {
    NamedMaterial named = loadNamedMaterial(r.file, r.material);
    if (!named.fileErrors && !named.material) throw RenderUsageError{named.missing};
    return named;
}

int lobePlotCommand(const RenderArgs& r) {
    Compiler compiler;
    int exitCode = kExitOk;
    std::unique_ptr<Kernel> kernel = compileForRender(compiler, r, exitCode);
    if (!kernel) return exitCode;
    preview::LobePlotOptions opt;
    const CheckedMaterial& m = kernel->material();
    opt.wholeSphere = scattersBelowSurface(m);
    if (opt.wholeSphere) opt.incidentDegrees = {0, 40, 70, 140};  // 140: light arriving from inside
    if (!r.thetaI.empty()) opt.incidentDegrees = r.thetaI;
    if (r.size) opt.width = *r.size, opt.height = *r.size * (opt.wholeSphere ? 9 : 5) / 8;
    if (opt.wholeSphere && !r.size) opt.height = opt.width * 9 / 8;
    opt.title = fmt::format("{}: f |cos(theta_o)| in the plane of incidence{}", m.name,
                            opt.wholeSphere ? ", both sides of the surface" : "");
    preview::LobePlotResult result = preview::writeLobePlot(*kernel, opt, r.out);
    if (!result.error.empty()) {
        std::fprintf(stderr, "facet: render: %s\n", result.error.c_str());
        return kExitFailed;
    }
    if (!result.warning.empty()) std::fprintf(stderr, "facet: render: warning: %s\n", result.warning.c_str());
    for (size_t i = 0; i < result.peakValue.size(); ++i)
        std::printf("theta_i %g: peak of luminance(f) %s = %.6g at theta_o = %.2f\n", opt.incidentDegrees[i],
                    opt.wholeSphere ? "|cos(theta_o)|" : "cos(theta_o)", result.peakValue[i], result.peakThetaDeg[i]);
    std::printf("wrote %s\n", r.out.c_str());
    if (result.invalidLanes) {
        std::fprintf(stderr, "facet: render: %lld kernel lanes were invalid\n", (long long)result.invalidLanes);
        return kExitFailed;
    }
    return kExitOk;
}

// One NDF of --compare: NAME, or NAME:PARAM=VALUE[:PARAM=VALUE] with the
// values of its shape parameters (student_t:gamma=3); the others take their
// typical values.
struct CompareModel {
    const NdfEntry* ndf = nullptr;
    std::vector<double> shape;  // per tableShapeParams entry
    std::string shapeText;      // " gamma=3", for the legend
};

CompareModel parseCompareModel(const std::string& field) {
    std::vector<std::string> parts;
    for (size_t start = 0;;) {
        size_t colon = field.find(':', start);
        parts.push_back(field.substr(start, colon - start));
        if (colon == std::string::npos) break;
        start = colon + 1;
    }
    const ModelInfo* info = findModel(ModelSlot::Ndf, parts[0]);  // names and aliases of the language
    if (!info || ndfEntry(*info).wholeLobe) {
        std::vector<std::string> plottable;
        for (const ModelInfo* m : catalogSlot(ModelSlot::Ndf))
            if (!ndfEntry(*m).wholeLobe) plottable.push_back(m->name);
        throw RenderUsageError{fmt::format("--compare: '{}' is not an NDF with a distribution to plot ({})", parts[0],
                                           fmt::join(plottable, ", "))};
    }
    CompareModel out;
    out.ndf = &ndfEntry(*info);
    std::vector<std::string> names;
    for (int p : out.ndf->tableShapeParams) {
        names.push_back(out.ndf->canonical[p].name);
        out.shape.push_back(out.ndf->canonical[p].typical);
    }
    for (size_t i = 1; i < parts.size(); ++i) {
        size_t eq = parts[i].find('=');
        std::string name = parts[i].substr(0, eq);
        auto it = std::find(names.begin(), names.end(), name);
        if (it == names.end())
            throw RenderUsageError{fmt::format("--compare: '{}' has no shape parameter '{}' (its shape parameters: {})",
                                               out.ndf->name, name, names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", ")))};
        std::optional<double> value = eq == std::string::npos ? std::nullopt : parseNumber(parts[i].substr(eq + 1));
        const ModelParam& param = out.ndf->canonical[out.ndf->tableShapeParams[size_t(it - names.begin())]];
        if (!value || !(*value >= param.lo && *value <= param.hi))
            throw RenderUsageError{fmt::format("--compare: '{}' is not NAME=VALUE with {} in [{:g}, {:g}]", parts[i],
                                               name, param.lo, param.hi)};
        out.shape[size_t(it - names.begin())] = *value;
        out.shapeText += fmt::format(" {}={:g}", name, *value);
    }
    return out;
}

int ndfPlotCommand(const RenderArgs& r) {
    std::vector<preview::NdfCurve> curves;
    std::vector<double> alphas = r.alphas;
    preview::NdfPlotOptions opt;
    if (r.size) opt.width = *r.size, opt.height = *r.size * 5 / 8;
    if (!r.compare.empty()) {
        // Several NDFs at matched roughness.
        if (alphas.empty()) alphas = {0.3};
        std::vector<CompareModel> models;
        for (const std::string& field : splitFields(r.compare)) models.push_back(parseCompareModel(field));
        for (double a : alphas)
            for (const CompareModel& m : models)
                curves.push_back({fmt::format("{}{}, alpha = {:g}", m.ndf->name, m.shapeText, a),
                                  preview::ndfAtAlpha(*m.ndf, a, m.shape)});
        opt.title = alphas.size() == 1 ? fmt::format("D(theta_m) at matched roughness alpha = {:g}", alphas[0])
                                       : std::string("D(theta_m) at matched roughness");
    } else {
        NamedMaterial named = loadRenderMaterial(r);
        const CheckedMaterial* m = named.material;
        if (!m) return kExitMaterialError;
        // D is a property of one microfacet lobe: a combination, or a lobe
        // with only a diffuse term, has none to plot.
        if (m->combinesLobes() || !m->singleLobe().hasNdf()) {
            std::fprintf(stderr, "%s: error: material '%s': %s\n", m->loc.str().c_str(), m->name.c_str(),
                         m->combinesLobes() ? "combines lobes; the D plot needs a material of one microfacet lobe"
                                            : "has no ndf (a diffuse lobe); there is no D to plot");
            return kExitFailed;
        }
        const NdfEntry& model = ndfEntry(*m->singleLobe().ndf.model);
        if (model.wholeLobe) {
            std::fprintf(stderr, "%s: error: material '%s': the %s model has no microfacet distribution D to plot\n",
                         m->loc.str().c_str(), m->name.c_str(), model.name);
            return kExitFailed;
        }
        Interpreter<double> interp(*m);
        ResolvedMaterial<double> resolved = interp.resolve(nullptr);
        // The material's own shape parameters (gtr's gamma), else the typical ones.
        std::vector<double> shape;
        std::string shapeText;
        for (int p : model.tableShapeParams) {
            shape.push_back(resolved.valid ? resolved.ndfArgs[p] : model.canonical[p].typical);
            shapeText += fmt::format(", {} = {:g}", model.canonical[p].name, shape.back());
        }
        if (alphas.empty()) alphas = {0.1, 0.2, 0.3, 0.5, 0.8};
        for (double a : alphas)
            curves.push_back({fmt::format("alpha = {:g}", a), preview::ndfAtAlpha(model, a, shape)});
        opt.title = fmt::format("{}: {} D(theta_m){}", m->name, model.name, shapeText);
    }
    if (std::string err = preview::writeNdfPlot(curves, opt, r.out); !err.empty()) {
        std::fprintf(stderr, "facet: render: %s\n", err.c_str());
        return kExitFailed;
    }
    std::printf("wrote %s (%zu curves)\n", r.out.c_str(), curves.size());
    return kExitOk;
}

// The equal-area grid of the pdf plot: square-ish cells, 2 columns per row.
constexpr int kPdfPlotRows = 48, kPdfPlotColumns = 96;

int pdfPlotCommand(const RenderArgs& r) {
    std::array<double, 3> wo;
    if (std::string why = parseViewDirection("--wo", r.wo, wo); !why.empty()) throw RenderUsageError{why};
    NamedMaterial named = loadRenderMaterial(r);
    const CheckedMaterial* m = named.material;
    if (!m) return kExitMaterialError;
    if (std::string why = viewSideProblem("--wo", r.wo, wo, *m); !why.empty()) throw RenderUsageError{why};
    std::unique_ptr<Interpreter<double>> sampler = referenceInterpreter(*m);

    SphereGrid grid = SphereGrid::equalArea(kPdfPlotRows, kPdfPlotColumns);
    CellHistogram samples(grid);
    SampleUniforms uniforms(r.seed);  // those of `facet sample`: a seed draws the same samples
    auto uniform = [&] { return uniforms.next(); };
    long invalid = 0;
    for (long i = 0; i < r.samples; ++i) {
        double u[3] = {uniform(), uniform(), uniform()};
        SampleResult<double> s = sampler->sample(wo.data(), u, nullptr);
        invalid += !s.valid;
        if (s.valid && s.pdf > 0) samples.add(grid, s.wi);
        else samples.addNone();
    }
    if (invalid) {
        std::fprintf(stderr, "facet: render: %ld of %ld samples are invalid (the material's default inputs are not "
                     "finite, or a result overflowed)\n", invalid, r.samples);
        return kExitFailed;
    }
    auto pdf = [&](const Vec3<double>& wi) {
        double w[3] = {wi.x, wi.y, wi.z};
        PdfResult<double> p = sampler->pdf(w, wo.data(), nullptr);
        return p.valid ? p.pdf : 0.0;
    };
    // Cell integrals to 1% of a sample: far below the counts' noise.
    FitOutcome fit = fitToPdf(grid, samples, pdf, FitSettings{0.01 / double(r.samples)});
    const Chi2Outcome& chi2 = fit.chi2;
    double mass = fit.integral;
    long none = samples.unbinned;
    preview::SampleHistogram h;
    h.rows = grid.rings(), h.columns = grid.sectors();
    h.observed = std::move(samples.observed);
    h.expected = std::move(fit.expected);

    preview::PdfPlotOptions opt;
    if (r.size) opt.width = *r.size, opt.height = *r.size * 3 / 8;
    opt.title = fmt::format("{}: importance samples of wi for wo = ({})", m->name, r.wo);
    std::string verdict = chi2.dof > 0 ? fmt::format("chi-square {:.1f}, {} degrees of freedom, p = {:.3g}",
                                                     chi2.statistic, chi2.dof, chi2.pValue)
                                       : chi2.failure;
    opt.subtitle = fmt::format("{} cells of equal solid angle; pdf integral {:.6f}; {}", grid.cellCount(), mass, verdict);
    std::string warning;
    if (std::string err = preview::writePdfPlot(h, opt, r.out, &warning); !err.empty()) {
        std::fprintf(stderr, "facet: render: %s\n", err.c_str());
        return kExitFailed;
    }
    if (!warning.empty()) std::fprintf(stderr, "facet: render: warning: %s\n", warning.c_str());
    std::printf("%ld samples (%ld with no direction), %d cells: pdf integral %.6f; %s\n", r.samples, none,
                grid.cellCount(), mass, chi2.failure.empty() ? verdict.c_str() : chi2.failure.c_str());
    std::printf("wrote %s\n", r.out.c_str());
    return kExitOk;
}

// The first lobe of the material (default inputs) that the random walk
// supports, drawn by WalkPlot.
int walkPlotCommand(const RenderArgs& r) {
    NamedMaterial named = loadRenderMaterial(r);
    const CheckedMaterial* m = named.material;
    if (!m) return kExitMaterialError;
    std::unique_ptr<Interpreter<double>> interp = referenceInterpreter(*m);
    ResolvedBsdf<double> all = interp->resolveAll(nullptr);
    if (!all.valid) {
        std::fprintf(stderr, "facet: render: %s's default inputs are not finite\n", m->name.c_str());
        return kExitFailed;
    }
    std::string reasons;
    for (size_t i = 0; i < all.lobes.size(); ++i) {
        std::string why = MicrosurfaceWalk::unsupported(all.lobes[i]);
        if (!why.empty()) {
            reasons += fmt::format("{}lobe '{}': {}", reasons.empty() ? "" : "; ", m->lobes[i].name, why);
            continue;
        }
        preview::WalkPlotOptions opt;
        if (!r.thetaI.empty()) opt.incidentDegrees = r.thetaI[0];
        if (r.samplesGiven) opt.paths = r.samples;
        opt.seed = r.seed;
        if (r.size) opt.plot.width = *r.size, opt.plot.height = *r.size * 5 / 8;
        opt.plot.title = fmt::format("{}{}: theta_i = {:g}, {} walks per angle", m->name,
                                     m->combinesLobes() ? " lobe " + m->lobes[i].name : "", opt.incidentDegrees, opt.paths);
        preview::WalkPlotResult result = preview::writeWalkPlot(all.lobes[i], opt, r.out);
        if (!result.error.empty()) {
            std::fprintf(stderr, "facet: render: %s\n", result.error.c_str());
            return kExitFailed;
        }
        if (!result.warning.empty()) std::fprintf(stderr, "facet: render: warning: %s\n", result.warning.c_str());
        std::printf("peak of luminance(f) cos(theta_o): model %.6g, random walk %.6g\n", result.modelPeak,
                    result.walkPeak);
        std::printf("wrote %s\n", r.out.c_str());
        return kExitOk;
    }
    std::fprintf(stderr, "facet: render: no lobe of %s has a random walk (%s)\n", m->name.c_str(), reasons.c_str());
    return kExitFailed;
}

}  // namespace

int cmdRender(const std::vector<std::string>& args) {
    try {
        RenderArgs r = parseRenderArgs(args);
        if (r.plot == "lobe") return lobePlotCommand(r);
        if (r.plot == "ndf") return ndfPlotCommand(r);
        if (r.plot == "pdf") return pdfPlotCommand(r);
        if (r.plot == "walk") return walkPlotCommand(r);
        return renderSphereCommand(r);
    } catch (const RenderUsageError& e) {
        std::fprintf(stderr, "facet: render: %s\n%s", e.message.c_str(), kRenderUsage);
        return kExitUsage;
    }
}

}  // namespace facet
