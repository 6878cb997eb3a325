// ChiSquare: see ChiSquare.h.
#include "ChiSquare.h"

#include "Quadrature.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace facet {

namespace {

constexpr double kPi = std::numbers::pi;

// The 4-point Gauss-Legendre rule on [-1, 1].
constexpr double kNode[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
constexpr double kWeight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

struct Rect {
    double t0, t1, p0, p1;
};

template <typename F>
double rule(const F& f, const Rect& r) {
    double ht = (r.t1 - r.t0) / 2, mt = (r.t1 + r.t0) / 2, hp = (r.p1 - r.p0) / 2, mp = (r.p1 + r.p0) / 2, s = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) s += kWeight[i] * kWeight[j] * f(mt + ht * kNode[i], mp + hp * kNode[j]);
    return s * ht * hp;
}

template <typename F>
double adaptive(const F& f, const Rect& r, double whole, double tolerance, int depth) {
    double tm = (r.t0 + r.t1) / 2, pm = (r.p0 + r.p1) / 2;
    Rect q[4] = {{r.t0, tm, r.p0, pm}, {tm, r.t1, r.p0, pm}, {r.t0, tm, pm, r.p1}, {tm, r.t1, pm, r.p1}};
    double part[4], sum = 0;
    for (int k = 0; k < 4; ++k) sum += part[k] = rule(f, q[k]);
    if (depth <= 0 || std::abs(sum - whole) <= tolerance) return sum;
    double out = 0;
    for (int k = 0; k < 4; ++k) out += adaptive(f, q[k], part[k], tolerance / 2, depth - 1);
    return out;
}

// Q(a, x) = Gamma(a, x) / Gamma(a): a power series for P = 1 - Q below
// x = a + 1, a continued fraction (modified Lentz) for Q above.
double gammaQ(double a, double x) {
    if (x <= 0) return 1;
    double prefactor = std::exp(-x + a * std::log(x) - std::lgamma(a));
    if (x < a + 1) {
        double term = 1 / a, sum = term;
        for (int n = 1; n < 100000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (term < sum * 1e-16) break;
        }
        return std::max(0.0, 1 - prefactor * sum);
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1 / d;
        double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-16) break;
    }
    return prefactor * h;
}

}  // namespace

SphereGrid::SphereGrid(std::vector<double> thetaEdges, std::vector<double> phiEdges)
    : theta_(std::move(thetaEdges)), phi_(std::move(phiEdges)) {}

SphereGrid SphereGrid::equalArea(int rows, int columns) {
    std::vector<double> theta, phi;
    for (int i = 0; i <= rows; ++i) theta.push_back(i == rows ? kPi : std::acos(1 - 2.0 * i / rows));
    for (int j = 0; j <= columns; ++j) phi.push_back(2 * kPi * j / columns);
    return SphereGrid(std::move(theta), std::move(phi));
}

SphereGrid SphereGrid::forLobe(double viewTheta, double peakTheta, double peakPhi, double firstTheta,
                               double firstPhi, double maxTheta, double maxPhi) {
    using quadrature::gradedBreaks;
    std::vector<double> theta =
        gradedBreaks(0, kPi, {{peakTheta, firstTheta}, {kPi / 2, 0}, {kPi - viewTheta, 0}}, maxTheta);
    std::vector<double> phi = gradedBreaks(peakPhi - kPi, peakPhi + kPi, {{peakPhi, firstPhi}}, maxPhi);
    return SphereGrid(std::move(theta), std::move(phi));
}

int SphereGrid::cellOf(const Vec3<double>& w) const {
    if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z)) return -1;
    double r = std::sqrt(w.x * w.x + w.y * w.y);
    if (r == 0 && w.z == 0) return -1;
    double t = std::atan2(r, w.z);
    double p = std::atan2(w.y, w.x);
    double p0 = phi_.front();
    p = p0 + std::fmod(std::fmod(p - p0, 2 * kPi) + 2 * kPi, 2 * kPi);
    auto index = [](const std::vector<double>& e, double x) {
        int i = int(std::upper_bound(e.begin(), e.end(), x) - e.begin()) - 1;
        return std::clamp(i, 0, int(e.size()) - 2);
    };
    return index(theta_, t) * sectors() + index(phi_, p);
}

