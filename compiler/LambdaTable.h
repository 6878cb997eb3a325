// LambdaTable: the Smith Lambda of a shape-invariant NDF without a closed
// form, tabulated by quadrature (NdfEntry::tabulatedLambda). The interpreter
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
// relative accuracy where it is tiny). It is integrated with 12-point
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
// precision in 1 + Lambda).
// Lookup: u = (x - x0) / h; below the grid z(x0) (f(a) = f(0) - a/2 + ...,
// relative error < 1e-6 for a < 1e-7); 4-point Lagrange inside; beyond the
// grid's end linear in x from the last two nodes (the power-law tail).
// Then (n.v) Lambda(v) = sqrt(proj) f(a), proj = (vx ax)^2 + (vy ay)^2,
// a = vz / sqrt(proj) (the anisotropic stretch), 0 where proj = 0.
// Accuracy (tests/energy, LambdaTableTests): within 1e-6 relative of Lambda
// against an independent 2D quadrature and against the closed forms of ggx
// and beckmann put through the same tabulation.
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

// Bumped whenever the table contents would change.
constexpr int kLambdaTableVersion = 1;

class LambdaTable {
public:
    static constexpr double kX0 = -16.11809565095832;  // log(1e-7)
    static constexpr double kStep = 1.0 / 128;
    static constexpr int kSize = 4127 + 1;              // to log(1e7)
    static constexpr double kLogFloor = -690.7755278982137;  // log(1e-300)

    const NdfEntry* ndf = nullptr;
    std::vector<double> shape;  // the values of the NDF's tableShapeParams
    std::vector<double> z;      // kSize nodes, z[i] = log f(exp(kX0 + i kStep))
    double buildMillis = 0;     // the quadrature's time (read back from a cache file)
    std::string origin = "built";  // or "disk"

    // Node coordinate u = (log(a) - kX0) / kStep clamped below at 0; the
    // slope of z per node beyond the last one.
    double endSlope() const { return z[kSize - 1] - z[kSize - 2]; }
    // f(a) = a Lambda(a) from the nodes as described above, for u >= 0.
    double fAt(double u) const;
    // (n.v) Lambda(v) for proj = (vx ax)^2 + (vy ay)^2 and vz >= 0.
    double cosLambda(double proj, double vz) const;
    // "student_t_g1.8".
    std::string name() const;
};

// The table's name for `ndf` with `shape`: the NDF and each shape value
// after its tag, printed shortest round-trip exact ("student_t_g1.8").
std::string lambdaTableName(const NdfEntry& ndf, const std::vector<double>& shape);

// (n.v) Lambda(v) of the isotropic lobe with alpha = 1 of `ndf` (shape
// values given), by the quadrature above in double: the table's nodes.
double quadratureCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double theta);

// Node i of the table: z = log f at a = exp(kX0 + i kStep) from the given
// (n.v) Lambda, floored at kLogFloor.
double lambdaTableNode(const NdfEntry& ndf, const std::vector<double>& shape, int i,
                       double (*cosLambdaAt)(const NdfEntry&, const std::vector<double>&, double) = quadratureCosLambda);

// The table of `ndf` for the given shape values from the process's memory
// layer (built there on first use, then shared; thread-safe). `ndf` must be
// shapeInvariant.
std::shared_ptr<const LambdaTable> lambdaTable(const NdfEntry& ndf, const std::vector<double>& shape);
// (n.v) Lambda(v) of `ndf` with the one shape value `shape`, from its
// table, for the entries' reference cosLambda. The last table per thread is
// kept: lambdaTable() locks a shared map, and an evaluation asks for the
// same shape value lane after lane.
double tabulatedCosLambda(const NdfEntry& ndf, double shape, double proj, double vz);
// The memory layer's table of (ndf, shape), or null (nothing is built).
std::shared_ptr<const LambdaTable> residentLambdaTable(const NdfEntry& ndf, const std::vector<double>& shape);
// Puts `table` (e.g. loaded from a cache file) into the memory layer unless
// that already holds its key; returns the memory layer's table.
std::shared_ptr<const LambdaTable> adoptLambdaTable(std::shared_ptr<const LambdaTable> table);

// The table built for another D: `build` gives the nodes' (n.v) Lambda at
// theta (tests put closed-form Lambdas through the same tabulation).
std::shared_ptr<LambdaTable> tabulateCosLambda(const NdfEntry& ndf, const std::vector<double>& shape,
                                               double (*cosLambdaAt)(const NdfEntry&, const std::vector<double>&,
                                                                     double));

// A Smith masking with an NDF whose Lambda is tabulated: why the material
// cannot have it (its shape parameters must be finite constants within the
// entry's lambdaShapeError), "" when it can; `loc` is set to the argument.
std::string tabulatedLambdaUnsupported(const CheckedMaterial& material, SourceLoc& loc);
// The clamped constant shape values of the material's NDF.
std::vector<double> tabulatedLambdaShape(const CheckedMaterial& material);
// Whether the material's Smith masking needs its NDF's Lambda table.
bool usesTabulatedLambda(const CheckedMaterial& material);

}  // namespace facet
