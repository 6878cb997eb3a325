// Tests of the lit-sphere preview (apps/preview/SphereRender): image size
// and values, the highlight where the mirror geometry puts it, the SIMD and
// scalar kernels' renders against the interpreter's, the sky estimator
// against an independent quadrature of the directional albedo, determinism
// across thread counts, and the written PNG / EXR files.
#include "Interpreter.h"
#include "Kernel.h"
#include "SamplingVariance.h"
#include "SphereRender.h"

#include <OpenImageIO/imagebuf.h>
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <numbers>

using namespace facet;
using namespace facet::preview;

namespace {

std::unique_ptr<Kernel> compileSource(Compiler& compiler, const std::string& source, const std::string& options) {
    CompileOptions opt;
    REQUIRE(CompileOptions::parse(options, opt) == "");
    DiagnosticEngine diags;
    std::unique_ptr<Kernel> k = compiler.compileText(source, "test.mat", "", opt, diags);
    INFO(diags.str());
    REQUIRE(k);
    return k;
}

std::unique_ptr<Kernel> compileMaterialFile(Compiler& compiler, const std::string& name, const std::string& options) {
    CompileOptions opt;
    REQUIRE(CompileOptions::parse(options, opt) == "");
    DiagnosticEngine diags;
    std::unique_ptr<Kernel> k =
        compiler.compileFile(std::string(FACET_SOURCE_DIR) + "/materials/" + name + ".mat", "", opt, diags);
    INFO(diags.str());
    REQUIRE(k);
    return k;
}

const char* kSmoothGgx = R"(material smooth_ggx {
    ndf = ggx(0.05);
    masking = smith_height_correlated;
    fresnel = schlick(0.04);
})";

// Mean over covered pixels of |a - b| / |b| per channel (b the reference;
// pixels where the reference is ~0 compare absolutely).
double meanRelativeDifference(const SphereImage& a, const SphereImage& b) {
    double sum = 0;
    int64_t count = 0;
    for (int y = 0; y < a.size; ++y)
        for (int x = 0; x < a.size; ++x) {
            if (b.coverage[size_t(y) * b.size + x] <= 0) continue;
            for (int c = 0; c < 3; ++c) {
                double ref = b.at(x, y, c), v = a.at(x, y, c);
                sum += std::fabs(v - ref) / std::max(std::fabs(ref), 1e-6);
                ++count;
            }
        }
    REQUIRE(count > 0);
    return sum / double(count);
}

}  // namespace

TEST_SUITE("render") {

TEST_CASE("a rendered sphere has the requested size, finite non-negative radiance and a round silhouette") {
    Compiler compiler;
    auto kernel = compileMaterialFile(compiler, "plastic", "backend=simd");
    for (int size : {33, 64}) {
        SphereScene scene;
        scene.size = size;
        scene.skySamples = 8;
        SphereImage img = renderSphere(*kernel, scene);
        CHECK(img.size == size);
        REQUIRE(img.radiance.size() == size_t(size) * size * 3);
        double covered = 0;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                float cov = img.coverage[size_t(y) * size + x];
                CHECK((cov >= 0 && cov <= 1));
                covered += cov;
                for (int c = 0; c < 3; ++c) {
                    float v = img.at(x, y, c);
                    REQUIRE(std::isfinite(v));
                    CHECK(v >= 0);
                    if (cov == 0) CHECK(v == 0);
                }
            }
        // The disk of diameter 0.9 size, up to the antialiased edge.
        double area = std::numbers::pi * std::pow(0.45 * size, 2);
        CHECK(covered == doctest::Approx(area).epsilon(0.02));
        CHECK(img.stats.invalidLanes == 0);
        CHECK(img.stats.evaluations == img.stats.pixels);
        CHECK(img.stats.samples == img.stats.pixels * scene.skySamples);
        // Red plastic (albedo 0.6, 0.05, 0.04): the body colour dominates.
        double r = 0, g = 0;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) r += img.at(x, y, 0), g += img.at(x, y, 1);
        CHECK(r > 3 * g);
    }
}

