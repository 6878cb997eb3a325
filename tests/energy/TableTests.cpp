// The E tables (compiler/reference/KullaConty.h): closed-form values, interpolation
// error, the exact consistency of EcAvg with the interpolated rows, the
// quadrature's convergence for every pair the checker accepts, and the table
// build time per pair.
#include "EnergyTestUtil.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

using namespace energy;
using facet::EnergyTable;
using facet::EnergyTableKey;

namespace {

// The table key of an NDF and a masking (names in the language) with the
// values of their shape parameters.
EnergyTableKey key(const char* ndf, const char* masking, std::vector<double> shape = {}) {
    EnergyTableKey key;
    key.ndf = &facet::ndfEntry(facet::modelNamed(facet::ModelSlot::Ndf, ndf));
    key.masking = &facet::maskingEntry(facet::modelNamed(facet::ModelSlot::Masking, masking));
    key.shape = std::move(shape);
    return key;
}

}  // namespace

TEST_SUITE("tables") {

TEST_CASE("closed forms: GGX alpha = 1 at normal incidence, E = 1 - ln 2") {
    // D = 1/pi for GGX alpha = 1; at mu_o = 1, Lambda_o = 0 and G = 2 mu_i / (1 + mu_i):
    // E = 1/(4 pi) Int G dwi = Int_0^1 2 mu/(1 + mu) dmu = 2 (1 - ln 2) / 2 ... = 1 - ln 2.
    for (const char* m : {"smith_height_correlated", "smith_separable"}) {
        auto t = memoryTables().get(key("ggx", m));
        CHECK(t->ecAt(1, 1) == doctest::Approx(std::log(2.0)).epsilon(1e-6));
        CHECK(facet::directionalAlbedo(t->key, 1, 1) == doctest::Approx(1 - std::log(2.0)).epsilon(1e-9));
    }
    // Lookups clamp: alpha beyond the grid uses the end rows, mu outside [0, 1] the end columns.
    auto t = memoryTables().get(key("ggx", "smith_height_correlated"));
    CHECK(t->ecAt(0.5, 3.0) == t->ecAt(0.5, 1.0));
    CHECK(t->ecAt(0.5, 1e-7) == t->ecAt(0.5, 1e-4));
    CHECK(t->ecAt(1.5, 0.3) == t->ecAt(1.0, 0.3));
    CHECK(t->ecAt(-1, 0.3) == t->ecAt(0.0, 0.3));
    CHECK(t->validate() == "");
    // A row pre-blended at a constant alpha interpolates like the full table.
    for (double alpha : {1e-4, 0.0123, 0.3, 1.0}) {
        std::vector<float> row = t->rowAt(alpha);
        for (double mu : {0.0, 0.003, 0.2, 0.77, 1.0}) {
            double u = t->muCoord(mu);
            int j = std::min(int(u), t->muCount - 2);
            double lin = row[j] + (double(row[j + 1]) - row[j]) * (u - j);
            CHECK(lin == doctest::Approx(t->ecAt(mu, alpha)).epsilon(1e-6));
        }
    }
}

TEST_CASE("EcAvg equals the integral of the interpolated Ec at every alpha (exact consistency)") {
    auto t = memoryTables().get(key("beckmann", "smith_separable"));
    const physics::GaussLegendre g(4);
    double worst = 0;
    for (double alpha : {1e-4, 3e-4, 0.0123, 0.05, 0.0777, 0.31, 0.5, 0.999, 1.0}) {
        // 2 Int Ec(mu) mu dmu with mu = s^2, one panel per table cell in s (exact for the interpolant).
        double sum = 0;
        int cells = t->muCount - 1;
        for (int c = 0; c < cells; ++c) {
            double s0 = double(c) / cells, s1 = double(c + 1) / cells;
            for (size_t k = 0; k < g.x.size(); ++k) {
                double s = (s0 + s1) / 2 + (s1 - s0) / 2 * g.x[k];
                sum += g.w[k] * (s1 - s0) / 2 * t->ecAt(s * s, alpha) * 4 * s * s * s;
            }
        }
        worst = std::max(worst, std::abs(sum - t->ecAvgAt(alpha)));
        CHECK(sum == doctest::Approx(t->ecAvgAt(alpha)).epsilon(1e-6));
    }
    MESSAGE("max |2 Int Ec_interp mu dmu - EcAvg| = ", worst);
}

// Bilinear interpolation error of E at the cell centres (the worst place for
// bilinear interpolation), against the quadrature at the same point.
TEST_CASE("interpolation error at cell centres") {
    struct Pair {
        const char* ndf;
        const char* masking;
    };
    const Pair pairs[] = {{"ggx", "smith_height_correlated"},
                          {"ggx", "smith_separable"},
                          {"beckmann", "smith_height_correlated"},
                          {"beckmann", "smith_separable"}};
    for (const Pair& p : pairs) {
        auto t = memoryTables().get(key(p.ndf, p.masking));
        struct Pt {
            double mu, alpha, err;
            bool inside;
        };
        std::vector<Pt> pts;
        for (int i = 0; i + 1 < t->alphaCount; ++i)
            for (int j = 0; j + 1 < t->muCount; ++j) {
                double ra = (std::sqrt(t->alphaNode(i)) + std::sqrt(t->alphaNode(i + 1))) / 2;
                double rm = (std::sqrt(t->muNode(j)) + std::sqrt(t->muNode(j + 1))) / 2;
                Pt pt{rm * rm, ra * ra, 0, false};
                pt.inside = pt.alpha >= 0.05 && pt.mu >= 0.05;
                if (pt.inside || (i % 3 == 0 && j % 3 == 0)) pts.push_back(pt);
            }
        parallelFor(pts.size(), [&](size_t k) {
            double e = facet::directionalAlbedo(t->key, pts[k].mu, pts[k].alpha);
            pts[k].err = std::abs((1 - e) - t->ecAt(pts[k].mu, pts[k].alpha));
        });
        double in = 0, all = 0, in2 = 0;
        const Pt* worst = nullptr;
        for (const Pt& pt : pts) {
            all = std::max(all, pt.err);
            if (pt.inside && pt.err > in) {
                in = pt.err;
                worst = &pt;
            }
            if (pt.alpha >= 0.2 && pt.mu >= 0.2) in2 = std::max(in2, pt.err);
        }
        REQUIRE(worst);
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "%s: %d x %d table; max |E - E_table| at cell centres: %.2e in [0.05, 1]^2 (at mu %.3f "
                      "alpha %.3f), %.2e in [0.2, 1]^2, %.2e over the whole grid (sampled)",
                      t->key.name().c_str(), t->muCount, t->alphaCount, in, worst->mu, worst->alpha, in2, all);
        MESSAGE(buf);
        CHECK(in < 1e-3);
        CHECK(in2 < 3e-4);
    }
}

