// LayerAlbedo: the layer's tables by the reference's own quadrature (see
// LayerAlbedo.h and docs/design-notes/layer-albedo-scaling.md, sections 5 and 7).
#include "LayerAlbedo.h"

#include "LobeCombination.h"
#include "Quadrature.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace facet {

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr int kN = MuTable::kNodes;
const double kMapScale = std::exp(6.0) - 1;  // mu = (e^{6x} - 1) / (e^6 - 1)

double xOfMu(double mu) { return std::log1p(std::clamp(mu, MuTable::kMuMin, 1.0) * kMapScale) / 6; }
double muOfX(double x) { return std::expm1(6 * x) / kMapScale; }

using Rgb = std::array<double, 3>;

// ---- the quadrature ---------------------------------------------------------
//
// Int q(mu_i) f(wi, wo) mu_i dwi at n.wo = mu over the half vector h
// (dwi = 4 (wo.h) dwh), so every microfacet lobe is centred on h = n:
// theta_h on Gauss-Legendre panels graded toward 0 and 2 atan(alpha) for
// each lobe's roughness (its peak and shoulder) and toward the square-root
// kinks where the azimuth range starts to shrink ((pi/2 - theta_o)/2) and
// ends ((pi/2 + theta_o)/2); the azimuth over the whole ring where it is
// whole, else over [-phi_max, phi_max] on panels halving toward the cut.
// Both signs of phi are integrated: anisotropic lobes need no symmetry.
// Diffuse and Kulla-Conty terms are smooth in h and integrate on the same
// points. sink(mu_i, rgb weight) receives each point.
template <typename F, typename Sink>
void forEachPoint(const F& f, const std::vector<double>& scales, double mu, Sink&& sink) {
    mu = std::clamp(mu, MuTable::kMuMin, 1.0);
    const double so = std::sqrt(std::max(0.0, (1 - mu) * (1 + mu)));
    const double thetaO = std::atan2(so, mu);
    const double thetaFull = (kPi / 2 - thetaO) / 2, thetaEnd = (kPi / 2 + thetaO) / 2;
    std::vector<quadrature::GradePoint> specials = {{thetaFull, 1e-3}, {thetaEnd, 1e-3}, {thetaO / 2, 1e-3}};
    for (double s : scales) specials.push_back({0, s / 8}), specials.push_back({2 * s, s / 4});
    if (scales.empty()) specials.push_back({0, 0.05});
    const std::vector<double> br = quadrature::gradedBreaks(0, thetaEnd, specials, 0.1);
    const auto& gt = quadrature::gaussLegendre<double>(8);
    const auto& gp = quadrature::gaussLegendre<double>(6);
    const Vec3<double> wo{so, 0, mu};
    // Azimuth panels as fractions of [0, phi_max]: halving toward the cut.
    static const double cut[] = {0, 0.5, 0.75, 0.875, 0.9375, 1};
    static const double ring[] = {0, 0.25, 0.5, 0.75, 1};
    for (size_t p = 0; p + 1 < br.size(); ++p) {
        const double a = br[p], b = br[p + 1];
        if (!(b > a)) continue;
        for (size_t i = 0; i < gt.x.size(); ++i) {
            const double th = (a + b) / 2 + (b - a) / 2 * gt.x[i], wth = (b - a) / 2 * gt.w[i];
            const double st = std::sin(th), ct = std::cos(th);
            double phiMax = kPi;
            const bool whole = th <= thetaFull || so == 0;
            if (!whole) {
                const double num = -mu * std::cos(2 * th), den = so * std::sin(2 * th);
                phiMax = std::acos(den > 0 ? std::clamp(num / den, -1.0, 1.0) : (num < 0 ? -1.0 : 1.0));
            }
            if (phiMax <= 0) continue;
            const double* edges = whole ? ring : cut;
            const int panels = whole ? 4 : 5;
            for (int side = -1; side <= 1; side += 2)
                for (int q = 0; q < panels; ++q) {
                    const double lo = edges[q] * phiMax, hi = edges[q + 1] * phiMax;
                    for (size_t k = 0; k < gp.x.size(); ++k) {
                        const double phi = side * ((lo + hi) / 2 + (hi - lo) / 2 * gp.x[k]);
                        const double w = wth * (hi - lo) / 2 * gp.w[k];
                        const Vec3<double> h{st * std::cos(phi), st * std::sin(phi), ct};
                        const double oh = wo.x * h.x + wo.z * h.z;
                        const Vec3<double> wi{2 * oh * h.x - wo.x, 2 * oh * h.y, 2 * oh * h.z - wo.z};
                        if (!(wi.z > 0) || !(oh > 0)) continue;  // round-off at the cut
                        const Rgb v = f(wi, wo);
                        const double jac = wi.z * 4 * oh * st * w;
                        sink(wi.z, Rgb{v[0] * jac, v[1] * jac, v[2] * jac});
                    }
                }
        }
    }
}

