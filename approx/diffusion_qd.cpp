// Quantized diffusion [dEonIrving11] for a semi-infinite medium: the time-resolved diffusion
// Green's function of the extended (beam) source with the better dipole's boundary, quantised in
// time into a sum of 2D Gaussians.
//
// In time tau = c t (a length), the infinite-medium Green's function of
//   d(phi)/d(tau) = D lap(phi) - sigma_a phi
// is e^{-sigma_a tau} times a 3D Gaussian of variance v = 2 D tau per axis: a lateral 2D Gaussian
// G2(v, r) = e^{-r^2/(2v)}/(2 pi v) times a depth Gaussian g_v(z) = e^{-z^2/(2v)}/sqrt(2 pi v).
// The beam deposits the source alpha' sigma_t' e^{-sigma_t' z'} dz' (Grosjean's collided source,
// reduced coefficients); the boundary is the extrapolated one of the better dipole, an image of
// opposite sign 2 z_b above each source point. Integrating the depth Gaussians over the source:
//   w_phi(v, d) = int_0^inf alpha' sigma_t' e^{-sigma_t' z} g_v(z + d) dz
//              = (alpha' sigma_t'/2) e^{-d^2/(2v)} erfcx((d + sigma_t' v)/sqrt(2v)),
//   w_E(v, d)  = int_0^inf alpha' sigma_t' e^{-sigma_t' z} ((z + d)/v) g_v(z + d) dz
//              = sigma_t' (alpha' g_v(d) - w_phi(v, d)),
// the surface fluence is w_phi(v, 0) - w_phi(v, 2 z_b) and the outward flux D (w_E(v, 0) +
// w_E(v, 2 z_b)), and the exitance weight is W(v) = C_phi (fluence) + C_E (flux).
// Quantisation: in [tau_i, tau_{i+1}] the Gaussians take v_i = D (tau_i + tau_{i+1}) (the
// interval's midpoint) and the absorption is integrated exactly, w_i = int e^{-sigma_a tau} dtau.
// R_d(r) = alpha' sum_i w_i W(v_i) G2(v_i, r) (the second alpha' is Grosjean's, as in the better
// dipole). The erfcx form and the integral form of the fluence difference below keep every term
// free of overflow and cancellation for v from 1e-6 to 1e40 mean free paths squared.
#include "approx/diffusion.h"

#include "approx/diffusion_detail.h"

#include <cmath>
#include <stdexcept>

namespace ssslab::approx {

using diffusion_detail::erfcx;
using diffusion_detail::kPi;
using diffusion_detail::one_minus_sqrtpi_x_erfcx;

namespace {

// erfcx(x0) - e^{-u^2} erfcx(x0 + u), u >= 0: the fluence of a source and its image, in units of
// alpha' sigma_t'/2. For small u the difference is written as the integral of its derivative,
// (2/sqrt(pi)) int_0^u e^{-t^2} [h(x0 + t) + sqrt(pi) t erfcx(x0 + t)] dt with h(x) = 1 -
// sqrt(pi) x erfcx(x) > 0, which has no cancellation (late times, where the image is close).
double fluence_difference(double x0, double u) {
    if (u > 0.5) return erfcx(x0) - std::exp(-u * u) * erfcx(x0 + u);
    auto integrand = [&](double t) {
        return std::exp(-t * t) *
               (one_minus_sqrtpi_x_erfcx(x0 + t) + std::sqrt(kPi) * t * erfcx(x0 + t));
    };
    return 2 / std::sqrt(kPi) * diffusion_detail::gauss_kronrod15(integrand, 0.0, u).value;
}

// w_E(v, d) / (alpha' sigma_t') = e^{-d^2/(2v)} [h(x)/sqrt(2 pi v) + d erfcx(x)/(2v)],
// x = (d + sigma_t' v)/sqrt(2v): g_v(d) - (sigma_t'/2) e^{-d^2/2v} erfcx(x) without cancellation.
double flux_weight(double v, double d, double st) {
    const double x = (d + st * v) / std::sqrt(2 * v);
    return std::exp(-d * d / (2 * v)) *
           (one_minus_sqrtpi_x_erfcx(x) / std::sqrt(2 * kPi * v) + d * erfcx(x) / (2 * v));
}

}  // namespace

QuantizedDiffusion::QuantizedDiffusion(const DiffusionMedium& m, const DiffusionOptions& o)
    : DiffusionProfile(m) {
    validate(m, o.fresnel);
    if (!(o.qd_ratio > 1 && o.qd_ratio <= 100))
        throw std::invalid_argument("qd: qd_ratio must be in (1, 100]");
    if (!(o.qd_first_width > 0 && o.qd_first_width <= 1))
        throw std::invalid_argument("qd: qd_first_width must be in (0, 1] mean free paths");
    const double alpha = m.reduced_albedo();
    if (alpha == 0) return;
    const double st = m.sigma_t_reduced(), sa = m.sigma_a;
    const double diff = (2 * sa + m.sigma_s_reduced()) / (3 * st * st);  // Grosjean's D
    const FresnelMomentPair c = fresnel_moments(m.eta, o.fresnel);
    const double a = (1 + 3 * c.c2) / (1 - 2 * c.c1);
    const double c_phi = 0.25 * (1 - 2 * c.c1), c_e = 0.5 * (1 - 3 * c.c2);
    const double image = 4 * a * diff;  // 2 z_b: distance of the image of a source point

    // Terms decay at least like (tau_i/tau_{i+1})^{1/2} per step once past their maximum (the
    // late-time flux of the 1D problem falls as tau^{-3/2}), so the rest of the sum is below
    // term / (1 - ratio^{-1/2}).
    const double tail = 1 / (1 - 1 / std::sqrt(o.qd_ratio));
    const double width = o.qd_first_width / st;
    double t0 = 0, t1 = width * width / diff, previous = 0;
    for (int i = 0; i < 200000; ++i) {
        const double v = diff * (t0 + t1);
        // int_{t0}^{t1} e^{-sigma_a tau} dtau, exact also at sigma_a = 0.
        const double wi = std::exp(-sa * t0) * diffusion_detail::one_minus_exp_over(sa, t1 - t0);
        if (wi == 0) break;  // absorption has removed everything later
        const double x0 = st * std::sqrt(v / 2), u = image / std::sqrt(2 * v);
        const double fluence = 0.5 * st * fluence_difference(x0, u);
        const double flux = diff * st * (flux_weight(v, 0.0, st) + flux_weight(v, image, st));
        const double weight = alpha * alpha * wi * (c_phi * fluence + c_e * flux);
        weights_.push_back(weight);
        variances_.push_back(v);
        total_ += weight;
        if (weight < previous && weight * tail < 1e-16 * total_) break;
        previous = weight;
        t0 = t1;
        t1 *= o.qd_ratio;
    }
}

double QuantizedDiffusion::eval_rd(double r) const {
    double sum = 0;
    for (size_t i = 0; i < weights_.size(); ++i) {
        const double v = variances_[i];
        sum += weights_[i] * std::exp(-r * r / (2 * v)) / (2 * kPi * v);
    }
    return sum;
}

}  // namespace ssslab::approx