TEST_CASE("the highlight of a smooth GGX material lies where the normal is the half vector") {
    Compiler compiler;
    auto kernel = compileSource(compiler, kSmoothGgx, "backend=simd");
    struct Light {
        double theta, phi;
    };
    for (Light light : {Light{45, 135}, Light{30, 0}, Light{60, 250}, Light{20, 90}}) {
        SphereScene scene;
        scene.size = 160;
        scene.skySamples = 16;
        scene.lightThetaDeg = light.theta, scene.lightPhiDeg = light.phi;
        SphereImage img = renderSphere(*kernel, scene);
        int bestX = -1, bestY = -1;
        double best = -1;
        for (int y = 0; y < img.size; ++y)
            for (int x = 0; x < img.size; ++x) {
                float rgb[3] = {img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)};
                if (luminance(rgb) > best) best = luminance(rgb), bestX = x, bestY = y;
            }
        std::optional<std::array<double, 2>> expected = highlightPixel(scene);
        REQUIRE(expected);
        INFO(fmt::format("light ({}, {}): brightest pixel ({}, {}), analytic ({:.2f}, {:.2f})", light.theta, light.phi,
                         bestX, bestY, (*expected)[0], (*expected)[1]));
        CHECK(std::hypot(bestX - (*expected)[0], bestY - (*expected)[1]) <= 2.0);
    }
    // Sanity of the analytic position itself: light along the view axis
    // puts the highlight at the image centre.
    SphereScene front;
    front.size = 101;
    front.lightThetaDeg = 0;
    CHECK((*highlightPixel(front))[0] == doctest::Approx(50.0));
    CHECK((*highlightPixel(front))[1] == doctest::Approx(50.0));
}

TEST_CASE("the SIMD and scalar kernels render what the interpreter renders (mean relative difference < 1e-4)") {
    Compiler compiler;
    SphereScene scene;
    scene.size = 40;
    scene.skySamples = 16;
    for (const char* name : {"gold", "brushed_metal", "plastic", "legacy_blinn_phong"}) {
        auto interp = compileMaterialFile(compiler, name, "backend=interp");
        SphereImage reference = renderSphere(*interp, scene);
        for (const char* backend : {"simd", "scalar"}) {
            auto kernel = compileMaterialFile(compiler, name, fmt::format("backend={};math=exact", backend));
            SphereImage img = renderSphere(*kernel, scene);
            double diff = meanRelativeDifference(img, reference);
            INFO(fmt::format("{} {}: mean relative difference {:.3g}", name, backend, diff));
            CHECK(diff < 1e-4);
            CHECK(img.stats.invalidLanes == 0);
        }
    }
    // The measure is sensitive: a rougher copy of the material differs by far more.
    auto smooth = compileMaterialFile(compiler, "gold", "backend=simd");
    auto rough = compileMaterialFile(compiler, "gold", "backend=simd;set.roughness=0.9");
    CHECK(meanRelativeDifference(renderSphere(*rough, scene), renderSphere(*smooth, scene)) > 0.05);
}

