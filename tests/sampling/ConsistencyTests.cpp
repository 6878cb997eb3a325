// The reference sampler's entry points against eval and pdf (SPEC 8):
// sampled pdf = pdf(wi, wo), weight = f cos / pdf, bounded visible-normal
// weights on the hard-case sample, invalid lanes, and the numbers behind
// each NDF's visibleNormals trait.
#include "SamplingCases.h"
#include "SamplingCheck.h"

#include "HardCases.h"
#include "LambdaTable.h"

#include <doctest/doctest.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace {

using namespace sampling_test;
using facet::PdfResult;
using facet::SampleResult;

constexpr double kPi = std::numbers::pi;

V3 viewAt(double degrees, double azimuth = 0.3) {
    double t = degrees * kPi / 180;
    return {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
}

// Finite and of length 1 within 1e-3 (SPEC 2).
bool isUnit(const std::array<double, 3>& w) {
    for (double x : w)
        if (!std::isfinite(x)) return false;
    return std::abs(std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) - 1) <= 1e-3;
}

double relDiff(double a, double b) {
    double scale = std::max(std::abs(a), std::abs(b));
    return scale == 0 ? 0 : std::abs(a - b) / scale;
}

}  // namespace

TEST_CASE("sampling: the sampled pdf is pdf(wi, wo) and the weight is f cos / pdf") {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uniform(0, 1);
    double worstPdf = 0, worstWeight = 0;
    int samples = 0, below = 0;
    for (const Combo& c : combos())
        for (double alpha : {0.01, 0.1, 0.5, 1.0})
            for (double theta : {0.0, 45.0, 80.0, 89.9}) {
                auto m = makeMaterial(c, alpha);
                REQUIRE(m);
                const facet::Interpreter<double>& interp = *m->interpreter;
                V3 o = viewAt(theta);
                double wo[3] = {o.x, o.y, o.z};
                for (int i = 0; i < 16; ++i) {
                    double u[3] = {uniform(rng), uniform(rng), uniform(rng)};
                    SampleResult<double> s = interp.sample(wo, u, nullptr);
                    INFO(c.name(), " alpha ", alpha, " theta_o ", theta, " u ", u[0], " ", u[1], " ", u[2]);
                    REQUIRE(s.valid);
                    REQUIRE(s.pdf > 0);
                    double wi[3] = {s.wi.x, s.wi.y, s.wi.z};
                    PdfResult<double> p = interp.pdf(wi, wo, nullptr);
                    REQUIRE(p.valid);
                    worstPdf = std::max(worstPdf, relDiff(p.pdf, s.pdf));
                    CHECK(relDiff(p.pdf, s.pdf) <= 1e-5);
                    facet::EvalResult<double> f = interp.eval(wi, wo, nullptr);
                    REQUIRE(f.valid);
                    for (int ch = 0; ch < 3; ++ch) {
                        double expected = s.wi.z > 0 ? f.rgb[ch] * s.wi.z / s.pdf : 0.0;
                        worstWeight = std::max(worstWeight, relDiff(s.weight[ch], expected));
                        CHECK(relDiff(s.weight[ch], expected) <= 1e-5);
                    }
                    ++samples;
                    below += s.wi.z <= 0;
                }
            }
    MESSAGE(fmt::format("{} samples ({} below the horizon): worst relative pdf difference {:.3g}, weight {:.3g}",
                        samples, below, worstPdf, worstWeight));
}