// Angular widths (atan alpha) of the microfacet lobes under `node`.
void lobeScales(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node, std::vector<double>& out) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    if (n.kind == BsdfKind::Lobe) {
        const ResolvedMaterial<double>& l = r.lobes.at(size_t(n.lobe));
        if (l.ndf && l.ndf->equivalentAlphas) {
            std::array<double, 2> a = l.ndf->equivalentAlphas(l.ndfArgs);
            out.push_back(std::atan(std::max(std::min(a[0], a[1]), kMinAlpha)));
        } else if (l.ndf) {
            out.push_back(0.05);
        }
        return;
    }
    if (n.a >= 0) lobeScales(m, r, n.a, out);
    if (n.b >= 0) lobeScales(m, r, n.b, out);
}

// f of the sub-expression `node` in double.
Rgb subtreeBrdf(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node, const Vec3<double>& wi,
                const Vec3<double>& wo) {
    const Vec3<double> sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
    return CombinationEval<double>(m, r, &r, wi, wo, sum).node(node);
}

// ---- the cache --------------------------------------------------------------
//
// Keyed by what the table is computed from: the sub-expression's shape and
// the resolved values of its lobes and weights (bytes), so materials and
// input values that resolve alike share one bake. Bounded: cleared when
// full (tables in use are shared_ptrs and stay alive).
constexpr size_t kCacheLimit = 512;

struct CacheEntry {
    std::once_flag once;
    std::shared_ptr<const MuTable> table;
};
std::mutex cacheMutex;
std::map<std::string, std::shared_ptr<CacheEntry>>& cache() {
    static auto* c = new std::map<std::string, std::shared_ptr<CacheEntry>>();  // outlives other statics
    return *c;
}

template <typename T>
void put(std::string& key, const T& value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    key.append(bytes, sizeof(T));
}
void putArgs(std::string& key, const ModelArgs<double>& a) {
    for (const auto& v : a.value) put(key, v);
    for (bool g : a.given) key.push_back(g ? '1' : '0');
    for (double d : a.derived) put(key, d);
}
// whiten() makes every Fresnel term of a layer's base 1, except inside a
// nested layer's top, which its own bake sees as it is: the one rule both
// whiten() and the whitened key (putSubtree) follow.
bool whitensFirstChild(const BsdfNode& n) { return n.kind != BsdfKind::Layer; }

const FresnelEntry* noFresnel() {
    static const FresnelEntry* none = &fresnelEntry(*findModel(ModelSlot::Fresnel, "none"));
    return none;
}

// The key of a subtree. `white`: as whiten() would leave it (every Fresnel
// term 1 where whiten() reaches), without copying the resolved material.
void putSubtree(std::string& key, const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node,
                bool white = false) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    key.push_back(char('a' + int(n.kind)));
    put(key, r.weights.at(size_t(node)));
    if (n.kind == BsdfKind::Lobe) {
        const ResolvedMaterial<double>& l = r.lobes.at(size_t(n.lobe));
        const FresnelEntry* fresnel = white ? noFresnel() : l.fresnel;
        for (const void* p : {(const void*)l.ndf, (const void*)l.masking, (const void*)fresnel,
                              (const void*)l.energy, (const void*)l.diffuse})
            put(key, p);
        putArgs(key, l.ndfArgs), putArgs(key, l.maskingArgs);
        putArgs(key, white ? ModelArgs<double>{} : l.fresnelArgs);
        putArgs(key, l.diffuseArgs);
        if (l.energy && l.energy->compensates) {
            key += l.energyTable ? l.energyTable->key.name() : std::string("-");
            put(key, l.energyAlpha), put(key, l.ecAvg), put(key, white ? Rgb{1, 1, 1} : l.favg);
        }
        return;
    }
    if (n.a >= 0) putSubtree(key, m, r, n.a, white && whitensFirstChild(n));
    key.push_back('|');
    if (n.b >= 0) putSubtree(key, m, r, n.b, white);
    key.push_back(')');
}