// Every NDF x masking pair the checker accepts with energy = kulla_conty:
// the table's default quadrature against a much finer one.
TEST_CASE("quadrature convergence for every accepted pair") {
    facet::EnergyQuadrature fine;
    fine.thetaPoints = 12;
    fine.thetaMaxPanel = 0.05;
    fine.kinkPanel = 1e-4;
    fine.phiPoints = 12;
    fine.phiPanels = 8;
    // One key per (NDF, masking) of the catalog, from the first example of
    // each with its inputs made constants (`let`: a table is keyed by
    // constant shape values). Every pair of a microfacet NDF (all but the
    // whole lobes) must be accepted.
    auto constants = [](std::string inputs) {
        for (size_t at; (at = inputs.find("input ")) != std::string::npos;) inputs.replace(at, 6, "let ");
        return inputs;
    };
    std::vector<EnergyTableKey> keys;
    for (const facet::ModelInfo* n : facet::catalogSlot(facet::ModelSlot::Ndf)) {
        const facet::NdfEntry& ndf = facet::ndfEntry(*n);
        for (const facet::ModelInfo* m : facet::catalogSlot(facet::ModelSlot::Masking)) {
            const facet::MaskingEntry& masking = facet::maskingEntry(*m);
            const facet::ModelExample& n0 = ndf.examples.at(0);
            std::string maskStmt = masking.name, maskLets;
            if (!masking.examples.empty())
                maskStmt = masking.examples[0].stmt, maskLets = constants(masking.examples[0].inputs);
            std::string body = constants(n0.inputs) + maskLets + n0.extra + " ndf = " + n0.stmt +
                               "; masking = " + maskStmt + "; energy = kulla_conty;";
            bool accepted = physics::checkerAccepts(body);
            INFO(ndf.name, " with ", masking.name, ": ", body);
            CHECK(accepted != ndf.wholeLobe);
            if (!accepted) continue;
            facet::DiagnosticEngine diags;
            auto prog = facet::loadProgramText("material t {" + body + "}", "t.mat", diags);
            keys.push_back(facet::energyTableKey(prog.materials[0]));
        }
    }
    struct Job {
        EnergyTableKey key;
        double mu, alpha, diff = 0;
    };
    std::vector<Job> jobs;
    for (const EnergyTableKey& k : keys)
        for (double alpha : {1e-3, 0.05, 0.3, 1.0})
            for (double mu : {0.0, 0.01, 0.1, 0.5, 1.0}) jobs.push_back({k, mu, alpha});
    parallelFor(jobs.size(), [&](size_t i) {
        Job& j = jobs[i];
        double a = facet::directionalAlbedo(j.key, j.mu, j.alpha), b = facet::directionalAlbedo(j.key, j.mu, j.alpha, fine);
        // Compare 1 - E clamped like the table (E > 1 pairs store 0); relative to E for the unbounded `none`.
        j.diff = std::abs(a - b) / std::max(1.0, std::abs(b));
    });
    double worst = 0;
    std::string at;
    for (const Job& j : jobs) {
        INFO(j.key.name(), " mu=", j.mu, " alpha=", j.alpha);
        CHECK(j.diff < 1e-4);
        if (j.diff > worst) {
            worst = j.diff;
            at = j.key.name() + " mu=" + physics::num(j.mu) + " alpha=" + physics::num(j.alpha);
        }
    }
    MESSAGE(keys.size(), " pairs: max |E_default - E_fine| = ", worst, " (at ", at, ")");
}

TEST_CASE("table build time per pair") {
    const EnergyTableKey keys[] = {
        key("ggx", "smith_height_correlated"),
        key("ggx", "smith_separable"),
        key("beckmann", "smith_height_correlated"),
        key("beckmann", "smith_separable"),
        key("ggx", "smith_height_direction_correlated"),
        key("blinn_phong", "smith_height_correlated"),
        key("gaussian", "neumann"),
        key("gtr", "schlick_smith", {1.0, 0.125}),
    };
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    for (const EnergyTableKey& k : keys) {
        auto t = facet::buildEnergyTable(k);
        CHECK(t->validate() == "");
        char buf[200];
        std::snprintf(buf, sizeof buf, "build %-45s %d x %d: %7.1f ms (%u threads)", k.name().c_str(), t->muCount,
                      t->alphaCount, t->buildMillis, threads);
        MESSAGE(buf);
    }
}

}  // TEST_SUITE
