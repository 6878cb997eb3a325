// LambdaTable: the quadrature, the tabulation and the lookups of tabulated
// Smith Lambdas (LambdaTable.h), and the checks of materials that use them.
#include "LambdaTable.h"
#include "Immortal.h"

#include "KullaConty.h"
#include "Material.h"
#include "Quadrature.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <thread>

namespace facet {
namespace {

// r - atan(r) without cancellation for small r.
double rMinusAtan(double r) {
    if (r > 0.125) return r - std::atan(r);
    double r2 = r * r, term = r * r2, sum = 0;
    for (int k = 3; k <= 15; k += 2) {
        sum += (k % 4 == 3 ? term : -term) / k;
        term *= r2;
    }
    return sum;
}

// The integrand 2 D(w) cos(w) (S - B atan(S/B)) at w (m at polar angle
// pi/2 - w), given t = theta - w separately (both accurate near their zero).
double integrand(const NdfFormulas<double>& f, const ModelArgs<double>& args, double theta, double w, double t) {
    if (!(w > 0) || !(t > 0)) return 0;
    double sw = std::sin(w), cw = std::cos(w);
    double D = f.D(args, {cw, 0, sw});
    if (!(D > 0)) return 0;
    double S = std::sqrt(std::sin(t) * std::sin(theta + w));
    double B = std::cos(theta) * sw;
    double bracket = B > 0 ? B * rMinusAtan(S / B) : S;
    return 2 * D * cw * bracket;
}

}  // namespace

double quadratureCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double alpha, double theta) {
    if (!(theta > 0)) return 0;
    const NdfFormulas<double>& f = ndf.formulas.get<double>();
    ModelArgs<double> args = ndf.argsAtAlpha(alpha, shape);
    f.derive(args);
    // 8 points per panel: within 9.1e-10 relative of 24 points on panels a
    // quarter as wide (cut at 1e-12, first edge panel 1e-9), over 19 shapes
    // of the six tabulated NDFs at 12 alphas x 18 slopes each;
    // 12 points (1e-10) cost half as much again for nothing the table's
    // interpolation (4.5e-8) could show.
    const quadrature::GaussLegendre<double>& gl = quadrature::gaussLegendre<double>(8);
    // Normalized coordinates: w = theta s on [0, 1/2] (graded toward the
    // horizon, s = 0) and t = theta s on [0, 1/2] (graded toward m's
    // visibility edge, t = 0), so that both ends keep their precision.
    constexpr double kHorizonCut = 1e-9;
    std::vector<double> horizon = quadrature::gradedBreaks(kHorizonCut, 0.5, {{kHorizonCut, kHorizonCut}}, 1.0 / 16);
    std::vector<double> edge = quadrature::gradedBreaks(0, 0.5, {{0, 1e-7}}, 1.0 / 16);
    auto byW = [&](double s) { return integrand(f, args, theta, theta * s, theta * (1 - s)); };
    auto byT = [&](double s) { return integrand(f, args, theta, theta * (1 - s), theta * s); };
    double sum = quadrature::integratePanels(byW, horizon, gl) + quadrature::integratePanels(byT, edge, gl);
    // [0, kHorizonCut]: the power law g ~ s^p through two points there.
    double g1 = byW(kHorizonCut), g0 = byW(kHorizonCut / 2);
    if (g1 > 0 && g0 > 0) {
        double p = std::log2(g1 / g0);
        if (p > -1) sum += g1 * kHorizonCut / (p + 1);
    }
    return theta * sum;
}

LambdaAxes lambdaAxes(const NdfEntry& ndf) {
    return ndf.shapeInvariant ? LambdaAxes::Slope : LambdaAxes::SlopeAlpha;
}

namespace {

// asinh(s b), b = 1/alpha^2 - 1 formed as (1 - alpha)(1 + alpha) / alpha^2,
// which keeps its relative accuracy near alpha = 1.
double rowCoordinate(double s, double alpha) {
    return std::asinh(s * (1 - alpha) * (1 + alpha) / (alpha * alpha));
}

}  // namespace

double LambdaGrid::rowOf(double alpha) const { return (rowCoordinate(rowScale, alpha) - y0) / yStep; }