template <typename Build>
std::shared_ptr<const MuTable> cached(const std::string& key, const Build& build) {
    std::shared_ptr<CacheEntry> entry;
    {
        std::lock_guard<std::mutex> lock(cacheMutex);
        auto& c = cache();
        auto it = c.find(key);
        if (it == c.end()) {
            if (c.size() >= kCacheLimit) c.clear();
            it = c.emplace(key, std::make_shared<CacheEntry>()).first;
        }
        entry = it->second;
    }
    // Built outside the lock: a nested layer's bake asks the cache again.
    std::call_once(entry->once, [&] { entry->table = build(); });
    return entry->table;
}

// ---- the bakes --------------------------------------------------------------

// The base as the layer's bake sees it: Fresnel 1 in its lobes (F_avg 1
// for Kulla-Conty); a nested layer's top keeps its Fresnel (it is that
// layer's coat).
void whiten(const CheckedMaterial& m, int node, ResolvedBsdf<double>& r) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    if (n.kind == BsdfKind::Lobe) {
        ResolvedMaterial<double>& l = r.lobes.at(size_t(n.lobe));
        l.fresnel = noFresnel();
        l.fresnelArgs = {};
        l.favg = {1, 1, 1};
        return;
    }
    if (whitensFirstChild(n) && n.a >= 0) whiten(m, n.a, r);
    if (n.b >= 0) whiten(m, n.b, r);
}

// A tree of diffuse lobes (no layer): the closed form applies.
bool lambertian(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node) {
    const BsdfNode& n = m.bsdf.at(size_t(node));
    if (n.kind == BsdfKind::Lobe) {
        const ResolvedMaterial<double>& l = r.lobes.at(size_t(n.lobe));
        return !l.ndf && !(l.energy && l.energy->compensates);
    }
    if (n.kind == BsdfKind::Layer) return false;
    return (n.a < 0 || lambertian(m, r, n.a)) && (n.b < 0 || lambertian(m, r, n.b));
}

// 2 Int_0^1 E(mu) mu dmu of the linearly interpolated table (8-point
// Gauss-Legendre per node interval, in x): exactly the integral of what is
// looked up, so that a white Lambert base keeps its energy up to the
// interpolation of E_top alone.
Rgb cosineAverage(const MuTable& t) {
    const auto& gl = quadrature::gaussLegendre<double>(8);
    Rgb out{};
    const double h = 1.0 / (kN - 1);
    for (int j = 0; j + 1 < kN; ++j)
        for (size_t i = 0; i < gl.x.size(); ++i) {
            const double s = (1 + gl.x[i]) / 2, x = (j + s) * h;
            const double mu = muOfX(x), dmu = 6 * std::exp(6 * x) / kMapScale * h / 2 * gl.w[i];
            for (int c = 0; c < 3; ++c) out[c] += 2 * ((1 - s) * t.v[j][c] + s * t.v[j + 1][c]) * mu * dmu;
        }
    return out;
}

