// KullaConty: the E tables by quadrature, lookups, and the Fresnel averages.
#include "KullaConty.h"

#include "ExprEval.h"
#include "Interpolation.h"
#include "DielectricLobe.h"
#include "Interpreter.h"
#include "Quadrature.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <mutex>
#include <thread>

namespace facet {

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

using quadrature::gaussLegendre;
using quadrature::GradePoint;
using quadrature::gradedBreaks;
using quadrature::integratePanels;

// The lobe of a table key at one alpha as a reference material: the
// specular lobe with F = 1, or the non-absorbing interface of relative
// index key.interfaceEta over the whole sphere in importance transport (its
// R + T is the power it scatters).
ResolvedMaterial<double> tableLobe(const EnergyTableKey& key, double alpha) {
    ResolvedMaterial<double> r = lobeAtAlpha(*key.ndf, *key.masking, alpha, key.shape);
    if (key.interfaceEta == 0) return r;
    r.fresnel = &fresnelEntry(*findModel(ModelSlot::Fresnel, "dielectric"));
    r.fresnelArgs = {};
    r.fresnelArgs.set(r.fresnel->refractiveIndexParam, key.interfaceEta);
    r.scatter = Scatter::Both;
    r.transport = Transport::Importance;
    return r;
}

// E(mu) = Int f(wi, wo) (n.wi) dwi with F = 1, integrated over the half
// vector h (dwi = 4 (wo.h) dwh), so the lobe is always centred on h = n:
//   E = Int D(h) G(wi, wo, h) (wo.h) / (n.wo) dwh   over {h : wi.z > 0}.
// theta_h runs on Gauss-Legendre panels graded toward 0 (the peak, width
// ~alpha) and toward the two square-root kinks of the azimuthal integral:
// the full circle of h qualifies up to theta_h = (pi/2 - theta_o)/2 and none
// beyond (pi/2 + theta_o)/2. At each theta_h the azimuth covers exactly
// {phi : cos(phi) > -cos(theta_o) cos(2 theta_h) / (sin(theta_o) sin(2 theta_h))}
// (the lobe is isotropic, so the half range [0, phi_max] is integrated twice),
// on panels halving toward the cut. Maskings with a min/max (cook_torrance,
// neumann, the direction-correlated Smith forms) have kinks where wo.h takes
// known values; they are azimuth break points, and the theta_h where such a
// kink enters or leaves the azimuth range are graded theta_h break points.
// The direction-correlated forms also vary quickly where wi passes the
// normal (theta_h = theta_o / 2, phi = 0): graded there too.
double albedoOf(const ResolvedMaterial<double>& m, double alpha, double mu, const EnergyQuadrature& q) {
    mu = std::clamp(mu, q.muZero, 1.0);
    double so = std::sqrt(std::max(0.0, (1 - mu) * (1 + mu)));
    double thetaO = std::atan2(so, mu);
    const double wox = so, woz = mu;
    double thetaFull = (kPi / 2 - thetaO) / 2, thetaEnd = (kPi / 2 + thetaO) / 2;
    const AlbedoKinks& kinks = m.masking->albedoKinks;
    const bool azimuthal = kinks.azimuthal;
    const bool kinkMasking = kinks.atWoH;
    // Kelemen's G (n.wi)(n.wo)/(wo.h)^2 makes the integrand D (n.wi)/(wo.h), which rises from 0
    // at the cut within a layer of width ~mu in wo.h: more azimuth panels toward the cut.
    const int kelemenExtra = kinks.cutLayer && mu < 0.25 ? std::min(24, int(std::ceil(std::log2(0.25 / mu)))) : 0;

    // cos(phi) of the cut at theta_h (phi_max = acos), clamped to [-1, 1].
    auto cutCos = [&](double th) {
        double num = -mu * std::cos(2 * th), den = so * std::sin(2 * th);
        if (den <= 0) return num < 0 ? -1.0 : 1.0;
        return std::clamp(num / den, -1.0, 1.0);
    };
    // The values of wo.h at the masking's kinks, at theta_h (NaN: none).
    auto kinkValues = [&](double ct, double out[3]) {
        out[0] = mu / ct;  // n.wi = n.wo: the max / min of the two directions switch
        out[1] = kinks.vCavity ? 2 * ct * mu : NAN;  // 2 (n.h)(n.wo)/(wo.h) = 1
        double d = 2 * ct - 1 / (2 * ct);
        out[2] = kinks.vCavity && d > 0 ? mu / d : NAN;  // 2 (n.h)(n.wi)/(wo.h) = 1
    };

    // The peak's angular width: alpha is the slope scale for ggx, beckmann
    // and gtr, an angle for gaussian; blinn_phong uses its Beckmann alpha.
    double scale = std::atan(alpha);
    // (The second special keeps panels narrow over the shoulder of
    // Gaussian-like peaks: beckmann, blinn_phong, gaussian.)
    std::vector<GradePoint> specials = {
        {0, scale / 8}, {2 * scale, scale / 4}, {thetaFull, q.kinkPanel}, {thetaEnd, q.kinkPanel}};
    if (azimuthal) specials.push_back({thetaO / 2, q.kinkPanel});
    if (kinkMasking) {
        // theta_h where a kink's cos(phi) = (oh* - mu ct)/(so st) crosses 1 or the cut.
        const int n = 256;
        double prev[6];
        for (int i = 0; i <= n; ++i) {
            double th = thetaEnd * (i + 0.5) / (n + 1);
            double st = std::sin(th), ct = std::cos(th), v[3], g[6];
            kinkValues(ct, v);
            for (int k = 0; k < 3; ++k) {
                double c = (v[k] - mu * ct) / (so * st);
                g[2 * k] = c - 1;
                g[2 * k + 1] = c - cutCos(th);
            }
            if (so == 0) {
                // Normal incidence: wo.h = ct on the whole ring, so a kink is a theta_h.
                for (int k = 0; k < 3; ++k) g[2 * k] = v[k] - ct, g[2 * k + 1] = NAN;
            }
            if (i > 0)
                for (int k = 0; k < 6; ++k) {
                    if (!(prev[k] * g[k] < 0)) continue;
                    // bisect g_k between the two samples
                    double a = thetaEnd * (i - 0.5) / (n + 1), b = th, ga = prev[k];
                    for (int it = 0; it < 60; ++it) {
                        double mid = (a + b) / 2;
                        double sm = std::sin(mid), cm = std::cos(mid), vm[3];
                        kinkValues(cm, vm);
                        double c = (vm[k / 2] - mu * cm) / (so * sm);
                        double gm = so == 0 ? vm[k / 2] - cm : (k % 2 ? c - cutCos(mid) : c - 1);
                        if ((gm < 0) == (ga < 0)) {
                            a = mid;
                            ga = gm;
                        } else {
                            b = mid;
                        }
                    }
                    specials.push_back({(a + b) / 2, q.kinkPanel});
                }
            std::copy(g, g + 6, prev);
        }
    }
    std::vector<double> br = gradedBreaks(0, thetaEnd, specials, q.thetaMaxPanel);
    const auto& gt = gaussLegendre<double>(q.thetaPoints);
    const auto& gp = gaussLegendre<double>(q.phiPoints);
    auto inner = [&](double th) {
        double st = std::sin(th), ct = std::cos(th);
        double phiMax = std::acos(cutCos(th));
        if (phiMax <= 0) return 0.0;
        // f (n.wi) dwi = D G / (4 (n.wi)(n.wo)) (n.wi) 4 (wo.h) dwh = D G (wo.h) / (n.wo) dwh,
        // with the reference D and G (F = 1); D(h) is constant along the ring.
        const Vec3<double> wo{wox, 0, woz};
        const double d = m.D({st, 0, ct});
        if (d == 0) return 0.0;
        auto g = [&](double phi) {
            Vec3<double> h{st * std::cos(phi), st * std::sin(phi), ct};
            double oh = wox * h.x + woz * h.z;
            Vec3<double> wi{2 * oh * h.x - wox, 2 * oh * h.y, 2 * oh * h.z - woz};  // unit
            if (wi.z <= 0 || oh <= 0) return 0.0;  // round-off at the cut
            return m.G(wi, wo, h) * oh;
        };
        // Panels halving toward the cut phi_max, where the masking of wi
        // falls to 0 within a boundary layer of width ~alpha.
        std::vector<double> pb = {0};
        double rest = phiMax;
        for (int k = 1; k < q.phiPanels + kelemenExtra; ++k) {
            rest /= 2;
            pb.push_back(phiMax - rest);
        }
        pb.push_back(phiMax);
        if (kinkMasking && so * st > 0) {
            double v[3];
            kinkValues(ct, v);
            for (double oh : v) {
                double c = (oh - mu * ct) / (so * st);
                if (c > -1 && c < 1) {
                    double phi = std::acos(c);
                    if (phi > 0 && phi < phiMax) pb.push_back(phi);
                }
            }
            if (azimuthal)  // toward phi = 0: wi passes near the normal, lambda(phi) is steep
                for (double f = phiMax / 4; f > phiMax * 1e-2; f /= 4) pb.push_back(f);
            std::sort(pb.begin(), pb.end());
        }
        return 2 * d / mu * integratePanels(g, pb, gp) * st;
    };
    return integratePanels(inner, br, gt);
}

std::string shortNumber(double x) { return fmt::format("{}", x); }

}  // namespace

