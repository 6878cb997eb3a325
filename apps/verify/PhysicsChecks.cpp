// PhysicsChecks: graded Gauss-Legendre quadrature of the reference
// interpreter's terms (see PhysicsChecks.h).
#include "PhysicsChecks.h"

#include "Interpreter.h"
#include "KullaConty.h"
#include "LayerAlbedo.h"
#include "Quadrature.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

namespace facet {

namespace {

using V = Vec3<double>;
constexpr double kPi = std::numbers::pi;

double deg(double d) { return d * kPi / 180; }
V dirOf(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}
double dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

using quadrature::GradePoint;

// Sum of 8-point Gauss-Legendre panels between the break points.
template <typename F>
double integratePanels(const F& f, const std::vector<double>& br) {
    static const quadrature::GaussLegendre<double>& gl8 = quadrature::gaussLegendre<double>(8);
    return quadrature::integratePanels(f, br, gl8);
}

// Half-width of {phi : cos(phi - center) > num/den} (den >= 0).
double halfWidth(double num, double den) {
    if (den <= 0) return num < 0 ? kPi : 0;
    double k = num / den;
    if (k <= -1) return kPi;
    if (k >= 1) return 0;
    return std::acos(k);
}

// The lobe geometry of a resolved NDF: its smallest roughness (the peak
// width) and its anisotropy.
struct Lobe {
    double scale = 1;   // smallest roughness, <= 1
    double ratio = 1;   // min/max roughness
};
Lobe lobeOf(const ResolvedMaterial<double>& r) {
    Lobe l;
    auto [ax, ay] = r.ndf->equivalentAlphas(r.ndfArgs);
    l.scale = std::min({ax, ay, 1.0});
    l.ratio = std::min(ax, ay) / std::max(ax, ay);
    return l;
}

// Hemisphere integral of f(m) dw: theta on `thetaBreaks`, at each theta the
// azimuth over [center - hw, center + hw], graded toward the center (a kink
// of some integrands) and, for anisotropic lobes, the principal axes.
struct Grid {
    std::vector<double> thetaBreaks;
    double center = 0;
    int phiPanels = 8;     // per half of the azimuth range
    double axisH0 = 0;     // > 0: grade toward phi = k pi/2 with this first width
};

template <typename F, typename HW>
double hemisphere(const F& f, const HW& hw, const Grid& g) {
    auto inner = [&](double theta) {
        double w = hw(theta);
        if (w <= 0) return 0.0;
        double st = std::sin(theta), ct = std::cos(theta);
        auto h = [&](double phi) { return f(V{st * std::cos(phi), st * std::sin(phi), ct}); };
        std::vector<GradePoint> sp = {{g.center, w / g.phiPanels / 64}};
        if (g.axisH0 > 0)
            for (int k = -8; k <= 8; ++k) sp.push_back({k * kPi / 2, g.axisH0});
        return integratePanels(h, quadrature::gradedBreaks(g.center - w, g.center + w, sp, w / g.phiPanels)) * st;
    };
    return integratePanels(inner, g.thetaBreaks);
}

Grid ndfGrid(const Lobe& l, double kinkTheta, double center) {
    Grid g;
    std::vector<GradePoint> sp = {{0, l.scale / 8}};
    if (kinkTheta > 0) sp.push_back({kinkTheta, 1e-5});
    g.thetaBreaks = quadrature::gradedBreaks(0, kPi / 2, sp, 0.1);
    g.center = center;
    g.phiPanels = l.ratio < 0.5 ? 16 : 8;
    g.axisH0 = l.ratio < 0.5 ? l.ratio / 8 : 0;
    return g;
}

std::string fmtSlots(const CheckedMaterial& m, const std::vector<double>& slots) {
    std::string out;
    for (int s = 0; s < m.slotCount; ++s) out += fmt::format("{}{}={:.6g}", out.empty() ? "" : " ", m.slotName(s), slots[s]);
    return out.empty() ? "defaults" : out;
}

// Why the F = 1 albedo of this pair is not bounded by 1 by construction
// ("" when it is: Smith with an exact Lambda, or the V-cavity).
std::string energyNote(const NdfEntry& ndf, const MaskingEntry& masking) {
    if (*ndf.energyNote) return ndf.energyNote;
    if (masking.smith) return *ndf.lambdaNote ? std::string(ndf.lambdaNote) + ", an approximation: rough exponents exceed 1" : "";
    return masking.energyNote;
}

// The identity of a resolved model use: its entry and its clamped arguments.
std::vector<double> argsKey(const ModelInfo& model, const ModelArgs<double>& args) {
    std::vector<double> key = {double(int(model.slot)), double(model.id)};
    for (const std::array<double, 3>& p : args.value) key.insert(key.end(), p.begin(), p.end());
    return key;
}

struct Worst {
    PhysicsCheck c;
    bool set = false;
    void add(const std::string& name, const std::string& where, double value, double expected, double error,
             double tol, bool enforced, const std::string& note) {
        if (set && !(error > c.error)) return;
        c = {name, where, value, expected, error, tol, enforced, note};
        set = true;
    }
};

}  // namespace

namespace {

// A combination of lobes (SPEC 10): each lobe's own checks (named "lobe
// NAME: ..."), then the whole combination's reciprocity and its albedo
// (LayerAlbedo's graded quadrature over the half vector, at its 65 cosines),
// <= 1 where the combination adds no lobes (a sum's weights are the user's).
std::vector<PhysicsCheck> combinationChecks(const CheckedMaterial& m, const PhysicsOptions& options) {
    std::vector<PhysicsCheck> out;
    for (size_t l = 0; l < m.lobes.size(); ++l) {
        if (!m.lobes[l].hasNdf()) continue;  // a diffuse lobe: nothing to integrate
        for (PhysicsCheck c : physicsChecks(lobeView(m, int(l)), options)) {
            c.name = "lobe " + m.lobes[l].name + ": " + c.name;
            out.push_back(std::move(c));
        }
    }
    Interpreter<double> interp(m);
    std::vector<double> slots = m.defaultSlots();
    ResolvedBsdf<double> r = interp.resolveAll(slots.data());
    const std::string where = fmtSlots(m, slots);
    if (!r.valid) {
        out.push_back({"inputs", where, 0, 0, 1, 0, true, "the material's parameters are not finite here"});
        return out;
    }
    bool adds = false;
    for (const BsdfNode& n : m.bsdf) adds |= n.kind == BsdfKind::Sum;
    {
        std::shared_ptr<const MuTable> albedo = albedoTable(m, r, int(m.bsdf.size()) - 1);
        Worst energy;
        for (int j = 0; j < MuTable::kNodes; ++j)
            for (int ch = 0; ch < 3; ++ch) {
                double a = albedo->v[size_t(j)][size_t(ch)];
                energy.add("combination energy <= 1", fmt::format("{} mu_o={:.4g} ch {}", where, MuTable::nodeMu(j), ch),
                           a, 1, std::max(0.0, a - 1), 1e-3, !adds,
                           adds ? "a sum of lobes adds their albedos; its weights are the user's" : "");
            }
        out.push_back(energy.c);
    }
    {
        Worst rec;
        std::mt19937_64 rng(12345);
        std::uniform_real_distribution<double> uni(0, 1);
        for (int i = 0; i < options.reciprocityPairs; ++i) {
            double zi = uni(rng), zo = uni(rng);
            if (i % 4 == 0) zi = std::pow(10.0, -7 * uni(rng));  // grazing
            V a = dirOf(std::acos(zi), 2 * kPi * uni(rng)), b = dirOf(std::acos(zo), 2 * kPi * uni(rng));
            double wa[3] = {a.x, a.y, a.z}, wb[3] = {b.x, b.y, b.z};
            EvalResult<double> f = interp.eval(wa, wb, slots.data()), g = interp.eval(wb, wa, slots.data());
            for (int ch = 0; ch < 3; ++ch) {
                double e = std::fabs(f.rgb[ch] - g.rgb[ch]) / std::max(std::fabs(f.rgb[ch]), 1e-300);
                rec.add("combination reciprocity",
                        fmt::format("{} wi=({:.9g},{:.9g},{:.9g}) wo=({:.9g},{:.9g},{:.9g})", where, a.x, a.y, a.z, b.x,
                                    b.y, b.z),
                        g.rgb[ch], f.rgb[ch], e, 1e-9, true, "");
            }
        }
        out.push_back(rec.c);
    }
    return out;
}

}  // namespace

std::vector<PhysicsCheck> physicsChecks(const CheckedMaterial& m, const PhysicsOptions& options) {
    if (m.combinesLobes()) return combinationChecks(m, options);
    if (!m.singleLobe().hasNdf()) return {};  // a diffuse lobe alone
    std::vector<PhysicsCheck> out;
    std::shared_ptr<const EnergyTable> table;
    if (m.singleLobe().compensatesEnergy()) table = buildEnergyTable(energyTableKey(m));
    Interpreter<double> interp(m, table);

    // Input settings: defaults, then each ranged float input at its ends.
    std::vector<std::vector<double>> settings = {m.defaultSlots()};
    for (const CheckedInput& in : m.inputs) {
        if (in.type != ValueType::Float || !in.hasRange) continue;
        for (double v : {in.lo, in.hi}) {
            std::vector<double> s = m.defaultSlots();
            s[in.firstSlot] = v;
            settings.push_back(s);
        }
    }
    std::set<std::vector<double>> seenNdf, seenEnergy;
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> uni(0, 1);

    for (const std::vector<double>& slots : settings) {
        ResolvedMaterial<double> r = interp.resolve(slots.data());
        std::string where0 = fmtSlots(m, slots);
        if (!r.valid) {
            out.push_back({"inputs", where0, 0, 0, 1, 0, true, "the material's parameters are not finite here"});
            continue;
        }
        Lobe lobe = lobeOf(r);
        bool aniso = lobe.ratio < 1;
        std::vector<double> phis = aniso ? std::vector<double>{0, 45, 120} : std::vector<double>{0};
        std::string where = where0 + " (" + r.ndf->describe(r.ndfArgs) + ")";
        std::vector<double> ndfKey = argsKey(*r.ndf, r.ndfArgs);

        // ---- NDF identities (not ward) ----
        if (!r.ndf->wholeLobe && seenNdf.insert(ndfKey).second) {
            Worst norm, area, furnace;
            double n = hemisphere([&](const V& mm) { return r.D(mm) * mm.z; }, [](double) { return kPi; },
                                  ndfGrid(lobe, 0, 0));
            norm.add("ndf normalization", where, n, 1, std::fabs(n - 1), 1e-3, true, "");
            bool smith = r.masking->smith;
            std::string furnaceNote =
                *r.ndf->lambdaNote ? std::string(r.ndf->lambdaNote) + ", exact only for large exponents" : "";
            for (double tv : options.thetas)
                for (double pv : phis) {
                    if (tv == 0 && pv != 0) continue;
                    V v = dirOf(deg(tv), deg(pv));
                    std::string at = fmt::format("{} theta_v={} phi_v={}", where, tv, pv);
                    if (tv > 0) {
                        double a = hemisphere([&](const V& mm) { return r.D(mm) * dot(v, mm); },
                                              [](double) { return kPi; }, ndfGrid(lobe, 0, deg(pv)));
                        area.add("projected area", at, a, v.z, std::fabs(a - v.z), 1e-3, true, "");
                    }
                    if (smith) {
                        double tvr = deg(tv);
                        double w = hemisphere(
                            [&](const V& mm) { return r.smithG1(v, mm) * r.D(mm) * std::max(0.0, dot(v, mm)); },
                            [&](double th) {
                                return halfWidth(-std::cos(tvr) * std::cos(th), std::sin(tvr) * std::sin(th));
                            },
                            ndfGrid(lobe, tv > 0 ? kPi / 2 - tvr : 0, deg(pv)));
                        furnace.add("weak white furnace", at, w, v.z, std::fabs(w - v.z), 1e-3, furnaceNote.empty(),
                                    furnaceNote);
                    }
                }
            for (Worst* w : {&norm, &area, &furnace})
                if (w->set) out.push_back(w->c);
        }

        // ---- energy <= 1 with F = 1 (and the Kulla-Conty furnace) ----
        std::vector<double> energyKey = ndfKey, maskingKey = argsKey(*r.masking, r.maskingArgs);
        energyKey.insert(energyKey.end(), maskingKey.begin(), maskingKey.end());
        if (seenEnergy.insert(energyKey).second) {
            ResolvedMaterial<double> white = r.specularLobe();
            ResolvedMaterial<double> kc = white;
            bool hasKc = r.energy->compensates;
            if (hasKc) {
                kc.energy = r.energy;
                kc.favg = {1, 1, 1};
            }
            std::string note = energyNote(*r.ndf, *r.masking);
            Worst energy, furnace;
            for (double to : options.thetas)
                for (double po : phis) {
                    if (to == 0 && po != 0) continue;
                    double tor = deg(to), por = deg(po);
                    V wo = dirOf(tor, por);
                    Grid g;
                    double thetaFull = (kPi / 2 - tor) / 2, thetaEnd = (kPi / 2 + tor) / 2;
                    g.thetaBreaks = quadrature::gradedBreaks(
                        0, thetaEnd, {{0, lobe.scale / 8}, {thetaFull, 1e-4}, {thetaEnd, 1e-4}}, 0.08);
                    g.center = por;
                    g.phiPanels = aniso ? 16 : 8;
                    g.axisH0 = lobe.ratio < 0.5 ? lobe.ratio / 8 : 0;
                    auto hw = [&](double th) {
                        return halfWidth(-std::cos(tor) * std::cos(2 * th), std::sin(tor) * std::sin(2 * th));
                    };
                    auto albedo = [&](const ResolvedMaterial<double>& mat) {
                        return hemisphere(
                            [&](const V& h) {
                                double oh = dot(wo, h);
                                V wi{2 * oh * h.x - wo.x, 2 * oh * h.y - wo.y, 2 * oh * h.z - wo.z};
                                if (wi.z <= 0) return 0.0;
                                return mat.brdf(wi, wo)[0] * wi.z * 4 * oh;
                            },
                            hw, g);
                    };
                    std::string at = fmt::format("{} theta_o={} phi_o={}", where, to, po);
                    double a = albedo(white);
                    energy.add("energy <= 1 (F = 1)", at, a, 1, std::max(0.0, a - 1), 1e-3, note.empty(), note);
                    if (hasKc) {
                        double ak = albedo(kc);
                        std::string kcNote = !note.empty() ? "single scattering not conserving: " + note
                                             : aniso       ? "anisotropic: looked up at the geometric-mean roughness"
                                                           : "";
                        furnace.add("kulla-conty white furnace", at, ak, 1, std::fabs(ak - 1), 0.01, kcNote.empty(),
                                    kcNote);
                    }
                }
            for (Worst* w : {&energy, &furnace})
                if (w->set) out.push_back(w->c);
        }

        // ---- reciprocity ----
        {
            Worst rec;
            // A random-walk lobe's eval adds one walk's estimate, reciprocal
            // in expectation only (its walk starts from wo): the deterministic
            // part is checked, the walk by `ctest -R compiled_walk`.
            const bool walks = r.energy && r.energy->walks;
            const ResolvedMaterial<double> deterministic = walks ? r.withoutEnergy() : r;
            const std::string recNote = walks ? "single scattering: random_walk's estimate is reciprocal in expectation" : "";
            auto check = [&](const V& a, const V& b, const std::string& label) {
                std::array<double, 3> f = deterministic.brdf(a, b), g = deterministic.brdf(b, a);
                for (int ch = 0; ch < 3; ++ch) {
                    double den = std::max(std::fabs(f[ch]), 1e-300);
                    double e = std::fabs(f[ch] - g[ch]) / den;
                    rec.add("reciprocity", fmt::format("{} {} wi=({:.9g},{:.9g},{:.9g}) wo=({:.9g},{:.9g},{:.9g})",
                                                       where, label, a.x, a.y, a.z, b.x, b.y, b.z),
                            g[ch], f[ch], e, 1e-9, true, recNote);
                }
            };
            for (int i = 0; i < options.reciprocityPairs; ++i) {
                double zi = uni(rng), zo = uni(rng);
                if (i % 4 == 0) zi = std::pow(10.0, -7 * uni(rng));  // grazing
                V a = dirOf(std::acos(zi), 2 * kPi * uni(rng)), b = dirOf(std::acos(zo), 2 * kPi * uni(rng));
                check(a, b, "random");
            }
            out.push_back(rec.c);
        }
    }
    return out;
}

}  // namespace facet
