// WholeSphereChecks: the furnace from both sides and generalized
// reciprocity of a whole-sphere lobe (see WholeSphereChecks.h).
#include "WholeSphereChecks.h"

#include "ChiSquare.h"
#include "DielectricEnergy.h"
#include "DielectricLobe.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace facet {
namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double kCompensatedBound = 0.01;  // SPEC 11
constexpr double kEnergySlack = 1e-3;       // the quadrature's error on R + T <= 1
constexpr double kReciprocityBound = 1e-8;  // the two directions' roundings in the facet normal

// R + T from wo: Int f(wi, wo) |n.wi| dwi over the sphere.
double furnace(const ResolvedMaterial<double>& r, const Vec3<double>& wo) {
    SphereGrid grid = SphereGrid::equalArea(24, 48);
    PdfFunction integrand = [&](const Vec3<double>& wi) {
        Vec3<double> sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
        return dielectricBsdf(r, wi, wo, sum)[0] * std::abs(wi.z);
    };
    double total = 0;
    for (double cell : integrateCells(grid, integrand, 1e-7)) total += cell;
    return total;
}

// The lobe at roughness alpha (isotropic, the NDF's shape values kept).
ResolvedMaterial<double> atAlpha(const ResolvedMaterial<double>& base, double alpha, const std::vector<double>& shape) {
    ResolvedMaterial<double> r = base;
    r.ndfArgs = r.ndf->argsAtAlpha(alpha, shape);
    r.ndf->formulas.get<double>().derive(r.ndfArgs);
    return r;
}

}  // namespace

WholeSphereReport wholeSphereChecks(const CheckedMaterial& m, const Interpreter<double>& interp) {
    WholeSphereReport report;
    const CheckedLobe& lobe = m.singleLobe();
    ResolvedMaterial<double> base = interp.resolve(nullptr);
    base.transport = Transport::Importance;
    ResolvedMaterial<double> plain = base;
    plain.energy = &energyEntry(*findModel(ModelSlot::Energy, "none"));
    plain.energyTable = plain.energyTableInside = nullptr;

    // The compensation's tables: the material's, or built for its eta.
    std::shared_ptr<const EnergyTable> outside = base.energyTable, inside = base.energyTableInside;
    std::vector<double> ndfShape;
    if (!outside) {
        if (auto why = kullaContyUnsupported(m, lobe)) {
            report.compensationNote = why->message;
        } else {
            EnergyTableKey key = energyTableKey(m, lobe);
            outside = buildEnergyTable(key);
            inside = lobe.thin ? outside : buildEnergyTable(insideTableKey(key));
        }
    }
    if (outside) {
        const EnergyTableKey& key = outside->key;
        ndfShape.assign(key.shape.begin(), key.shape.begin() + long(key.ndf->tableShapeParams.size()));
    } else {
        for (int p : base.ndf->tableShapeParams) ndfShape.push_back(base.ndfArgs.value[size_t(p)][0]);
    }

    const double eta = clampedEta(base, 0);
    const double thetas[] = {0, 30, 60, 80, 89};
    for (double alpha : {0.2, 0.5, 1.0})
        for (bool in : {false, true}) {
            FurnaceRow row;
            row.alpha = alpha;
            row.eta = eta;
            row.inside = in;
            row.compensated = outside != nullptr;
            ResolvedMaterial<double> p = atAlpha(plain, alpha, ndfShape), c = p;
            if (row.compensated) {
                c.energy = &energyEntry(*findModel(ModelSlot::Energy, "kulla_conty"));
                resolveWholeSphereCompensation(c, outside, inside);
            }
            row.plainMin = row.compensatedMin = INFINITY;
            row.plainMax = row.compensatedMax = -INFINITY;
            for (double theta : thetas) {
                double t = theta * kPi / 180;
                Vec3<double> wo{std::sin(t) * std::cos(0.3), std::sin(t) * std::sin(0.3), std::cos(t) * (in ? -1 : 1)};
                double e = furnace(p, wo);
                row.plainMin = std::min(row.plainMin, e);
                row.plainMax = std::max(row.plainMax, e);
                std::string where = fmt::format("alpha {} eta {:.4g} {} theta_o {}", alpha, eta,
                                                in ? "inside" : "outside", theta);
                report.checks.push_back(
                    PhysicsCheck{"energy <= 1 (R + T)", where, e, 1, std::max(0.0, e - 1), kEnergySlack, true, {}});
                if (!row.compensated) continue;
                double ec = furnace(c, wo);
                row.compensatedMin = std::min(row.compensatedMin, ec);
                row.compensatedMax = std::max(row.compensatedMax, ec);
                report.checks.push_back(
                    PhysicsCheck{"compensated furnace", where, ec, 1, std::abs(1 - ec), kCompensatedBound, true, {}});
            }
            report.furnace.push_back(row);
        }

    // Generalized reciprocity in radiance transport, the material as it is.
    ResolvedMaterial<double> radiance = interp.resolve(nullptr);
    radiance.transport = Transport::Radiance;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    auto uniformSphere = [&] {
        double z = 1 - 2 * u(rng), s = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u(rng);
        return Vec3<double>{s * std::cos(phi), s * std::sin(phi), z};
    };
    double worst = 0;
    std::string worstWhere = "all pairs 0";
    for (int k = 0; k < 512; ++k) {
        Vec3<double> wi = uniformSphere(), wo = uniformSphere();
        double ni = wi.z > 0 || lobe.thin ? 1 : eta, no = wo.z > 0 || lobe.thin ? 1 : eta;
        Vec3<double> sum{wi.x + wo.x, wi.y + wo.y, wi.z + wo.z};
        double a = dielectricBsdf(radiance, wi, wo, sum)[0] / (no * no);
        double b = dielectricBsdf(radiance, wo, wi, sum)[0] / (ni * ni);
        double scale = std::max(std::abs(a), std::abs(b));
        double rel = scale > 1e-300 ? std::abs(a - b) / scale : 0;
        if (rel >= worst && scale > 0) {
            worst = rel;
            worstWhere = fmt::format("wi ({:.3f}, {:.3f}, {:.3f}) wo ({:.3f}, {:.3f}, {:.3f})", wi.x, wi.y, wi.z, wo.x,
                                     wo.y, wo.z);
        }
    }
    report.checks.push_back(
        PhysicsCheck{"generalized reciprocity", worstWhere, worst, 0, worst, kReciprocityBound, true, {}});
    return report;
}

}  // namespace facet
