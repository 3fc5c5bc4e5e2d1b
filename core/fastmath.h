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
/// errors are below 5e-17 and 2e-18 there. tests/test_fastmath.cpp checks the error bound.
inline void sincos_2pi(double u, double* sin_out, double* cos_out) {
    const int k4 = static_cast<int>(4.0 * u + 0.5);  // nearest quadrant; u >= 0, so truncation
    const double r = u - 0.25 * k4;                  // is floor
    const double t = 6.28318530717958647692 * r;
    const double t2 = t * t;
    const double sn =
        t * (1.0 +
             t2 * (-1.0 / 6 +
                   t2 * (1.0 / 120 +
                         t2 * (-1.0 / 5040 +
                               t2 * (1.0 / 362880 + t2 * (-1.0 / 39916800 +
                                                          t2 * (1.0 / 6227020800 +
                                                                t2 * (-1.0 / 1307674368000))))))));
    const double cs =
        1.0 +
        t2 * (-0.5 +
              t2 * (1.0 / 24 +
                    t2 * (-1.0 / 720 +
                          t2 * (1.0 / 40320 + t2 * (-1.0 / 3628800 +
                                                    t2 * (1.0 / 479001600 +
                                                          t2 * (-1.0 / 87178291200 +
                                                                t2 * (1.0 / 20922789888000))))))));
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
