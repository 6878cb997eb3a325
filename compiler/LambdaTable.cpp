// LambdaTable: the quadrature, the tabulation and the lookups of tabulated
// Smith Lambdas (LambdaTable.h), and the checks of materials that use them.
#include "LambdaTable.h"

#include "KullaConty.h"
#include "Material.h"
#include "Quadrature.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>

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

double quadratureCosLambda(const NdfEntry& ndf, const std::vector<double>& shape, double theta) {
    if (!(theta > 0)) return 0;
    const NdfFormulas<double>& f = ndf.formulas.get<double>();
    ModelArgs<double> args = ndf.argsAtAlpha(1.0, shape);
    f.derive(args);
    const quadrature::GaussLegendre<double>& gl = quadrature::gaussLegendre<double>(12);
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

double lambdaTableNode(const NdfEntry& ndf, const std::vector<double>& shape, int i,
                       double (*cosLambdaAt)(const NdfEntry&, const std::vector<double>&, double)) {
    // alpha = 1: tan(theta) = 1/a, and f = a Lambda = (n.v) Lambda / sin(theta).
    double a = std::exp(LambdaTable::kX0 + i * LambdaTable::kStep);
    double theta = std::atan2(1.0, a);
    double f = cosLambdaAt(ndf, shape, theta) / std::sin(theta);
    internal_assert(std::isfinite(f) && f >= 0) << "tabulated Lambda of " << lambdaTableName(ndf, shape) << ": f("
                                                 << a << ") = " << f;
    return std::max(std::log(f), LambdaTable::kLogFloor);
}

std::shared_ptr<LambdaTable> tabulateCosLambda(const NdfEntry& ndf, const std::vector<double>& shape,
                                               double (*cosLambdaAt)(const NdfEntry&, const std::vector<double>&,
                                                                     double)) {
    internal_assert(ndf.shapeInvariant) << "tabulated Lambda of " << ndf.name << ", which is not shape-invariant";
    auto start = std::chrono::steady_clock::now();
    auto table = std::make_shared<LambdaTable>();
    table->ndf = &ndf;
    table->shape = shape;
    table->z.resize(LambdaTable::kSize);
    for (int i = 0; i < LambdaTable::kSize; ++i) table->z[i] = lambdaTableNode(ndf, shape, i, cosLambdaAt);
    table->buildMillis = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return table;
}

double LambdaTable::fAt(double u) const {
    double uc = std::min(u, kSize - 1.0);
    // Nodes i-1 .. i+2 around uc, kept inside the grid.
    double fi = std::clamp(std::floor(uc), 1.0, kSize - 3.0);
    double s = uc - fi;
    int i = int(fi);
    double w0 = -s * (s - 1) * (s - 2) / 6, w1 = (s + 1) * (s - 1) * (s - 2) / 2;
    double w2 = -(s + 1) * s * (s - 2) / 2, w3 = (s + 1) * s * (s - 1) / 6;
    double zz = w0 * z[i - 1] + w1 * z[i] + w2 * z[i + 1] + w3 * z[i + 2];
    if (u > uc) zz += (u - uc) * endSlope();
    return std::exp(zz);
}

double LambdaTable::cosLambda(double proj, double vz) const {
    if (!(proj > 0)) return 0;  // v = n (or alpha = 0): nothing is masked
    double root = std::sqrt(proj);
    double u = std::max((std::log(vz) - std::log(root) - kX0) / kStep, 0.0);
    return root * fAt(u);
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
        static MemoryLayer layer;
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

double tabulatedCosLambda(const NdfEntry& ndf, double shape, double proj, double vz) {
    thread_local const NdfEntry* memoNdf = nullptr;
    thread_local double memoShape = 0;
    thread_local std::shared_ptr<const LambdaTable> memo;
    if (!memo || memoNdf != &ndf || memoShape != shape) {
        memo = lambdaTable(ndf, {shape});
        memoNdf = &ndf;
        memoShape = shape;
    }
    return memo->cosLambda(proj, vz);
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

std::string tabulatedLambdaUnsupported(const CheckedMaterial& m, SourceLoc& loc) {
    const ModelUse& use = m.ndf;
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
                               m.masking.model->name, ndf.name, what, what, in->name);
        double v = constantOf(e, m);
        if (!std::isfinite(v))
            return fmt::format("masking '{}' with ndf '{}' needs a finite {}, got {}", m.masking.model->name, ndf.name,
                               what, v);
        shape.push_back(std::clamp(v, ndf.canonical[p].lo, ndf.canonical[p].hi));
    }
    if (ndf.lambdaShapeError) {
        std::string why = ndf.lambdaShapeError(shape);
        if (!why.empty()) return fmt::format("masking '{}' with ndf '{}': {}", m.masking.model->name, ndf.name, why);
    }
    return "";
}

bool usesTabulatedLambda(const CheckedMaterial& m) {
    return m.masking.model && m.masking.model->smith && m.ndf.model && ndfEntry(*m.ndf.model).tabulatedLambda;
}

std::vector<double> tabulatedLambdaShape(const CheckedMaterial& m) {
    const NdfEntry& ndf = ndfEntry(*m.ndf.model);
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) {
        internal_assert(m.ndf.has(p) && !inputUsed(*m.ndf.args[p], m))
            << "tabulated Lambda: " << ndf.name << " " << ndf.canonical[p].name << " is not constant";
        shape.push_back(std::clamp(constantOf(*m.ndf.args[p], m), ndf.canonical[p].lo, ndf.canonical[p].hi));
    }
    return shape;
}

}  // namespace facet