// Does the expression depend on an input (directly or through lets)? Returns
// the first input found.
const CheckedInput* inputUsed(const Expr& e, const CheckedMaterial& m, int depth) {
    struct Finder : ExprVisitor {
        const CheckedMaterial& m;
        int depth;
        const CheckedInput* found = nullptr;
        Finder(const CheckedMaterial& mat, int d) : m(mat), depth(d) {}
        void visitName(const NameExpr& n) override {
            if (found) return;
            if (n.binding == BindingKind::Input && n.index >= 0 && n.index < int(m.inputs.size()))
                found = &m.inputs[n.index];
            else if (n.binding == BindingKind::Let && n.index >= 0 && n.index < int(m.lets.size()) && depth < 1000)
                found = inputUsed(*m.lets[n.index].value, m, depth + 1);
        }
    } f(m, depth);
    f.visit(e);
    return f.found;
}

// Value of an input-free expression (channel 0).
double constantOf(const Expr& e, const CheckedMaterial& m) {
    std::function<Value<double>(const NameExpr&)> lookup = [&](const NameExpr& n) -> Value<double> {
        internal_assert(n.binding == BindingKind::Let) << "input in a constant expression: " << n.name;
        return evaluateExpr<double>(*m.lets.at(n.index).value, lookup);
    };
    return evaluateExpr<double>(e, lookup).c[0];
}

