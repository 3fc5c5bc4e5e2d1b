// The multipole of a finite slab [DJ05]: the classical dipole's constants, the real source and
// its images about both extrapolated boundaries. Image sums near the source axis, the equivalent
// eigenmode expansion (Poisson summation of the same image lattice) far from it, and closed-form
// totals from the geometric series of the poles' e^{-sigma_tr |z|}.
#include "approx/diffusion.h"

#include "approx/diffusion_detail.h"

#include <cmath>
#include <stdexcept>

namespace ssslab::approx {

using diffusion_detail::kInf;
using diffusion_detail::kPi;

namespace {

// sum_{i in Z} sgn(i P + c) e^{-s |i P + c|} for 0 < c < P: a row of poles' share of 2 pi int
// z (1 + s d) e^{-s d}/d^3 r dr = sgn(z) e^{-s |z|}. Two geometric series; written with expm1 so
// that s -> 0 (limit 1 - 2 c / P) and s P -> inf stay exact.
double pole_row_total(double c, double period, double s) {
    if (s == 0) return 1 - 2 * c / period;
    const double den = std::expm1(-s * period);
    if (2 * c <= period) return std::exp(-s * c) * std::expm1(-s * (period - 2 * c)) / den;
    return -std::exp(-s * (period - c)) * std::expm1(-s * (2 * c - period)) / den;
}

// A pole at height z below the face: z (1 + s d) e^{-s d} / d^3, d = |(r, z)|, as ratios so that
// tiny or huge r neither overflows nor underflows early; odd in z.
double pole(double r, double z, double s) {
    const double d = std::hypot(r, z);
    return (z / d) / d / d * (1 + s * d) * std::exp(-s * d);
}

// Its derivative in z: e^{-s d} [(1 + s d)/d^3 - z^2 (3 + 3 s d + s^2 d^2)/d^5].
double pole_derivative(double r, double z, double s) {
    const double d = std::hypot(r, z), q = z / d;
    return std::exp(-s * d) / (d * d * d) * ((1 + s * d) - q * q * (3 + 3 * s * d + s * s * d * d));
}

// Its antiderivative in z: -e^{-s d} / d.
double pole_integral(double r, double z, double s) {
    const double d = std::hypot(r, z);
    return -std::exp(-s * d) / d;
}

}  // namespace

Multipole::Multipole(const DiffusionMedium& m, const DiffusionOptions& o) : DiffusionProfile(m) {
    validate(m, o.fresnel);
    const double st = m.sigma_t_reduced();
    alpha_ = m.reduced_albedo();
    const double diff = 1 / (3 * st);
    sigma_tr_ = std::sqrt(3 * m.sigma_a * st);
    zb_ = 2 * classical_reflection_parameter(m.eta, o.fresnel) * diff;  // [DJ05] z_b = 2 A D
    d_ = m.thickness >= 1e300 ? kInf : m.thickness;  // beyond, the image lattice overflows
    if (std::isinf(d_) || o.multipole_source == MultipoleSource::paper) {
        if (!(1 / st < d_))
            throw std::invalid_argument(
                "multipole: the paper's source depth 1/sigma_t' = " + std::to_string(1 / st) +
                " is not inside the slab of thickness " + std::to_string(d_) +
                "; use MultipoleSource::truncated");
        z0_ = 1 / st;
        strength_ = alpha_;
    } else {
        // First collisions truncated to the slab: mass 1 - e^{-x}, mean depth (1 - x/(e^x - 1))
        // / sigma_t' (x/2 - x^2/12 + O(x^4) for small x).
        const double x = st * d_;
        strength_ = alpha_ * -std::expm1(-x);
        z0_ = (x < 1e-4 ? x / 2 - x * x / 12 : 1 - x / std::expm1(x)) / st;
    }
    const double s = sigma_tr_;
    if (std::isinf(d_)) {
        total_r_ = 0.5 * strength_ * (std::exp(-s * z0_) + std::exp(-s * (z0_ + 2 * zb_)));
        total_t_ = 0;
    } else {
        // Real poles at i P + z0, virtual ones at i P - z0 - 2 z_b (mod P: 2 d + 2 z_b - z0); for
        // the bottom face the heights are d - z (mod P: d - z0 and d + z0 + 2 z_b).
        const double period = 2 * (d_ + 2 * zb_);
        total_r_ =
            0.5 * strength_ *
            (pole_row_total(z0_, period, s) - pole_row_total(2 * d_ + 2 * zb_ - z0_, period, s));
        total_t_ =
            0.5 * strength_ *
            (pole_row_total(d_ - z0_, period, s) - pole_row_total(d_ + z0_ + 2 * zb_, period, s));
    }
}

double Multipole::eval_rd(double r) const {
    return profile(r, false);
}

double Multipole::td(double r) const {
    if (!(r >= 0)) throw std::invalid_argument("multipole: r must be >= 0");
    if (std::isinf(r)) return 0.0;
    return profile(r, true);
}

double Multipole::profile(double r, bool transmit) const {
    if (strength_ == 0) return 0.0;
    const double s = sigma_tr_;
    if (std::isinf(d_)) {
        if (transmit) return 0.0;
        return strength_ / (4 * kPi) * (pole(r, z0_, s) - pole(r, -z0_ - 2 * zb_, s));
    }
    const double c1 = transmit ? d_ - z0_ : z0_;
    const double c2 = transmit ? d_ + z0_ + 2 * zb_ : -z0_ - 2 * zb_;
    const double len = d_ + 2 * zb_;
    // Near the axis (r < L/2) the image sum converges fast and the modes slowly. Far from it, with
    // weak absorption on the slab's scale (sigma_tr L <= 1), the first modes dominate and the
    // image lattice cancels; with strong absorption either may cancel (the modes down from
    // e^{-sigma_tr r} to the nearest poles' e^{-sigma_tr distance}), so both are summed and the one
    // with the smaller cancellation (sum of |terms| over |sum|) is taken.
    Series best;
    if (r < 0.5 * len) {
        best = image_sum(r, c1, c2);
    } else if (sigma_tr_ * len <= 1) {
        best = mode_sum(r, transmit);
    } else {
        best = image_sum(r, c1, c2);
        const Series modes = mode_sum(r, transmit);
        if (modes.cancellation() < best.cancellation()) best = modes;
    }
    // Rounding in the cancelling sums (at most ~1e-16 of `magnitude`) can leave a value that is
    // truly ~0 slightly negative.
    return std::max(0.0, strength_ * best.value);
}

// R (or T) / strength by images, i in [-n, n], and both tails by the midpoint Euler-Maclaurin
// formula, sum_{i > n} g(i) = int_{n+1/2}^inf g dx + g'(n + 1/2)/24 + O(g''), with the integral
// from the antiderivative of the poles. With absorption the poles beyond n P fall by e^{-60} or
// more against the nearest one (sigma_tr (sqrt(r^2 + (n P)^2) - r) >= 60) and the tails vanish;
// without, pairs decay like 1/i^3 and the remainder after 256 pairs is ~1e-16 of the sum.
Multipole::Series Multipole::image_sum(double r, double c1, double c2) const {
    const double s = sigma_tr_, period = 2 * (d_ + 2 * zb_);
    const double reach = s > 0 ? std::sqrt(120 * r / s + 3600 / (s * s)) : kInf;
    const int n = static_cast<int>(std::min(256.0, std::ceil(reach / period) + 2));
    double sum = 0, magnitude = 0;
    for (int i = -n; i <= n; ++i) {
        const double a = pole(r, i * period + c1, s), b = pole(r, i * period + c2, s);
        sum += a - b;
        magnitude += std::abs(a) + std::abs(b);
    }
    const double up = (n + 0.5) * period;
    sum += (-pole_integral(r, up + c1, s) + pole_integral(r, up + c2, s)) / period +
           period * (pole_derivative(r, up + c1, s) - pole_derivative(r, up + c2, s)) / 24;
    sum += (pole_integral(r, -up + c1, s) - pole_integral(r, -up + c2, s)) / period -
           period * (pole_derivative(r, -up + c1, s) - pole_derivative(r, -up + c2, s)) / 24;
    return {sum / (4 * kPi), magnitude / (4 * kPi)};
}

// R (or T) / strength by the eigenmodes of the slab between the extrapolated boundaries (width
// L): the same Green's function, (2/L) sum_n sin(k_n zeta) sin(k_n zeta0) K0(kappa_n r) /
// (2 pi D), differentiated at the faces. k_n K0(kappa_n r) eventually falls by e^{-pi r/L} or
// more per mode: the sum stops 1e-17 below its largest term.
Multipole::Series Multipole::mode_sum(double r, bool transmit) const {
    const double s = sigma_tr_, len = d_ + 2 * zb_;
    double sum = 0, magnitude = 0, largest = 0;
    for (int k = 1;; ++k) {
        const double kn = k * kPi / len;
        const double arg = std::sqrt(s * s + kn * kn) * r;
        if (arg > 745) break;
        const double scale = kn * std::cyl_bessel_k(0.0, arg);
        largest = std::max(largest, scale);
        if (scale < 1e-17 * largest) break;
        const double sign = transmit && k % 2 == 0 ? -1.0 : 1.0;
        const double term = sign * scale * std::cos(kn * zb_) * std::sin(kn * (z0_ + zb_));
        sum += term;
        magnitude += std::abs(term);
    }
    return {sum / (kPi * len), magnitude / (kPi * len)};
}

}  // namespace ssslab::approx