// For every Smith-masked visible-normal pair and F <= 1, the weight of the
// single specular lobe is F G2 / G1(wo) <= F G1'(wo) / G1(wo), G1' the
// masking's and G1 the one the visible normals are normalized with (the
// same but for blinn_phong, whose masking uses the Beckmann Lambda), over
// the hard-case sample (roughness from 1e-5 to huge, anisotropy 1e4,
// grazing directions; each example of the NDF, its parameters as inputs)
// and u at 0, 1/2 and 1 - 2^-24.
TEST_CASE("sampling: visible-normal weights of a Smith lobe are at most G1'/G1") {
    const double uEdge[3] = {0, 0.5, 1 - std::ldexp(1.0, -24)};
    int checked = 0, materials = 0;
    double worst = 0;
    for (const facet::ModelInfo* n : facet::catalogSlot(facet::ModelSlot::Ndf)) {
        const facet::NdfEntry& ndf = facet::ndfEntry(*n);
        if (!ndf.visibleNormals) continue;
        for (const facet::ModelInfo* mk : facet::catalogSlot(facet::ModelSlot::Masking)) {
            if (!facet::maskingEntry(*mk).smith) continue;
            for (const facet::ModelExample& ex : ndf.examples) {
                // A tabulated Lambda needs constant shape parameters within the
                // entry's domain: examples that make them inputs have no Smith
                // masking.
                if (ndf.tabulatedLambda) {
                    auto plain = loadMaterial(fmt::format("material t {{ {} ndf = {}; {} }}", ex.inputs, ex.stmt, ex.extra));
                    REQUIRE(plain);
                    facet::SourceLoc loc;
                    if (!facet::tabulatedLambdaUnsupported(*plain->material, plain->material->singleLobe(), loc).empty()) continue;
                }
                for (const char* fresnel : {"none", "schlick(0.9)"}) {
                    std::string text = fmt::format("material t {{ {} ndf = {}; masking = {}; fresnel = {}; {} }}",
                                                   ex.inputs, ex.stmt, mk->name, fresnel, ex.extra);
                    std::string error;
                    auto m = loadMaterial(text, &error);
                    INFO(text, "\n", error);
                    REQUIRE(m);
                    ++materials;
                    facet::HardCaseOptions options;
                    for (const facet::HardCase& hc : facet::hardCases(*m->material, options)) {
                        if (hc.invalidInput || !(hc.wo[2] > 0)) continue;
                        facet::ResolvedMaterial<double> r = m->interpreter->resolve(hc.slots.data());
                        if (!r.valid || !facet::visibleNormalSampling(r)) continue;
                        double len = std::sqrt(hc.wo[0] * hc.wo[0] + hc.wo[1] * hc.wo[1] + hc.wo[2] * hc.wo[2]);
                        V3 wo{hc.wo[0] / len, hc.wo[1] / len, hc.wo[2] / len};
                        double bound = (wo.z + r.ndf->formulas.d->visibleCosLambda(r.ndfArgs, wo)) /
                                       (wo.z + r.cosLambda(wo));
                        for (double u1 : uEdge)
                            for (double u2 : uEdge) {
                                double u[3] = {0.5, u1, u2};
                                SampleResult<double> s = m->interpreter->sample(hc.wo.data(), u, hc.slots.data());
                                if (!s.valid) continue;
                                ++checked;
                                for (double w : s.weight) {
                                    worst = std::max(worst, w / std::max(bound, 1.0));
                                    INFO(facet::describeCase(*m->material, hc), " u ", u1, " ", u2, " bound ", bound);
                                    CHECK(w <= bound * (1 + 1e-5));
                                }
                            }
                    }
                }
            }
        }
    }
    CHECK(materials > 0);
    MESSAGE(fmt::format("{} samples of {} materials: largest weight over max(1, G1'/G1) {:.9g}", checked, materials,
                        worst));
}

