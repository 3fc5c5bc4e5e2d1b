// Diffusion profiles: medium validation, Fresnel moments, the common annulus average, the
// classical and better dipoles, normalized diffusion, the factory and parameter inversion.
// The multipole, quantized diffusion and photon beam diffusion live in their own files.
#include "approx/diffusion.h"

#include "approx/diffusion_detail.h"
#include "core/format.h"

#include <cmath>
#include <functional>
#include <stdexcept>

namespace ssslab::approx {

using diffusion_detail::kInf;
using diffusion_detail::kPi;

namespace {

// C_i = int_0^1 F(mu) mu^i dmu (i = 1, 2) by quadrature. For eta > 1 the total internal
// reflection part [0, mu_c] is mu_c^{i+1}/(i+1) and the rest is integrated over the transmitted
// cosine w (mu dmu = w dw / eta^2), in which F has no square-root kink at the critical angle.
double exact_moment(int i, double eta) {
    if (eta == 1.0) return 0.0;
    if (eta < 1) {
        return diffusion_detail::integrate(
            [&](double mu) { return diffusion_detail::fresnel_inside(mu, eta) * std::pow(mu, i); },
            {0.0, 0.25, 0.5, 0.75, 1.0}, 1e-14, 1e-17);
    }
    const double mu_c = std::sqrt(1 - 1 / (eta * eta));
    const double tir = std::pow(mu_c, i + 1) / (i + 1);
    const double rest = diffusion_detail::integrate(
        [&](double w) {
            const double mu = std::sqrt(1 - (1 - w * w) / (eta * eta));
            return diffusion_detail::fresnel_from_cosines(mu, w, eta) * std::pow(mu, i - 1) * w /
                   (eta * eta);
        },
        {0.0, 0.25, 0.5, 0.75, 1.0}, 1e-14, 1e-17);
    return tir + rest;
}

// pbrt's FresnelMoment1/2 (pbrt-v3 src/core/bssrdf.cpp), d'Eon's fits [dEon12].
double fit_moment1(double eta) {
    const double e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1)
        return 0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5;
    return -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5;
}

double fit_moment2(double eta) {
    const double e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1)
        return 0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5;
    const double r = 1 / eta, r2 = r * r, r3 = r2 * r;
    return -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * e2 +
           54.9327 * e3 - 9.00603 * e4 + 0.63942 * e5;
}

}  // namespace

// ---- Medium and Fresnel -------------------------------------------------------------------------

void validate(const DiffusionMedium& m, FresnelMoments fresnel) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("diffusion medium: " + what);
    };
    if (!(m.sigma_a >= 0) || !std::isfinite(m.sigma_a))
        fail("sigma_a must be finite and >= 0, got " + format_g(m.sigma_a, 17));
    if (!(m.sigma_s >= 0) || !std::isfinite(m.sigma_s))
        fail("sigma_s must be finite and >= 0, got " + format_g(m.sigma_s, 17));
    if (!(m.sigma_a + m.sigma_s > 0)) fail("sigma_a + sigma_s must be > 0");
    if (!(m.g > -1 && m.g < 1)) fail("g must be in (-1, 1), got " + format_g(m.g, 17));
    if (fresnel == FresnelMoments::fit && !(m.eta >= 0.25 && m.eta <= 2.5))
        fail("eta must be in [0.25, 2.5] with the papers' Fresnel fits, got " +
             format_g(m.eta, 17));
    if (fresnel == FresnelMoments::exact && !(m.eta > 0 && m.eta <= 10))
        fail("eta must be in (0, 10] with exact Fresnel moments, got " + format_g(m.eta, 17));
    if (!(m.thickness > 0)) fail("thickness must be > 0, got " + format_g(m.thickness, 17));
}

FresnelMomentPair fresnel_moments(double eta, FresnelMoments mode) {
    if (mode == FresnelMoments::fit) return {fit_moment1(eta), fit_moment2(eta)};
    return {exact_moment(1, eta), exact_moment(2, eta)};
}