// ---- key ------------------------------------------------------------------

std::string EnergyTableKey::name() const {
    std::string s;
    size_t i = 0;
    for (const ModelInfo* model : {static_cast<const ModelInfo*>(ndf), static_cast<const ModelInfo*>(masking)}) {
        s += s.empty() ? "" : "_";
        s += model->name;
        for (int p : model->tableShapeParams) s += fmt::format("_{}{}", model->canonical[p].tableTag, shortNumber(shape.at(i++)));
    }
    if (interfaceEta != 0) s += fmt::format("_interface{}", shortNumber(interfaceEta));
    return s;
}

bool EnergyTableKey::operator<(const EnergyTableKey& o) const {
    if (ndf->id != o.ndf->id) return ndf->id < o.ndf->id;
    if (masking->id != o.masking->id) return masking->id < o.masking->id;
    if (shape != o.shape) return shape < o.shape;
    return interfaceEta < o.interfaceEta;
}

std::optional<EnergyUnsupported> kullaContyUnsupported(const CheckedMaterial& m, const CheckedLobe& lobe) {
    if (!lobe.ndf.model || !lobe.masking.model) return std::nullopt;
    const NdfEntry& ndf = ndfEntry(*lobe.ndf.model);
    if (ndf.wholeLobe)
        return EnergyUnsupported{lobe.energy.loc,
                                 fmt::format("energy 'kulla_conty' needs a microfacet NDF with a masking term; ndf '{}' "
                                             "is a whole BRDF lobe with its own normalization and no roughness-only "
                                             "albedo table; use 'energy = none', or a microfacet NDF such as ggx or "
                                             "beckmann",
                                             ndf.name)};
    // A rough interface's table is built for one eta (its R + T depends on
    // it); a thin sheet's is the reflection table (DielectricEnergy.h).
    std::vector<std::pair<const ModelUse*, int>> constants;
    if (lobe.wholeSphere() && !lobe.thin && lobe.fresnel.model)
        constants.push_back({&lobe.fresnel, fresnelEntry(*lobe.fresnel.model).refractiveIndexParam});
    for (const ModelUse* use : {&lobe.ndf, &lobe.masking})
        for (int p : use->model->tableShapeParams) constants.push_back({use, p});
    for (auto [use, p] : constants) {
        if (p < 0 || !use->has(p)) continue;
        const Expr& e = *use->args[p];
        const char* what = use->model->canonical[p].name;
        std::string model = fmt::format("{} '{}'", modelSlotName(use->model->slot), use->model->name);
        if (const CheckedInput* in = inputUsed(e, m))
            return EnergyUnsupported{e.loc, fmt::format("energy 'kulla_conty' with {} needs a constant {} (its "
                                                        "albedo table is built for one {}); this one depends on "
                                                        "input '{}'",
                                                        model, what, what, in->name)};
        double v = constantOf(e, m);
        if (!std::isfinite(v))
            return EnergyUnsupported{e.loc, fmt::format("energy 'kulla_conty' with {} needs a finite {}, got {}",
                                                        model, what, v)};
    }
    return std::nullopt;
}

