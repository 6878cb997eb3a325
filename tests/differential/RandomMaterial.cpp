// RandomMaterial: see RandomMaterial.h.
#include "RandomMaterial.h"

#include "models/ModelCatalog.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace facet::test {

namespace {

struct Combo {
    const NdfEntry* ndf;
    bool anisotropic;  // alpha_x and alpha_y apart (NDFs that have both)
    const ModelInfo* masking;
    const char* fresnel;  // a Fresnel model and the range of its values
    const char* diffuse;
};

bool hasAlphaXY(const NdfEntry& ndf) { return paramIndex(ndf, "alpha_x") >= 0 && paramIndex(ndf, "alpha_y") >= 0; }

// Every NDF (isotropic, and anisotropic where it has alpha_x and alpha_y) x
// masking of the catalog that the checker accepts (a whole lobe takes masking
// none only; a Smith masking needs an NDF with a Smith Lambda), x the Fresnel
// value ranges below x diffuse.
std::vector<Combo> combinations() {
    const char* fresnels[] = {"none", "schlick_f0", "schlick_eta", "dielectric", "dielectric_tir", "conductor"};
    const char* diffuses[] = {"none", "lambert"};
    std::vector<Combo> out;
    for (const ModelInfo* n : catalogSlot(ModelSlot::Ndf)) {
        const NdfEntry& ndf = ndfEntry(*n);
        for (bool aniso : {false, true}) {
            if (aniso && !hasAlphaXY(ndf)) continue;
            for (const ModelInfo* m : catalogSlot(ModelSlot::Masking)) {
                if (ndf.wholeLobe && std::string(m->name) != "none") continue;
                if (m->smith && !hasSmithLambda(ndf)) continue;
                for (const char* f : fresnels)
                    for (const char* d : diffuses) out.push_back({&ndf, aniso, m, f, d});
            }
        }
    }
    return out;
}

class Gen {
public:
    explicit Gen(uint64_t seed) : rng_(seed) {}
    double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
    int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }

    std::vector<std::string> floatInputs;  // names of float inputs in [0, 1]
    std::vector<std::string> rgbInputs;

    // An expression with values in [0, 1], well conditioned.
    std::string unit(int depth = 0) {
        int choice = pick(depth > 2 ? 2 : 9);
        switch (choice) {
            case 0: return fmt::format("{:.6g}", uniform(0, 1));
            case 1:
                if (floatInputs.empty()) return fmt::format("{:.6g}", uniform(0, 1));
                return floatInputs[pick(int(floatInputs.size()))];
            case 2: return fmt::format("({} * {})", unit(depth + 1), unit(depth + 1));
            case 3: return fmt::format("sqrt({})", unit(depth + 1));
            case 4: return fmt::format("mix({}, {}, {})", unit(depth + 1), unit(depth + 1), unit(depth + 1));
            case 5: return fmt::format("min({}, {})", unit(depth + 1), unit(depth + 1));
            case 6: return fmt::format("max({}, {})", unit(depth + 1), unit(depth + 1));
            case 7: return fmt::format("exp(-{})", unit(depth + 1));
            default: return fmt::format("clamp(({} + {}) * 0.5, 0, 1)", unit(depth + 1), unit(depth + 1));
        }
    }
    // A float parameter in [lo, hi]: constant or driven by inputs.
    std::string ranged(double lo, double hi) {
        if (pick(3) == 0) return fmt::format("{:.6g}", uniform(lo, hi));
        return fmt::format("({} + {} * {})", lo, hi - lo, unit());
    }
    // An rgb parameter with channels in [lo, hi].
    std::string rgbRanged(double lo, double hi) {
        switch (pick(3)) {
            case 0: return ranged(lo, hi);  // float promoted to rgb
            case 1: return fmt::format("rgb({}, {}, {})", ranged(lo, hi), ranged(lo, hi), ranged(lo, hi));
            default:
                if (rgbInputs.empty()) return ranged(lo, hi);
                return fmt::format("({} + {} * {} * {})", lo, hi - lo, rgbInputs[pick(int(rgbInputs.size()))], unit());
        }
    }

private:
    std::mt19937_64 rng_;
};

