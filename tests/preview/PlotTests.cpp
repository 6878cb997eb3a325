// Tests of the `facet render --plot lobe|ndf|walk` plots (apps/preview/Plots.*, WalkPlot.*)
// and their drawing surface (PlotCanvas): the numbers the plots report
// against independent computations, the images they write read back through
// OpenImageIO, and errors that come back as messages.
#include "Interpreter.h"
#include "Kernel.h"
#include "PdfPlot.h"
#include "PlotCanvas.h"
#include "Plots.h"
#include "WalkPlot.h"

#include <OpenImageIO/imagebuf.h>
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <cstdlib>  // mkdtemp

using namespace facet;
using namespace facet::preview;

namespace {

constexpr double kPi = std::numbers::pi;

// A directory of its own per test case, removed afterwards.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "facet_plot_tests_XXXXXX").string();
        REQUIRE(mkdtemp(pattern.data()) != nullptr);
        path = pattern;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

std::unique_ptr<Kernel> compileKernel(Compiler& compiler, const std::string& text) {
    CompileOptions options;
    REQUIRE(CompileOptions::parse("cache=memory", options).empty());  // no disk cache from tests
    DiagnosticEngine diags;
    auto kernel = compiler.compileText(text, "plot_test.mat", "", options, diags);
    REQUIRE_MESSAGE(kernel, diags.str());
    return kernel;
}

const char* kSmoothGgx = R"(
material smooth {
    ndf     = ggx(0.1);
    masking = smith_height_correlated;
    fresnel = schlick(0.04);
}
)";

// The same lobe with a coloured Fresnel term, so that the luminance weights matter.
const char* kSmoothCopper = R"(
material smooth_copper {
    ndf     = ggx(0.1);
    masking = smith_height_correlated;
    fresnel = schlick(rgb(0.95, 0.64, 0.54));
}
)";

// 2 pi Int_0^{pi/2} D(theta) cos(theta) sin(theta) dtheta for an isotropic D,
// composite Simpson on a step fine enough for the alpha = 0.1 lobes.
double projectedNdfIntegral(const ResolvedMaterial<double>& r) {
    const int n = 20000;  // even
    const double h = (kPi / 2) / n;
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
        double t = i * h;
        double f = r.D({std::sin(t), 0.0, std::cos(t)}) * std::cos(t) * std::sin(t);
        sum += f * (i == 0 || i == n ? 1 : i % 2 ? 4 : 2);
    }
    return 2 * kPi * sum * h / 3;
}

// What an image written by a plot looks like, read back through OIIO.
struct ImageSummary {
    bool ok = false;
    std::string error;
    int width = 0, height = 0, channels = 0;
    long dark = 0;      // near-black pixels: text, axes, the surface
    long coloured = 0;  // saturated pixels: the curves
    long white = 0;     // background
};

ImageSummary readBack(const std::string& path) {
    ImageSummary s;
    OIIO::ImageBuf img(path);
    if (!img.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
        s.error = img.geterror();
        return s;
    }
    const OIIO::ImageSpec& spec = img.spec();
    s.ok = true;
    s.width = spec.width, s.height = spec.height, s.channels = spec.nchannels;
    if (s.channels < 3) return s;
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
            float p[4] = {};
            img.getpixel(x, y, p, 4);
            float hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
            if (hi < 0.3f) ++s.dark;
            if (hi - lo > 0.3f) ++s.coloured;
            if (lo > 0.97f) ++s.white;
        }
    return s;
}

const NdfEntry& ndf(const char* name) { return ndfEntry(modelNamed(ModelSlot::Ndf, name)); }

// Pixels of the two ends of the pdf plot's colour ramp (zero and full scale).
struct RampEnds {
    long zero = 0, full = 0;
};

