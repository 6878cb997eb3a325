// KullaContyEval: f_ms of `energy = kulla_conty` in the reference
// interpreter, for any real type (double, long double, wider).
//
// Written with arithmetic, comparisons and conversions only, plus the
// material's own Fresnel function, so it works for every Real the
// interpreter is instantiated with. Table lookups happen in double (the
// table nodes are floats; double interpolation of them is exact to ~1e-16).
#pragma once

#include "Interpreter.h"
#include "KullaConty.h"
#include "Quadrature.h"

#include <array>
#include <memory>
#include <vector>

namespace facet {

// The roughness the E table is looked up with (see KullaConty.h): the
// NDF's equivalent roughness, the geometric mean of the two for an
// anisotropic lobe.
template <typename Real>
double energyAlpha(const ResolvedMaterial<Real>& r) {
    std::array<double, 2> a = r.ndf->equivalentAlphas(convertArgs<double>(r.ndfArgs));
    return a[0] == a[1] ? a[0] : std::sqrt(a[0] * a[1]);
}

// F_avg = 2 Int_0^1 F(mu) mu dmu of channel ch, by 8-point Gauss-Legendre on
// the panels of fresnelAverageBreaks (break points in double, nodes and sums
// in Real). Schlick in closed form, (20 f0 + 1)/21.
template <typename Real>
Real fresnelAverage(const ResolvedMaterial<Real>& r, int ch) {
    if (std::optional<Real> closed = r.fresnel->formulas.template get<Real>().closedFormAverage(r.fresnelArgs, ch))
        return *closed;
    // Last result per thread: materials with constant parameters integrate once.
    struct Memo {
        const FresnelEntry* model;
        Real eta, k, value;
        bool set = false;
    };
    thread_local Memo memo[3];
    // The exact terms' parameters: eta, and k for a conductor (0 otherwise).
    Real eta = r.fresnelArgs.channel(0, ch), k = r.fresnelArgs.given[1] ? r.fresnelArgs.channel(1, ch) : Real(0);
    Memo& mm = memo[ch];
    if (mm.set && mm.model == r.fresnel && mm.eta == eta && mm.k == k) return mm.value;

    std::vector<double> br = fresnelAverageBreaks(double(eta), double(k));
    static const quadrature::GaussLegendre<Real>& gl8 = quadrature::gaussLegendre<Real>(8);
    Real sum = quadrature::integratePanels([&](Real mu) { return r.F(mu, ch) * mu; }, br, gl8);
    Real value = 2 * sum;
    if (value > 1) value = 1;
    mm = {r.fresnel, eta, k, value, true};
    return value;
}

// Fills the kulla_conty fields of a resolved material: the table, the lookup
// roughness, 1 - E_avg, and F_avg per channel.
template <typename Real>
void resolveKullaConty(ResolvedMaterial<Real>& r, std::shared_ptr<const EnergyTable> table) {
    r.energyTable = std::move(table);
    r.energyAlpha = Real(energyAlpha(r));
    r.ecAvg = Real(r.energyTable->ecAvgAt(double(r.energyAlpha)));
    for (int ch = 0; ch < 3; ++ch) r.favg[ch] = fresnelAverage(r, ch);
}

// f_ms(wi, wo) for cosines ci = n.wi, co = n.wo (both > 0), rgb.
template <typename Real>
std::array<Real, 3> kullaContyBrdf(const ResolvedMaterial<Real>& r, Real ci, Real co) {
    std::array<Real, 3> out{};
    if (!r.energy->compensates || !r.energyTable) return out;
    double a = double(r.energyAlpha);
    Real ecI = Real(r.energyTable->ecAt(double(ci), a)), ecO = Real(r.energyTable->ecAt(double(co), a));
    Real lobe = kullaContyLobe(ecI, ecO, r.ecAvg);
    for (int ch = 0; ch < 3; ++ch) out[ch] = lobe * kullaContyFresnelTerm(r.favg[ch], r.ecAvg);
    return out;
}

}  // namespace facet
