#include "core/quadrature.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace ssslab {

void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
    if (n < 1) throw std::invalid_argument("gauss_legendre: n must be >= 1");
    x.assign(static_cast<size_t>(n), 0.0);
    w.assign(static_cast<size_t>(n), 0.0);
    // P_n(z) and P_n'(z) by the three-term recurrence.
    auto legendre = [n](double z, double& dp) {
        double p0 = 1, p1 = z;
        for (int k = 2; k <= n; ++k) {
            const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        return p1;
    };
    for (int i = 0; i < n; ++i) {
        double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; ++it) {
            const double dz = legendre(z, dp) / dp;
            z -= dz;
            if (std::abs(dz) < 1e-16) break;
        }
        legendre(z, dp);
        x[static_cast<size_t>(n - 1 - i)] = z;
        w[static_cast<size_t>(n - 1 - i)] = 2.0 / ((1 - z * z) * dp * dp);
    }
}

}  // namespace ssslab