RampEnds countRampEnds(const std::string& path) {
    RampEnds ends;
    OIIO::ImageBuf img(path);
    REQUIRE(img.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < img.spec().height; ++y)
        for (int x = 0; x < img.spec().width; ++x) {
            float p[4] = {};
            img.getpixel(x, y, p, 4);
            if (p[0] > 0.2f && p[0] < 0.35f && p[1] < 0.06f && p[2] > 0.27f && p[2] < 0.4f) ++ends.zero;
            if (p[0] > 0.93f && p[1] > 0.85f && p[2] < 0.25f) ++ends.full;
        }
    return ends;
}

}  // namespace

TEST_SUITE("plots") {

TEST_CASE("ndfAtAlpha sets the fields each NDF needs") {
    ResolvedMaterial<double> ggx = ndfAtAlpha(ndf("ggx"), 0.3);
    CHECK(ggx.valid);
    CHECK(ggx.ndf == &ndf("ggx"));
    CHECK(ggx.ndfArgs[0] == 0.3);  // alpha_x
    CHECK(ggx.ndfArgs[1] == 0.3);  // alpha_y
    // GGX and Beckmann at the normal: 1 / (pi alpha^2).
    for (double a : {0.1, 0.3, 0.7}) {
        CHECK(ndfAtAlpha(ndf("ggx"), a).D({0, 0, 1}) == doctest::Approx(1 / (kPi * a * a)).epsilon(1e-12));
        CHECK(ndfAtAlpha(ndf("beckmann"), a).D({0, 0, 1}) == doctest::Approx(1 / (kPi * a * a)).epsilon(1e-12));
    }
    // Blinn-Phong: the Walter et al. 2007 matched exponent 2/alpha^2 - 2.
    CHECK(ndfAtAlpha(ndf("blinn_phong"), 0.3).ndfArgs[0] == doctest::Approx(2 / 0.09 - 2).epsilon(1e-12));
    CHECK(ndfAtAlpha(ndf("gtr"), 0.3, {1.5}).ndfArgs[paramIndex(ndf("gtr"), "gamma")] == 1.5);
    CHECK(ndfAtAlpha(ndf("gtr"), 0.3).ndfArgs[paramIndex(ndf("gtr"), "gamma")] == 2);  // the typical gamma
    CHECK(ndfAtAlpha(ndf("gaussian"), 0.3).ndfArgs.derived[0] == doctest::Approx(gaussianNdfNorm(0.3)));
    // Outside the domain: alpha clamps like the interpreter's, NaN is invalid.
    CHECK(ndfAtAlpha(ndf("ggx"), 0).ndfArgs[0] == kMinAlpha);
    CHECK_FALSE(ndfAtAlpha(ndf("ggx"), std::nan("")).valid);
}

TEST_CASE("ndfAtAlpha gives normalized distributions") {
    // Every microfacet NDF of the catalog at its typical shape, and gtr at gamma = 1 (Berry).
    struct Case {
        const NdfEntry* model;
        std::vector<double> shape;
    };
    std::vector<Case> cases;
    for (const ModelInfo* m : catalogSlot(ModelSlot::Ndf))
        if (!ndfEntry(*m).wholeLobe) cases.push_back({&ndfEntry(*m), {}});
    cases.push_back({&ndf("gtr"), {1.0}});
    for (const Case& c : cases)
        for (double alpha : {0.1, 0.3, 0.7}) {
            CAPTURE(c.model->name);
            CAPTURE(c.shape.size());
            CAPTURE(alpha);
            CHECK(projectedNdfIntegral(ndfAtAlpha(*c.model, alpha, c.shape)) == doctest::Approx(1).epsilon(1e-3));
        }
}

TEST_CASE("lobe plot of a smooth GGX material peaks in the mirror direction") {
    TempDir dir;
    Compiler compiler;
    auto kernel = compileKernel(compiler, kSmoothGgx);
    LobePlotOptions options;
    options.incidentDegrees = {30, 60};
    options.width = 480, options.height = 300;
    options.title = "smooth GGX";
    std::string path = dir.file("lobe.png");
    LobePlotResult r = writeLobePlot(*kernel, options, path);
    REQUIRE_MESSAGE(r.error.empty(), r.error);
    CHECK(r.invalidLanes == 0);
    REQUIRE(r.peakValue.size() == 2);
    REQUIRE(r.peakThetaDeg.size() == 2);
    CHECK(std::abs(r.peakThetaDeg[0] - 30) <= 1);
    CHECK(std::abs(r.peakThetaDeg[1] - 60) <= 1);

    ImageSummary img = readBack(path);
    REQUIRE_MESSAGE(img.ok, img.error);
    CHECK(img.width == 480);
    CHECK(img.height == 300);
    CHECK((img.channels == 3 || img.channels == 4));
    long pixels = long(img.width) * img.height;
    CHECK(img.dark > 200);            // the surface line, labels
    CHECK(img.coloured > 300);        // two curves and their incident rays
    CHECK(img.white > pixels / 2);    // mostly background: not a filled or garbage image
}

TEST_CASE("lobe plot peak values are Rec. 709 luminance times cos(theta_o)") {
    TempDir dir;
    Compiler compiler;
    auto kernel = compileKernel(compiler, kSmoothCopper);
    LobePlotOptions options;
    options.incidentDegrees = {0, 45, 75};
    options.width = 200, options.height = 150;
    LobePlotResult r = writeLobePlot(*kernel, options, dir.file("copper.png"));
    REQUIRE_MESSAGE(r.error.empty(), r.error);
    REQUIRE(r.peakValue.size() == 3);
    // Recompute the value at each reported peak with the double interpreter.
    Interpreter<double> interp(kernel->material());
    for (size_t i = 0; i < 3; ++i) {
        CAPTURE(i);
        double ti = options.incidentDegrees[i] * kPi / 180, to = r.peakThetaDeg[i] * kPi / 180;
        double wi[3] = {-std::sin(ti), 0, std::cos(ti)}, wo[3] = {std::sin(to), 0, std::cos(to)};
        EvalResult<double> f = interp.eval(wi, wo, nullptr);
        REQUIRE(f.valid);
        double lum = 0.2126 * f.rgb[0] + 0.7152 * f.rgb[1] + 0.0722 * f.rgb[2];
        CHECK(r.peakValue[i] == doctest::Approx(lum * std::cos(to)).epsilon(1e-4));
        CHECK(std::abs(r.peakThetaDeg[i] - options.incidentDegrees[i]) <= 1);
    }
}

TEST_CASE("lobe plot of a material that reflects nothing has zero curves") {
    // eta = 1: no Fresnel reflection at any angle, f = 0 everywhere.
    TempDir dir;
    Compiler compiler;
    auto kernel = compileKernel(compiler, R"(
material clear {
    ndf     = ggx(0.3);
    masking = smith_height_correlated;
    fresnel = dielectric(1);
}
)");
    LobePlotOptions options;
    options.width = 320, options.height = 200;
    std::string path = dir.file("zero.png");
    LobePlotResult r = writeLobePlot(*kernel, options, path);
    REQUIRE_MESSAGE(r.error.empty(), r.error);
    REQUIRE(r.peakValue.size() == options.incidentDegrees.size());
    for (double p : r.peakValue) CHECK(p == 0);
    for (double t : r.peakThetaDeg) CHECK(std::isfinite(t));
    ImageSummary img = readBack(path);
    REQUIRE_MESSAGE(img.ok, img.error);
    CHECK(img.width == 320);
}

TEST_CASE("lobe plot errors come back as messages") {
    TempDir dir;
    Compiler compiler;
    auto kernel = compileKernel(compiler, kSmoothGgx);
    auto errorFor = [&](LobePlotOptions o, const std::string& path) { return writeLobePlot(*kernel, o, path).error; };
    LobePlotOptions good;
    good.width = 128, good.height = 96;

    std::string unwritable = errorFor(good, dir.file("no/such/dir/lobe.png"));
    CHECK(unwritable.find("lobe.png") != std::string::npos);
    CHECK_FALSE(errorFor(good, "").empty());

    for (double bad : {90.0, -5.0, 120.0, std::nan("")}) {
        LobePlotOptions o = good;
        o.incidentDegrees = {30, bad};
        std::string e = errorFor(o, dir.file("bad.png"));
        CAPTURE(bad);
        CHECK(e.find("theta_i") != std::string::npos);
    }
    LobePlotOptions none = good;
    none.incidentDegrees.clear();
    CHECK_FALSE(errorFor(none, dir.file("none.png")).empty());
    LobePlotOptions small = good;
    small.width = 63;
    CHECK(errorFor(small, dir.file("small.png")).find("63") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("bad.png")));
    CHECK_FALSE(std::filesystem::exists(dir.file("small.png")));
}