EnergyTableKey energyTableKey(const CheckedMaterial& m) { return energyTableKey(m, m.singleLobe()); }

EnergyTableKey energyTableKey(const CheckedMaterial& m, const CheckedLobe& lobe) {
    EnergyTableKey key;
    key.ndf = &ndfEntry(*lobe.ndf.model);
    key.masking = &maskingEntry(*lobe.masking.model);
    internal_assert(!key.ndf->wholeLobe) << "kulla_conty table requested for ndf " << key.ndf->name;
    for (const ModelUse* use : {&lobe.ndf, &lobe.masking})
        for (int p : use->model->tableShapeParams) {
            internal_assert(!inputUsed(*use->args[p], m)) << "kulla_conty: " << use->model->name << " "
                                                           << use->model->canonical[p].name << " is not constant";
            // Clamped to the domain as resolve() does.
            const ModelParam& param = use->model->canonical[p];
            key.shape.push_back(std::clamp(constantOf(*use->args[p], m), param.lo, param.hi));
        }
    if (lobe.wholeSphere() && !lobe.thin) {
        const FresnelEntry& fresnel = fresnelEntry(*lobe.fresnel.model);
        int p = fresnel.refractiveIndexParam;
        internal_assert(p >= 0 && lobe.fresnel.has(p) && !inputUsed(*lobe.fresnel.args[p], m))
            << "kulla_conty on refracting lobe '" << lobe.name << "' without a constant eta";
        const ModelParam& param = fresnel.canonical[p];
        key.interfaceEta = clampedFromOne(std::clamp(constantOf(*lobe.fresnel.args[p], m), param.lo, param.hi));
    }
    return key;
}

std::string EnergyQuadrature::describe() const {
    return fmt::format("half-vector Gauss-Legendre: theta_h {} points per panel, panels graded from atan(alpha)/8 "
                       "at 0 and {} at the azimuth-cut kinks, max width {}; azimuth {} panels halving toward the "
                       "cut x {} points; mu = 0 node at mu = {}; interfaces: visible normals on a {} x {} "
                       "midpoint grid",
                       thetaPoints, kinkPanel, thetaMaxPanel, phiPanels, phiPoints, muZero, facetGrid, facetGrid);
}

// ---- table ----------------------------------------------------------------