Vec3<double> SphereGrid::direction(double t, double p) {
    double st = std::sin(t);
    return {st * std::cos(p), st * std::sin(p), std::cos(t)};
}

std::vector<double> integrateCells(const SphereGrid& grid, const PdfFunction& pdf, double tolerance, int maxDepth) {
    std::vector<double> out(grid.cellCount());
    const std::vector<double>&te = grid.thetaEdges(), &pe = grid.phiEdges();
    for (int i = 0; i < grid.rings(); ++i) {
        // theta = t0 + (t1 - t0)(3 s^2 - 2 s^3), s in [0, 1]: its derivative
        // vanishes like s at both edges, which makes an edge singularity
        // like |theta - edge|^-1/2 bounded (a heavy-tailed NDF's D ~
        // mz^(2 gamma - 4) has one on the ring n.wi = -n.wo, an edge of the
        // lobe grids) and leaves a smooth integrand smooth.
        const double t0 = te[i], width = te[i + 1] - te[i];
        auto f = [&](double s, double p) {
            double t = t0 + width * s * s * (3 - 2 * s);
            return pdf(grid.direction(t, p)) * std::sin(t) * 6 * width * s * (1 - s);
        };
        for (int j = 0; j < grid.sectors(); ++j) {
            Rect r{0, 1, pe[j], pe[j + 1]};
            out[i * grid.sectors() + j] = adaptive(f, r, rule(f, r), tolerance, maxDepth);
        }
    }
    return out;
}

FitOutcome fitToPdf(const SphereGrid& grid, const CellHistogram& samples, const PdfFunction& pdf,
                    const FitSettings& s) {
    FitOutcome out;
    out.expected = integrateCells(grid, pdf, s.tolerance);
    for (int i = 0; i < grid.rings(); ++i)
        for (int j = 0; j < grid.sectors(); ++j) {
            double p = out.expected[size_t(i * grid.sectors() + j)];
            out.integral += p;
            if (grid.thetaEdges()[size_t(i)] >= std::numbers::pi / 2) out.belowHorizon += p;
        }
    double scale = s.renormalize ? double(samples.draws - samples.unbinned) / out.integral : double(samples.draws);
    for (double& e : out.expected) e *= scale;
    out.chi2 = chi2Test(samples.observed, out.expected, s.level, s.minExpected);
    return out;
}

Chi2Outcome chi2Test(const std::vector<double>& observed, const std::vector<double>& expected, double level,
                     double minExpected) {
    Chi2Outcome out;
    std::vector<size_t> order(expected.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double total = 0;
    for (double o : observed) total += o;
    double poolObserved = 0, poolExpected = 0;
    int cells = 0;
    for (size_t i : order) {
        double o = observed[i], e = expected[i];
        if (e <= 0) {
            // Samples where the pdf integrates to nothing: a wrong sampler,
            // up to a few strays from rounding at the edge of a support.
            if (o > std::max(1.0, 1e-5 * total)) {
                out.failure = fmt::format("{} samples in a cell whose expected count is {}", o, e);
                return out;
            }
            poolObserved += o;
        } else if (e < minExpected || (poolExpected > 0 && poolExpected < minExpected)) {
            poolObserved += o;
            poolExpected += e;
        } else {
            out.statistic += (o - e) * (o - e) / e;
            ++cells;
        }
    }
    if (poolExpected > 0) {
        out.statistic += (poolObserved - poolExpected) * (poolObserved - poolExpected) / poolExpected;
        ++cells;
    }
    out.dof = cells - 1;
    if (out.dof < 1) {
        out.failure = fmt::format("too few cells with enough expected samples ({})", cells);
        return out;
    }
    out.pValue = chi2Survival(out.statistic, out.dof);
    if (!(out.pValue >= level))
        out.failure = fmt::format("chi-square {:.1f} with {} degrees of freedom: p = {:.3g} < {:.3g}", out.statistic,
                                  out.dof, out.pValue, level);
    return out;
}

double chi2Survival(double x, int dof) { return gammaQ(dof / 2.0, x / 2); }

double sidakLevel(double level, int tests) { return -std::expm1(std::log1p(-level) / tests); }

}  // namespace facet