TEST_CASE("a plot without a usable font is drawn without text, with a warning") {
    TempDir dir;
    Compiler compiler;
    auto kernel = compileKernel(compiler, kSmoothGgx);
    LobePlotOptions options;
    options.width = 240, options.height = 160;
    options.fontPath = dir.file("missing.ttf");
    LobePlotResult r = writeLobePlot(*kernel, options, dir.file("nofont.png"));
    CHECK(r.error.empty());
    CHECK_FALSE(r.warning.empty());
    CHECK(readBack(dir.file("nofont.png")).ok);

    NdfPlotOptions ndfOptions;
    ndfOptions.width = 240, ndfOptions.height = 160;
    ndfOptions.fontPath = options.fontPath;
    std::string warning;
    CHECK(writeNdfPlot({{"ggx", ndfAtAlpha(ndf("ggx"), 0.3)}}, ndfOptions, dir.file("nofont_ndf.png"), &warning)
              .empty());
    CHECK_FALSE(warning.empty());
}

TEST_CASE("NDF plot is written at the requested size, log and linear") {
    TempDir dir;
    std::vector<NdfCurve> curves;
    for (double a : {0.1, 0.3, 0.7}) curves.push_back({"ggx alpha = " + std::to_string(a), ndfAtAlpha(ndf("ggx"), a)});
    curves.push_back({"beckmann alpha = 0.3", ndfAtAlpha(ndf("beckmann"), 0.3)});
    for (bool log : {true, false}) {
        CAPTURE(log);
        NdfPlotOptions options;
        options.width = 500, options.height = 320;
        options.title = "D(theta_m)";
        options.logScale = log;
        std::string path = dir.file(log ? "ndf_log.png" : "ndf_linear.png");
        std::string warning;
        std::string e = writeNdfPlot(curves, options, path, &warning);
        REQUIRE_MESSAGE(e.empty(), e);
        ImageSummary img = readBack(path);
        REQUIRE_MESSAGE(img.ok, img.error);
        CHECK(img.width == 500);
        CHECK(img.height == 320);
        CHECK((img.channels == 3 || img.channels == 4));
        CHECK(img.dark > 200);
        CHECK(img.coloured > 300);
    }
}