double fresnel_diffuse_reflectance(double eta, FresnelMoments mode) {
    if (mode == FresnelMoments::exact) return 2 * exact_moment(1, eta);
    // [Bitterli13 Eq. 2.30] (Egan & Hilgeman, as [Jensen01]); fitted for internal reflection with
    // total internal reflection, eta >= 1. Below, d'Eon's fit of 2 C1.
    if (eta >= 1) return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    return 2 * fit_moment1(eta);
}

double classical_reflection_parameter(double eta, FresnelMoments mode) {
    const double fdr = fresnel_diffuse_reflectance(eta, mode);
    return (1 + fdr) / (1 - fdr);
}

double better_reflection_parameter(double eta, FresnelMoments mode) {
    const FresnelMomentPair c = fresnel_moments(eta, mode);
    return (1 + 3 * c.c2) / (1 - 2 * c.c1);
}

double normal_incidence_transmittance(double eta) {
    const double r = (eta - 1) / (eta + 1);
    return 1 - r * r;
}

// ---- DiffusionProfile ---------------------------------------------------------------------------

double DiffusionProfile::rd(double r) const {
    if (!(r >= 0))
        throw std::invalid_argument("diffusion profile: r must be >= 0, got " + format_g(r, 17));
    if (std::isinf(r)) return 0.0;
    return eval_rd(r);
}

double DiffusionProfile::annulus_mean(double r0, double r1) const {
    if (!(r0 >= 0 && r1 > r0 && std::isfinite(r1)))
        throw std::invalid_argument("annulus_mean: need 0 <= r0 < r1 < inf, got r0 = " +
                                    format_g(r0, 17) + ", r1 = " + format_g(r1, 17));
    // int 2 pi r R dr = int 2 pi r^2 R d(ln r): smooth in ln r for R ~ r^-p, p < 2.
    const double tol = std::max(1e-10, rd_accuracy());
    double integral;
    if (r0 == 0) {
        // r = r1 e^{-s}, s in [0, 64]: every profile here is O(1/r) at 0, so the disc of radius
        // r1 e^{-64} holds less than e^{-64} of the annulus.
        integral = diffusion_detail::integrate(
            [&](double s) {
                const double r = r1 * std::exp(-s);
                return 2 * kPi * r * r * eval_rd(r);
            },
            {0, 0.5, 1, 2, 4, 8, 16, 32, 64}, tol);
    } else {
        const double span = std::log(r1 / r0);
        const int n = std::max(1, static_cast<int>(std::ceil(span / 0.5)));
        std::vector<double> breaks;
        for (int k = 0; k <= n; ++k) breaks.push_back(span * k / n);
        integral = diffusion_detail::integrate(
            [&](double s) {
                const double r = std::min(r0 * std::exp(s), r1);
                return 2 * kPi * r * r * eval_rd(r);
            },
            breaks, tol);
    }
    return integral / (kPi * (r1 - r0) * (r1 + r0));
}

// ---- Classical dipole [Jensen01; Bitterli13 §2.5] -----------------------------------------------

ClassicalDipole::ClassicalDipole(const DiffusionMedium& m, const DiffusionOptions& o)
    : DiffusionProfile(m) {
    validate(m, o.fresnel);
    const double st = m.sigma_t_reduced();
    alpha_ = m.reduced_albedo();
    const double d = 1 / (3 * st);              // [Bitterli13 Eq. 2.22]
    sigma_tr_ = std::sqrt(3 * m.sigma_a * st);  // sqrt(sigma_a / D)
    a_ = classical_reflection_parameter(m.eta, o.fresnel);
    zr_ = 1 / st;            // [Bitterli13 Eq. 2.35]
    zv_ = zr_ + 4 * a_ * d;  // image above z_b = 2 A D
}

double ClassicalDipole::eval_rd(double r) const {
    if (alpha_ == 0) return 0.0;
    // z (1 + s d) e^{-s d} / d^3 as ratios, so that r -> 0 or r -> inf neither overflows.
    auto pole = [&](double z) {
        const double d = std::hypot(r, z);
        return (z / d) / d / d * (1 + sigma_tr_ * d) * std::exp(-sigma_tr_ * d);
    };
    return alpha_ / (4 * kPi) * (pole(zr_) + pole(zv_));  // [Bitterli13 Eq. 2.37]
}

