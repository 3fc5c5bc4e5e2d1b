// Analytic diffusion reflectance profiles and their parameter inversion.
//
// Every model gives the radial diffuse reflectance profile R_d(r) [1/L^2] of a homogeneous medium
// lit at the origin by a unit-power pencil beam at normal incidence, and its total diffuse
// reflectance R_dr = 2 pi int_0^inf R_d(r) r dr [-]. Lengths are in any unit L: the coefficients
// are in 1/L and r is in L (ssslab's profiles use mm or cm; the caller converts).
//
// Conventions, per model (the flags of DiffusionProfile state them so callers compare like with
// like; the Monte Carlo engines count reflectance per *incident* photon, including the entry
// Fresnel factor 1 - R_sp, and include single scattering):
//
//   name                  single scattering   entry Fresnel   boundary (A)
//   dipole                no                  no              A = (1 + F_dr) / (1 - F_dr)
//   better-dipole         no                  no              A = (1 + 3 C2) / (1 - 2 C1)
//   multipole             no                  no              as dipole (both faces)
//   qd                    no                  no              as better-dipole
//   pbd                   yes (see PbdTerms)  no              as better-dipole, exact Fresnel (SS)
//   burley-*              yes (fit to MC)     no              via the surface albedo A
//
// "No entry Fresnel" means: R_d is per unit power *entering* the medium (the refracted beam);
// multiply by normal_incidence_transmittance(eta) for reflectance per incident photon. Every
// profile includes the exit through the boundary (it is the radiant exitance leaving the surface).
// F_dr, C1, C2 are internal (light inside the medium meets the boundary) and eta is the index of
// the medium over the index outside, on both faces of a slab.
//
// Papers: [Jensen01] Jensen, Marschner, Levoy, Hanrahan, A practical model for subsurface light
// transport, SIGGRAPH 2001; [JB02] Jensen, Buhler 2002; [Bitterli13] (papers/README.md);
// [dEon12] d'Eon, A better dipole, 2012; [DJ05] Donner, Jensen, Light diffusion in multi-layered
// translucent materials, SIGGRAPH 2005; [dEonIrving11] d'Eon, Irving, A quantized-diffusion model
// for rendering translucent materials, SIGGRAPH 2011; [Habel13] Habel, Christensen, Jarosz, Photon
// beam diffusion, EGSR 2013, as pbrt-v3/v4 implement it (src/core/bssrdf.cpp, src/pbrt/bssrdf.cpp:
// BeamDiffusionMS, BeamDiffusionSS, FresnelMoment1/2; equation numbers [pbrt3 Eq. 15.x] are the
// book's, as pbrt's comments cite them); [CB15] Christensen, Burley, Approximate reflectance
// profiles for efficient subsurface scattering, Pixar 2015.
#pragma once