TEST_CASE("NDF plot errors come back as messages") {
    TempDir dir;
    NdfPlotOptions options;
    options.width = 200, options.height = 150;
    std::vector<NdfCurve> ggx{{"ggx", ndfAtAlpha(ndf("ggx"), 0.3)}};
    CHECK_FALSE(writeNdfPlot(ggx, options, dir.file("no/such/dir/ndf.png")).empty());
    CHECK_FALSE(writeNdfPlot({}, options, dir.file("empty.png")).empty());
    CHECK(writeNdfPlot({{"ward", ndfAtAlpha(ndf("ward"), 0.3)}}, options, dir.file("ward.png")).find("ward") !=
          std::string::npos);
    CHECK_FALSE(writeNdfPlot({{"nan", ndfAtAlpha(ndf("ggx"), std::nan(""))}}, options, dir.file("nan.png")).empty());
    NdfPlotOptions tiny = options;
    tiny.height = 10;
    CHECK_FALSE(writeNdfPlot(ggx, tiny, dir.file("tiny.png")).empty());
}

TEST_CASE("pdf plot: both panels on one colour scale") {
    TempDir dir;
    SampleHistogram h;
    h.rows = 8, h.columns = 16;
    h.expected.assign(128, 10.0);
    PdfPlotOptions options;
    options.width = 600, options.height = 225;
    options.title = "test";
    // The sampler matches its pdf: both panels at full scale, nothing at zero.
    h.observed = h.expected;
    REQUIRE(writePdfPlot(h, options, dir.file("same.png")).empty());
    RampEnds same = countRampEnds(dir.file("same.png"));
    CHECK(same.full > 2 * 200 * 90);
    CHECK(same.zero < 100);  // the colour bar's first steps
    // No samples at all: the histogram panel turns to the zero colour and
    // the pdf panel keeps its colour (the scale is shared, not per panel).
    h.observed.assign(128, 0.0);
    REQUIRE(writePdfPlot(h, options, dir.file("none.png")).empty());
    RampEnds none = countRampEnds(dir.file("none.png"));
    CHECK(none.full == doctest::Approx(same.full / 2.0).epsilon(0.05));
    CHECK(none.zero == doctest::Approx(same.full / 2.0).epsilon(0.05));
}