// A shape parameter of an NDF with a tabulated Smith Lambda under a Smith
// masking: a constant (the table is built for one value), one of a few
// around the typical value so that the tables are shared between materials.
double tabulatedShapeValue(Gen& g, const NdfEntry& ndf, const ModelParam& param) {
    const double factors[] = {0.9, 1.25, 1.5};
    double v = std::clamp(param.typical * factors[g.pick(3)], param.lo, param.hi);
    if (ndf.lambdaShapeError && !ndf.lambdaShapeError({v}).empty()) v = param.typical;
    return v;
}

}  // namespace

int randomMaterialCombinationCount() { return int(combinations().size()); }

namespace {

// The inputs (and a let) of a random material, named u*, c* and l0.
std::string randomInputs(Gen& g) {
    std::string body;
    int nFloat = g.pick(3), nRgb = g.pick(2);
    for (int k = 0; k < nFloat; ++k) {
        std::string name = fmt::format("u{}", k);
        body += fmt::format("    input {} = {:.4g} in 0 .. 1;\n", name, g.uniform(0, 1));
        g.floatInputs.push_back(name);
    }
    for (int k = 0; k < nRgb; ++k) {
        std::string name = fmt::format("c{}", k);
        body += fmt::format("    input {} = rgb({:.4g}, {:.4g}, {:.4g}) in 0 .. 1;\n", name, g.uniform(0, 1),
                            g.uniform(0, 1), g.uniform(0, 1));
        g.rgbInputs.push_back(name);
    }
    if (g.pick(2)) {
        body += fmt::format("    let l0 = {};\n", g.unit());
        g.floatInputs.push_back("l0");  // lets are usable like inputs from here on
    }
    return body;
}

// The model statements of one lobe of combination c, each line indented by `indent`.
std::string lobeStatements(Gen& g, const Combo& c, const std::string& indent) {
    std::string body;
    // The NDF's parameters: roughnesses as random expressions in [0.02, 1]
    // ([0.05, 0.6] for a whole lobe), shape parameters around their typical
    // value, anything else (Blinn-Phong's exponent) from a random roughness.
    const NdfEntry& ndf = *c.ndf;
    std::vector<double> shape;
    for (int p : ndf.tableShapeParams) shape.push_back(ndf.canonical[p].typical);
    ModelArgs<double> atAlpha = ndf.argsAtAlpha(g.uniform(0.05, 1.0), shape);
    const double alphaLo = ndf.wholeLobe ? 0.05 : 0.02, alphaHi = ndf.wholeLobe ? 0.6 : 1.0;
    std::string args;
    for (size_t p = 0; p < ndf.canonical.size(); ++p) {
        const ModelParam& param = ndf.canonical[p];
        std::string name = param.name, value;
        if (name == "alpha_y" && !c.anisotropic) continue;
        bool isShape = std::find(ndf.tableShapeParams.begin(), ndf.tableShapeParams.end(), int(p)) !=
                       ndf.tableShapeParams.end();
        if (name.rfind("alpha", 0) == 0) value = g.ranged(alphaLo, alphaHi);
        else if (isShape && ndf.tabulatedLambda && c.masking->smith)
            value = fmt::format("{:.9g}", tabulatedShapeValue(g, ndf, param));
        else if (isShape) value = g.ranged(std::max(param.lo, 0.5 * param.typical), 1.5 * param.typical);
        else value = fmt::format("{:.9g}", atAlpha[int(p)]);
        if (name == "alpha_x" && !c.anisotropic) name = "alpha";
        args += (args.empty() ? "" : ", ") + name + " = " + value;
    }
    body += fmt::format("{}ndf = {}({});\n", indent, ndf.name, args);

    std::string masking = c.masking->name;
    if (masking == "schlick_smith") body += fmt::format("{}masking = schlick_smith({});\n", indent, g.ranged(0, 1));
    else body += fmt::format("{}masking = {};\n", indent, masking);

    std::string fresnel = c.fresnel;
    if (fresnel == "schlick_f0") body += fmt::format("{}fresnel = schlick({});\n", indent, g.rgbRanged(0, 1));
    else if (fresnel == "schlick_eta") body += fmt::format("{}fresnel = schlick(eta = {});\n", indent, g.rgbRanged(1.1, 3.0));
    else if (fresnel == "dielectric") body += fmt::format("{}fresnel = dielectric({});\n", indent, g.rgbRanged(1.1, 2.5));
    else if (fresnel == "dielectric_tir") body += fmt::format("{}fresnel = dielectric({});\n", indent, g.rgbRanged(0.4, 0.9));
    else if (fresnel == "conductor")
        body += fmt::format("{}fresnel = conductor(eta = {}, k = {});\n", indent, g.rgbRanged(0.1, 3.0), g.rgbRanged(0, 5));
    if (std::string(c.diffuse) == "lambert") body += fmt::format("{}diffuse = lambert({});\n", indent, g.rgbRanged(0, 1));
    return body;
}

}  // namespace