#include "core/material.h"
#include "core/profile.h"

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::approx {

// ---- Medium and options -------------------------------------------------------------------------

/// A homogeneous medium for the diffusion models; any length unit L.
struct DiffusionMedium {
    double sigma_a = 0;  ///< absorption coefficient [1/L], >= 0
    double sigma_s = 0;  ///< scattering coefficient [1/L], >= 0; sigma_a + sigma_s > 0
    double g = 0;        ///< Henyey-Greenstein mean cosine [-], -1 < g < 1
    double eta = 1;      ///< index of the medium / index outside [-], see validate()
    /// Slab thickness [L]: the multipole's; every other model is semi-infinite and ignores it.
    double thickness = std::numeric_limits<double>::infinity();

    /// Reduced scattering coefficient sigma_s' = sigma_s (1 - g) [1/L] (the similarity relation
    /// through which every diffusion model sees g).
    double sigma_s_reduced() const { return sigma_s * (1 - g); }
    /// Reduced extinction sigma_t' = sigma_a + sigma_s' [1/L]; 1/sigma_t' is the reduced mean
    /// free path.
    double sigma_t_reduced() const { return sigma_a + sigma_s_reduced(); }
    /// Reduced albedo alpha' = sigma_s' / sigma_t' [-].
    double reduced_albedo() const { return sigma_s_reduced() / sigma_t_reduced(); }
    /// Single-scattering albedo sigma_s / (sigma_a + sigma_s) [-].
    double albedo() const { return sigma_s / (sigma_a + sigma_s); }
};

/// How the models get the Fresnel moments C_i = int_0^1 F_r(eta, mu) mu^i dmu of the inside of
/// the boundary (F_dr = 2 C1).
enum class FresnelMoments {
    /// The papers' polynomial fits: F_dr of Egan & Hilgeman [Jensen01; Bitterli13 Eq. 2.30] for
    /// eta >= 1 (for eta < 1, where that fit does not apply, d'Eon's fit of 2 C1), C1 and C2 of
    /// d'Eon [dEon12] as pbrt's FresnelMoment1/2. Valid for 0.25 <= eta <= 2.5.
    fit,
    /// The angular integrals of the exact unpolarised Fresnel reflectance, by quadrature; any eta.
    exact,
};

/// Where the multipole puts its real source.
enum class MultipoleSource {
    /// [DJ05]: a source of strength alpha' at depth 1/sigma_t'. Valid only when the slab is
    /// thicker than 1/sigma_t' (std::invalid_argument otherwise).
    paper,
    /// The first-collision distribution truncated to the slab: strength alpha' (1 - e^{-sigma_t'
    /// d}) at the mean collision depth inside, 1/sigma_t' - d / (e^{sigma_t' d} - 1). Equal to
    /// `paper` up to terms in e^{-sigma_t' d}; stays physical (R, T -> 0) for thin slabs.
    truncated,
};

/// Which scattering orders the photon-beam-diffusion profile contains.
enum class PbdTerms {
    both,      ///< BeamDiffusionMS + BeamDiffusionSS (pbrt's tabulated profile)
    multiple,  ///< BeamDiffusionMS only
    single,    ///< BeamDiffusionSS only
};

/// Definition of the effective transport coefficient sigma_tr, and so of the diffuse mean free
/// path l_d = 1 / sigma_tr, for parameter inversion.
enum class TransportDefinition {
    classical,  ///< sigma_tr = sqrt(3 sigma_a sigma_t') [Jensen01; Bitterli13 Eq. 3.3]
    grosjean,   ///< sigma_tr = sqrt(sigma_a / D_G), D_G = (2 sigma_a + sigma_s') / (3 sigma_t'^2)
};

/// Options of the models; each model reads its own part. Defaults follow the papers.
struct DiffusionOptions {
    /// dipole, multipole, better-dipole, qd, pbd (multiple scattering).
    FresnelMoments fresnel = FresnelMoments::fit;
    /// multipole
    MultipoleSource multipole_source = MultipoleSource::truncated;
    /// qd: ratio of consecutive quantisation times, t_{i+1} = ratio t_i (the golden ratio, as
    /// implementations of [dEonIrving11] use); > 1.
    double qd_ratio = 1.6180339887498949;
    /// qd: standard deviation of the first (narrowest) Gaussian in reduced mean free paths
    /// 1/sigma_t'; it bounds the resolution of the profile near r = 0. > 0.
    double qd_first_width = 1e-3;
    /// pbd: scattering orders in rd() and total_rd().
    PbdTerms pbd_terms = PbdTerms::both;
    /// pbd: 0 integrates the beam (depth) integrals to convergence (1e-10); N > 0 uses pbrt's
    /// N-point midpoint rule in the exponential CDF (pbrt uses 100) for bit-level comparisons
    /// with pbrt's tables.
    int pbd_depth_samples = 0;
    /// burley-*: the surface albedo A [-] (total diffuse reflectance, single scattering
    /// included). Unset: A = the pbd model's total (multiple + single scattering) for the same
    /// medium and options (fresnel, pbd_depth_samples), per entering photon.
    std::optional<double> surface_albedo;
};

/// Throws std::invalid_argument naming the field unless sigma_a, sigma_s >= 0 and finite,
/// sigma_a + sigma_s > 0, -1 < g < 1, 0 < eta (<= 2.5 and >= 0.25 with FresnelMoments::fit,
/// <= 10 with exact), thickness > 0 (infinity allowed).
void validate(const DiffusionMedium& m, FresnelMoments fresnel);

// ---- Fresnel helpers ----------------------------------------------------------------------------

/// The Fresnel moments C1, C2 of the inside of the boundary [-].
struct FresnelMomentPair {
    double c1 = 0, c2 = 0;
};
/// C1(eta), C2(eta) by `mode` (FresnelMoments::fit: pbrt's FresnelMoment1/2, d'Eon's fits).
FresnelMomentPair fresnel_moments(double eta, FresnelMoments mode);
/// Internal diffuse Fresnel reflectance F_dr(eta) [-]: the fit of FresnelMoments::fit
/// (Egan & Hilgeman [Bitterli13 Eq. 2.30] for eta >= 1), or 2 C1 exactly.
double fresnel_diffuse_reflectance(double eta, FresnelMoments mode);
/// Classical internal reflection parameter A = (1 + F_dr) / (1 - F_dr) [Jensen01].
double classical_reflection_parameter(double eta, FresnelMoments mode);
/// Moment-based internal reflection parameter A = (1 + 3 C2) / (1 - 2 C1) [dEon12].
double better_reflection_parameter(double eta, FresnelMoments mode);
/// Fresnel transmittance 1 - R_sp at normal incidence, R_sp = ((eta - 1) / (eta + 1))^2 [-]:
/// the factor from reflectance per entering photon to reflectance per incident photon.
double normal_incidence_transmittance(double eta);

// ---- Profiles -----------------------------------------------------------------------------------

/// A radial diffuse reflectance profile of one medium (a value type once built; thread-safe).
class DiffusionProfile {
  public:
    virtual ~DiffusionProfile() = default;
    /// The factory name ("dipole", "better-dipole", ...).
    virtual std::string name() const = 0;
    /// R_d(r) [1/L^2] at distance r >= 0 [L] from the point of incidence, per unit power
    /// entering. Finite for r > 0 (underflows to 0 for large r); at r = 0 finite for dipole,
    /// better-dipole, multipole, qd, and +infinity where the model diverges there (pbd: R ~ 1/r
    /// from single and ~log(1/r) from multiple scattering; burley: ~1/r); 0 at r = +inf. Throws
    /// std::invalid_argument for r < 0 or NaN.
    double rd(double r) const;
    /// R_dr = 2 pi int_0^inf R_d(r) r dr [-], per unit power entering.
    virtual double total_rd() const = 0;
    /// Whether R_d contains single scattering.
    virtual bool includes_single_scattering() const = 0;
    /// Whether R_d carries the entry Fresnel factor 1 - R_sp (false for every model here).
    virtual bool includes_entry_fresnel() const { return false; }
    /// The area average (int_{r0}^{r1} R_d 2 pi r dr) / (pi (r1^2 - r0^2)) [1/L^2] over the
    /// annulus 0 <= r0 < r1 < inf: what a Monte Carlo radial bin measures. Adaptive Gauss-Kronrod
    /// in ln r (r = r1 e^{-s}, s in [0, 64] for r0 = 0), so the integrable singularities at 0 of
    /// the models here (1/r, log(1/r)) are integrated accurately; relative accuracy 1e-10 (or
    /// rd_accuracy(), if coarser).
    double annulus_mean(double r0, double r1) const;
    /// The medium the profile was built for.
    const DiffusionMedium& medium() const { return medium_; }
    /// The relative accuracy of rd()'s values where it is coarser than double's (0 here): a
    /// model evaluated in float (a .bssrdf file's GLSL, approx/tabulated_profile.h). Integrals of
    /// the profile (annulus_mean, integrate_sphere) are not refined below it: the adaptive
    /// quadratures would otherwise chase the table's interpolation to 1e-10.
    virtual double rd_accuracy() const { return 0; }

  protected:
    explicit DiffusionProfile(const DiffusionMedium& m) : medium_(m) {}
    /// R_d(r) for a validated r >= 0.
    virtual double eval_rd(double r) const = 0;

  private:
    DiffusionMedium medium_;
};

/// Classical dipole [Jensen01; Bitterli13 Eq. 2.33-2.37]: D = 1/(3 sigma_t'), sigma_tr =
/// sqrt(3 sigma_a sigma_t'), real source alpha' at z_r = 1/sigma_t', image at z_v = z_r + 4 A D,
/// R_d(r) = alpha'/(4 pi) [z_r (1 + sigma_tr d_r) e^{-sigma_tr d_r}/d_r^3
///                          + z_v (1 + sigma_tr d_v) e^{-sigma_tr d_v}/d_v^3],
/// R_dr = (alpha'/2)(e^{-sigma_tr z_r} + e^{-sigma_tr z_v}) [JB02; Bitterli13 Eq. 3.2].
/// Finite everywhere, also at alpha' = 1 (R_d ~ 1/r^3 for large r, R_dr = 1).
class ClassicalDipole final : public DiffusionProfile {
  public:
    ClassicalDipole(const DiffusionMedium& m, const DiffusionOptions& o = {});
    std::string name() const override { return "dipole"; }
    double total_rd() const override;
    bool includes_single_scattering() const override { return false; }
    /// The internal reflection parameter A in use.
    double reflection_parameter() const { return a_; }

  private:
    double eval_rd(double r) const override;
    double alpha_, sigma_tr_, zr_, zv_, a_;
};

/// d'Eon's better dipole [dEon12] (as pbrt's BeamDiffusionMS uses it per depth, and appleseed's
/// better_dipole_bssrdf): Grosjean's D = (2 sigma_a + sigma_s') / (3 sigma_t'^2), sigma_tr =
/// sqrt(sigma_a / D), z_r = 1/sigma_t', z_b = 2 A D with A = (1 + 3 C2)/(1 - 2 C1), image at
/// z_v = -z_r - 2 z_b, exitance C_phi phi + C_E E with C_phi = (1 - 2 C1)/4, C_E = (1 - 3 C2)/2
/// [pbrt3 Eq. 15.31, 15.32] and Grosjean's factor alpha' on the source (alpha'^2 in all):
/// R_d(r) = alpha'^2/(4 pi) [K(z_r, d_r) - K(z_v, d_v)],
/// K(z, d) = (C_E z (1 + sigma_tr d)/d^2 + C_phi/D) e^{-sigma_tr d}/d.
/// The BSSRDF's angular factor 1/(4 C_phi(1/eta)) [dEon12] normalises the directional
/// distribution of the exiting radiance and is not part of the radial exitance R_d.
/// R_dr = (alpha'^2/2) e^{-sigma_tr z_r} [C_E (1 + e^{-4 A D sigma_tr})
///                                        + C_phi (1 - e^{-4 A D sigma_tr}) / (D sigma_tr)].
class BetterDipole final : public DiffusionProfile {
  public:
    BetterDipole(const DiffusionMedium& m, const DiffusionOptions& o = {});
    std::string name() const override { return "better-dipole"; }
    double total_rd() const override;
    bool includes_single_scattering() const override { return false; }
    /// The internal reflection parameter A in use.
    double reflection_parameter() const { return a_; }

  private:
    double eval_rd(double r) const override;
    double alpha_, d_, sigma_tr_, zr_, zv_, a_, c_phi_, c_e_;
};

/// Multipole of a slab of thickness d [DJ05] with the classical dipole's constants (D, sigma_tr,
/// A from F_dr, the same boundary on both faces): the real source at z_0 and its images about the
/// extrapolated boundaries z = -z_b and z = d + z_b, z_b = 2 A D, at z_{r,i} = i P + z_0 and
/// z_{v,i} = i P - z_0 - 2 z_b, P = 2 (d + 2 z_b), i in Z:
/// R_d(r) = a/(4 pi) sum_i [z_{r,i} f(d_{r,i}) - z_{v,i} f(d_{v,i})], f(d) = (1 + sigma_tr d)
/// e^{-sigma_tr d}/d^3, and T_d(r) the same with d - z in place of z (distances to the bottom).
/// Evaluated by the image sum (with an Euler-Maclaurin tail) for r below half the extrapolated
/// thickness L = d + 2 z_b and beyond by the equivalent eigenmode expansion (a/(pi L)) sum_n k_n
/// cos(k_n z_b) sin(k_n (z_0 + z_b)) K0(kappa_n r), k_n = n pi / L, kappa_n^2 = sigma_tr^2 + k_n^2,
/// or the image sum, whichever cancels less; totals in closed form (geometric sums of the poles'
/// e^{-sigma_tr |z|}). For an infinite thickness (>= 1e300) it is the classical dipole.
class Multipole final : public DiffusionProfile {
  public:
    Multipole(const DiffusionMedium& m, const DiffusionOptions& o = {});
    std::string name() const override { return "multipole"; }
    double total_rd() const override { return total_r_; }
    bool includes_single_scattering() const override { return false; }
    /// Diffuse transmittance profile T_d(r) [1/L^2] at the bottom face, r from the point below
    /// the point of incidence; 0 for an infinite slab.
    double td(double r) const;
    /// Total diffuse transmittance T_dt = 2 pi int T_d r dr [-].
    double total_td() const { return total_t_; }

  private:
    struct Series {
        double value = 0, magnitude = 0;  ///< the sum and the sum of |terms|
        /// magnitude / |value| (1 for an empty sum): the rounding error's amplification.
        double cancellation() const {
            if (magnitude == 0) return 1;
            return value == 0 ? std::numeric_limits<double>::infinity()
                              : magnitude / std::abs(value);
        }
    };
    double eval_rd(double r) const override;
    double profile(double r, bool transmit) const;
    Series image_sum(double r, double c1, double c2) const;
    Series mode_sum(double r, bool transmit) const;
    double alpha_, sigma_tr_, zb_, z0_, strength_, d_, total_r_ = 0, total_t_ = 0;
};

/// Quantized diffusion [dEonIrving11] for the semi-infinite medium, with the better dipole's
/// boundary (D, A, C_phi, C_E, Grosjean's alpha'^2). The time-resolved diffusion Green's function
/// is a 3D Gaussian of variance 2 D tau per axis times e^{-sigma_a tau} (tau = c t, a length);
/// time is quantised into [tau_i, tau_{i+1}], tau_0 = 0, tau_{i+1} = qd_ratio tau_i, and in each
/// interval the Gaussians take the variance v_i = D (tau_i + tau_{i+1}) while the absorption is
/// integrated exactly, w_i = (e^{-sigma_a tau_i} - e^{-sigma_a tau_{i+1}})/sigma_a. The extended
/// source alpha' sigma_t' e^{-sigma_t' z} is integrated analytically against the depth Gaussian and
/// its image (erfc terms), giving the exitance weight W(v) = C_phi (w_phi(v, 0) - w_phi(v, 2 z_b))
/// + C_E D (w_E(v, 0) + w_E(v, 2 z_b)):
/// R_d(r) = alpha' sum_i w_i W(v_i) e^{-r^2/(2 v_i)} / (2 pi v_i), a sum of 2D Gaussians.
/// Quantisation and truncation follow `qd_ratio`, `qd_first_width`; the sum stops when the rest
/// is below 1e-16 of it. R_dr = alpha' sum_i w_i W(v_i) exactly (each Gaussian has unit mass).
class QuantizedDiffusion final : public DiffusionProfile {
  public:
    QuantizedDiffusion(const DiffusionMedium& m, const DiffusionOptions& o = {});
    std::string name() const override { return "qd"; }
    double total_rd() const override { return total_; }
    bool includes_single_scattering() const override { return false; }
    /// The Gaussians' weights alpha' w_i W(v_i) [-], summing to R_dr, in the order of time.
    const std::vector<double>& weights() const { return weights_; }
    /// The Gaussians' variances v_i per axis [L^2], increasing.
    const std::vector<double>& variances() const { return variances_; }

  private:
    double eval_rd(double r) const override;
    std::vector<double> weights_, variances_;
    double total_ = 0;
};

/// Photon beam diffusion [Habel13] as pbrt-v3/v4 implement it. Multiple scattering
/// (BeamDiffusionMS): better dipoles along the refracted beam, real source depth z with density
/// sigma_t' e^{-sigma_t' z}, each weighted by alpha'^2 and Habel's correction kappa = 1 -
/// e^{-2 sigma_t' (d_r + z)} [pbrt3 Eq. 15.24-15.32]. Single scattering (BeamDiffusionSS): the
/// exact first-order term of the beam attenuated by sigma_t (not reduced), the HG phase function
/// and the exact Fresnel transmittance of the exit (zero beyond the critical angle).
/// With pbd_depth_samples = 0 the beam integrals are integrated adaptively (rd to 1e-10, totals
/// semi-analytically to 1e-14); MS ~ log(1/r) and SS ~ 1/r as r -> 0, both +infinity at r = 0.
/// With N samples, pbrt's N-point rule (finite at 0). Totals: MS by a depth integral of
/// closed forms and an exponential integral plus a 1D quadrature; SS = 2 pi rho int_0^1
/// p(mu) (1 - F(mu)) mu/(1 + mu) dmu (the beam integral in closed form).
class PhotonBeamDiffusion final : public DiffusionProfile {
  public:
    PhotonBeamDiffusion(const DiffusionMedium& m, const DiffusionOptions& o = {});
    std::string name() const override { return "pbd"; }
    double total_rd() const override;
    bool includes_single_scattering() const override { return terms_ != PbdTerms::multiple; }
    /// BeamDiffusionMS(r) [1/L^2].
    double rd_multiple(double r) const;
    /// BeamDiffusionSS(r) [1/L^2].
    double rd_single(double r) const;
    /// Total of BeamDiffusionMS [-].
    double total_multiple() const { return total_ms_; }
    /// Total of BeamDiffusionSS [-].
    double total_single() const { return total_ss_; }

  private:
    double eval_rd(double r) const override;
    /// z kappa (C_phi phi + C_E E) of the dipole with its real source at depth z [1/L].
    double ms_at_depth(double r, double z) const;
    /// BeamDiffusionSS with pbrt's N-point rule [1/L^2].
    double ss_samples(double r) const;
    /// int_0^inf 2 pi r kappa (C_phi phi + C_E E) dr for the real source at depth z [-].
    double ms_total_at_depth(double z) const;
    double alpha_, sigma_t_r_, sigma_t_, rho_, d_, sigma_tr_, a_, c_phi_, c_e_;
    PbdTerms terms_;
    int samples_;
    double total_ms_ = 0, total_ss_ = 0;
};

/// Which of [CB15]'s three fits of the scaling s(A) is used, and with which length l.
enum class BurleyFit {
    searchlight,  ///< s = 1.85 - A + 7 |A - 0.8|^3, l = 1/sigma_t' [CB15 §3, Eq. 5]
    diffuse,      ///< s = 1.9 - A + 3.5 (A - 0.8)^2, l = 1/sigma_t' [CB15 §4]
    dmfp,         ///< s = 3.5 + 100 (A - 0.33)^4, l = 1/sigma_tr (Grosjean's D) [CB15 §5, Eq. 8]
};

/// Normalized diffusion [CB15, Eq. 2-3]: R(r) = A s (e^{-s r/l} + e^{-s r/(3 l)}) / (8 pi l r),
/// R_dr = A exactly. The fits were made to Monte Carlo references with isotropic scattering
/// (single scattering included); g enters through sigma_t' (similarity), eta only through A.
/// A: DiffusionOptions::surface_albedo, else the pbd total for the same medium. For dmfp at
/// sigma_a = 0, l = inf: R_d = 0 everywhere while total_rd() returns the limit A.
class NormalizedDiffusion final : public DiffusionProfile {
  public:
    NormalizedDiffusion(const DiffusionMedium& m, BurleyFit fit, const DiffusionOptions& o = {});
    std::string name() const override;
    double total_rd() const override { return a_; }
    bool includes_single_scattering() const override { return true; }
    /// The surface albedo A [-] in use.
    double surface_albedo() const { return a_; }
    /// The shape parameter d = l / s [L] in use (infinite for dmfp at sigma_a = 0).
    double shape_length() const { return d_; }

  private:
    double eval_rd(double r) const override;
    BurleyFit fit_;
    double a_, d_;
};

// ---- Factory and inversion ----------------------------------------------------------------------

/// The factory names: dipole, better-dipole, multipole, qd, pbd, burley-searchlight,
/// burley-diffuse, burley-dmfp.
const std::vector<std::string>& diffusion_model_names();

/// Build a model by name; the medium is validated first. Throws std::invalid_argument for an
/// unknown name (listing the known ones) or an invalid medium or option.
std::unique_ptr<DiffusionProfile> make_diffusion_profile(const std::string& name,
                                                         const DiffusionMedium& m,
                                                         const DiffusionOptions& o = {});

/// The diffuse mean free path l_d = 1 / sigma_tr [L] of a medium; infinity at sigma_a = 0.
double diffuse_mean_free_path(const DiffusionMedium& m, TransportDefinition def);

/// What parameter inversion starts from.
struct InversionTarget {
    double total_rd = 0;  ///< R_dr [-], per unit power entering, as the model defines it
    double ld = 1;        ///< diffuse mean free path 1 / sigma_tr [L], > 0
    double g = 0;         ///< anisotropy of the result [-]
    double eta = 1;       ///< relative index of the result [-]
    double thickness = std::numeric_limits<double>::infinity();  ///< multipole only [L]
};

/// Parameter inversion [Bitterli13 §3.4; JB02]: the medium (sigma_a, sigma_s) of the given g,
/// eta (and thickness) whose model `name` has total diffuse reflectance `t.total_rd` and diffuse
/// mean free path `t.ld`. With q = 1 - alpha', sigma_t' = 1 / (l_d sqrt(3 q)) (classical,
/// Bitterli13 Eq. 3.3) or 1 / (l_d sqrt(3 q / (1 + q))) (grosjean), sigma_s' = alpha' sigma_t',
/// sigma_a = sigma_t' - sigma_s' (Eq. 3.4-3.5), sigma_s = sigma_s' / (1 - g). R_dr is tabulated on
/// 25 reduced albedos in [0, 1 - 2^-52] and checked to be strictly increasing (std::domain_error
/// otherwise, e.g. for a burley model with a fixed surface albedo); a target outside the
/// attainable range [R_dr(0), R_dr(1 - 2^-52)] is std::invalid_argument. The root is then found
/// by Brent's method on ln q inside the bracketing grid cell, to ~4 eps relative in q.
DiffusionMedium invert_diffusion_parameters(
    const std::string& name, const InversionTarget& t, const DiffusionOptions& o = {},
    TransportDefinition def = TransportDefinition::classical);

/// Channel c of a homogeneous slab as the diffusion models see it: coefficients in 1/unit, the
/// index relative to the ambient above, the thickness in unit (quasi-infinite, >= 1e8 cm, as
/// infinity). Throws std::invalid_argument for a layered medium.
DiffusionMedium diffusion_medium(const Medium& m, int c, LengthUnit unit = LengthUnit::kCm);

}  // namespace ssslab::approx