double ClassicalDipole::total_rd() const {
    // [JB02; Bitterli13 Eq. 3.2]: 2 pi int z (1 + s d) e^{-s d}/d^3 r dr = e^{-s z}.
    return 0.5 * alpha_ * (std::exp(-sigma_tr_ * zr_) + std::exp(-sigma_tr_ * zv_));
}

// ---- Better dipole [dEon12] ---------------------------------------------------------------------

BetterDipole::BetterDipole(const DiffusionMedium& m, const DiffusionOptions& o)
    : DiffusionProfile(m) {
    validate(m, o.fresnel);
    const double st = m.sigma_t_reduced();
    alpha_ = m.reduced_albedo();
    d_ = (2 * m.sigma_a + m.sigma_s_reduced()) / (3 * st * st);  // Grosjean [pbrt3 Eq. 15.24]
    sigma_tr_ = std::sqrt(m.sigma_a / d_);
    const FresnelMomentPair c = fresnel_moments(m.eta, o.fresnel);
    a_ = (1 + 3 * c.c2) / (1 - 2 * c.c1);
    c_phi_ = 0.25 * (1 - 2 * c.c1);  // [pbrt3 Eq. 15.31]
    c_e_ = 0.5 * (1 - 3 * c.c2);     // [pbrt3 Eq. 15.32]
    zr_ = 1 / st;
    zv_ = -zr_ - 4 * a_ * d_;  // z_v = -z_r - 2 z_b, z_b = 2 A D [pbrt3 Eq. 15.28]
}

double BetterDipole::eval_rd(double r) const {
    if (alpha_ == 0) return 0.0;
    const double s = sigma_tr_;
    const double dr = std::hypot(r, zr_), dv = std::hypot(r, zv_);
    // Fluence: e^{-s dr}/dr - e^{-s dv}/dv without cancellation, dv - dr = (zv^2 - zr^2)/(dv + dr).
    const double delta = (-zv_ - zr_) * (-zv_ + zr_) / (dv + dr);
    const double phi = std::exp(-s * dr) * (delta + dr * -std::expm1(-s * delta)) / (dr * dv) / d_;
    // Vector irradiance -n.E: zr (1 + s dr) e^{-s dr}/dr^3 - zv (1 + s dv) e^{-s dv}/dv^3.
    const double e = (zr_ / dr) / dr / dr * (1 + s * dr) * std::exp(-s * dr) -
                     (zv_ / dv) / dv / dv * (1 + s * dv) * std::exp(-s * dv);
    return alpha_ * alpha_ / (4 * kPi) * (c_phi_ * phi + c_e_ * e);
}

double BetterDipole::total_rd() const {
    // 2 pi int e^{-s d}/d r dr = 2 pi e^{-s |z|}/s, 2 pi int z (1 + s d) e^{-s d}/d^3 r dr =
    // sgn(z) e^{-s |z|} (as in Hery's reparameterisation of the better dipole).
    const double s = sigma_tr_, gap = 4 * a_ * d_;  // |z_v| - z_r
    const double er = std::exp(-s * zr_);
    return 0.5 * alpha_ * alpha_ * er *
           (c_e_ * (1 + std::exp(-s * gap)) +
            c_phi_ / d_ * diffusion_detail::one_minus_exp_over(s, gap));
}

// ---- Normalized diffusion [CB15] ----------------------------------------------------------------

