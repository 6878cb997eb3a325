// LambdaTable: the Smith Lambda of an NDF without a closed form, tabulated
// by quadrature (NdfEntry::tabulatedLambda). The interpreter
// (the entry's cosLambda) and the JIT kernel (the entry's emitter, which
// embeds the nodes as constant data) both interpolate the same table, so the
// table is that NDF's Lambda, to the accuracy stated below.
//
// ---- the integral ----------------------------------------------------------
//
// (n.v)(1 + Lambda(v)) = Int (v.m)+ D(m) dm (the projected area of the
// visible microsurface), and Int (n.v)(n.m) D(m) dm = n.v, so
//   (n.v) Lambda(v) = Int [(v.m)+ - (n.v)(n.m)] D(m) dm.
// For an isotropic D the azimuth integral is closed-form: with m at polar
// angle pi/2 - w and v at theta, A = sin(theta) cos(w), B = cos(theta) sin(w),
// the bracket integrates over the azimuth to 0 where B >= A (w >= theta) and
// to 2 (sqrt(A^2 - B^2) - B acos(B/A)) where w < theta, so
//   (n.v) Lambda(v) = 2 Int_0^theta D(w) cos(w) (S - B atan(S/B)) dw,
//   S = sqrt(A^2 - B^2) = sqrt(sin(theta - w) sin(theta + w)),
// a sum of positive terms (no cancellation against n.v, so Lambda keeps its
// relative accuracy where it is tiny). It is integrated with 8-point
// Gauss-Legendre panels graded toward both ends (toward w = 0, where a
// heavy-tailed D may be singular like w^p, p > -1, the last piece below
// 1e-9 theta is added from the power law fitted there).
//
// ---- the table ---------------------------------------------------------------
//
// Shape invariance: Lambda depends on a = 1 / (alpha(v) tan(theta)) alone,
// so the table holds, for the isotropic lobe with alpha = 1 and the
// material's shape parameters (a per-material constant),
//   z(x) = log(f(a)), f(a) = a Lambda(a), x = log(a),
// f being smooth, finite at grazing (a -> 0, where Lambda ~ f(0)/a) and
// decaying like a power of a or a Gaussian in a at normal incidence.
// Nodes: x uniform in [log 1e-7, log 1e7], step 1/128 (4127 steps);
// z below log(1e-300) is stored as log(1e-300) (Lambda is then 0 to double
// precision in 1 + Lambda); then one grazing node, z = log f(0) (theta =
// pi/2, by the same quadrature).
// Lookup: u = (x - x0) / h; 4-point Lagrange inside; beyond the grid's end
// linear in x from the last two nodes (the power-law tail); below the grid
// (a < a0 = exp(x0), down to a = 0 at n.v = 0) z on the chord in a between
// z(0) and z(a0): z(0) + (z(a0) - z(0)) a / a0. With P the density of one
// slope component, f(a) = Int_a^inf (q - a) P(q) dq = f(0) - a/2 + P(0)
// a^2/2 + ..., so log f is smooth in a there and the chord is off by at
// most |P(0)/f(0) - 1/(4 f(0)^2)| a0^2 / 8 relative (an earlier table held
// f(a0), off by a0 / 2 / f(0): 1e-5 relative at n.v = 1e-6 on the (a,
// alpha) grid below, whose a0 is 1e-5).
// Then (n.v) Lambda(v) = sqrt(proj) f(a), proj = (vx ax)^2 + (vy ay)^2,
// a = vz / sqrt(proj) (the anisotropic stretch), 0 where proj = 0.
// Accuracy (tests/energy, LambdaTableTests): within 1e-6 relative of Lambda
// against an independent 2D quadrature and against the closed forms of ggx
// and beckmann put through the same tabulation.
//
// ---- the table in (a, alpha) -------------------------------------------------
//
// An isotropic NDF that is not shape-invariant (gtr, gaussian, abc, sgd:
// Lambda depends on alpha and theta separately) gets a table in two axes
// (axes SlopeAlpha; the catalog's shapeInvariant decides): the same z = log
// f(a) with a = 1 / (alpha tan theta), now for the lobe of roughness alpha
// (the entry's equivalentAlphas), per constant shape value.
// Rows: y = asinh(s b), b = 1/alpha^2 - 1, uniform with step 1/8 from the
// entry's lambdaAlphaHi down to alpha = 9e-5 < kMinAlpha. Toward alpha -> 0
// y ~ log(2 s) - 2 log(alpha), so the rows are uniform in log alpha (where
// the lobe is nearly shape-invariant and z barely depends on y); near
// alpha = 1 they are uniform in b, in which the lobes change: gtr's (1 + b
// sin^2)^-gamma falls over b ~ 1/gamma, so s (the entry's lambdaRowScale,
// ~ the exponent) keeps rows per unit of change the same for every gamma;
// past alpha = 1 (b < 0, sgd's equivalent roughness reaches 3) y stays
// finite. In each row x is uniform in [log 1e-5, log 9.9e6], step 1/16
// (443 nodes). Near shape invariance z barely depends on y; for gtr with
// gamma far from 2 the dependence runs along the diagonal (a uniform D has
// Lambda(theta) alone), which 6-point Lagrange across the rows resolves;
// along x a Gaussian-like cutoff (z ~ -a^2) needs 6 points too at this
// step. After the rows, one grazing node per row (log f(0) at the row's
// alpha). Lookup: 6 x 6-point Lagrange (each row's chord to its grazing
// node below the grid, its linear tail beyond it, as above); alpha outside the rows' range is
// clamped, with proj rescaled to the clamped alpha (beyond lambdaAlphaHi,
// Lambda is that of lambdaAlphaHi at the same direction). The quadrature
// is the one above at the row's alpha; the build runs on two threads.
// Accuracy (LambdaTableTests): within 1e-6 relative of the independent 2D
// quadrature for alpha in [1e-3, 1] and theta up to 89.99 deg (or 1e-11
// absolute where Lambda is tiny), for every tabulated NDF at the extremes
// of its shape parameter; (n.v) Lambda within 1e-7 from n.v = 1e-4 down to
// n.v = 0.
//
// ---- sharing and caching -----------------------------------------------------
//
// A table is a pure function of (NDF, shape values), immutable once made.
// lambdaTable() is the process's memory layer: the reference interpreter's
// catalog formulas, the plan and the emitters' embedded-table hooks (which
// see only the material) all ask it. A TableCache (tables/TableCache.h,
// one per Compiler) is the disk layer above it: before a kernel is planned
// it loads the table from its cache directory (or builds and writes it) and
// adopts it into the memory layer, so that no quadrature runs when the file
// is good.
#pragma once

