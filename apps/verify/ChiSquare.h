// ChiSquare: the goodness-of-fit machinery of the sampling checks (the
// sampling tests and `facet render --plot pdf`).
//
// The procedure is the one of pbrt-v4's and Mitsuba 3's chi-square tests of
// BSDF samplers (written anew here): bin N samples of wi into cells of the
// sphere, integrate the claimed pdf over each cell by adaptive quadrature
// (expected count N times the cell's probability), pool the cells whose
// expected count is small, compute Pearson's statistic and its p-value from
// the chi-square distribution, and reject at a significance level corrected
// for the number of tests run (Sidak). The cells also give the pdf's
// integral over the whole sphere, which must be 1 (the normalization check:
// a pdf off by a constant factor near 1 shifts every cell by the same small
// fraction, which Pearson's statistic hardly sees).
//
// The cells are rectangles in the polar angle and azimuth about the normal,
// with edges graded geometrically toward the lobe's peak (so that narrow
// lobes spread over many cells) and edges on the curves where the pdf
// jumps: the horizon (the cosine lobe ends there) and n.wi = -n.wo (where
// the half vector crosses the horizon). Quadrature within a cell then sees
// a smooth integrand.
#pragma once

#include "Interpreter.h"

#include <functional>
#include <string>
#include <vector>

namespace facet {

class SphereGrid {
public:
    // Polar edges from 0 to pi; azimuth edges over one turn (any start).
    SphereGrid(std::vector<double> thetaEdges, std::vector<double> phiEdges);
    // The grid for a lobe peaked at (theta, phi): edges graded from widths
    // firstTheta and firstPhi there, at most maxTheta and maxPhi wide
    // elsewhere, and edges at the horizon and at pi - viewTheta.
    // Equal-area cells: `rows` bands of cos(theta) from 1 to -1 (row 0 at
    // the normal), `columns` sectors of phi from 0 to 2 pi.
    static SphereGrid equalArea(int rows, int columns);
    static SphereGrid forLobe(double viewTheta, double peakTheta, double peakPhi, double firstTheta, double firstPhi,
                              double maxTheta = 0.13, double maxPhi = 0.2);
    int rings() const { return int(theta_.size()) - 1; }
    int sectors() const { return int(phi_.size()) - 1; }
    int cellCount() const { return rings() * sectors(); }
    // The cell of a direction (-1 for a non-finite or zero one).
    int cellOf(const Vec3<double>& w) const;
    static Vec3<double> direction(double theta, double phi);
    const std::vector<double>& thetaEdges() const { return theta_; }
    const std::vector<double>& phiEdges() const { return phi_; }

private:
    std::vector<double> theta_, phi_;
};

using PdfFunction = std::function<double(const Vec3<double>& wi)>;

// The integral of pdf over each cell (solid angle), by 4x4 Gauss-Legendre
// rules compared against the same rules on the cell's four quarters,
// subdividing where they differ by more than `tolerance` (split between
// the quarters) down to `maxDepth` levels. Theta is integrated through a
// substitution flat at both edges of the ring, so that an integrable
// singularity on a ring edge (|theta - edge|^-1/2) is integrated too.
std::vector<double> integrateCells(const SphereGrid& grid, const PdfFunction& pdf, double tolerance = 1e-9,
                                   int maxDepth = 9);

struct Chi2Outcome {
    double statistic = 0, pValue = 1;
    int dof = 0;
    std::string failure;  // "" when the null hypothesis stands
};

// Pearson's test of observed counts against expected counts (same length;
// expected sums to N within the pdf's normalization). Cells expected below
// minExpected are pooled, smallest first, until the pool reaches it. Fails
// when p < level, or when observed counts fall where nothing is expected.
Chi2Outcome chi2Test(const std::vector<double>& observed, const std::vector<double>& expected, double level,
                     double minExpected = 5);

// Sampled directions binned into the cells of a grid; a draw that gives no
// direction (pdf 0, or a wi in no cell: non-finite or zero) is counted apart.
struct CellHistogram {
    explicit CellHistogram(const SphereGrid& grid) : observed(size_t(grid.cellCount()), 0.0) {}
    std::vector<double> observed;  // per cell
    long draws = 0, unbinned = 0;
    void add(const SphereGrid& grid, const Vec3<double>& wi) {
        ++draws;
        int cell = grid.cellOf(wi);
        if (cell < 0) ++unbinned;
        else observed[size_t(cell)] += 1;
    }
    void addNone() { ++draws, ++unbinned; }
};

struct FitSettings {
    double tolerance;          // integrateCells' tolerance: per cell, in probability
    double level = 0.01;       // per test (already Sidak-corrected)
    double minExpected = 5;
    bool renormalize = false;  // expected counts scaled to the binned draws (the shape only)
};

struct FitOutcome {
    std::vector<double> expected;  // per cell: its probability times the draws (see renormalize)
    double integral = 0;           // the pdf over the whole sphere
    double belowHorizon = 0;       // ... over n.wi < 0 (a grid edge lies on the horizon)
    Chi2Outcome chi2;
};

// The whole goodness-of-fit run once the samples are binned: the pdf
// integrated over the same cells, its integral, the expected counts and
// Pearson's test (what the sampling tests, `facet render --plot pdf` and
// facet.testing.chi2 share).
FitOutcome fitToPdf(const SphereGrid& grid, const CellHistogram& samples, const PdfFunction& pdf,
                    const FitSettings& settings);

// P(X >= x) for X chi-square distributed with dof degrees of freedom.
double chi2Survival(double x, int dof);

// The per-test level that keeps the probability of any false rejection
// among `tests` independent tests at `level`: 1 - (1 - level)^(1/tests).
double sidakLevel(double level, int tests);

}  // namespace facet
