// Numerical building blocks shared by the diffusion profiles (approx/diffusion*.cpp only; not part
// of the public interface): adaptive Gauss-Kronrod quadrature, the scaled complementary error
// function, the dielectric Fresnel reflectance, the phase function and Brent's root finder.
//
// Precision: everything is double; the profiles are compared with Monte Carlo estimates whose
// relative standard errors are 1e-3 at best, but parameter inversion differentiates the totals
// numerically (through a root finder), so the quadratures are run to 1e-12 or tighter.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <vector>

namespace ssslab::approx::diffusion_detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- Adaptive Gauss-Kronrod quadrature (QUADPACK's 7/15-point pair, global subdivision) ---------

/// One Gauss-Kronrod panel: the 15-point Kronrod estimate and |K15 - G7| as its error.
struct Panel {
    double a, b, value, error;
    bool operator<(const Panel& o) const { return error < o.error; }
};

// Nodes and weights of QUADPACK's qk15 (Piessens et al. 1983): Kronrod nodes xgk[0..7] on
// [0, 1] (xgk[1], xgk[3], xgk[5], xgk[7] = 0 are the Gauss nodes), Kronrod weights wgk, Gauss
// weights wg of the nodes xgk[1], xgk[3], xgk[5], xgk[7].
inline constexpr std::array<double, 8> kXgk = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
inline constexpr std::array<double, 8> kWgk = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
inline constexpr std::array<double, 4> kWg = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

template <class F>
Panel gauss_kronrod15(F& f, double a, double b) {
    const double c = 0.5 * (a + b), h = 0.5 * (b - a);
    const double fc = f(c);
    double k = fc * kWgk[7], g = fc * kWg[3];
    for (size_t j = 0; j < 7; ++j) {
        const double x = h * kXgk[j];
        const double s = f(c - x) + f(c + x);
        k += kWgk[j] * s;
        if (j % 2 == 1) g += kWg[j / 2] * s;
    }
    return {a, b, k * h, std::abs((k - g) * h)};
}

/// Integral of f over the consecutive intervals [breaks[i], breaks[i+1]] (finite, increasing) by
/// globally adaptive Gauss-Kronrod: the panel with the largest error estimate is halved until the
/// summed estimate is below max(abs_tol, rel_tol |I|), or `max_panels` panels exist (the best
/// estimate is returned then). |K15 - G7| overestimates the error of K15 by orders of magnitude
/// on smooth integrands, so the result is usually far more accurate than requested.
template <class F>
double integrate(F&& f, const std::vector<double>& breaks, double rel_tol, double abs_tol = 0,
                 int max_panels = 4000) {
    std::priority_queue<Panel> heap;
    double value = 0, error = 0;
    for (size_t i = 0; i + 1 < breaks.size(); ++i) {
        if (!(breaks[i + 1] > breaks[i])) continue;
        const Panel p = gauss_kronrod15(f, breaks[i], breaks[i + 1]);
        value += p.value;
        error += p.error;
        heap.push(p);
    }
    int panels = static_cast<int>(heap.size());
    while (!heap.empty() && error > std::max(abs_tol, rel_tol * std::abs(value)) &&
           panels < max_panels) {
        const Panel p = heap.top();
        const double mid = 0.5 * (p.a + p.b);
        if (!(mid > p.a && mid < p.b)) break;  // the panel cannot be split further in double
        heap.pop();
        const Panel l = gauss_kronrod15(f, p.a, mid), r = gauss_kronrod15(f, mid, p.b);
        value += l.value + r.value - p.value;
        error += l.error + r.error - p.error;
        heap.push(l);
        heap.push(r);
        ++panels;
    }
    // Re-sum: the running updates above accumulate rounding.
    double sum = 0;
    while (!heap.empty()) {
        sum += heap.top().value;
        heap.pop();
    }
    return sum;
}

/// Breakpoints for integrating over [lo, hi] (0 < lo < hi) in the logarithm of the variable:
/// ln(lo), the logarithms of the `features` inside (lo, hi), ln(hi), and at least one point per
/// `decade_step` natural-log units, so that no panel spans many decades.
inline std::vector<double> log_breaks(double lo, double hi, const std::vector<double>& features,
                                      double decade_step = 4.0) {
    std::vector<double> p = {std::log(lo), std::log(hi)};
    for (double f : features)
        if (f > lo && f < hi) p.push_back(std::log(f));
    std::sort(p.begin(), p.end());
    std::vector<double> out = {p[0]};
    for (size_t i = 1; i < p.size(); ++i) {
        const double gap = p[i] - p[i - 1];
        if (!(gap > 0)) continue;
        const int n = std::max(1, static_cast<int>(std::ceil(gap / decade_step)));
        for (int k = 1; k < n; ++k) out.push_back(p[i - 1] + gap * k / n);
        out.push_back(p[i]);
    }
    return out;
}

// ---- Special functions --------------------------------------------------------------------------

/// The continued fraction K(x) = (1/2)/(x + 1/(x + (3/2)/(x + 2/(x + ...)))) of erfc (Laplace),
/// evaluated backwards with 64 terms: relative error below 1e-16 for x >= 2.
inline double erfc_continued_fraction(double x) {
    double t = 0;
    for (int n = 64; n >= 1; --n) t = (0.5 * n) / (x + t);
    return t;
}

/// erfcx(x) = exp(x^2) erfc(x) for x >= 0, to ~1e-15 relative, without overflow:
/// erfcx = 1 / (sqrt(pi) (x + K(x))) for x >= 2; exp(x^2) with x^2 split exactly below.
inline double erfcx(double x) {
    if (x >= 2) return 1.0 / (std::sqrt(kPi) * (x + erfc_continued_fraction(x)));
    const double hi = x * x, lo = std::fma(x, x, -hi);
    return std::exp(hi) * (1 + lo) * std::erfc(x);
}

/// 1 - sqrt(pi) x erfcx(x) for x >= 0 (in (0, 1]; ~1/(2x^2) for large x) without the
/// cancellation of the direct form: K / (x + K) for x >= 2.
inline double one_minus_sqrtpi_x_erfcx(double x) {
    if (x >= 2) {
        const double k = erfc_continued_fraction(x);
        return k / (x + k);
    }
    return 1 - std::sqrt(kPi) * x * erfcx(x);
}

/// Exponential integral E1(x) = int_x^inf e^{-t}/t dt for x > 0 (0 beyond underflow).
inline double expint_e1(double x) {
    if (x > 700) return 0.0;
    return -std::expint(-x);
}

/// (1 - e^{-s x}) / s, with its limit x at s = 0 (s >= 0, x >= 0).
inline double one_minus_exp_over(double s, double x) {
    if (s * x < 1e-300) return x;
    return -std::expm1(-s * x) / s;
}

// ---- Optics -------------------------------------------------------------------------------------

/// Unpolarised Fresnel reflectance of a smooth dielectric boundary for light travelling inside a
/// medium of relative index eta = n_inside / n_outside and meeting the boundary at cosine `mu`
/// (0 <= mu <= 1) to its normal. 1 under total internal reflection.
inline double fresnel_inside(double mu, double eta) {
    if (eta == 1.0) return 0.0;
    const double sin2_t = eta * eta * (1 - mu * mu);
    if (sin2_t >= 1) return 1.0;
    const double ct = std::sqrt(1 - sin2_t);
    const double rs = (eta * mu - ct) / (eta * mu + ct);
    const double rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

/// The same given both cosines: `mu` inside and `ct` of the transmitted direction (exact near
/// the critical angle, where ct -> 0 and computing it from mu would cancel).
inline double fresnel_from_cosines(double mu, double ct, double eta) {
    const double rs = (eta * mu - ct) / (eta * mu + ct);
    const double rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

/// Henyey-Greenstein phase function [1/sr] in pbrt's convention: `cos_theta` is the cosine
/// between the two directions pointing away from the scattering point, so the scattering cosine
/// is -cos_theta (pbrt-v3 PhaseHG, pbrt-v4 HenyeyGreenstein).
inline double phase_hg_pbrt(double cos_theta, double g) {
    const double denom = 1 + g * g + 2 * g * cos_theta;
    return (1 - g * g) / (4 * kPi * denom * std::sqrt(denom));
}

// ---- Root finding -------------------------------------------------------------------------------

/// Brent's method (Brent 1973, zeroin) for a root of f in [a, b], f(a) f(b) <= 0 given as fa, fb.
/// Stops when the bracket is below 4 eps |x| + tol, or after 300 iterations.
template <class F>
double brent(F&& f, double a, double b, double fa, double fb, double tol) {
    if (fa == 0) return a;
    if (fb == 0) return b;
    double c = a, fc = fa, d = b - a, e = d;
    for (int it = 0; it < 300; ++it) {
        if ((fb > 0) == (fc > 0)) {
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (std::abs(fc) < std::abs(fb)) {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        const double tol1 = 4 * std::numeric_limits<double>::epsilon() * std::abs(b) + 0.5 * tol;
        const double m = 0.5 * (c - b);
        if (std::abs(m) <= tol1 || fb == 0) return b;
        if (std::abs(e) >= tol1 && std::abs(fa) > std::abs(fb)) {
            // Inverse quadratic interpolation (secant when a == c).
            double p, q;
            const double s = fb / fa;
            if (a == c) {
                p = 2 * m * s;
                q = 1 - s;
            } else {
                const double qa = fa / fc, r = fb / fc;
                p = s * (2 * m * qa * (qa - r) - (b - a) * (r - 1));
                q = (qa - 1) * (r - 1) * (s - 1);
            }
            if (p > 0)
                q = -q;
            else
                p = -p;
            if (2 * p < std::min(3 * m * q - std::abs(tol1 * q), std::abs(e * q))) {
                e = d;
                d = p / q;
            } else {
                d = m;
                e = m;
            }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += std::abs(d) > tol1 ? d : (m > 0 ? tol1 : -tol1);
        fb = f(b);
    }
    return b;
}

}  // namespace ssslab::approx::diffusion_detail