std::shared_ptr<const MuTable> bakeG(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int layer) {
    const BsdfNode& n = m.bsdf.at(size_t(layer));
    std::shared_ptr<const MuTable> eTop = albedoTable(m, r, n.a);
    auto g = std::make_shared<MuTable>();
    std::array<Rgb, kN> u;
    for (int j = 0; j < kN; ++j)
        for (int c = 0; c < 3; ++c) u[j][c] = std::max(0.0, 1 - eTop->v[j][c]);
    if (lambertian(m, r, n.b)) {
        const Rgb eBar = cosineAverage(*eTop);
        for (int c = 0; c < 3; ++c) {
            const double den = 1 - eBar[c];
            for (int j = 0; j < kN; ++j) g->v[j][c] = den > 1e-12 ? u[j][c] / std::sqrt(den) : 0.0;
        }
        return g;
    }
    // M_jk = Int hat_k(x(mu_i)) f_base(wi, wo_j) mu_i dwi, A_j = sum_k M_jk.
    ResolvedBsdf<double> white = r;
    whiten(m, n.b, white);
    std::vector<double> scales;
    lobeScales(m, white, n.b, scales);
    std::vector<std::array<Rgb, kN>> mat(kN);
    std::array<Rgb, kN> albedo{};
    for (int j = 0; j < kN; ++j) {
        for (auto& row : mat[j]) row = Rgb{};
        forEachPoint([&](const Vec3<double>& wi, const Vec3<double>& wo) { return subtreeBrdf(m, white, n.b, wi, wo); },
                     scales, MuTable::nodeMu(j), [&](double muI, const Rgb& w) {
                         const double t = xOfMu(muI) * (kN - 1);
                         const int k = std::min(int(t), kN - 2);
                         const double s = t - k;
                         for (int c = 0; c < 3; ++c) {
                             mat[j][k][c] += (1 - s) * w[c];
                             mat[j][k + 1][c] += s * w[c];
                             albedo[j][c] += w[c];
                         }
                     });
    }
    // The symmetric Sinkhorn iteration g <- sqrt(g b / (M g)), b = u A
    // (design note 5, step 4). Where b vanishes (a mirror top at that
    // angle, or no base), g = 0: S = 0 there.
    for (int c = 0; c < 3; ++c) {
        std::array<double, kN> b, gc, mg;
        auto apply = [&](const std::array<double, kN>& x) {
            for (int j = 0; j < kN; ++j) {
                double s = 0;
                for (int k = 0; k < kN; ++k) s += mat[j][k][c] * x[k];
                mg[j] = s;
            }
        };
        std::array<double, kN> uc;
        for (int j = 0; j < kN; ++j) uc[j] = u[j][c], b[j] = u[j][c] * albedo[j][c];
        apply(uc);
        for (int j = 0; j < kN; ++j)
            gc[j] = b[j] > 1e-14 && albedo[j][c] > 0 ? uc[j] / std::sqrt(std::max(mg[j] / albedo[j][c], 1e-6)) : 0.0;
        for (int it = 0; it < 2000; ++it) {
            apply(gc);
            double change = 0;
            for (int j = 0; j < kN; ++j) {
                const double next = b[j] > 1e-14 && mg[j] > 1e-300 ? std::sqrt(gc[j] * b[j] / mg[j]) : 0.0;
                if (gc[j] > 0) change = std::max(change, std::abs(next - gc[j]) / gc[j]);
                gc[j] = next;
            }
            if (change < 1e-12) break;
        }
        for (int j = 0; j < kN; ++j) g->v[j][c] = std::isfinite(gc[j]) ? gc[j] : 0.0;
    }
    return g;
}

}  // namespace

double MuTable::nodeMu(int j) { return muOfX(double(j) / (kNodes - 1)); }

std::array<double, 3> MuTable::at(double mu) const {
    const double t = xOfMu(mu) * (kNodes - 1);
    const int j = std::min(int(t), kNodes - 2);
    const double s = t - j;
    return {(1 - s) * v[j][0] + s * v[j + 1][0], (1 - s) * v[j][1] + s * v[j + 1][1],
            (1 - s) * v[j][2] + s * v[j + 1][2]};
}

std::shared_ptr<const MuTable> albedoTable(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int node) {
    std::string key = "A";
    putSubtree(key, m, r, node);
    return cached(key, [&] {
        std::vector<double> scales;
        lobeScales(m, r, node, scales);
        auto t = std::make_shared<MuTable>();
        for (int j = 0; j < kN; ++j) {
            Rgb s{};
            forEachPoint([&](const Vec3<double>& wi, const Vec3<double>& wo) { return subtreeBrdf(m, r, node, wi, wo); },
                         scales, MuTable::nodeMu(j), [&](double, const Rgb& w) {
                             for (int c = 0; c < 3; ++c) s[c] += w[c];
                         });
            t->v[j] = s;
        }
        return std::shared_ptr<const MuTable>(t);
    });
}

std::shared_ptr<const MuTable> layerG(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int layer) {
    // g depends on the top and the base, not on the layer's weight.
    // Nor on what bakeG ignores of the base: all of a Lambertian base (the
    // closed form), a microfacet base's Fresnel terms (it is whitened), so
    // that lanes differing only there (a per-lane base color) share a bake.
    const BsdfNode& n = m.bsdf.at(size_t(layer));
    std::string key = "G";
    putSubtree(key, m, r, n.a);
    key.push_back('/');
    if (lambertian(m, r, n.b)) {
        key.push_back('L');
    } else {
        putSubtree(key, m, r, n.b, /*white=*/true);
    }
    return cached(key, [&] { return bakeG(m, r, layer); });
}

std::array<double, 3> layerScale(const CheckedMaterial& m, const ResolvedBsdf<double>& r, int layer, double muI,
                                 double muO) {
    std::shared_ptr<const MuTable> g = layerG(m, r, layer);
    const Rgb gi = g->at(muI), go = g->at(muO);
    Rgb s;
    for (int c = 0; c < 3; ++c) s[c] = gi[c] > 0 && go[c] > 0 ? gi[c] * go[c] : 0.0;
    return s;
}

}  // namespace facet
