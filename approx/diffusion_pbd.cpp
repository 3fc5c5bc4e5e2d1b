// Photon beam diffusion [Habel13] as pbrt-v3/v4 implement it (BeamDiffusionMS, BeamDiffusionSS):
// the beam integrals either by pbrt's N-point rule or integrated to convergence, and their
// totals semi-analytically.
#include "approx/diffusion.h"

#include "approx/diffusion_detail.h"

#include <cmath>
#include <stdexcept>

namespace ssslab::approx {

using diffusion_detail::fresnel_from_cosines;
using diffusion_detail::fresnel_inside;
using diffusion_detail::kInf;
using diffusion_detail::kPi;
using diffusion_detail::phase_hg_pbrt;

PhotonBeamDiffusion::PhotonBeamDiffusion(const DiffusionMedium& m, const DiffusionOptions& o)
    : DiffusionProfile(m), terms_(o.pbd_terms), samples_(o.pbd_depth_samples) {
    validate(m, o.fresnel);
    if (samples_ < 0) throw std::invalid_argument("pbd: pbd_depth_samples must be >= 0");
    sigma_t_r_ = m.sigma_t_reduced();
    sigma_t_ = m.sigma_a + m.sigma_s;
    alpha_ = m.reduced_albedo();  // rho' in pbrt
    rho_ = m.albedo();
    d_ = (2 * m.sigma_a + m.sigma_s_reduced()) / (3 * sigma_t_r_ * sigma_t_r_);  // [pbrt3 15.24]
    sigma_tr_ = std::sqrt(m.sigma_a / d_);
    const FresnelMomentPair c = fresnel_moments(m.eta, o.fresnel);
    a_ = (1 + 3 * c.c2) / (1 - 2 * c.c1);  // z_e = -2 D A [pbrt3 Eq. 15.28]
    c_phi_ = 0.25 * (1 - 2 * c.c1);        // [pbrt3 Eq. 15.31]
    c_e_ = 0.5 * (1 - 3 * c.c2);           // [pbrt3 Eq. 15.32]

    // Multiple scattering: int_0^inf sigma_t' e^{-sigma_t' z} rho'^2 g(z) dz with g(z) the
    // total of the corrected dipole at depth z (ms_total_at_depth).
    const double l = 1 / sigma_t_r_;
    if (alpha_ > 0) {
        if (samples_ > 0) {
            for (int i = 0; i < samples_; ++i) {
                const double z = -std::log1p(-(i + 0.5) / samples_) / sigma_t_r_;
                total_ms_ += alpha_ * alpha_ * ms_total_at_depth(z);
            }
            total_ms_ /= samples_;
        } else {
            total_ms_ = diffusion_detail::integrate(
                [&](double x) {
                    const double z = std::exp(x);
                    return z * sigma_t_r_ * std::exp(-sigma_t_r_ * z) * alpha_ * alpha_ *
                           ms_total_at_depth(z);
                },
                diffusion_detail::log_breaks(1e-16 * l, 45 * l, {4 * a_ * d_, l}, 2.0), 1e-14);
        }
    }
    // Single scattering.
    if (rho_ > 0) {
        const double eta = m.eta, g = m.g;
        if (samples_ > 0) {
            // pbrt's rule has no closed-form total: integrate 2 pi r SS_N(r) dr in ln r.
            const double lt = 1 / sigma_t_;
            total_ss_ = diffusion_detail::integrate(
                [&](double x) {
                    const double r = std::exp(x);
                    return 2 * kPi * r * r * ss_samples(r);
                },
                diffusion_detail::log_breaks(1e-14 * lt, 60 * lt, {lt}, 2.0), 1e-13);
        } else {
            // 2 pi int_0^inf r E_ss(r) dr = 2 pi rho int_0^1 p(mu) (1 - F(mu)) mu/(1 + mu) dmu:
            // the depth integral of sigma_s e^{-sigma_t t (1 + 1/mu)} is rho mu/(1 + mu). Over the
            // angle inside (eta <= 1) or outside (eta > 1, where F = 1 below the critical angle):
            // mu dmu = sin(t) cos(t) dt / eta^2 for the transmitted angle t.
            const std::vector<double> features = {g < 0 ? 1 + g : 1.0};
            const double angular = diffusion_detail::integrate(
                [&](double x) {
                    const double th = std::exp(x), st = std::sin(th), ct = std::cos(th);
                    if (eta <= 1) {
                        const double f = fresnel_inside(ct, eta);
                        return th * phase_hg_pbrt(ct, g) * (1 - f) * ct * st / (1 + ct);
                    }
                    const double mu = std::sqrt(1 - st * st / (eta * eta));
                    const double f = fresnel_from_cosines(mu, ct, eta);
                    return th * phase_hg_pbrt(mu, g) * (1 - f) * st * ct / (eta * eta * (1 + mu));
                },
                diffusion_detail::log_breaks(1e-12, kPi / 2, features, 2.0), 1e-14);
            total_ss_ = 2 * kPi * rho_ * angular;
        }
    }
}

double PhotonBeamDiffusion::total_rd() const {
    switch (terms_) {
        case PbdTerms::multiple:
            return total_ms_;
        case PbdTerms::single:
            return total_ss_;
        case PbdTerms::both:
        default:
            return total_ms_ + total_ss_;
    }
}

double PhotonBeamDiffusion::eval_rd(double r) const {
    switch (terms_) {
        case PbdTerms::multiple:
            return rd_multiple(r);
        case PbdTerms::single:
            return rd_single(r);
        case PbdTerms::both:
        default:
            return rd_multiple(r) + rd_single(r);
    }
}

// z kappa (C_phi phi + C_E E) of the better dipole with its real source at depth z, kappa = 1 -
// e^{-2 sigma_t' (d_r + z)} (BeamDiffusionMS's integrand without rho'^2 and times z). Written with
// the ratios z/d_r, z/d_v, (d_r + z)/d_r and kappa/(d_r + z), all bounded, so that it is finite
// for r and z from 1e-320 to 1e300.
double PhotonBeamDiffusion::ms_at_depth(double r, double z) const {
    const double s = sigma_tr_;
    const double zv = z + 4 * a_ * d_;  // |z_v|, z_v = -z + 2 z_e [pbrt3 Eq. 15.28]
    const double dr = std::hypot(r, z), dv = std::hypot(r, zv);
    const double sum = dr + z, x = 2 * sigma_t_r_ * sum;
    const double kappa_per = x < 1e-300 ? 2 * sigma_t_r_ : 2 * sigma_t_r_ * (-std::expm1(-x) / x);
    // Fluence [pbrt3 Eq. 15.27]: (1/(4 pi D)) (e^{-s dr}/dr - e^{-s dv}/dv), dv - dr exactly.
    const double delta = (zv - z) * (zv + z) / (dv + dr);
    const double phi = (z / dr) * (sum / dv) * std::exp(-s * dr) *
                       (delta + dr * -std::expm1(-s * delta)) / (4 * kPi * d_);
    // -n.E: (1/(4 pi)) (z (1 + s dr) e^{-s dr}/dr^3 - z_v (1 + s dv) e^{-s dv}/dv^3), z_v < 0.
    const double e = ((z / dr) * (z / dr) * (sum / dr) * (1 + s * dr) * std::exp(-s * dr) +
                      (z / dv) * (sum / dv) * (zv / dv) * (1 + s * dv) * std::exp(-s * dv)) /
                     (4 * kPi);
    return kappa_per * (c_phi_ * phi + c_e_ * e);
}

double PhotonBeamDiffusion::rd_multiple(double r) const {
    if (!(r >= 0)) throw std::invalid_argument("pbd: r must be >= 0");
    if (alpha_ == 0 || std::isinf(r)) return 0.0;
    const double w = alpha_ * alpha_;
    if (samples_ > 0) {
        // BeamDiffusionMS: depths -ln(1 - (i + 1/2)/N)/sigma_t', weights 1/N.
        double sum = 0;
        for (int i = 0; i < samples_; ++i) {
            const double z = -std::log1p(-(i + 0.5) / samples_) / sigma_t_r_;
            sum += ms_at_depth(r, z) / z;
        }
        return w * sum / samples_;
    }
    // int_0^inf sigma_t' e^{-sigma_t' z} kappa E dz in ln z; the integrand (times z) vanishes
    // like z/r below z ~ r (what lies below 1e-12 r is ~1e-12 of the rest) and like
    // e^{-sigma_t' z} beyond 45 mean free paths. At r = 0 it tends to a constant at z -> 0: the
    // integral diverges logarithmically.
    if (r == 0) return kInf;
    const double l = 1 / sigma_t_r_;
    const double lo = 1e-12 * std::min(r, l), hi = 45 * l;
    return w * diffusion_detail::integrate(
                   [&](double x) {
                       const double z = std::exp(x);
                       return sigma_t_r_ * std::exp(-sigma_t_r_ * z) * ms_at_depth(r, z);
                   },
                   diffusion_detail::log_breaks(lo, hi, {r, l, 4 * a_ * d_}), 1e-10);
}

// BeamDiffusionSS with pbrt's N-point rule: t_i = t_crit - ln(1 - (i + 1/2)/N)/sigma_t.
double PhotonBeamDiffusion::ss_samples(double r) const {
    const DiffusionMedium& m = medium();
    const double t_crit = r * std::sqrt(std::max(0.0, m.eta * m.eta - 1));
    double sum = 0;
    for (int i = 0; i < samples_; ++i) {
        const double t = t_crit - std::log1p(-(i + 0.5) / samples_) / sigma_t_;
        const double d = std::hypot(r, t), mu = t / d;
        sum += rho_ * std::exp(-sigma_t_ * (d + t_crit)) / (d * d) * phase_hg_pbrt(mu, m.g) *
               (1 - fresnel_inside(mu, m.eta)) * mu;
    }
    return sum / samples_;
}

double PhotonBeamDiffusion::rd_single(double r) const {
    if (!(r >= 0)) throw std::invalid_argument("pbd: r must be >= 0");
    if (rho_ == 0 || std::isinf(r)) return 0.0;
    if (samples_ > 0) return ss_samples(r);
    if (r == 0) return kInf;  // E_ss ~ 1/r
    // E_ss(r) = int_0^inf sigma_s e^{-sigma_t (t + d)} p(mu) (1 - F(mu)) mu / d^2 dt, mu = t/d.
    // With theta the angle of the path to the exit point from the normal, t = r cot(theta),
    // d = r / sin(theta): E_ss = (sigma_s / r) int_0^{pi/2} e^{-sigma_t r cot(theta/2)} p (1 - F)
    // cos(theta) dtheta; for eta > 1 over the transmitted angle (cos(theta) dtheta = cos(theta_t)
    // dtheta_t / eta), which removes the total internal reflection range and the Fresnel kink.
    const DiffusionMedium& m = medium();
    const double eta = m.eta, g = m.g, sr = sigma_t_ * r;
    if (sr > 745) return 0.0;  // e^{-sigma_t r cot(theta/2)} <= e^{-sigma_t r}
    // Below theta ~ sigma_t r / 400 the exponential is below e^{-800}; below 1e-12 the rest of
    // the integrand contributes ~1e-12 of it.
    const double lo = std::min(std::max(sr / 400, 1e-12), 0.5);
    std::vector<double> features = {sr, 2 * sr};
    if (g < 0) features.push_back(1 + g);
    const double integral = diffusion_detail::integrate(
        [&](double x) {
            const double th = std::exp(x), st = std::sin(th), ct = std::cos(th);
            if (eta <= 1) {
                const double cot_half = (1 + ct) / st;
                return th * std::exp(-sr * cot_half) * phase_hg_pbrt(ct, g) *
                       (1 - fresnel_inside(ct, eta)) * ct;
            }
            const double si = st / eta, mu = std::sqrt(1 - si * si);
            const double cot_half = (1 + mu) / si;
            return th * std::exp(-sr * cot_half) * phase_hg_pbrt(mu, g) *
                   (1 - fresnel_from_cosines(mu, ct, eta)) * ct / eta;
        },
        diffusion_detail::log_breaks(eta > 1 ? std::min(lo * eta, 1.0) : lo, kPi / 2, features),
        1e-10);
    return m.sigma_s / r * integral;
}

// g(z) = int_0^inf 2 pi r kappa (C_phi phi + C_E E) dr for the real source at depth z: the
// uncorrected dipole's total in closed form minus the e^{-2 sigma_t' (d_r + z)} part, whose d_r
// terms are closed forms (an exponential and E1) and whose d_v terms are integrated over
// u = d_r in [z, inf) (r dr = u du), a smooth integrand on the scale 1/(2 sigma_t').
double PhotonBeamDiffusion::ms_total_at_depth(double z) const {
    const double s = sigma_tr_, st = sigma_t_r_;
    const double zv = z + 4 * a_ * d_;  // |z_v|
    // Uncorrected: 2 pi int e^{-s d}/d r dr = 2 pi e^{-s |z|}/s and 2 pi int z (1 + s d)
    // e^{-s d}/d^3 r dr = sgn(z) e^{-s |z|}.
    const double full_phi =
        std::exp(-s * z) * diffusion_detail::one_minus_exp_over(s, zv - z) / (2 * d_);
    const double full_e = 0.5 * (std::exp(-s * z) + std::exp(-s * zv));
    // Correction, real-source terms: 2 pi int_z^inf u e^{-2 st (u + z)} [(1/(4 pi D)) e^{-s u}/u
    // + (1/(4 pi)) z (1 + s u) e^{-s u}/u^3] du, with b = 2 st + s:
    //   phi: e^{-2 st z} e^{-b z} / (2 D b);  E: (1/2) e^{-2 st z} (e^{-b z} - 2 st z E1(b z)).
    const double b = 2 * st + s, ez = std::exp(-2 * st * z), ebz = std::exp(-b * z);
    const double corr_phi_r = ez * ebz / (2 * d_ * b);
    const double corr_e_r = 0.5 * ez * (ebz - 2 * st * z * diffusion_detail::expint_e1(b * z));
    // Virtual-source terms: -(1/(4 pi D)) e^{-s dv}/dv in phi, + (1/(4 pi)) |z_v| (1 + s dv)
    // e^{-s dv}/dv^3 in -n.E, dv^2 = u^2 - z^2 + z_v^2; u = z + y.
    const double gap2 = (zv - z) * (zv + z);
    const double corr_v = diffusion_detail::integrate(
        [&](double y) {
            const double u = z + y, dv = std::sqrt(u * u + gap2);
            const double ev = std::exp(-s * dv - 2 * st * (u + z));
            return 0.5 * u * ev * (-c_phi_ / (d_ * dv) + c_e_ * zv * (1 + s * dv) / (dv * dv * dv));
        },
        {0.0, 0.25 / st, 1 / st, 4 / st, 40 / st}, 1e-14,
        1e-16 * (c_phi_ * full_phi + c_e_ * full_e));
    return c_phi_ * (full_phi - corr_phi_r) + c_e_ * (full_e - corr_e_r) - corr_v;
}

}  // namespace ssslab::approx