NormalizedDiffusion::NormalizedDiffusion(const DiffusionMedium& m, BurleyFit fit,
                                         const DiffusionOptions& o)
    : DiffusionProfile(m), fit_(fit) {
    validate(m, o.fresnel);
    if (o.surface_albedo) {
        a_ = *o.surface_albedo;
        if (!(a_ >= 0 && a_ <= 1))
            throw std::invalid_argument("burley: surface_albedo must be in [0, 1], got " +
                                        format_g(a_, 17));
    } else {
        DiffusionOptions pbd = o;
        pbd.pbd_terms = PbdTerms::both;
        a_ = PhotonBeamDiffusion(m, pbd).total_rd();
    }
    double s, l;
    switch (fit_) {
        case BurleyFit::searchlight:  // [CB15 Eq. 5]
            s = 1.85 - a_ + 7 * std::pow(std::abs(a_ - 0.8), 3);
            l = 1 / m.sigma_t_reduced();
            break;
        case BurleyFit::diffuse:  // [CB15 §4]
            s = 1.9 - a_ + 3.5 * (a_ - 0.8) * (a_ - 0.8);
            l = 1 / m.sigma_t_reduced();
            break;
        case BurleyFit::dmfp:  // [CB15 Eq. 8]
        default:
            s = 3.5 + 100 * std::pow(a_ - 0.33, 4);
            l = diffuse_mean_free_path(m, TransportDefinition::grosjean);
            break;
    }
    d_ = l / s;
}

std::string NormalizedDiffusion::name() const {
    switch (fit_) {
        case BurleyFit::searchlight:
            return "burley-searchlight";
        case BurleyFit::diffuse:
            return "burley-diffuse";
        case BurleyFit::dmfp:
        default:
            return "burley-dmfp";
    }
}

double NormalizedDiffusion::eval_rd(double r) const {
    if (a_ == 0 || std::isinf(d_)) return 0.0;
    if (r == 0) return kInf;
    // [CB15 Eq. 2]: A (e^{-r/d} + e^{-r/(3d)}) / (8 pi d r).
    return a_ / (8 * kPi * d_) * ((std::exp(-r / d_) + std::exp(-r / (3 * d_))) / r);
}

// ---- Factory ------------------------------------------------------------------------------------

namespace {

using Builder = std::function<std::unique_ptr<DiffusionProfile>(const DiffusionMedium&,
                                                                const DiffusionOptions&)>;

const std::vector<std::pair<std::string, Builder>>& builders() {
    static const std::vector<std::pair<std::string, Builder>> table = {
        {"dipole",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<ClassicalDipole>(m, o);
         }},
        {"better-dipole",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<BetterDipole>(m, o);
         }},
        {"multipole", [](const DiffusionMedium& m,
                         const DiffusionOptions& o) { return std::make_unique<Multipole>(m, o); }},
        {"qd",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<QuantizedDiffusion>(m, o);
         }},
        {"pbd",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<PhotonBeamDiffusion>(m, o);
         }},
        {"burley-searchlight",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<NormalizedDiffusion>(m, BurleyFit::searchlight, o);
         }},
        {"burley-diffuse",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<NormalizedDiffusion>(m, BurleyFit::diffuse, o);
         }},
        {"burley-dmfp",
         [](const DiffusionMedium& m, const DiffusionOptions& o) {
             return std::make_unique<NormalizedDiffusion>(m, BurleyFit::dmfp, o);
         }},
    };
    return table;
}

}  // namespace

const std::vector<std::string>& diffusion_model_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> n;
        for (const auto& b : builders()) n.push_back(b.first);
        return n;
    }();
    return names;
}