// Every material the hard-case sample generates (every NDF form x masking x
// Fresnel, parameters as unranged inputs), at the hard-case directions and
// inputs, with u at the ends of [0, 1): a lane is invalid exactly when its
// inputs are (or its result left the reference's range), and a valid lane
// has a finite non-negative pdf and weights and a unit (or zero) wi.
TEST_CASE("sampling: no NaN, Inf or negative result on the hard-case sample") {
    const double uEdge[2] = {0, 1 - std::ldexp(1.0, -24)};
    int valid = 0, invalid = 0, unexpected = 0;
    std::vector<facet::HardCaseMaterial> materials = facet::hardCaseMaterials();
    REQUIRE(!materials.empty());
    facet::HardCaseOptions options;
    options.inputSweeps = false;
    for (size_t i = 0; i < materials.size(); i += 3) {
        auto m = loadMaterial(materials[i].text);
        REQUIRE(m);
        for (const facet::HardCase& hc : facet::hardCases(*m->material, options))
            for (double u0 : uEdge)
                for (double u1 : uEdge)
                    for (double u2 : uEdge) {
                        double u[3] = {u0, u1, u2};
                        SampleResult<double> s = m->interpreter->sample(hc.wo.data(), u, hc.slots.data());
                        INFO(materials[i].name, " ", facet::describeCase(*m->material, hc));
                        // Sampling reads wo and the inputs, not wi.
                        bool invalidInput = !isUnit(hc.wo);
                        for (double x : hc.slots) invalidInput = invalidInput || !std::isfinite(x);
                        if (!s.valid) {
                            ++invalid;
                            CHECK(s.pdf == 0);
                            CHECK(s.wi.x == 0);
                            CHECK(s.weight[0] == 0);
                            unexpected += !invalidInput;
                            continue;
                        }
                        ++valid;
                        CHECK(!invalidInput);
                        CHECK(std::isfinite(s.pdf));
                        CHECK(s.pdf >= 0);
                        for (double w : s.weight) CHECK((std::isfinite(w) && w >= 0));
                        double len = std::sqrt(s.wi.x * s.wi.x + s.wi.y * s.wi.y + s.wi.z * s.wi.z);
                        CHECK((len == 0 || std::abs(len - 1) < 1e-9));
                    }
    }
    MESSAGE(fmt::format("{} valid and {} invalid lanes, {} of them invalid with valid inputs", valid, invalid,
                        unexpected));
    CHECK(unexpected == 0);
}

TEST_CASE("sampling: invalid lanes and directions below the horizon") {
    auto m = loadMaterial("material t { ndf = ggx(0.3); masking = smith_height_correlated; diffuse = lambert(0.5); }");
    REQUIRE(m);
    const facet::Interpreter<double>& interp = *m->interpreter;
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    double up[3] = {0, 0, 1}, half[3] = {0.5, 0.5, 0.5};
    auto expectInvalid = [](const SampleResult<double>& s) {
        CHECK_FALSE(s.valid);
        CHECK(s.pdf == 0);
        CHECK((s.wi.x == 0 && s.wi.y == 0 && s.wi.z == 0));
        CHECK((s.weight[0] == 0 && s.weight[1] == 0 && s.weight[2] == 0));
    };
    SUBCASE("invalid wo") {
        double bad[][3] = {{nan, 0, 1}, {0, inf, 1}, {0, 0, 1.01}, {0, 0, 0}, {0.5, 0.5, 0.5}};
        for (auto& wo : bad) expectInvalid(interp.sample(wo, half, nullptr));
        for (auto& wo : bad) CHECK_FALSE(interp.pdf(up, wo, nullptr).valid);
        for (auto& wi : bad) CHECK_FALSE(interp.pdf(wi, up, nullptr).valid);
    }
    SUBCASE("u outside [0, 1)") {
        double bad[][3] = {{1, 0.5, 0.5}, {0.5, -1e-300, 0.5}, {0.5, 0.5, nan}, {0.5, 0.5, inf}, {0.5, 1.5, 0.5}};
        for (auto& u : bad) expectInvalid(interp.sample(up, u, nullptr));
    }
    SUBCASE("a non-finite input") {
        auto in = loadMaterial("material t { input a = 0.3; ndf = ggx(a); masking = smith_separable; }");
        REQUIRE(in);
        double slots[1] = {nan};
        expectInvalid(in->interpreter->sample(up, half, slots));
        CHECK_FALSE(in->interpreter->pdf(up, up, slots).valid);
    }
    SUBCASE("wo below the horizon: a valid lane without a sample") {
        double wo[3] = {0.6, 0, -0.8};
        SampleResult<double> s = interp.sample(wo, half, nullptr);
        CHECK(s.valid);
        CHECK(s.pdf == 0);
        CHECK(s.weight[0] == 0);
        PdfResult<double> p = interp.pdf(up, wo, nullptr);
        CHECK(p.valid);
        CHECK(p.pdf == 0);
    }
    SUBCASE("wi below the horizon: pdf() reports the specular lobe's density there") {
        // NDF sampling (no Smith masking): wo.m < 0 sends wi below the horizon.
        auto nd = loadMaterial("material t { ndf = ggx(1); masking = implicit; }");
        REQUIRE(nd);
        double wo[3] = {std::sin(1.5), 0, std::cos(1.5)}, wi[3] = {0, 0, -1};
        PdfResult<double> p = nd->interpreter->pdf(wi, wo, nullptr);
        CHECK(p.valid);
        CHECK(p.pdf > 0);
        CHECK(nd->interpreter->eval(wi, wo, nullptr).rgb[0] == 0);
    }
}

