// Quadrature: Gauss-Legendre rules and graded break points (see Quadrature.h).
// QuadMath.h first: numeric_limits<__float128> for the __float128 rules.
#include "QuadMath.h"
#include "Immortal.h"
#include "Quadrature.h"

#include "Diagnostics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

namespace facet::quadrature {

template <typename Real>
const GaussLegendre<Real>& gaussLegendre(int n) {
    static std::mutex mutex;
    static auto& rules = immortal<std::array<std::unique_ptr<GaussLegendre<Real>>, 65>>();
    internal_assert(n >= 1 && n <= 64) << "Gauss-Legendre order " << n;
    std::lock_guard<std::mutex> lock(mutex);
    if (!rules[n]) {
        auto r = std::make_unique<GaussLegendre<Real>>();
        r->x.resize(n);
        r->w.resize(n);
        const Real tol = std::numeric_limits<Real>::epsilon() / 2;
        for (int i = 0; i < n; ++i) {
            // Start from the asymptotic root estimate, then Newton on P_n
            // (three-term recurrence) in Real.
            Real z = Real(std::cos(3.141592653589793238462643383279502884 * (i + 0.75) / (n + 0.5))), dp = 1;
            for (int it = 0; it < 100; ++it) {
                Real p0 = 1, p1 = z;
                for (int k = 2; k <= n; ++k) {
                    Real p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                Real pn = n == 1 ? z : p1, pm = n == 1 ? Real(1) : p0;
                dp = n * (z * pn - pm) / (z * z - 1);
                Real dz = pn / dp;
                z -= dz;
                if ((dz < 0 ? -dz : dz) < tol) break;
            }
            r->x[i] = z;
            r->w[i] = 2 / ((1 - z * z) * dp * dp);
        }
        rules[n] = std::move(r);
    }
    return *rules[n];
}

template const GaussLegendre<float>& gaussLegendre<float>(int);
template const GaussLegendre<double>& gaussLegendre<double>(int);
template const GaussLegendre<long double>& gaussLegendre<long double>(int);
template const GaussLegendre<__float128>& gaussLegendre<__float128>(int);

std::vector<double> gradedBreaks(double a, double b, const std::vector<GradePoint>& points, double maxWidth) {
    std::vector<double> br = {a, b};
    for (const GradePoint& s : points) {
        if (!(s.at >= a && s.at <= b)) continue;
        br.push_back(s.at);
        if (!(s.h0 > 0)) continue;  // no grading (and no endless doubling of 0)
        for (double d = s.h0; d < b - a; d *= 2) {
            if (s.at - d > a) br.push_back(s.at - d);
            if (s.at + d < b) br.push_back(s.at + d);
        }
    }
    std::sort(br.begin(), br.end());
    std::vector<double> out;
    for (double x : br)
        if (out.empty() || x - out.back() > 1e-14 * std::max(1.0, std::fabs(x))) out.push_back(x);
    if (out.back() < b) out.back() = b;
    std::vector<double> fine;
    for (size_t i = 0; i + 1 < out.size(); ++i) {
        int n = std::max(1, int(std::ceil((out[i + 1] - out[i]) / maxWidth)));
        for (int k = 0; k < n; ++k) fine.push_back(out[i] + (out[i + 1] - out[i]) * k / n);
    }
    fine.push_back(out.back());
    return fine;
}

}  // namespace facet::quadrature