TEST_CASE("pdf plot errors come back as messages") {
    TempDir dir;
    SampleHistogram h;
    h.rows = 4, h.columns = 8;
    h.observed.assign(32, 1.0), h.expected.assign(32, 1.0);
    PdfPlotOptions options;
    CHECK(writePdfPlot(h, options, dir.file("ok.png")).empty());
    CHECK(writePdfPlot(h, options, "").find("no output path") != std::string::npos);
    SampleHistogram shortCounts = h;
    shortCounts.expected.pop_back();
    CHECK(writePdfPlot(shortCounts, options, dir.file("x.png")).find("31 expected counts") != std::string::npos);
    SampleHistogram negative = h;
    negative.observed[3] = -1;
    CHECK(writePdfPlot(negative, options, dir.file("x.png")).find("negative") != std::string::npos);
    SampleHistogram empty = h;
    empty.observed.assign(32, 0.0), empty.expected.assign(32, 0.0);
    CHECK(writePdfPlot(empty, options, dir.file("x.png")).find("nothing to draw") != std::string::npos);
    PdfPlotOptions tiny = options;
    tiny.height = 10;
    CHECK(writePdfPlot(h, tiny, dir.file("x.png")).find("plot size") != std::string::npos);
    CHECK_FALSE(writePdfPlot(h, options, dir.file("no/such/dir/x.png")).empty());
}

TEST_CASE("PlotCanvas strokes: width, dashes, text") {
    TempDir dir;
    PlotCanvas canvas(200, 100, findPlotFont());
    const Rgb black{0, 0, 0};
    canvas.line({10, 20}, {190, 20}, {black, 3});
    canvas.line({10, 60}, {190, 60}, {black, 1, 10, 10});
    OIIO::ImageBuf img = canvas.resolved();
    REQUIRE(img.spec().width == 200);
    REQUIRE(img.spec().height == 100);
    auto grey = [&](int x, int y) {
        float p[3];
        img.getpixel(x, y, p, 3);
        return p[1];
    };
    // A 3-pixel line covers rows 19..21 at x = 100, and nothing 3 rows away.
    int covered = 0;
    for (int y = 15; y <= 25; ++y) covered += grey(100, y) < 0.5f;
    CHECK(covered == 3);
    // The dashed line alternates ink and gaps every ~10 pixels.
    int transitions = 0;
    for (int x = 11; x < 190; ++x) transitions += (grey(x, 60) < 0.5f) != (grey(x - 1, 60) < 0.5f);
    CHECK(transitions >= 14);
    CHECK(transitions <= 20);
    if (canvas.hasFont()) {
        double w = canvas.textWidth("0123456789", 20);
        CHECK(w > 80);  // DejaVu digits are 0.64 em: ~127 pixels
        CHECK(w < 180);
        CHECK(canvas.text({100, 90}, "abc", 12, black, HAlign::Center));
    }
    CHECK(canvas.write(dir.file("canvas.png")).empty());
    CHECK_FALSE(canvas.write(dir.file("no/such/dir/canvas.png")).empty());
}

}  // TEST_SUITE

