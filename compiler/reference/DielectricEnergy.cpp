// DielectricEnergy: the compensation of a whole-sphere lobe (see
// DielectricEnergy.h for the construction).
#include "QuadMath.h"
#include "DielectricEnergy.h"

#include "DielectricLobe.h"
#include "FresnelAverage.h"
#include "KullaContyEval.h"
#include "Quadrature.h"

#include <algorithm>
#include <cmath>

namespace facet {
namespace {

template <typename Real>
constexpr Real kPi = Real(3.141592653589793238462643383279502884L);

// The sampler draws from the compensation at most this often, so the
// single-scattering lobe always keeps a share of the samples.
constexpr double kMaxCompensationProbability = 0.9;

// Side of a direction: true outside (z > 0).
template <typename Real>
bool outside(const Vec3<Real>& w) { return w.z > 0; }

template <typename Real>
Real ecOn(const ResolvedMaterial<Real>& r, bool out, Real mu) {
    const EnergyTable& t = out ? *r.energyTable : *r.energyTableInside;
    return Real(t.ecAt(double(mu), double(r.energyAlpha)));
}

// The crossing share from wo's side and the kept shares (reflect, cross)
// averaged over the channels, for the sampler.
template <typename Real>
std::array<Real, 2> keptShares(const ResolvedMaterial<Real>& r, bool out) {
    const std::array<Real, 3>& x = out ? r.crossingOutside : r.crossingInside;
    Real cross = (x[0] + x[1] + x[2]) / 3;
    return {keepsPair(r, true) ? 1 - cross : Real(0), keepsPair(r, false) ? cross : Real(0)};
}

}  // namespace

// On the Fresnel average's panels.
template <typename Real>
Real sheetTransmittanceAverage(const ResolvedMaterial<Real>& r, int ch) {
    Real eta = r.fresnelArgs.channel(r.fresnel->refractiveIndexParam, ch);
    // Last result per thread and channel: every lane of a constant eta
    // integrates once (resolve() runs per lane).
    struct Memo {
        Real eta, value;
        bool set = false;
    };
    thread_local Memo memo[3];
    Memo& mm = memo[ch];
    if (mm.set && mm.eta == eta) return mm.value;
    std::vector<double> breaks = fresnelAverageBreaks(double(eta), 0.0);
    static const quadrature::GaussLegendre<Real>& gl8 = quadrature::gaussLegendre<Real>(8);
    Real sum = quadrature::integratePanels(
        [&](Real mu) {
            Real F = r.F(mu, ch);
            return (1 - F) / (1 + F) * mu;
        },
        breaks, gl8);
    mm = {eta, std::clamp(2 * sum, Real(0), Real(1)), true};
    return mm.value;
}

CrossingConstants crossingConstants(const CheckedMaterial& material) {
    // The lobe without its compensation resolves without tables; the
    // index is the same.
    CheckedMaterial plain = material;
    for (const ModelInfo* m : catalogSlot(ModelSlot::Energy))
        if (!energyEntry(*m).compensates) plain.singleLobe().energy.model = m;
    internal_assert(!plain.singleLobe().compensatesEnergy()) << "no energy model without compensation";
    ResolvedMaterial<double> r = Interpreter<double>(plain).resolve(nullptr);
    CrossingConstants out;
    if (r.thin) {
        for (int ch = 0; ch < 3; ++ch) out.sheetCrossing[size_t(ch)] = sheetTransmittanceAverage(r, ch);
    } else {
        double eta = clampedEta(r, 0);
        out.eta2 = eta * eta;
        out.smoothCrossing = 1 - fresnelAverage(r, 0);
    }
    return out;
}

EnergyTableKey insideTableKey(const EnergyTableKey& outside) {
    EnergyTableKey inside = outside;
    if (outside.interfaceEta != 0) inside.interfaceEta = 1 / outside.interfaceEta;
    return inside;
}

template <typename Real>
void resolveWholeSphereCompensation(ResolvedMaterial<Real>& r, std::shared_ptr<const EnergyTable> outsideTable,
                                    std::shared_ptr<const EnergyTable> insideTable) {
    r.energyTable = std::move(outsideTable);
    r.energyTableInside = std::move(insideTable);
    r.energyAlpha = Real(energyAlpha(r));
    r.ecAvg = Real(r.energyTable->ecAvgAt(double(r.energyAlpha)));
    r.ecAvgInside = Real(r.energyTableInside->ecAvgAt(double(r.energyAlpha)));
    if (r.thin) {
        for (int ch = 0; ch < 3; ++ch) r.crossingOutside[ch] = r.crossingInside[ch] = sheetTransmittanceAverage(r, ch);
        return;
    }
    // x_o = min(1 - F_avg, eta^2 A_i / A_o), x_i = x_o A_o / (eta^2 A_i).
    Real eta = clampedEta(r, 0), eta2 = eta * eta;
    Real ao = r.ecAvg, ai = r.ecAvgInside;
    Real xo = 1 - fresnelAverage(r, 0);
    if (ao > 0 && eta2 * ai < xo * ao) xo = eta2 * ai / ao;
    Real xi = ai > 0 ? std::min(Real(1), xo * ao / (eta2 * ai)) : Real(0);
    r.crossingOutside = {xo, xo, xo};
    r.crossingInside = {xi, xi, xi};
}

template <typename Real>
std::array<Real, 3> wholeSphereCompensation(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi,
                                            const Vec3<Real>& wo) {
    using std::abs;
    std::array<Real, 3> out{};
    if (!r.energyTable || !r.energyTableInside || wi.z == 0 || wo.z == 0) return out;
    bool so = outside(wo), si = outside(wi), crossing = so != si;
    if (!keepsPair(r, !crossing)) return out;
    Real a = si ? r.ecAvg : r.ecAvgInside;  // the side wi leaves on
    if (!(a > 0)) return out;
    Real lobe = ecOn(r, so, abs(wo.z)) * ecOn(r, si, abs(wi.z)) / (kPi<Real> * a);
    if (crossing && !r.thin) {
        // Radiance transport: eta_o^2 / eta_i^2 times the importance form,
        // 1 / eta^2 with wo outside and eta^2 with wo inside.
        Real eta = clampedEta(r, 0), eta2 = eta * eta;
        if (r.transport == Transport::Radiance) lobe = so ? lobe / eta2 : lobe * eta2;
    }
    const std::array<Real, 3>& x = so ? r.crossingOutside : r.crossingInside;
    for (int ch = 0; ch < 3; ++ch) out[ch] = (crossing ? x[ch] : 1 - x[ch]) * lobe;
    return out;
}

template <typename Real>
Real compensationProbability(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo) {
    using std::abs;
    if (!r.energyTable || !r.energyTableInside || wo.z == 0) return 0;
    auto [reflect, cross] = keptShares(r, outside(wo));
    Real p = ecOn(r, outside(wo), abs(wo.z)) * (reflect + cross);
    return std::clamp(p, Real(0), Real(kMaxCompensationProbability));
}

template <typename Real>
Real compensationPdf(const ResolvedMaterial<Real>& r, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    using std::abs;
    if (wi.z == 0 || wo.z == 0) return 0;
    auto [reflect, cross] = keptShares(r, outside(wo));
    if (!(reflect + cross > 0)) return 0;
    bool crossing = outside(wi) != outside(wo);
    return (crossing ? cross : reflect) / (reflect + cross) * abs(wi.z) / kPi<Real>;
}

template <typename Real>
Vec3<Real> sampleCompensation(const ResolvedMaterial<Real>& r, const Vec3<Real>& wo, const std::array<Real, 3>& u) {
    using std::cos; using std::sin; using std::sqrt;
    auto [reflect, cross] = keptShares(r, outside(wo));
    if (!(reflect + cross > 0)) return {0, 0, 0};
    bool crossing = u[0] * (reflect + cross) >= reflect;
    Real radius = sqrt(u[1]), phi = 2 * kPi<Real> * u[2], z = sqrt(1 - u[1]);
    if (!(z > 0)) return {0, 0, 0};
    bool up = outside(wo) != crossing;
    return {radius * cos(phi), radius * sin(phi), up ? z : -z};
}

#define FACET_WHOLE_SPHERE_COMPENSATION(Real)                                                                    \
    template Real sheetTransmittanceAverage(const ResolvedMaterial<Real>&, int);                                  \
    template void resolveWholeSphereCompensation(ResolvedMaterial<Real>&, std::shared_ptr<const EnergyTable>,    \
                                                 std::shared_ptr<const EnergyTable>);                            \
    template std::array<Real, 3> wholeSphereCompensation(const ResolvedMaterial<Real>&, const Vec3<Real>&,       \
                                                         const Vec3<Real>&);                                     \
    template Real compensationProbability(const ResolvedMaterial<Real>&, const Vec3<Real>&);                     \
    template Real compensationPdf(const ResolvedMaterial<Real>&, const Vec3<Real>&, const Vec3<Real>&);          \
    template Vec3<Real> sampleCompensation(const ResolvedMaterial<Real>&, const Vec3<Real>&,                     \
                                           const std::array<Real, 3>&);
FACET_WHOLE_SPHERE_COMPENSATION(float)
FACET_WHOLE_SPHERE_COMPENSATION(double)
FACET_WHOLE_SPHERE_COMPENSATION(long double)
FACET_WHOLE_SPHERE_COMPENSATION(__float128)
#undef FACET_WHOLE_SPHERE_COMPENSATION

}  // namespace facet