std::unique_ptr<DiffusionProfile> make_diffusion_profile(const std::string& name,
                                                         const DiffusionMedium& m,
                                                         const DiffusionOptions& o) {
    for (const auto& b : builders())
        if (b.first == name) return b.second(m, o);
    std::string known;
    for (const auto& n : diffusion_model_names()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown diffusion model '" + name + "'; known models: " + known);
}

// ---- Parameter inversion [Bitterli13 §3.4] ------------------------------------------------------

double diffuse_mean_free_path(const DiffusionMedium& m, TransportDefinition def) {
    if (m.sigma_a == 0) return kInf;
    const double st = m.sigma_t_reduced();
    if (def == TransportDefinition::classical) return 1 / std::sqrt(3 * m.sigma_a * st);
    const double d = (2 * m.sigma_a + m.sigma_s_reduced()) / (3 * st * st);
    return std::sqrt(d / m.sigma_a);
}

DiffusionMedium invert_diffusion_parameters(const std::string& name, const InversionTarget& t,
                                            const DiffusionOptions& o, TransportDefinition def) {
    if (!(t.ld > 0) || !std::isfinite(t.ld))
        throw std::invalid_argument("inversion: ld must be finite and > 0, got " +
                                    format_g(t.ld, 17));
    if (!std::isfinite(t.total_rd))
        throw std::invalid_argument("inversion: total_rd must be finite");
    // The medium of reduced albedo 1 - q, q = e^x: [Bitterli13 Eq. 3.3-3.5].
    auto medium = [&](double x) {
        const double q = std::exp(x), alpha = -std::expm1(x);
        const double st = def == TransportDefinition::classical
                              ? 1 / (t.ld * std::sqrt(3 * q))
                              : 1 / (t.ld * std::sqrt(3 * q / (1 + q)));
        DiffusionMedium m;
        m.sigma_a = q * st;
        m.sigma_s = alpha * st / (1 - t.g);
        m.g = t.g;
        m.eta = t.eta;
        m.thickness = t.thickness;
        return m;
    };
    auto total = [&](double x) { return make_diffusion_profile(name, medium(x), o)->total_rd(); };
    // The grid: alpha' = 0, 0.1, ..., 0.9, then ln q evenly down to ln 2^-52.
    std::vector<double> xs;
    for (int k = 0; k < 10; ++k) xs.push_back(std::log1p(-0.1 * k));
    const double x_min = -52 * std::log(2.0), x_09 = std::log(0.1);
    for (int k = 1; k <= 15; ++k) xs.push_back(x_09 + (x_min - x_09) * k / 15);
    std::vector<double> rs;
    for (double x : xs) rs.push_back(total(x));
    for (size_t k = 1; k < xs.size(); ++k) {
        if (rs[k] > rs[k - 1]) continue;
        const std::string a0 = format_g(-std::expm1(xs[k - 1]), 17),
                          a1 = format_g(-std::expm1(xs[k]), 17);
        throw std::domain_error("inversion: R_dr of model '" + name +
                                "' is not strictly increasing in the reduced albedo: R_dr(" + a0 +
                                ") = " + format_g(rs[k - 1], 17) + ", R_dr(" + a1 + ") = " +
                                format_g(rs[k], 17) + "; the inversion would be ambiguous");
    }
    if (!(t.total_rd >= rs.front() && t.total_rd <= rs.back()))
        throw std::invalid_argument(
            "inversion: total_rd = " + format_g(t.total_rd, 17) + " is outside the range [" +
            format_g(rs.front(), 17) + ", " + format_g(rs.back(), 17) + "] model '" + name +
            "' attains for g = " + format_g(t.g, 17) + ", eta = " + format_g(t.eta, 17));
    size_t k = 1;
    while (k + 1 < xs.size() && rs[k] < t.total_rd) ++k;
    const double x =
        diffusion_detail::brent([&](double xx) { return total(xx) - t.total_rd; }, xs[k - 1], xs[k],
                                rs[k - 1] - t.total_rd, rs[k] - t.total_rd, 0.0);
    DiffusionMedium m = medium(x);
    validate(m, o.fresnel);
    return m;
}

DiffusionMedium diffusion_medium(const Medium& m, int c, LengthUnit unit) {
    require_homogeneous(m, "the diffusion models");
    const double per_cm = unit == LengthUnit::kMm ? 10.0 : 1.0;  // unit lengths per cm
    DiffusionMedium d;
    d.sigma_a = m.sigma_a_per_cm[c] / per_cm;
    d.sigma_s = m.sigma_s_per_cm[c] / per_cm;
    d.g = m.g[c];
    d.eta = m.eta / m.eta_above;
    d.thickness =
        m.thickness_cm >= 1e8 ? std::numeric_limits<double>::infinity() : m.thickness_cm * per_cm;
    return d;
}

}  // namespace ssslab::approx