TEST_CASE("under a constant sky the sphere shows the directional albedo (sky estimator vs quadrature)") {
    // white_furnace: GGX + height-correlated Smith, F = 1, no light. The
    // radiance leaving each pixel is L_sky * E(mu_o), E the directional
    // albedo; E is computed here by a midpoint rule over the hemisphere
    // with the interpreter, independently of the sampling in the renderer.
    Compiler compiler;
    auto kernel = compileMaterialFile(compiler, "white_furnace", "backend=simd");
    Interpreter<double> interp(kernel->material());
    auto albedo = [&](double mu) {
        const int nt = 600, np = 300;
        double wo[3] = {std::sqrt(1 - mu * mu), 0, mu}, sum = 0;
        for (int i = 0; i < nt; ++i) {
            double ct = (i + 0.5) / nt;  // uniform in cos(theta): dw = dcos dphi
            double st = std::sqrt(1 - ct * ct);
            for (int j = 0; j < np; ++j) {
                double phi = std::numbers::pi * (j + 0.5) / np;  // symmetric in phi: half the circle, times 2
                double wi[3] = {st * std::cos(phi), st * std::sin(phi), ct};
                sum += interp.eval(wi, wo, nullptr).rgb[0] * ct;
            }
        }
        return sum * (1.0 / nt) * (2 * std::numbers::pi / np);
    };
    SphereScene scene;
    scene.size = 96;
    scene.sky = SkyModel::Constant;
    scene.skyRadiance = 1;
    scene.lightIrradiance = 0;
    scene.skySamples = 64;
    SphereImage img = renderSphere(*kernel, scene);
    // Pixels in rings of constant mu_o = n.v; the ring average shrinks the
    // Monte Carlo noise of single pixels.
    for (double mu : {0.95, 0.7, 0.4, 0.2}) {
        double sum = 0;
        int count = 0;
        double R = 0.45 * scene.size;
        for (int y = 0; y < img.size; ++y)
            for (int x = 0; x < img.size; ++x) {
                double dx = (x + 0.5 - img.size / 2.0) / R, dy = (y + 0.5 - img.size / 2.0) / R;
                double m = std::sqrt(std::max(0.0, 1 - dx * dx - dy * dy));
                if (img.coverage[size_t(y) * img.size + x] < 1 || std::fabs(m - mu) > 0.02) continue;
                sum += img.at(x, y, 0);
                ++count;
            }
        REQUIRE(count >= 8);
        double rendered = sum / count, expected = albedo(mu);
        INFO(fmt::format("mu {}: ring of {} pixels {:.5f}, quadrature {:.5f}", mu, count, rendered, expected));
        CHECK(expected < 1.0);
        CHECK(rendered == doctest::Approx(expected).epsilon(0.003));  // measured: within 0.04%
    }
}

TEST_CASE("renders are deterministic: one thread or two give the same image") {
    Compiler compiler;
    auto kernel = compileMaterialFile(compiler, "copper", "backend=simd");
    SphereScene scene;
    scene.size = 48;
    scene.skySamples = 8;
    scene.threads = 1;
    SphereImage one = renderSphere(*kernel, scene);
    scene.threads = 2;
    SphereImage two = renderSphere(*kernel, scene);
    CHECK(two.stats.threads == 2);
    CHECK(one.radiance == two.radiance);
    CHECK(one.coverage == two.coverage);
}