double LambdaGrid::alphaAt(double row) const {
    double b = std::sinh(y0 + row * yStep) / rowScale;
    return 1 / std::sqrt(1 + b);
}

LambdaGrid lambdaGrid(const NdfEntry& ndf, const std::vector<double>& shape, LambdaAxes axes) {
    if (axes == LambdaAxes::Slope)
        return {LambdaTable::kX0, LambdaTable::kStep, LambdaTable::kSize, 0, 1, 1, 1};
    LambdaRows spec = ndf.lambdaRows ? ndf.lambdaRows(shape) : LambdaRows{};
    internal_assert(spec.scale > 0 && spec.step > 0 && spec.alphaLo > 0 && spec.alphaLo < spec.alphaHi)
        << "Lambda rows of " << lambdaTableName(ndf, shape);
    LambdaGrid g{LambdaTable::kAlphaX0, LambdaTable::kAlphaXStep, LambdaTable::kAlphaXSize, 0, spec.step, 1,
                 spec.scale};
    // From alphaHi down to alphaLo, in whole steps of at most spec.step (a
    // row beyond either end would hold the Lambda of clamped parameters).
    double yHi = rowCoordinate(spec.scale, spec.alphaHi), yLo = rowCoordinate(spec.scale, spec.alphaLo);
    g.rows = int(std::ceil((yLo - yHi) / spec.step)) + 1;
    g.y0 = yHi;
    g.yStep = (yLo - yHi) / (g.rows - 1);
    g.alphaLo = g.alphaAt(g.rows - 1);
    g.alphaHi = g.alphaAt(0);
    return g;
}

double lambdaTableNode(const NdfEntry& ndf, const std::vector<double>& shape, const LambdaGrid& g, int k,
                       CosLambdaSource cosLambdaAt) {
    // tan(theta) = 1/(a alpha), and f = a Lambda = (n.v) Lambda / (alpha sin(theta));
    // a grazing node (after the rows) has a = 0, theta = pi/2.
    bool grazing = k >= g.size * g.rows;
    double a = grazing ? 0 : std::exp(g.x0 + (k % g.size) * g.step);
    double alpha = g.alphaAt(grazing ? k - g.size * g.rows : k / g.size);
    double theta = std::atan2(1.0, a * alpha);
    double f = cosLambdaAt(ndf, shape, alpha, theta) / (alpha * std::sin(theta));
    internal_assert(std::isfinite(f) && f >= 0) << "tabulated Lambda of " << lambdaTableName(ndf, shape) << ": f("
                                                 << a << ", alpha " << alpha << ") = " << f;
    return std::max(std::log(f), LambdaTable::kLogFloor);
}

std::shared_ptr<LambdaTable> tabulateCosLambda(const NdfEntry& ndf, const std::vector<double>& shape,
                                               CosLambdaSource cosLambdaAt, LambdaAxes axes) {
    internal_assert(ndf.shapeInvariant || axes == LambdaAxes::SlopeAlpha)
        << "a Lambda table in a alone of " << ndf.name << ", which is not shape-invariant";
    auto start = std::chrono::steady_clock::now();
    auto table = std::make_shared<LambdaTable>();
    table->ndf = &ndf;
    table->shape = shape;
    table->axes = axes;
    table->grid = lambdaGrid(ndf, shape, axes);
    const LambdaGrid& g = table->grid;
    table->z.resize(size_t(g.nodeCount()));
    // Two threads for a SlopeAlpha table (45k-146k nodes): even and odd nodes.
    int threads = axes == LambdaAxes::Slope ? 1 : 2;
    table->buildThreads = threads;
    auto fill = [&](int first) {
        for (int k = first; k < int(table->z.size()); k += threads)
            table->z[k] = lambdaTableNode(ndf, shape, g, k, cosLambdaAt);
    };
    std::vector<std::thread> helpers;
    for (int t = 1; t < threads; ++t) helpers.emplace_back(fill, t);
    fill(0);
    for (std::thread& h : helpers) h.join();
    table->buildMillis = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return table;
}