#include "SourceLoc.h"
#include "models/ModelCatalog.h"

#include <memory>
#include <string>
#include <vector>

namespace facet {

struct CheckedMaterial;
struct CheckedLobe;

// Bumped whenever the table contents would change.
constexpr int kLambdaTableVersion = 5;

// What a table's nodes span. Slope: the Lambda of a shape-invariant NDF, a
// function of a alone (one row, alpha = 1). SlopeAlpha: the Lambda of an
// isotropic NDF that is not shape-invariant (NdfEntry::shapeInvariant
// decides), a function of a and alpha, one row of x nodes per y = log alpha.
enum class LambdaAxes { Slope, SlopeAlpha };
LambdaAxes lambdaAxes(const NdfEntry& ndf);

// The nodes of a table: x = log a at x0 + i step (i < size), row
// coordinate y = asinh(rowScale (1/alpha^2 - 1)) at y0 + j yStep (j <
// rows); z[j size + i]. A Slope table has one row (alpha = 1).
struct LambdaGrid {
    double x0, step;
    int size;
    double y0, yStep;
    int rows;
    double rowScale;
    double alphaLo = 1, alphaHi = 1;   // of the last and the first row
    double rowOf(double alpha) const;  // (y(alpha) - y0) / yStep, unclamped
    double alphaAt(double row) const;  // the inverse
    // The grazing nodes follow the rows: z[grazingNode(j)] = log f(0) of row j.
    int grazingNode(int row) const { return size * rows + row; }
    int nodeCount() const { return size * rows + rows; }
};
// The grid of the table of `ndf` with `shape` on `axes`.
LambdaGrid lambdaGrid(const NdfEntry& ndf, const std::vector<double>& shape, LambdaAxes axes);

class LambdaTable {
public:
    static constexpr double kX0 = -16.11809565095832;  // log(1e-7)
    static constexpr double kStep = 1.0 / 128;
    static constexpr int kSize = 4127 + 1;              // to log(1e7)
    static constexpr double kLogFloor = -690.7755278982137;  // log(1e-300)
    // The SlopeAlpha grid (see above).
    static constexpr double kAlphaX0 = -11.512925464970229;  // log(1e-5)
    static constexpr double kAlphaXStep = 1.0 / 16;
    static constexpr int kAlphaXSize = 442 + 1;              // to log(9.9e6)
    static constexpr int kAlphaOrder = 6;                    // Lagrange points along x and y

    const NdfEntry* ndf = nullptr;
    std::vector<double> shape;  // the values of the NDF's tableShapeParams
    LambdaAxes axes = LambdaAxes::Slope;
    LambdaGrid grid{};          // lambdaGrid(*ndf, shape, axes)
    std::vector<double> z;      // grid.nodeCount() nodes, z = log f: the rows, then each row's f(0)
    double buildMillis = 0;     // the quadrature's time (read back from a cache file)
    int buildThreads = 0;       // the threads the quadrature ran on (0: not built here)
    std::string origin = "built";  // or "disk"