TEST_CASE("PNG and EXR files are written at the requested size; bad scenes and paths are reported") {
    Compiler compiler;
    auto kernel = compileMaterialFile(compiler, "silver", "backend=simd");
    SphereScene scene;
    scene.size = 72;
    scene.skySamples = 4;
    SphereImage img = renderSphere(*kernel, scene);
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "facet-render-test";
    std::filesystem::create_directories(dir);
    std::string png = (dir / "silver.png").string(), exr = (dir / "silver.exr").string();
    REQUIRE(writeSphereImage(img, scene, png) == "");
    REQUIRE(writeSphereImage(img, scene, exr) == "");

    OIIO::ImageBuf readPng(png);
    REQUIRE(readPng.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    CHECK(readPng.spec().width == 72);
    CHECK(readPng.spec().height == 72);
    CHECK(readPng.spec().nchannels == 3);
    CHECK(readPng.nativespec().format == OIIO::TypeDesc::UINT8);
    // Corner: the background grey; centre: the lit sphere, brighter.
    float corner[3], centre[3];
    readPng.getpixel(0, 0, corner, 3);
    readPng.getpixel(36, 36, centre, 3);
    CHECK(corner[0] == doctest::Approx(0.5).epsilon(0.05));
    CHECK(luminance(centre) > luminance(corner));

    OIIO::ImageBuf readExr(exr);
    REQUIRE(readExr.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    CHECK(readExr.spec().width == 72);
    CHECK(readExr.spec().nchannels == 4);
    float px[4];
    readExr.getpixel(36, 36, px, 4);
    CHECK(px[3] == 1.0f);  // alpha: fully covered
    CHECK(px[0] == doctest::Approx(img.at(36, 36, 0)).epsilon(1e-3));  // linear radiance (half float)
    readExr.getpixel(0, 0, px, 4);
    CHECK(px[3] == 0.0f);

    CHECK(writeSphereImage(img, scene, "/nonexistent-dir/x.png").find("cannot write") != std::string::npos);
    SphereScene bad;
    bad.size = 4;
    CHECK(validateScene(bad).find("size") != std::string::npos);
    bad = SphereScene{};
    bad.lightThetaDeg = std::nan("");
    CHECK(validateScene(bad).find("finite") != std::string::npos);
    bad = SphereScene{};
    bad.skySamples = -1;
    CHECK(validateScene(bad).find("samples") != std::string::npos);
    CHECK(validateScene(SphereScene{}) == "");
}

TEST_CASE("tone curve: 0 maps to 0, increasing, saturating at 1") {
    CHECK(acesFilmic(0) == 0);
    double prev = 0;
    for (double x = 0.01; x < 100; x *= 1.5) {
        if (x < 5) CHECK(acesFilmic(x) > prev);  // the fit reaches 1 near x = 10 and is clamped there
        else CHECK(acesFilmic(x) >= prev);
        prev = acesFilmic(x);
    }
    CHECK(acesFilmic(0.18) == doctest::Approx(0.2666).epsilon(0.01));  // mid grey
    CHECK(acesFilmic(1e6) == 1.0);
}

}  // TEST_SUITE

// The technique study (SamplingVariance.h) at a small size: visible
// normals give the lowest RMSE of the three techniques wherever the NDF has
// a visible-normal sampler. (That each technique's pdf is right is the
// chi-square tests' job.)
TEST_CASE("visible-normal sampling has the lowest image error of the three techniques") {
    facet::Compiler compiler;
    facet::preview::VarianceSettings settings;
    settings.size = 48;
    settings.referenceSamples = 1024;
    std::vector<facet::preview::VarianceRow> rows = facet::preview::measureSamplingVariance(compiler, settings);
    REQUIRE(rows.size() == 6);
    MESSAGE(facet::preview::varianceTable(rows, settings));
    int withVisible = 0;
    for (const facet::preview::VarianceRow& r : rows) {
        CAPTURE(r.material);
        REQUIRE(r.rmse.size() == 3);
        for (const auto& v : r.rmse)
            if (v) CHECK(std::isfinite(*v));
        CHECK(r.rmse[1]);  // NDF and cosine sampling apply to every NDF
        CHECK(r.rmse[2]);
        CHECK(r.referenceMean > 0);
        if (!r.rmse[0]) continue;
        ++withVisible;
        CHECK(*r.rmse[0] < *r.rmse[1]);
        CHECK(*r.rmse[0] < *r.rmse[2]);
    }
    CHECK(withVisible == 6);  // GGX, Beckmann and Blinn-Phong at both roughnesses
}

TEST_CASE("a material that scatters below its surface is lit through it: light from behind reaches the camera") {
    // Sky off, the light behind the sphere (theta 150 from the view axis):
    // only a thin rim, where the surface turns toward it, reflects it to the
    // camera; with lightThrough the light that crosses the surface adds
    // the rest.
    Compiler compiler;
    auto glass = compileSource(compiler, R"(material glass {
        ndf = ggx(0.2); masking = smith_height_correlated; fresnel = dielectric(1.5); scatter = both; })",
                               "backend=interp;cache=memory");
    SphereScene scene;
    scene.size = 48;
    scene.sky = SkyModel::None;
    scene.lightThetaDeg = 150, scene.lightPhiDeg = 90;
    auto total = [&](const SphereImage& img) {
        double sum = 0;
        for (float v : img.radiance) sum += v;
        return sum;
    };
    scene.lightThrough = true;
    SphereImage through = renderSphere(*glass, scene);
    CHECK(through.stats.invalidLanes == 0);
    double lit = total(through);
    CHECK(lit > 1);
    scene.lightThrough = false;
    double reflected = total(renderSphere(*glass, scene));
    CHECK(reflected > 0);
    CHECK(lit > 3 * reflected);
}