namespace {

// n-point Lagrange weights (n even) at coordinate c of nodes [0, size - 1]
// (size >= n): returns the stencil's first node, kept inside the grid.
int lagrangeStencil(double c, int size, int n, double* w) {
    int half = n / 2;
    double fi = std::clamp(std::floor(c), half - 1.0, double(size - 1 - half));
    double s = c - fi;
    for (int k = 0; k < n; ++k) {
        double wk = 1;
        for (int m = 0; m < n; ++m)
            if (m != k) wk *= (s - (m - half + 1)) / double(k - m);
        w[k] = wk;
    }
    return int(fi) - half + 1;
}

}  // namespace

double LambdaTable::endSlope(int j) const {
    const LambdaGrid& g = grid;
    return z[size_t(j) * g.size + g.size - 1] - z[size_t(j) * g.size + g.size - 2];
}

double LambdaTable::fAt(double u, double v) const {
    const LambdaGrid& g = grid;
    double uc = std::clamp(u, 0.0, g.size - 1.0);
    // 4 points along x for a Slope table, kAlphaOrder along both axes else.
    int nx = g.rows == 1 ? 4 : LambdaTable::kAlphaOrder, ny = g.rows == 1 ? 1 : LambdaTable::kAlphaOrder;
    double wx[LambdaTable::kAlphaOrder], wy[LambdaTable::kAlphaOrder] = {1};
    int i = lagrangeStencil(uc, g.size, nx, wx);
    int j = g.rows == 1 ? 0 : lagrangeStencil(std::clamp(v, 0.0, g.rows - 1.0), g.rows, ny, wy);
    double zz = 0, zGrazing = 0;
    for (int r = 0; r < ny; ++r) {
        const double* row = z.data() + size_t(j + r) * g.size;
        double zr = 0;
        for (int k = 0; k < nx; ++k) zr += wx[k] * row[i + k];
        if (u > uc) zr += (u - uc) * endSlope(j + r);
        zz += wy[r] * zr;
        zGrazing += wy[r] * z[g.grazingNode(j + r)];
    }
    if (!(u < 0)) return std::exp(zz);
    // Below the grid: the chord in a from z(0) to z(a0), a / a0 = exp(u step).
    return std::exp(zGrazing + (zz - zGrazing) * std::exp(u * g.step));
}

double LambdaTable::cosLambda(double proj, double vz, double alpha) const {
    if (!(proj > 0)) return 0;  // v = n (or alpha = 0): nothing is masked
    const LambdaGrid& g = grid;
    double v = 0;
    if (axes == LambdaAxes::SlopeAlpha) {
        double clamped = std::clamp(alpha, g.alphaLo, g.alphaHi);
        proj *= (clamped / alpha) * (clamped / alpha);
        v = std::clamp(g.rowOf(clamped), 0.0, g.rows - 1.0);
    }
    double root = std::sqrt(proj);
    double u = (std::log(vz) - std::log(root) - g.x0) / g.step;  // -inf at vz = 0
    return root * fAt(u, v);
}

std::string lambdaTableName(const NdfEntry& ndf, const std::vector<double>& shape) {
    std::string s = ndf.name;
    for (size_t i = 0; i < ndf.tableShapeParams.size(); ++i)
        s += fmt::format("_{}{}", ndf.canonical[ndf.tableShapeParams[i]].tableTag, shape.at(i));
    return s;
}

std::string LambdaTable::name() const { return lambdaTableName(*ndf, shape); }

namespace {

// The process's memory layer (LambdaTable.h).
struct MemoryLayer {
    using Key = std::pair<const NdfEntry*, std::vector<double>>;
    std::mutex mutex;  // building (~0.5 s) under the lock: one build per key
    std::map<Key, std::shared_ptr<const LambdaTable>> tables;
    static MemoryLayer& get() {
        static MemoryLayer& layer = immortal<MemoryLayer>();
        return layer;
    }
};

}  // namespace

