// Small numerical kernels for the Monte Carlo engines' inner loops.
#pragma once

#include <cmath>

namespace ssslab {

/// sin(2 pi u) and cos(2 pi u) for u in [0, 1], to within about 2 ulp of the exact value.
///
/// The azimuth of every scattering event needs both; glibc's sincos() took 20 % of the MCML
/// engine's time (15 ns per call). Here u is split exactly into a quadrant q and a remainder
/// r = u - q/4 in [-1/8, 1/8] (Sterbenz: no rounding), and sin/cos of theta = 2 pi r in
/// [-pi/4, pi/4] come from their Taylor series through theta^15 and theta^16, whose truncation
/// errors are below 5e-17 and 2e-18 there. tests/test_sampling.cpp checks the error bound.
inline void sincos_2pi(double u, double* sin_out, double* cos_out) {
    const int k4 = static_cast<int>(4.0 * u + 0.5);  // nearest quadrant; u >= 0, so truncation
    const double r = u - 0.25 * k4;                  // is floor
    const double t = 6.28318530717958647692 * r;
    const double x = t * t, x2 = x * x, x4 = x2 * x2;
    // Estrin's scheme: the polynomials in x = theta^2 in three levels instead of eight (Horner),
    // which shortens the dependency chain the transport waits on.
    const double s01 = 1.0 + x * (-1.0 / 6), s23 = 1.0 / 120 + x * (-1.0 / 5040);
    const double s45 = 1.0 / 362880 + x * (-1.0 / 39916800);
    const double s67 = 1.0 / 6227020800 + x * (-1.0 / 1307674368000);
    const double sn = t * ((s01 + x2 * s23) + x4 * (s45 + x2 * s67));
    const double c01 = 1.0 + x * -0.5, c23 = 1.0 / 24 + x * (-1.0 / 720);
    const double c45 = 1.0 / 40320 + x * (-1.0 / 3628800);
    const double c67 = 1.0 / 479001600 + x * (-1.0 / 87178291200);
    const double cs = (c01 + x2 * c23) + x4 * ((c45 + x2 * c67) + x4 * (1.0 / 20922789888000));
    // angle = k pi/2 + theta. The quadrant is selected arithmetically (exact: the products
    // are by 0, 1 or -1): branches here would be mispredicted half the time.
    const int k = k4 & 3;
    const double odd = static_cast<double>(k & 1), even = 1.0 - odd;
    const double s = even * sn + odd * cs;
    const double c = even * cs + odd * sn;
    *sin_out = static_cast<double>(1 - (k & 2)) * s;
    *cos_out = static_cast<double>(1 - ((k + 1) & 2)) * c;
}

}  // namespace ssslab
