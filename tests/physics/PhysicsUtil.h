// PhysicsUtil: shared helpers of the physics tests.
//
// The physics tests check the reference interpreter (double precision)
// against the physics it is meant to implement: NDF normalization, the
// projected-area and weak-white-furnace identities, reciprocity, energy
// conservation and hand-computed values. This header holds what they share:
//   - building a ResolvedMaterial from a few lines of material source, so every
//     test goes through the real parser, checker and Interpreter::resolve;
//   - hemisphere quadrature: Gauss-Legendre panels graded geometrically toward
//     the points where the integrand is peaked or has a kink, and an azimuth
//     range per polar angle so that a discontinuity of the integrand (the
//     horizon of wi, the back side of a microfacet) is an end point of the
//     azimuthal integral and never falls inside a Gauss-Legendre panel.
// Brute force (uniform grids) would need millions of points per integral for
// alpha = 0.05 at grazing angles; graded panels need a few tens of thousands.
#pragma once

#include "Checker.h"
#include "Interpreter.h"
#include "models/ModelCatalog.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace physics {

using facet::Vec3;
using Material = facet::ResolvedMaterial<double>;
constexpr double kPi = std::numbers::pi;

inline double deg(double d) { return d * kPi / 180; }
inline Vec3<double> dir(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}
inline double dot(const Vec3<double>& a, const Vec3<double>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3<double> normalize(const Vec3<double>& v) {
    double l = std::sqrt(dot(v, v));
    return {v.x / l, v.y / l, v.z / l};
}

// Parses and checks `material t { <body> }` and resolves it with default
// inputs. Fails the current test (and returns a default material) if the
// checker rejects it.
inline Material makeMaterial(const std::string& body) {
    facet::DiagnosticEngine diags;
    std::string text = "material t {\n" + body + "\n}\n";
    facet::CheckedProgram program = facet::loadProgramText(text, "physics.mat", diags);
    INFO("material source:\n", text, "\ndiagnostics:\n", diags.str());
    REQUIRE_FALSE(diags.hasErrors());
    const facet::CheckedMaterial* m = program.find("t");
    REQUIRE(m != nullptr);
    facet::Interpreter<double> interp(*m);
    Material r = interp.resolve(nullptr);
    REQUIRE(r.valid);
    return r;
}

// True if the checker accepts the body (used to enumerate NDF x masking pairs).
inline bool checkerAccepts(const std::string& body) {
    facet::DiagnosticEngine diags;
    facet::loadProgramText("material t {\n" + body + "\n}\n", "physics.mat", diags);
    return !diags.hasErrors();
}

// n-point Gauss-Legendre rule on [-1, 1], computed by Newton iteration on
// P_n (so that the nodes do not depend on a table typed in by hand).
struct GaussLegendre {
    std::vector<double> x, w;
    explicit GaussLegendre(int n) : x(n), w(n) {
        for (int i = 0; i < n; ++i) {
            double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0;
            for (int it = 0; it < 100; ++it) {
                double p0 = 1, p1 = z;
                for (int k = 2; k <= n; ++k) {
                    double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                double pn = n == 1 ? z : p1, pm = n == 1 ? 1 : p0;
                dp = n * (z * pn - pm) / (z * z - 1);
                double dz = pn / dp;
                z -= dz;
                if (std::abs(dz) < 1e-16) break;
            }
            x[i] = z;
            w[i] = 2 / ((1 - z * z) * dp * dp);
        }
    }
};

inline const GaussLegendre& gl8() {
    static const GaussLegendre g(8);
    return g;
}

// Integral of f over [a, b] with one Gauss-Legendre panel per interval
// between consecutive break points.
template <typename F>
double integratePanels(const F& f, const std::vector<double>& breaks, const GaussLegendre& g = gl8()) {
    double sum = 0;
    for (size_t p = 0; p + 1 < breaks.size(); ++p) {
        double a = breaks[p], b = breaks[p + 1];
        if (!(b > a)) continue;
        double mid = (a + b) / 2, half = (b - a) / 2, s = 0;
        for (size_t i = 0; i < g.x.size(); ++i) s += g.w[i] * f(mid + half * g.x[i]);
        sum += s * half;
    }
    return sum;
}

// Break points on [a, b]: a, b, each special point, panels growing
// geometrically (factor 2) away from each special point starting at width
// h0 (its own scale), and no panel wider than maxWidth. Near a peak of width
// alpha the panels are ~alpha/8 wide; near a square-root kink they start at
// ~1e-5 so that the kink costs nothing in accuracy.
struct Special {
    double at;
    double h0;
};
inline std::vector<double> gradedBreaks(double a, double b, const std::vector<Special>& specials,
                                        double maxWidth) {
    std::vector<double> br = {a, b};
    for (const Special& s : specials) {
        if (s.at < a || s.at > b) continue;
        br.push_back(s.at);
        for (double d = s.h0; d < b - a; d *= 2) {
            if (s.at - d > a) br.push_back(s.at - d);
            if (s.at + d < b) br.push_back(s.at + d);
        }
    }
    std::sort(br.begin(), br.end());
    std::vector<double> out;
    for (double x : br)
        if (out.empty() || x - out.back() > 1e-13) out.push_back(x);
    std::vector<double> fine;
    for (size_t i = 0; i + 1 < out.size(); ++i) {
        int n = std::max(1, int(std::ceil((out[i + 1] - out[i]) / maxWidth)));
        for (int k = 0; k < n; ++k) fine.push_back(out[i] + (out[i + 1] - out[i]) * k / n);
    }
    fine.push_back(out.back());
    return fine;
}

// Half-width of the azimuth range {phi : cos(phi - center) > num/den} at one
// polar angle, den >= 0: pi when the whole circle qualifies, 0 when none does.
inline double halfWidth(double num, double den) {
    if (den <= 0) return num < 0 ? kPi : 0;
    double k = num / den;
    if (k <= -1) return kPi;
    if (k >= 1) return 0;
    return std::acos(k);
}

// Integral over the upper hemisphere of f(m) dw, m = dir(theta, phi),
// theta in [0, thetaMax] on the given break points; at each theta the
// azimuth runs over [center - hw(theta), center + hw(theta)], split at the
// center (where some integrands have a kink), each half in phiPanels
// Gauss-Legendre panels.
struct Hemisphere {
    std::vector<double> thetaBreaks;
    double center = 0;
    int phiPanels = 16;
};
template <typename F, typename HW>
double integrateHemisphere(const F& f, const HW& hw, const Hemisphere& h) {
    auto inner = [&](double theta) {
        double w = hw(theta);
        if (w <= 0) return 0.0;
        double st = std::sin(theta), ct = std::cos(theta);
        auto g = [&](double phi) {
            Vec3<double> m{st * std::cos(phi), st * std::sin(phi), ct};
            return f(m);
        };
        std::vector<double> br;
        for (int k = -h.phiPanels; k <= h.phiPanels; ++k) br.push_back(h.center + w * k / h.phiPanels);
        return integratePanels(g, br) * st;
    };
    return integratePanels(inner, h.thetaBreaks);
}

// Decimal text of a double that the lexer reads back exactly.
inline std::string num(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return buf;
}

// `name(p0 = v0, p1 = v1, ...)`: the source of an NDF statement's model
// with every canonical parameter of the entry at `a`.
inline std::string callOf(const facet::NdfEntry& ndf, const facet::ModelArgs<double>& a) {
    std::string text = std::string(ndf.name) + "(";
    for (size_t p = 0; p < ndf.canonical.size(); ++p)
        text += (p ? ", " : "") + std::string(ndf.canonical[p].name) + " = " + num(a[int(p)]);
    return text + ")";
}

// The entry's arguments at roughness `alpha` with its shape parameters at
// their typical values.
inline facet::ModelArgs<double> typicalArgsAtAlpha(const facet::NdfEntry& ndf, double alpha) {
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) shape.push_back(ndf.canonical[p].typical);
    return ndf.argsAtAlpha(alpha, shape);
}

}  // namespace physics