double EnergyTable::muNode(int j) const {
    double x = double(j) / (muCount - 1);
    return x * x;
}

double EnergyTable::alphaScale() const { return (alphaCount - 1) / (std::sqrt(alphaMax) - std::sqrt(alphaMin)); }
double EnergyTable::alphaOffset() const { return -std::sqrt(alphaMin) * alphaScale(); }

double EnergyTable::alphaNode(int i) const {
    if (i == 0) return alphaMin;
    if (i == alphaCount - 1) return alphaMax;
    double r = std::sqrt(alphaMin) + (std::sqrt(alphaMax) - std::sqrt(alphaMin)) * i / (alphaCount - 1);
    return r * r;
}

double EnergyTable::muCoord(double mu) const {
    if (!(mu > 0)) return 0;
    if (mu >= 1) return muCount - 1;
    return std::sqrt(mu) * (muCount - 1);
}

double EnergyTable::alphaCoord(double alpha) const {
    if (!(alpha > alphaMin)) return 0;
    if (alpha >= alphaMax) return alphaCount - 1;
    return std::clamp(std::sqrt(alpha) * alphaScale() + alphaOffset(), 0.0, double(alphaCount - 1));
}

double EnergyTable::ecAt(double mu, double alpha) const {
    double u = muCoord(mu), v = alphaCoord(alpha);
    int j = std::min(int(u), muCount - 2), i = std::min(int(v), alphaCount - 2);
    return bilinear(ec.data(), muCount, i, j, u - j, v - i);
}

double EnergyTable::ecAvgAt(double alpha) const {
    double v = alphaCoord(alpha);
    int i = std::min(int(v), alphaCount - 2);
    double t = v - i;
    return ecAvg[i] + (double(ecAvg[i + 1]) - ecAvg[i]) * t;
}

std::vector<float> EnergyTable::rowAt(double alpha) const {
    double v = alphaCoord(alpha);
    int i = std::min(int(v), alphaCount - 2);
    double t = v - i;
    std::vector<float> row(muCount);
    const float* r0 = &ec[size_t(i) * muCount];
    const float* r1 = r0 + muCount;
    for (int j = 0; j < muCount; ++j) row[j] = float(r0[j] + (double(r1[j]) - r0[j]) * t);
    return row;
}

void EnergyTable::computeAverages() {
    // Within cell j of a row, u = j + t and mu = (u/M)^2 (M = muCount - 1), so
    // 2 Int Ec mu dmu = (4/M^4) Sum_j Int_0^1 Ec(t) (j + t)^3 dt, a degree-4
    // polynomial per cell: the 3-point Gauss-Legendre rule is exact.
    const auto& g = gaussLegendre<double>(3);
    double M = muCount - 1;
    ecAvg.assign(alphaCount, 0);
    for (int i = 0; i < alphaCount; ++i) {
        const float* row = &ec[size_t(i) * muCount];
        double sum = 0;
        for (int j = 0; j + 1 < muCount; ++j)
            for (int p = 0; p < 3; ++p) {
                double t = (g.x[p] + 1) / 2, w = g.w[p] / 2;
                double e = row[j] + (double(row[j + 1]) - row[j]) * t;
                sum += w * e * std::pow(j + t, 3);
            }
        ecAvg[i] = float(4 * sum / (M * M * M * M));
    }
}

std::string EnergyTable::validate() const {
    if (muCount < 2 || alphaCount < 2) return fmt::format("bad grid {} x {}", muCount, alphaCount);
    if (ec.size() != size_t(muCount) * alphaCount) return fmt::format("ec has {} values, expected {}", ec.size(), size_t(muCount) * alphaCount);
    if (ecAvg.size() != size_t(alphaCount)) return fmt::format("ecAvg has {} values, expected {}", ecAvg.size(), alphaCount);
    if (!(alphaMin > 0 && alphaMax > alphaMin)) return "bad alpha range";
    for (float x : ec)
        if (!(x >= 0 && x <= 1)) return fmt::format("ec value {} is not in [0, 1]", x);
    for (float x : ecAvg)
        if (!(x >= 0 && x <= 1)) return fmt::format("ecAvg value {} is not in [0, 1]", x);
    return "";
}