    // The slope of z per node beyond the last one of row j.
    double endSlope(int j = 0) const;
    // f = a Lambda from the nodes as described above at the node
    // coordinates u = (log(a) - x0) / step (-inf at a = 0) and v =
    // grid.rowOf(alpha) in [0, rows - 1] (0 for a Slope table).
    double fAt(double u, double v = 0) const;
    // (n.v) Lambda(v) for proj = (vx ax)^2 + (vy ay)^2 and vz >= 0; a
    // SlopeAlpha table also needs the (isotropic) alpha, which it clamps
    // to its alpha range (beyond alphaHi the Lambda of alphaHi at the
    // same direction).
    double cosLambda(double proj, double vz, double alpha = 1) const;
    // "student_t_g1.8".
    std::string name() const;
};

// The table's name for `ndf` with `shape`: the NDF and each shape value
// after its tag, printed shortest round-trip exact ("student_t_g1.8").
std::string lambdaTableName(const NdfEntry& ndf, const std::vector<double>& shape);

// (n.v) Lambda(v) of the isotropic lobe with roughness alpha of `ndf`
// (shape values given) at polar angle theta, by the quadrature above in
// double: the table's nodes.
double quadratureCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double alpha, double theta);

// A source of (n.v) Lambda(alpha, theta) for the nodes.
using CosLambdaSource = double (*)(const NdfEntry&, const std::vector<double>&, double alpha, double theta);

// Node k = j size + i of a table on `grid`: z = log f at a = exp(x0 + i
// step), alpha = grid.alphaAt(j), from the given (n.v) Lambda, floored
// at kLogFloor.
double lambdaTableNode(const NdfEntry& ndf, const std::vector<double>& shape, const LambdaGrid& grid, int k,
                       CosLambdaSource cosLambdaAt = quadratureCosLambda);

// The table of `ndf` for the given shape values from the process's memory
// layer (built there on first use, then shared; thread-safe), on the axes
// of lambdaAxes(ndf).
std::shared_ptr<const LambdaTable> lambdaTable(const NdfEntry& ndf, const std::vector<double>& shape);
// (n.v) Lambda(v) of `ndf` with the shape values `shape` (one or none),
// from its table, for the entries' reference cosLambda (alpha: the
// isotropic roughness, for a SlopeAlpha table). The last table per thread is
// kept: lambdaTable() locks a shared map, and an evaluation asks for the
// same shape value lane after lane.
double tabulatedCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double proj, double vz,
                          double alpha = 1);
// The memory layer's table of (ndf, shape), or null (nothing is built).
std::shared_ptr<const LambdaTable> residentLambdaTable(const NdfEntry& ndf, const std::vector<double>& shape);
// Puts `table` (e.g. loaded from a cache file) into the memory layer unless
// that already holds its key; returns the memory layer's table.
std::shared_ptr<const LambdaTable> adoptLambdaTable(std::shared_ptr<const LambdaTable> table);

// The table built from another source of Lambda, or on other axes than
// the entry's (tests put closed-form Lambdas, and shape-invariant NDFs,
// through the same tabulation).
std::shared_ptr<LambdaTable> tabulateCosLambda(const NdfEntry& ndf, const std::vector<double>& shape,
                                               CosLambdaSource cosLambdaAt, LambdaAxes axes);
inline std::shared_ptr<LambdaTable> tabulateCosLambda(const NdfEntry& ndf, const std::vector<double>& shape,
                                                      CosLambdaSource cosLambdaAt) {
    return tabulateCosLambda(ndf, shape, cosLambdaAt, lambdaAxes(ndf));
}

// A Smith masking with an NDF whose Lambda is tabulated: why the material
// cannot have it (its shape parameters must be finite constants within the
// entry's lambdaShapeError), "" when it can; `loc` is set to the argument.
std::string tabulatedLambdaUnsupported(const CheckedMaterial& material, const CheckedLobe& lobe, SourceLoc& loc);
// The clamped constant shape values of the lobe's NDF.
std::vector<double> tabulatedLambdaShape(const CheckedMaterial& material, const CheckedLobe& lobe);
// Whether the lobe's Smith masking needs its NDF's Lambda table.
bool usesTabulatedLambda(const CheckedLobe& lobe);
// The same two for the single lobe of a material that does not combine lobes.
std::vector<double> tabulatedLambdaShape(const CheckedMaterial& material);
bool usesTabulatedLambda(const CheckedMaterial& material);

}  // namespace facet
