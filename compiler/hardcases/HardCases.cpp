// HardCases: the hard-case sample and the double-vs-__float128 reference
// comparison (see HardCases.h).
//
// QuadMath.h first: this file instantiates nothing of the interpreter, but
// it computes with __float128 and must see the std:: overloads.
#include "QuadMath.h"

#include "HardCases.h"

#include "Checker.h"
#include "Interpreter.h"
#include "KullaConty.h"
#include "LambdaTable.h"
#include "WholeSphereCases.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <numbers>
#include <set>

namespace facet {

namespace {

constexpr double kPi = std::numbers::pi;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
// A float denormal that is exact in float and double (2^-140 = 7.2e-43).
const double kFloatDenormal = std::ldexp(1.0, -140);
// A double denormal (2^-1060 = 8.1e-320); it is 0 once rounded to float.
const double kDoubleDenormal = std::ldexp(1.0, -1060);

using Vec = std::array<double, 3>;

Vec unitDir(double z, double phi) {
    double r = std::sqrt(std::max(0.0, (1 - z) * (1 + z)));
    return {r * std::cos(phi), r * std::sin(phi), z};
}
Vec scaled(const Vec& v, double s) { return {v[0] * s, v[1] * s, v[2] * s}; }
Vec normalized(const Vec& v) {
    double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return scaled(v, 1 / l);
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

std::string num(double x) {
    if (std::isnan(x)) return "NaN";
    if (std::isinf(x)) return x > 0 ? "Inf" : "-Inf";
    if (x == kFloatDenormal) return "fdenorm";
    if (x == -kFloatDenormal) return "-fdenorm";
    if (x == kDoubleDenormal) return "ddenorm";
    if (x == 0 && std::signbit(x)) return "-0";
    return fmt::format("{:.6g}", x);
}

struct Pair {
    Vec wi, wo;
    std::string label;
};

class Generator {
public:
    Generator(const CheckedMaterial& m, const HardCaseOptions& o) : m_(m), opt_(o), defaults_(m.defaultSlots()) {}

    std::vector<HardCase> run() {
        directionCases();
        for (const DirectionPair& p : wholeSphereDirectionPairs(m_)) push(p.wi, p.wo, defaults_, p.label);
        if (opt_.inputSweeps) inputCases();
        return std::move(out_);
    }

private:
    // Through a volatile float: GCC 12.2 at -O2 drops the double -> float ->
    // double round trip when the SLP vectorizer pairs two of them (the
    // first two components of a direction came back unrounded).
    double r(double x) const {
        if (!opt_.roundToFloat) return x;
        volatile float f = float(x);
        return double(f);
    }
    Vec r(const Vec& v) const { return {r(v[0]), r(v[1]), r(v[2])}; }

    void push(const Vec& wi, const Vec& wo, const std::vector<double>& slots, std::string label) {
        HardCase c;
        c.wi = r(wi);
        c.wo = r(wo);
        c.slots.resize(slots.size());
        for (size_t s = 0; s < slots.size(); ++s) c.slots[s] = r(slots[s]);
        c.label = std::move(label);
        bool invalid = false;
        for (const Vec* w : {&c.wi, &c.wo}) {
            const Vec& v = *w;
            if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
                invalid = true;
                continue;
            }
            double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (!(std::fabs(len - 1) <= kUnitTolerance)) invalid = true;
        }
        for (double x : c.slots)
            if (!std::isfinite(x)) invalid = true;
        c.invalidInput = invalid;
        out_.push_back(std::move(c));
    }
    void push(const Pair& p, const std::vector<double>& slots, const std::string& prefix) {
        push(p.wi, p.wo, slots, prefix.empty() ? p.label : prefix + " / " + p.label);
    }

    // ---- directions ----

    // The grazing elevations: n.w in {0, denormal, 1e-7, 1e-4, 1e-2} and two
    // ordinary ones.
    static std::vector<double> grazingZ(bool withDoubleDenormal) {
        std::vector<double> z = {0.0, kFloatDenormal};
        if (withDoubleDenormal) z.push_back(kDoubleDenormal);
        for (double v : {1e-7, 1e-4, 1e-2, 0.5, 1.0}) z.push_back(v);
        return z;
    }

    // Grazing pairs at azimuth difference dphi in {0, pi} (the small set
    // crossed with the parameter ladder).
    std::vector<Pair> grazingPairsSmall() const {
        std::vector<Pair> out;
        for (double zi : {kFloatDenormal, 1e-7, 1e-4, 1e-2, 1.0})
            for (double zo : {kFloatDenormal, 1e-7, 1e-4, 1e-2, 1.0})
                for (double dphi : {0.0, kPi}) {
                    if ((zi == 1 || zo == 1) && dphi != 0) continue;
                    out.push_back({unitDir(zi, 0), unitDir(zo, dphi),
                                   fmt::format("grazing n.wi={} n.wo={} dphi={}", num(zi), num(zo),
                                               dphi == 0 ? "0" : "pi")});
                }
        out.push_back({unitDir(0.5, 0.3), scaled(unitDir(0.5, 0.3), 1), "wi=wo theta=60"});
        {
            Vec wi = unitDir(0.5, 0.3);
            out.push_back({wi, {-wi[0], -wi[1], wi[2]}, "mirror n.h=1 theta=60"});
        }
        out.push_back({unitDir(1e-5, 0), {-std::sqrt(1 - 1e-10 - 1e-10), 1e-5, 1e-5}, "near-opposite e=1e-5 d=1e-5"});
        return out;
    }

    // The four directions of the per-input value sweeps.
    std::vector<Pair> sweepPairs() const {
        Vec mirror = unitDir(0.5, 0.3);
        return {{{0, 0, 1}, {0, 0, 1}, "wi=wo=n"},
                {unitDir(std::sqrt(0.5), 0), unitDir(0.5, 2.0), "general"},
                {unitDir(1e-4, 0), unitDir(0.5, kPi), "grazing n.wi=1e-4"},
                {mirror, {-mirror[0], -mirror[1], mirror[2]}, "mirror n.h=1"}};
    }

    void directionCases() {
        const std::vector<double>& d = defaults_;
        // Grazing grid, wi at azimuth 0.
        std::vector<double> Z = grazingZ(true);
        const double dphis[] = {0.0, kPi / 2, kPi, kPi - 1e-3, 1.0};
        const char* dphiNames[] = {"0", "pi/2", "pi", "pi-1e-3", "1"};
        for (double zi : Z)
            for (double zo : Z)
                for (int k = 0; k < 5; ++k) {
                    if ((zi == 1 || zo == 1) && k != 0) continue;
                    push(unitDir(zi, 0), unitDir(zo, dphis[k]), d,
                         fmt::format("grazing n.wi={} n.wo={} dphi={}", num(zi), num(zo), dphiNames[k]));
                }
        // Rotated frames (anisotropic NDFs see the azimuth).
        for (double phi0 : {kPi / 2, 0.7, 2.3})
            for (double zi : {1e-7, 1e-2, 0.5})
                for (double zo : {1e-7, 1e-2, 0.5})
                    for (double dphi : {kPi, 1.0})
                        push(unitDir(zi, phi0), unitDir(zo, phi0 + dphi), d,
                             fmt::format("rotated phi={} n.wi={} n.wo={} dphi={}", num(phi0), num(zi), num(zo),
                                         num(dphi)));
        // wi = wo = n, and retro-reflection wi = wo.
        push({0, 0, 1}, {0, 0, 1}, d, "wi=wo=n");
        for (double z : {kFloatDenormal, 1e-7, 1e-4, 0.5})
            for (double phi : {0.0, 0.7})
                push(unitDir(z, phi), unitDir(z, phi), d, fmt::format("wi=wo n.w={} phi={}", num(z), num(phi)));
        // n.h = 1 exactly: mirror pairs (negating x and y is exact in float).
        for (double z : {kFloatDenormal, 1e-7, 1e-4, 1e-2, 0.3, 0.8, 1 - 1e-7})
            for (double phi : {0.0, kPi / 2, 0.7, 2.5, -1.0}) {
                Vec wi = r(unitDir(z, phi));
                push(wi, {-wi[0], -wi[1], wi[2]}, d, fmt::format("mirror n.h=1 n.w={} phi={}", num(z), num(phi)));
            }
        // n.h within 1e-7 of 1 (tilt sqrt(2e-7)) and h tilted by 1e-7 .. 1e-3.
        for (double delta : {1e-7, std::sqrt(2e-7), 1e-5, 1e-3})
            for (double psi : {0.0, 1.1})
                for (double z : {1e-4, 0.3, 0.9}) {
                    Vec h = {std::sin(delta) * std::cos(psi), std::sin(delta) * std::sin(psi), std::cos(delta)};
                    Vec wi = unitDir(z, 2.0);
                    double c = dot(wi, h);
                    Vec wo = normalized({2 * c * h[0] - wi[0], 2 * c * h[1] - wi[1], 2 * c * h[2] - wi[2]});
                    push(wi, wo, d,
                         fmt::format("near mirror theta_h={} (n.h=1-{}) psi={} n.wi={}", num(delta),
                                     num(1 - std::cos(delta)), num(psi), num(z)));
                }
        // wi + wo nearly zero (both above the horizon).
        for (double e : {1e-7, 1e-5, 1e-3})
            for (double dd : {0.0, 1e-7, 1e-5})
                for (double phi0 : {0.0, 0.7}) {
                    double c0 = std::cos(phi0), s0 = std::sin(phi0);
                    double a = std::sqrt(1 - e * e), b = std::sqrt(1 - e * e - dd * dd);
                    Vec wi = {a * c0, a * s0, e};
                    // wo = -wi horizontally, offset by dd perpendicular to it.
                    Vec wo = {-b * c0 - dd * s0, -b * s0 + dd * c0, e};
                    push(wi, wo, d, fmt::format("near-opposite n.w={} offset={} phi={}", num(e), num(dd), num(phi0)));
                }
        push({1, 0, 0}, {-1, 0, 0}, d, "opposite on the horizon wi+wo=0");
        push({0.6, 0, 0.8}, {-0.6, 0, -0.8}, d, "wi+wo=0 exactly (wo below)");
        push({0, 0, 1}, {0, 0, -1}, d, "wi=n wo=-n");
        // One or both directions below the horizon.
        for (double z : {-0.5, -1e-7, -kFloatDenormal, -0.0}) {
            for (const Vec& other : {Vec{0, 0, 1}, unitDir(0.5, 2.0)}) {
                push(unitDir(z, 0.4), other, d, fmt::format("below horizon n.wi={} n.wo={}", num(z), num(other[2])));
                push(other, unitDir(z, 0.4), d, fmt::format("below horizon n.wo={} n.wi={}", num(z), num(other[2])));
            }
        }
        push(unitDir(-0.5, 0), unitDir(-0.3, 2), d, "both below the horizon");
        push(unitDir(-0.5, 0), unitDir(-0.5, kPi), d, "both below, mirror");
        // Lengths: within 1e-3 of 1 is valid (renormalized); beyond is invalid.
        Vec a = unitDir(0.6, 0.3), b = unitDir(0.7, 2.5);
        for (double s : {1 + 9e-4, 1 - 9e-4, 1 + 2e-3, 1 - 2e-3, 1e30, 1e-30}) {
            push(scaled(a, s), b, d, fmt::format("|wi|={}", num(s)));
            push(a, scaled(b, s), d, fmt::format("|wo|={}", num(s)));
        }
        push({0, 0, 0}, b, d, "wi=0");
        push(a, {0, 0, 0}, d, "wo=0");
        for (int comp = 0; comp < 3; ++comp)
            for (double bad : {kNaN, kInf, -kInf}) {
                Vec wi = a, wo = b;
                wi[comp] = bad;
                push(wi, b, d, fmt::format("wi[{}]={}", comp, num(bad)));
                wo[comp] = bad;
                push(a, wo, d, fmt::format("wo[{}]={}", comp, num(bad)));
            }
        push({kFloatDenormal, 0, 1}, {0, -kFloatDenormal, 1}, d, "denormal direction components");
        push({1e-30, 1e-30, 1}, {-1e-30, 1e-30, 1}, d, "tiny direction components");
        push({kFloatDenormal, 1, kFloatDenormal}, {-kFloatDenormal, 1, 1e-7}, d, "denormal grazing along y");
    }

    // ---- inputs ----

    struct SlotInfo {
        const CheckedInput* input;
        int channel;
    };

    // The value sweep of one slot: range ends and beyond, 0, denormal, tiny,
    // the roughness ladder, 1 +- 1e-6, exponents, huge, negative, NaN, Inf.
    static std::vector<double> sweepValues(const CheckedInput& in) {
        std::vector<double> v = {0.0,   -0.0,  kFloatDenormal, 1e-38, 1e-30, 1e-10, 1e-7, 1e-5, 1e-4, 1e-3,
                                 1e-2,  0.1,   0.5,            1 - 1e-6, 1.0, 1 + 1e-6, 1.5, 2.0, 10.0, 100.0,
                                 1e3,   1e4,   1e6,            2e8,   1e9,   1e20, 1e30, double(FLT_MAX),
                                 -1e-7, -0.5,  -1.0,           -1e30, -double(FLT_MAX), kNaN, kInf, -kInf};
        if (in.hasRange) {
            double w = in.hi - in.lo;
            for (double x : {in.lo, in.hi, in.lo - 1, in.hi + 1, in.lo - 10 * w, in.hi + 10 * w,
                             std::nextafter(in.lo, -kInf), std::nextafter(in.hi, kInf)})
                v.push_back(x);
        }
        return v;
    }
    // The parameter ladder crossed with the grazing directions.
    static std::vector<double> ladderValues(const CheckedInput& in) {
        std::vector<double> v = {1e-5, 1e-4, 1e-3, 1e-2, 0.5, 1.0, 2.0, 1e6};
        if (in.hasRange) {
            v.push_back(in.lo);
            v.push_back(in.hi);
        }
        return v;
    }

    void inputCases() {
        const CheckedMaterial& m = m_;
        std::vector<Pair> sweep = sweepPairs(), graze = grazingPairsSmall();
        for (const CheckedInput& in : m.inputs) {
            bool rgb = in.type == ValueType::Rgb;
            // All channels together.
            for (double v : sweepValues(in)) {
                std::vector<double> s = defaults_;
                for (int ch = 0; ch < in.slotCount(); ++ch) s[in.firstSlot + ch] = v;
                for (const Pair& p : sweep) push(p, s, fmt::format("input {}={}", in.name, num(v)));
            }
            // One channel at a time.
            if (rgb) {
                static const char* chName[3] = {"r", "g", "b"};
                for (int ch = 0; ch < 3; ++ch)
                    for (double v : {0.0, 1.0, 1e30, -1.0, kNaN, kInf}) {
                        std::vector<double> s = defaults_;
                        s[in.firstSlot + ch] = v;
                        for (const Pair& p : sweep) push(p, s, fmt::format("input {}.{}={}", in.name, chName[ch], num(v)));
                    }
            }
            // The ladder against grazing directions.
            std::vector<double> ladder = rgb ? std::vector<double>{0.0, 1e-4, 0.5, 1 - 1e-6, 1.0, 1 + 1e-6, 2.0, 1e3}
                                             : ladderValues(in);
            for (double v : ladder) {
                std::vector<double> s = defaults_;
                for (int ch = 0; ch < in.slotCount(); ++ch) s[in.firstSlot + ch] = v;
                for (const Pair& p : graze) push(p, s, fmt::format("input {}={}", in.name, num(v)));
            }
        }
        // Pairs of float inputs at opposite ends (alpha_x / alpha_y = 1e4).
        std::vector<const CheckedInput*> floats;
        for (const CheckedInput& in : m.inputs)
            if (in.type == ValueType::Float) floats.push_back(&in);
        for (const CheckedInput* a : floats)
            for (const CheckedInput* b : floats) {
                if (a == b) continue;
                std::vector<std::pair<double, double>> vals = {{1e-4, 1.0}, {1e-5, 2.0}, {1e-3, 10.0}};
                if (a->hasRange && b->hasRange) vals.push_back({a->lo, b->hi});
                for (auto [va, vb] : vals) {
                    std::vector<double> s = defaults_;
                    s[a->firstSlot] = va;
                    s[b->firstSlot] = vb;
                    std::string prefix = fmt::format("inputs {}={} {}={}", a->name, num(va), b->name, num(vb));
                    for (const Pair& p : sweep) push(p, s, prefix);
                    for (const Pair& p : graze) push(p, s, prefix);
                }
            }
        // Every slot at once.
        if (m.slotCount > 0)
            for (double v : {0.0, 1e-4, 1.0, 1e30, kNaN, kInf}) {
                std::vector<double> s(m.slotCount, v);
                for (const Pair& p : sweep) push(p, s, fmt::format("all inputs={}", num(v)));
            }
    }

    const CheckedMaterial& m_;
    HardCaseOptions opt_;
    std::vector<double> defaults_;
    std::vector<HardCase> out_;
};

}  // namespace

std::vector<HardCase> hardCases(const CheckedMaterial& material, const HardCaseOptions& options) {
    return Generator(material, options).run();
}

std::string describeSlots(const CheckedMaterial& material, const std::vector<double>& slots) {
    std::string out;
    for (int s = 0; s < material.slotCount && s < int(slots.size()); ++s)
        out += fmt::format("{}{}={:.9g}", out.empty() ? "" : " ", material.slotName(s), slots[s]);
    return out;
}

std::string describeCase(const CheckedMaterial& material, const HardCase& c) {
    std::string slots = describeSlots(material, c.slots);
    return fmt::format("wi=({:.9g},{:.9g},{:.9g}) wo=({:.9g},{:.9g},{:.9g}){}{} [{}]", c.wi[0], c.wi[1], c.wi[2],
                       c.wo[0], c.wo[1], c.wo[2], slots.empty() ? "" : " ", slots, c.label);
}

// ---- generated materials --------------------------------------------------

namespace {

// The checked material of a generated text, or null where the checker
// rejects it (an NDF without a closed-form Lambda under a Smith masking, a
// whole-lobe NDF with a masking term, ...).
std::optional<CheckedMaterial> checked(const std::string& text) {
    DiagnosticEngine diags;
    CheckedProgram p = loadProgramText(text, "hardcase.mat", diags);
    if (diags.hasErrors() || p.materials.empty()) return std::nullopt;
    return p.materials.front();
}

}  // namespace

std::vector<HardCaseMaterial> hardCaseMaterials(std::vector<std::string>* rejected) {
    std::vector<HardCaseMaterial> out;
    auto add = [&](const std::string& name, const std::string& body) {
        std::string text = "material " + name + " {\n" + body + "}\n";
        if (std::optional<CheckedMaterial> m = checked(text))
            out.push_back({name, text, m->singleLobe().ndf.model->name, m->singleLobe().masking.model->name, m->singleLobe().fresnel.model->name});
        else if (rejected)
            rejected->push_back(text);
    };
    // Whether a Smith masking can go with this NDF example: a closed-form
    // Lambda, or a tabulated one whose shape parameters the example makes
    // constants within the entry's domain.
    auto smithAccepts = [](const ModelInfo& ndf, const ModelExample& ex) {
        if (ndf.smith) return true;
        if (!ndfEntry(ndf).tabulatedLambda) return false;
        std::optional<CheckedMaterial> m = checked("material t {\n" + ex.inputs + "\nndf = " + ex.stmt + ";\n" + ex.extra + "}\n");
        SourceLoc loc;
        return m && tabulatedLambdaUnsupported(*m, m->singleLobe(), loc).empty();
    };
    // Every example of every NDF x masking x Fresnel model the checker
    // accepts, parameters as unranged inputs. A sparse example is combined
    // only with the representative masking and Fresnel models.
    std::vector<const ModelInfo*> ndfs = catalogSlot(ModelSlot::Ndf), maskings = catalogSlot(ModelSlot::Masking),
                                  fresnels = catalogSlot(ModelSlot::Fresnel);
    for (const ModelInfo* n : ndfs)
        for (const ModelExample& ne : n->examples) {
            const bool withSmith = smithAccepts(*n, ne);
            for (const ModelInfo* g : maskings)
                for (const ModelExample& ge : g->examples)
                    for (const ModelInfo* f : fresnels)
                        for (const ModelExample& fe : f->examples) {
                            if (g->smith && !withSmith) continue;
                            if (ndfEntry(*n).wholeLobe && std::string_view(g->name) != "none") continue;
                            bool sparse = ne.sparse || ge.sparse || fe.sparse;
                            if (sparse && (!g->representative && !ge.sparse)) continue;
                            if (sparse && (!f->representative && !fe.sparse)) continue;
                            std::string body = ne.inputs + "\n" + ge.inputs + "\n" + fe.inputs + "\nndf = " + ne.stmt +
                                               ";\nmasking = " + ge.stmt + ";\nfresnel = " + fe.stmt + ";\n" + ne.extra +
                                               ge.extra + fe.extra + "\n";
                            add("hc_" + ne.key + "_" + ge.key + "_" + fe.key, body);
                        }
        }
    // Each model's own extremes: constant parameters at the edges of its
    // domain (folded by the JIT) and range-clamped inputs.
    for (const ModelInfo* m : catalog())
        for (const ModelHardCase& c : m->hardCases) add(c.name, c.body + "\n");
    return out;
}

// ---- double against __float128 ------------------------------------------------

using Quad = __float128;

struct QuadReference::Impl {
    const CheckedMaterial& material;
    std::shared_ptr<const EnergyTable> table;
    Interpreter<double> d;
    Interpreter<Quad> q;
    static std::shared_ptr<const EnergyTable> tableFor(const CheckedMaterial& m,
                                                       std::shared_ptr<const EnergyTable> given) {
        // (a combination's lobes build theirs in the interpreters)
        if (m.combinesLobes() || !m.singleLobe().compensatesEnergy()) return nullptr;
        return given ? given : buildEnergyTable(energyTableKey(m));
    }
    Impl(const CheckedMaterial& m, std::shared_ptr<const EnergyTable> given)
        : material(m), table(tableFor(m, std::move(given))), d(m, table), q(m, table) {}