TableGrid defaultTableGrid(const EnergyTableKey& key) {
    if (key.interfaceEta != 0) return {kInterfaceGrid, kInterfaceGrid};
    return {EnergyTable::kMuCount, EnergyTable::kAlphaCount};
}

// E of the table's lobe at (mu, alpha): the reflection albedo, or an interface's R + T.
double tableAlbedo(const EnergyTableKey& key, const ResolvedMaterial<double>& m, double alpha, double mu,
                   const EnergyQuadrature& q) {
    if (key.interfaceEta != 0) return interfaceAlbedo(m, std::clamp(mu, q.muZero, 1.0), q.facetGrid);
    return albedoOf(m, std::max(alpha, kMinAlpha), mu, q);
}

double directionalAlbedo(const EnergyTableKey& key, double mu, double alpha, const EnergyQuadrature& q) {
    return tableAlbedo(key, tableLobe(key, alpha), alpha, mu, q);
}

std::shared_ptr<EnergyTable> buildEnergyTable(const EnergyTableKey& key, const EnergyQuadrature& q, int threads,
                                              int muCount, int alphaCount, double alphaMax) {
    auto start = std::chrono::steady_clock::now();
    auto t = std::make_shared<EnergyTable>();
    t->key = key;
    t->muCount = muCount > 0 ? muCount : defaultTableGrid(key).mu;
    t->alphaCount = alphaCount > 0 ? alphaCount : defaultTableGrid(key).alpha;
    t->alphaMax = alphaMax;
    t->quadrature = q;
    t->ec.assign(size_t(t->muCount) * t->alphaCount, 0);
    int nt = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
    nt = std::min(nt, t->alphaCount);
    auto work = [&](int first) {
        for (int i = first; i < t->alphaCount; i += nt) {
            double alpha = t->alphaNode(i);
            ResolvedMaterial<double> m = tableLobe(key, alpha);
            for (int j = 0; j < t->muCount; ++j) {
                double e = tableAlbedo(key, m, alpha, t->muNode(j), q);
                // Clamp: where the lobe creates energy (E > 1) nothing is added.
                double c = std::clamp(1 - e, 0.0, 1.0);
                if (!std::isfinite(e)) c = 0;
                t->ec[size_t(i) * t->muCount + j] = float(c);
            }
        }
    };
    if (nt == 1) {
        work(0);
    } else {
        std::vector<std::thread> pool;
        for (int k = 0; k < nt; ++k) pool.emplace_back(work, k);
        for (auto& th : pool) th.join();
    }
    t->computeAverages();
    t->buildMillis = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    t->origin = "built";
    return t;
}

// ---- the interpreter's table slot -------------------------------------------

EnergyTableSlot::EnergyTableSlot(EnergyTableKey key, std::shared_ptr<const EnergyTable> table)
    : key_(key), table_(std::move(table)) {
    if (table_) {
        internal_assert(table_->key == key_) << "energy table " << table_->key.name()
                                             << " given for a material that needs " << key_.name();
    }
}

const std::shared_ptr<const EnergyTable>& EnergyTableSlot::get() {
    std::call_once(once_, [&] {
        if (!table_) table_ = key_.interfaceEta != 0 ? residentInterfaceTable(key_) : buildEnergyTable(key_);
    });
    return table_;
}

std::shared_ptr<const EnergyTable> residentInterfaceTable(const EnergyTableKey& key) {
    internal_assert(key.interfaceEta != 0) << "residentInterfaceTable of reflection table " << key.name();
    // Immutable tables, never evicted: a process meets a handful of
    // refracting materials. One lock for the build too (a second caller of
    // the same key waits instead of building it again).
    static std::mutex mutex;
    static std::map<EnergyTableKey, std::shared_ptr<const EnergyTable>> tables;
    std::lock_guard<std::mutex> lock(mutex);
    std::shared_ptr<const EnergyTable>& table = tables[key];
    if (!table) table = buildEnergyTable(key);
    return table;
}

}  // namespace facet