std::shared_ptr<const LambdaTable> lambdaTable(const NdfEntry& ndf, const std::vector<double>& shape) {
    // The last table per thread: the interpreter asks for the same one on
    // every evaluation.
    thread_local MemoryLayer::Key lastKey;
    thread_local std::shared_ptr<const LambdaTable> last;
    if (last && lastKey.first == &ndf && lastKey.second == shape) return last;
    MemoryLayer& layer = MemoryLayer::get();
    std::lock_guard<std::mutex> lock(layer.mutex);
    std::shared_ptr<const LambdaTable>& slot = layer.tables[{&ndf, shape}];
    if (!slot) slot = tabulateCosLambda(ndf, shape, quadratureCosLambda);
    lastKey = {&ndf, shape};
    last = slot;
    return slot;
}

double tabulatedCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double proj, double vz,
                          double alpha) {
    thread_local const NdfEntry* memoNdf = nullptr;
    thread_local std::vector<double> memoShape;
    thread_local std::shared_ptr<const LambdaTable> memo;
    if (!memo || memoNdf != &ndf || memoShape != shape) {
        memo = lambdaTable(ndf, shape);
        memoNdf = &ndf;
        memoShape = shape;
    }
    return memo->cosLambda(proj, vz, alpha);
}

std::shared_ptr<const LambdaTable> residentLambdaTable(const NdfEntry& ndf, const std::vector<double>& shape) {
    MemoryLayer& layer = MemoryLayer::get();
    std::lock_guard<std::mutex> lock(layer.mutex);
    auto it = layer.tables.find({&ndf, shape});
    return it == layer.tables.end() ? nullptr : it->second;
}

std::shared_ptr<const LambdaTable> adoptLambdaTable(std::shared_ptr<const LambdaTable> table) {
    MemoryLayer& layer = MemoryLayer::get();
    std::lock_guard<std::mutex> lock(layer.mutex);
    std::shared_ptr<const LambdaTable>& slot = layer.tables[{table->ndf, table->shape}];
    if (!slot) slot = std::move(table);
    return slot;
}

std::string tabulatedLambdaUnsupported(const CheckedMaterial& m, const CheckedLobe& lobe, SourceLoc& loc) {
    const ModelUse& use = lobe.ndf;
    const NdfEntry& ndf = ndfEntry(*use.model);
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) {
        const char* what = ndf.canonical[p].name;
        if (!use.has(p)) continue;
        const Expr& e = *use.args[p];
        loc = e.loc;
        if (const CheckedInput* in = inputUsed(e, m))
            return fmt::format("masking '{}' with ndf '{}' needs a constant {} (its Smith Lambda is tabulated for "
                               "one {}); this one depends on input '{}'",
                               lobe.masking.model->name, ndf.name, what, what, in->name);
        double v = constantOf(e, m);
        if (!std::isfinite(v))
            return fmt::format("masking '{}' with ndf '{}' needs a finite {}, got {}", lobe.masking.model->name, ndf.name,
                               what, v);
        shape.push_back(std::clamp(v, ndf.canonical[p].lo, ndf.canonical[p].hi));
    }
    if (ndf.lambdaShapeError) {
        std::string why = ndf.lambdaShapeError(shape);
        if (!why.empty()) return fmt::format("masking '{}' with ndf '{}': {}", lobe.masking.model->name, ndf.name, why);
    }
    return "";
}

bool usesTabulatedLambda(const CheckedLobe& lobe) {
    return lobe.masking.model && lobe.masking.model->smith && lobe.ndf.model &&
           ndfEntry(*lobe.ndf.model).tabulatedLambda;
}

bool usesTabulatedLambda(const CheckedMaterial& m) { return usesTabulatedLambda(m.singleLobe()); }

std::vector<double> tabulatedLambdaShape(const CheckedMaterial& m) { return tabulatedLambdaShape(m, m.singleLobe()); }

std::vector<double> tabulatedLambdaShape(const CheckedMaterial& m, const CheckedLobe& lobe) {
    const ModelUse& use = lobe.ndf;
    const NdfEntry& ndf = ndfEntry(*use.model);
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) {
        internal_assert(use.has(p) && !inputUsed(*use.args[p], m))
            << "tabulated Lambda: " << ndf.name << " " << ndf.canonical[p].name << " is not constant";
        shape.push_back(std::clamp(constantOf(*use.args[p], m), ndf.canonical[p].lo, ndf.canonical[p].hi));
    }
    return shape;
}

}  // namespace facet
