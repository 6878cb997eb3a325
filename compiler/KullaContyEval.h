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

#include <array>
#include <memory>
#include <vector>

namespace facet {

// The roughness the E table is looked up with (see KullaConty.h).
template <typename Real>
double energyAlpha(const ResolvedMaterial<Real>& r) {
    using std::sqrt;
    switch (r.ndf) {
        case NdfModel::BlinnPhong: return std::sqrt(2 / (double(r.exponent) + 2));
        case NdfModel::Ggx:
        case NdfModel::Beckmann: return std::sqrt(double(r.alphaX) * double(r.alphaY));
        default: return double(r.alphaX);
    }
}

// F_avg = 2 Int_0^1 F(mu) mu dmu of channel ch, by Gauss-Legendre panels
// graded toward grazing incidence and toward the critical angle of total
// internal reflection (break points in double, sums in Real). Schlick in
// closed form, (20 f0 + 1)/21.
template <typename Real>
Real fresnelAverage(const ResolvedMaterial<Real>& r, int ch) {
    switch (r.fresnel) {
        case FresnelModel::None: return Real(1);
        case FresnelModel::Schlick: {
            Real f0 = r.f0[ch];
            if (r.schlickFromEta) {
                Real q = (r.eta[ch] - 1) / (r.eta[ch] + 1);
                f0 = q * q;
            }
            return (20 * f0 + 1) / 21;
        }
        case FresnelModel::Dielectric:
        case FresnelModel::Conductor: break;
    }
    // Last result per thread: materials with constant eta / k integrate once.
    struct Memo {
        FresnelModel model;
        Real eta, k, value;
        bool set = false;
    };
    thread_local Memo memo[3];
    Real eta = r.eta[ch], k = r.fresnel == FresnelModel::Conductor ? r.k[ch] : Real(0);
    Memo& mm = memo[ch];
    if (mm.set && mm.model == r.fresnel && mm.eta == eta && mm.k == k) return mm.value;

    double n = double(eta), kk = double(k);
    double mag = std::sqrt(n * n + kk * kk);
    std::vector<double> br = {0, 1};
    double h0 = std::min(1.0, 1 / std::max(mag, 1e-12)) / 64;
    for (double d = h0; d < 1; d *= 2) br.push_back(d);
    if (n < 1) {
        double c = std::sqrt((1 - n) * (1 + n));
        br.push_back(c);
        for (double d = 1e-6; d < 1; d *= 2) {
            if (c - d > 0) br.push_back(c - d);
            if (c + d < 1) br.push_back(c + d);
        }
    }
    for (int i = 1; i < 16; ++i) br.push_back(i / 16.0);
    std::sort(br.begin(), br.end());
    br.erase(std::unique(br.begin(), br.end()), br.end());
    // 8-point Gauss-Legendre nodes and weights on [-1, 1].
    static const long double x8[4] = {0.1834346424956498049394761423601839807L, 0.5255324099163289858177390491892463490L,
                                      0.7966664774136267395915539364758304368L, 0.9602898564975362316835608685694729904L};
    static const long double w8[4] = {0.3626837833783619829651504492771956121L, 0.3137066458778872873379622019866013132L,
                                      0.2223810344533744705443559944262408844L, 0.1012285362903762591525313543099621901L};
    Real sum = 0;
    for (size_t p = 0; p + 1 < br.size(); ++p) {
        Real a = Real(br[p]), b = Real(br[p + 1]);
        Real mid = (a + b) / 2, half = (b - a) / 2, s = 0;
        for (int i = 0; i < 4; ++i) {
            Real d = half * Real(x8[i]);
            Real m1 = mid - d, m2 = mid + d;
            s += Real(w8[i]) * (r.F(m1, ch) * m1 + r.F(m2, ch) * m2);
        }
        sum += s * half;
    }
    Real value = 2 * sum;
    if (value > 1) value = 1;
    mm = {r.fresnel, eta, k, value, true};
    return value;
}

// Fills the kulla_conty fields of a resolved material: the table, the lookup
// roughness, 1 - E_avg, and F_avg per channel.
template <typename Real>
void resolveKullaConty(ResolvedMaterial<Real>& r, std::shared_ptr<const EnergyTable> table) {
    r.energy = EnergyModel::KullaConty;
    r.energyTable = std::move(table);
    r.energyAlpha = Real(energyAlpha(r));
    r.ecAvg = Real(r.energyTable->ecAvgAt(double(r.energyAlpha)));
    for (int ch = 0; ch < 3; ++ch) r.favg[ch] = fresnelAverage(r, ch);
}

// f_ms(wi, wo) for cosines ci = n.wi, co = n.wo (both > 0), rgb.
template <typename Real>
std::array<Real, 3> kullaContyBrdf(const ResolvedMaterial<Real>& r, Real ci, Real co) {
    std::array<Real, 3> out{};
    if (r.energy != EnergyModel::KullaConty || !r.energyTable) return out;
    double a = double(r.energyAlpha);
    Real ecI = Real(r.energyTable->ecAt(double(ci), a)), ecO = Real(r.energyTable->ecAt(double(co), a));
    Real lobe = kullaContyLobe(ecI, ecO, r.ecAvg);
    for (int ch = 0; ch < 3; ++ch) out[ch] = lobe * kullaContyFresnelTerm(r.favg[ch], r.ecAvg);
    return out;
}

}  // namespace facet