RandomMaterial randomMaterial(uint64_t seed, int i) {
    static const std::vector<Combo> combos = combinations();
    const Combo& c = combos[size_t(i) % combos.size()];
    Gen g(seed * 1000003u + uint64_t(i));
    std::string body = randomInputs(g);
    body += lobeStatements(g, c, "    ");
    RandomMaterial out;
    out.combination = fmt::format("{}{}/{}/{}/{}", c.ndf->name, c.anisotropic ? "_aniso" : "", c.masking->name,
                                  c.fresnel, c.diffuse);
    out.text = fmt::format("material random_{} {{\n{}}}\n", i, body);
    return out;
}

RandomMaterial randomMultiLobeMaterial(uint64_t seed, int i) {
    static const std::vector<Combo> combos = combinations();
    Gen g(seed * 2000003u + uint64_t(i));
    std::string body = randomInputs(g);
    const int lobes = 2 + g.pick(2);
    // Lobe k cycles through the combinations at its own stride, so that every
    // NDF is a top (lobe 0) and a base (lobe 1) within a few hundred materials.
    // A layer's top, and a microfacet base of it, take constant parameters:
    // the compiled backends bake the layer's tables from them.
    const int kind = g.pick(4);  // 0 sum, 1 scale + sum, 2 mix, 3 layer
    std::vector<std::string> names, combination;
    for (int k = 0; k < lobes; ++k) {
        std::string name = fmt::format("lobe{}", k);
        names.push_back(name);
        const bool diffuseOnly = k == lobes - 1 && g.pick(3) == 0;
        const bool constant = kind == 3 && k < 2;
        std::vector<std::string> savedF, savedC;
        if (constant) std::swap(savedF, g.floatInputs), std::swap(savedC, g.rgbInputs);
        if (diffuseOnly) {
            body += fmt::format("    lobe {} {{\n        diffuse = lambert({});\n    }}\n", name, g.rgbRanged(0, 1));
            combination.push_back("lambert");
        } else {
            const Combo& c = combos[(size_t(i) * (k == 0 ? 7 : k == 1 ? 11 : 13) + size_t(k)) % combos.size()];
            body += fmt::format("    lobe {} {{\n{}    }}\n", name, lobeStatements(g, c, "        "));
            combination.push_back(fmt::format("{}{}/{}/{}/{}", c.ndf->name, c.anisotropic ? "_aniso" : "",
                                              c.masking->name, c.fresnel, c.diffuse));
        }
        if (constant) std::swap(savedF, g.floatInputs), std::swap(savedC, g.rgbInputs);
    }
    std::string expr;
    switch (kind) {
        case 0: expr = names[0] + " + " + names[1]; break;
        case 1: expr = fmt::format("{} * {} + {} * {}", g.unit(), names[0], g.rgbRanged(0, 1), names[1]); break;
        case 2: expr = fmt::format("mix({}, {}, {})", names[0], names[1], g.unit()); break;
        default:
            expr = g.pick(2) ? fmt::format("layer({}, {})", names[0], names[1])
                             : fmt::format("layer({}, {}, weight = {})", names[0], names[1], g.unit());
    }
    if (lobes == 3) expr = g.pick(2) ? fmt::format("{} + {} * {}", expr, g.unit(), names[2])
                                     : fmt::format("mix({}, {}, {})", names[2], expr, g.unit());
    RandomMaterial out;
    for (const std::string& c : combination) out.combination += (out.combination.empty() ? "" : " | ") + c;
    out.combination = "bsdf = " + expr + ": " + out.combination;
    out.text = fmt::format("material random_lobes_{} {{\n{}    bsdf = {};\n}}\n", i, body, expr);
    return out;
}

}  // namespace facet::test