// visibleNormals is a claim about numbers: the visible-normal density
// G1(wo) (wo.m)+ D(m) / (n.wo) integrates to 1 only when its Lambda
// (visibleCosLambda) is exact for D. Checked by quadrature for every NDF
// with the trait. Where an entry's masking Lambda differs from it
// (blinn_phong: Beckmann's at an equivalent roughness), the masking Lambda
// would be off by several percent: that is why the entry has its own.
// Shape parameters (a tabulated Lambda's) at their typical value and above
// and below it, one parameter varied at a time. Not closer to the low end:
// student_t below gamma = 2 has D ~ mz^(2 gamma - 4), singular at the
// horizon, which the cell quadrature below does not resolve (gamma 1.6
// integrates to 0.94 with either Lambda); the chi-square runs cover it.
std::vector<std::vector<double>> shapesToCheck(const facet::NdfEntry& ndf) {
    std::vector<double> typical;
    for (int p : ndf.tableShapeParams) typical.push_back(ndf.canonical[p].typical);
    std::vector<std::vector<double>> shapes{typical};
    for (size_t i = 0; i < typical.size(); ++i)
        for (double offset : {0.7, 10.0}) {
            const facet::ModelParam& param = ndf.canonical[ndf.tableShapeParams[i]];
            if (param.lo + offset >= param.hi) continue;
            shapes.push_back(typical);
            shapes.back()[i] = param.lo + offset;
        }
    return shapes;
}

TEST_CASE("sampling: visibleNormals holds where the visible-normal density integrates to 1") {
    for (const facet::ModelInfo* n : facet::catalogSlot(facet::ModelSlot::Ndf)) {
        const facet::NdfEntry& ndf = facet::ndfEntry(*n);
        if (!facet::hasSmithLambda(ndf)) {
            CHECK_FALSE(ndf.visibleNormals);  // no Lambda, no G1(wo)
            continue;
        }
        for (const std::vector<double>& shape : shapesToCheck(ndf)) {
            facet::ResolvedMaterial<double> r = facet::lobeAtAlpha(
                ndf, facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, "none")), 0.5, shape);
            const facet::NdfFormulas<double>& f = *ndf.formulas.d;
            double worst = 0, worstMasking = 0, lambdaGap = 0;
            for (double theta : {30.0, 60.0, 80.0, 89.0}) {
                V3 wo = viewAt(theta);
                auto integral = [&](double g) {  // g = (n.wo) / G1(wo)
                    auto density = [&](const V3& m) {
                        double om = m.x * wo.x + m.y * wo.y + m.z * wo.z;
                        return m.z > 0 && om > 0 ? r.D(m) * om / g : 0.0;
                    };
                    std::vector<double> cells = integrateCells(SphereGrid::forLobe(kPi / 2, 0, 0, 0.05, 0.2), density);
                    double total = 0;
                    for (double c : cells) total += c;
                    return total;
                };
                double visible = f.visibleCosLambda(r.ndfArgs, wo), masking = r.cosLambda(wo);
                worst = std::max(worst, std::abs(integral(wo.z + visible) - 1));
                worstMasking = std::max(worstMasking, std::abs(integral(wo.z + masking) - 1));
                lambdaGap = std::max(lambdaGap, relDiff(visible, masking));
            }
            MESSAGE(fmt::format("{}{}: the visible-normal density integrates to 1 within {:.3g} ({:.3g} with the "
                                "masking's Lambda){}",
                                ndf.name, shape.empty() ? "" : fmt::format(" shape {}", fmt::join(shape, ",")), worst,
                                worstMasking, ndf.visibleNormals ? "" : " (sampled through its NDF)"));
            if (ndf.visibleNormals) CHECK(worst < 1e-4);
            // A Lambda other than the masking's exists because the masking's is
            // an approximation (not a table of the same Lambda).
            if (lambdaGap > 1e-5) CHECK(worstMasking > 0.05);
        }
    }
}