TEST_CASE("walk plot: the random walk above single scattering on a rough white lobe; errors as messages") {
    TempDir dir;
    WalkPlotOptions options;
    options.paths = 200;
    options.plot.width = 480, options.plot.height = 300;
    ResolvedMaterial<double> rough = ndfAtAlpha(ndf("ggx"), 0.8);  // F = 1, no compensation
    WalkPlotResult result = writeWalkPlot(rough, options, dir.file("walk.png"));
    REQUIRE_MESSAGE(result.error.empty(), result.error);
    // Multiple scattering adds to the lobe (the white walk keeps what
    // masking loses): its peak is above the single-scattering one.
    CHECK(result.walkPeak > 1.05 * result.modelPeak);
    ImageSummary img = readBack(dir.file("walk.png"));
    REQUIRE_MESSAGE(img.ok, img.error);
    CHECK(img.width == 480);
    CHECK(img.coloured > 300);
    CHECK(writeWalkPlot(ndfAtAlpha(ndf("gaussian"), 0.3), options, dir.file("g.png")).error.find("no random walk") !=
          std::string::npos);
    WalkPlotOptions grazing = options;
    grazing.incidentDegrees = 95;
    CHECK_FALSE(writeWalkPlot(rough, grazing, dir.file("t.png")).error.empty());
    CHECK_FALSE(writeWalkPlot(rough, options, dir.file("no/such/dir/walk.png")).error.empty());
}

TEST_CASE("lobe plot over the whole circle: a refracting lobe peaks at Snell's angle below the surface") {
    TempDir dir;
    Compiler compiler;
    CompileOptions options;
    REQUIRE(CompileOptions::parse("backend=interp;cache=memory", options).empty());
    DiagnosticEngine diags;
    auto kernel = compiler.compileText(R"(material glass {
        ndf = ggx(0.05); masking = smith_height_correlated; fresnel = dielectric(1.5); scatter = both; })",
                                       "glass.mat", "", options, diags);
    REQUIRE_MESSAGE(kernel, diags.str());
    LobePlotOptions plot;
    plot.wholeSphere = true;
    plot.incidentDegrees = {0, 40, 150};  // 150: from inside, 30 degrees from the inward normal
    plot.width = 480, plot.height = 540;
    std::string path = dir.file("lobe.png");
    LobePlotResult r = writeLobePlot(*kernel, plot, path);
    REQUIRE_MESSAGE(r.error.empty(), r.error);
    CHECK(r.invalidLanes == 0);
    REQUIRE(r.peakThetaDeg.size() == 3);
    // Straight through at normal incidence; refracted toward the normal at 40.
    CHECK(std::abs(std::abs(r.peakThetaDeg[0]) - 180) <= 1);
    double refracted = 180 - std::asin(std::sin(40 * kPi / 180) / 1.5) * 180 / kPi;
    CHECK(std::abs(r.peakThetaDeg[1] - refracted) <= 1.5);
    // From inside at 30 degrees (below the critical angle, 41.8): out, away from the normal.
    double out = std::asin(1.5 * std::sin(30 * kPi / 180)) * 180 / kPi;
    CHECK(std::abs(r.peakThetaDeg[2] - out) <= 2);
    ImageSummary img = readBack(path);
    REQUIRE_MESSAGE(img.ok, img.error);
    CHECK(img.width == 480);
    CHECK(img.height == 540);
    // Beyond 90 degrees only for a whole-sphere plot.
    plot.wholeSphere = false;
    CHECK(writeLobePlot(*kernel, plot, path).error.find("outside [0, 90)") != std::string::npos);
}
