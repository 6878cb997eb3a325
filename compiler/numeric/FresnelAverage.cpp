// FresnelAverage: F_avg by quadrature of an unpolarized Fresnel reflectance,
// and its tables (FresnelAverage.h).
#include "FresnelAverage.h"
#include "Immortal.h"

#include "Interpolation.h"
#include "Quadrature.h"

#include <algorithm>
#include <cmath>
#include <complex>

namespace facet {

namespace {

// Unpolarized reflectance of a smooth interface to the complex index
// N = eta + i k at incidence cosine c: (|rs|^2 + |rp|^2)/2, with
// g = sqrt(N^2 - 1 + c^2) (N cos theta_t; the principal root decays into the
// medium, and for a dielectric past the critical angle it is imaginary,
// which gives |rs| = |rp| = 1). The amplitudes are written with
// N^2 - 1 = (N - 1)(N + 1) factored out, so that F -> 0 without
// cancellation as N -> 1: c - g = -(N^2 - 1) / (c + g), and
// N^2 c - g = (N^2 - 1)(N^2 c^2 - (1 - c^2)) / (N^2 c + g).
double reflectance(std::complex<double> N, double c) {
    const std::complex<double> e = (N - 1.0) * (N + 1.0), N2 = N * N;
    const double s2 = (1 - c) * (1 + c);
    const std::complex<double> g = std::sqrt(e + c * c);
    const std::complex<double> rs = -e / ((c + g) * (c + g));
    const std::complex<double> rp = e * (N2 * (c * c) - s2) / ((N2 * c + g) * (N2 * c + g));
    return (std::norm(rs) + std::norm(rp)) / 2;
}

double averageOf(double eta, double k) {
    const std::complex<double> N(eta, k);
    std::vector<double> breaks = fresnelAverageBreaks(eta, k);
    auto integrand = [&](double mu) { return reflectance(N, mu) * mu; };
    return 2 * quadrature::integratePanels(integrand, breaks, quadrature::gaussLegendre<double>(12));
}

}  // namespace

std::vector<double> fresnelAverageBreaks(double eta, double k) {
    double mag = std::hypot(eta, k);  // no overflow to inf (h0 = 0) for huge eta or k
    std::vector<quadrature::GradePoint> sp = {{0, std::min(1.0, 1 / std::max(mag, 1e-12)) / 64}};
    if (eta < 1) {
        sp.push_back({std::sqrt((1 - eta) * (1 + eta)), 1e-6});
    } else {
        // sqrt|N^2 - 1|, N^2 - 1 = (eta - 1)(eta + 1) - k^2 + 2i eta k
        // (factored: no cancellation near eta = 1). A wider peak is resolved
        // by the 1/16 panels.
        double peak = std::sqrt(std::hypot((eta - 1) * (eta + 1) - k * k, 2 * eta * k));
        if (peak < 1.0 / 16) sp.push_back({peak, peak / 8});
    }
    return quadrature::gradedBreaks(0, 1, sp, 1.0 / 16);
}

double fresnelAverageDielectric(double eta) {
    if (std::isinf(eta)) return 1;
    return averageOf(std::max(eta, kFresnelAverageMinEta), 0);
}

double fresnelAverageConductor(double eta, double k) {
    if (std::isinf(eta) || std::isinf(k)) return 1;
    return averageOf(std::max(eta, kFresnelAverageMinEta), std::max(k, 0.0));
}

double conductorSchlickAverage(double eta, double k) {
    if (std::isinf(eta) || std::isinf(k)) return 1;
    double f0 = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
    return fresnelAverageSchlick(f0);
}

double FresnelAverageTables::dielectricAt(double eta) const {
    if (!(eta > 0)) eta = kFresnelAverageMinEta;
    auto lookup = [&](double e) {  // e >= 1
        double s = std::isinf(e) ? 1 : (e - 1) / (e + 1);
        double u = std::sqrt(std::clamp(s, 0.0, 1.0)) * (kDielectricCount - 1);
        int i = std::min(int(u), kDielectricCount - 2);
        double t = u - i;
        return s * (dielectric[i] + (double(dielectric[i + 1]) - dielectric[i]) * t);
    };
    if (eta >= 1) return lookup(eta);
    return 1 - eta * eta * (1 - lookup(1 / eta));
}

double FresnelAverageTables::conductorAt(double eta, double k) const {
    eta = std::max(eta, kFresnelAverageMinEta);
    k = std::max(k, 0.0);
    auto coord = [](double x) {
        double a = std::isinf(x) ? 1 : x / (x + 1);
        return std::clamp(a, 0.0, 1.0) * (kConductorCount - 1);
    };
    double u = coord(eta), v = coord(std::sqrt(k));
    int i = std::min(int(u), kConductorCount - 2), j = std::min(int(v), kConductorCount - 2);
    double residual = bilinear(conductor.data(), kConductorCount, j, i, u - i, v - j);
    return std::min(1.0, conductorSchlickAverage(eta, k) + residual);
}

const FresnelAverageTables& fresnelAverageTables() {
    static const FresnelAverageTables& tables = immortal<FresnelAverageTables>([] {
        FresnelAverageTables t;
        t.dielectric.resize(FresnelAverageTables::kDielectricCount);
        for (int i = 0; i < FresnelAverageTables::kDielectricCount; ++i) {
            // Nodes uniform in sqrt(s), values F_avg / s (2/3 at s = 0):
            // F_avg itself vanishes at s = 0, where interpolating it would be
            // exact only in absolute terms, and F_avg / s drops by 1.5% over
            // the first 1e-3 of s.
            double r = double(i) / (FresnelAverageTables::kDielectricCount - 1), s = r * r;
            t.dielectric[i] = i == 0 ? float(2.0 / 3) : s >= 1 ? 1.0f : float(fresnelAverageDielectric((1 + s) / (1 - s)) / s);
        }
        const int n = FresnelAverageTables::kConductorCount;
        t.conductor.resize(size_t(n) * n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                double a = double(i) / (n - 1), b = double(j) / (n - 1);
                double eta = a / (1 - a), rk = b / (1 - b);  // eta, sqrt(k)
                double v = (a >= 1 || b >= 1)
                               ? 0.0
                               : fresnelAverageConductor(eta, rk * rk) - conductorSchlickAverage(eta, rk * rk);
                t.conductor[size_t(j) * n + i] = float(v);
            }
        return t;
    }());
    return tables;
}

}  // namespace facet