    // Quad evaluation at inputs x = (wi, wo, slots).
    bool evalQ(const std::vector<Quad>& x, std::array<Quad, 3>& rgb) const {
        EvalResult<Quad> r = q.eval(&x[0], &x[3], x.size() > 6 ? &x[6] : nullptr);
        rgb = r.rgb;
        return r.valid;
    }
    std::vector<Quad> inputsOf(const HardCase& c) const {
        std::vector<Quad> x(6 + c.slots.size());
        for (int i = 0; i < 3; ++i) {
            x[i] = c.wi[i];
            x[3 + i] = c.wo[i];
        }
        for (size_t s = 0; s < c.slots.size(); ++s) x[6 + s] = c.slots[s];
        return x;
    }
};

QuadReference::QuadReference(const CheckedMaterial& material, std::shared_ptr<const EnergyTable> table)
    : impl_(new Impl(material, std::move(table))) {}
QuadReference::~QuadReference() { delete impl_; }

bool QuadReference::evalQuad(const HardCase& c, std::array<double, 3>& rgb) const {
    std::array<Quad, 3> q;
    bool valid = impl_->evalQ(impl_->inputsOf(c), q);
    for (int ch = 0; ch < 3; ++ch) rgb[ch] = double(q[ch]);
    return valid;
}

bool QuadReference::subnormalDirection(const HardCase& c) {
    for (const Vec* w : {&c.wi, &c.wo})
        for (double x : *w)
            if (x != 0 && std::fabs(x) < DBL_MIN) return true;
    return false;
}

QuadComparison QuadReference::compare(const HardCase& c) const {
    QuadComparison out;
    EvalResult<double> d = impl_->d.eval(c.wi.data(), c.wo.data(), c.slots.empty() ? nullptr : c.slots.data());
    std::array<Quad, 3> q;
    bool qValid = impl_->evalQ(impl_->inputsOf(c), q);
    const Quad dblMax = DBL_MAX;
    bool beyond = false, borderline = false;
    for (Quad v : q) {
        Quad a = v < 0 ? -v : v;
        if (a > dblMax) beyond = true;
        // Near DBL_MAX an intermediate product (D / (ci co) before F < 1
        // multiplies it) may overflow where the result does not.
        if (a > dblMax / 16 && a < dblMax * 2) borderline = true;
    }
    out.doubleValid = d.valid;
    out.quadValid = qValid && !beyond;
    out.validMismatch = out.doubleValid != out.quadValid && !borderline;
    for (int ch = 0; ch < 3; ++ch) {
        out.d[ch] = d.valid ? d.rgb[ch] : 0.0;
        out.q[ch] = out.quadValid ? double(q[ch]) : 0.0;
    }
    if (out.doubleValid && out.quadValid) {
        // Results below 2^-900 (1e-271) compare absolutely: a factor of such
        // a result (D in its tail, mz^e) may be subnormal in double.
        const Quad floor = std::ldexp(Quad(1), -900);
        for (int ch = 0; ch < 3; ++ch) {
            Quad err = Quad(d.rgb[ch]) - q[ch];
            if (err < 0) err = -err;
            Quad den = q[ch] < 0 ? -q[ch] : q[ch];
            if (den < floor) den = floor;
            double rel = double(err / den);
            if (rel > out.relError) {
                out.relError = rel;
                out.channel = ch;
            }
        }
    }
    return out;
}

double QuadReference::condition(const HardCase& c) const {
    std::vector<Quad> x = impl_->inputsOf(c);
    std::array<Quad, 3> f0;
    bool v0 = impl_->evalQ(x, f0);
    const Quad u = std::ldexp(Quad(1), -53);
    std::array<Quad, 3> kappa{};
    for (size_t j = 0; j < x.size(); ++j) {
        if (!std::isfinite(x[j]) || x[j] == 0) continue;
        std::vector<Quad> xp = x;
        xp[j] = x[j] * (1 + u);
        std::array<Quad, 3> f1;
        bool v1 = impl_->evalQ(xp, f1);
        if (v1 != v0) return std::numeric_limits<double>::infinity();
        if (!v0) continue;
        for (int ch = 0; ch < 3; ++ch) {
            Quad diff = f1[ch] - f0[ch];
            if (diff < 0) diff = -diff;
            if (diff == 0) continue;
            Quad den = f0[ch] < 0 ? -f0[ch] : f0[ch];
            if (den == 0) return std::numeric_limits<double>::infinity();
            kappa[ch] += diff / (u * den);
        }
    }
    return double(std::max({kappa[0], kappa[1], kappa[2]}));
}

}  // namespace facet
