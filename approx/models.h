// The separable kernel models of Freude14 ch. 5 and the baselines they are compared with. Every
// model approximates one channel's Kernel2D (unit L1) by a SeparableKernel on the same grid.
#pragma once

#include "approx/image.h"
#include "approx/kernel2d.h"
#include "approx/separable.h"

#include <array>
#include <vector>

namespace ssslab::approx {

// ---- SVD rank-N [Freude14 §5.1; JimenezSupp §B] -------------------------------------------

/// The truncated SVD A_N = sum_{k <= N} sigma_k u_k v_k^T (Eq. 5.5, 5.8, 5.10): the best rank-N
/// approximation in the Frobenius norm (Eckart-Young). The kernel matrix is symmetric and even in
/// both variables, so its singular pairs are the eigenpairs of the n x n even block, computed by
/// Spectra's Lanczos solver (only the leading N, never a full decomposition); a negative
/// eigenvalue gives a term of sign -1. With `renormalize`, A is scaled to unit L1 (Eq. 5.12).
/// info: sigma_1..sigma_N, l1 (before renormalisation), iterations.
ModelResult svd_rank_n(const Kernel2D& k, int rank, bool renormalize);

/// The leading `count` singular values of the full 2n x 2n kernel matrix (Fig. 5.1).
std::vector<double> singular_values(const Kernel2D& k, int count);

// ---- Pre-integration [Freude14 §5.2, Eq. 5.17, 5.18; JimenezSupp §C] ------------------------

/// a_p(x) = integral of R_d(x, y) dy, A_p = a_p a_p^T / ||R_d||_1: exact for additively separable
/// irradiance (straight edges), energy-conserving by construction.
ModelResult preintegration(const Kernel2D& k);

// ---- Guided optimization [Freude14 §5.3, Eq. 5.19, 5.20; JimenezSupp §D] --------------------

struct GuideParams {
    double k = 1.0;  ///< exponent of the radial weight (x^2 + y^2)^(k/2), 0..4
    double b = 0.0;  ///< axis suppression (1 - e^{-b x^2})(1 - e^{-b y^2}); 0: none
};

/// argmin_a sum Gamma(x, y) (K(x, y) - a(x) a(y))^2 subject to ||a||_1^2 = ||K||_1 = 1, a >= 0,
/// with Gamma(x, y; k, b) = (x^2 + y^2)^(k/2) (1 - e^{-b x^2})(1 - e^{-b y^2}) on x, y in [-1, 1]
/// spanning the kernel grid (cell centres at (i + 1/2) / n), and b = 0 meaning no suppression
/// term (as the thesis treats it). For a >= 0 the constraint is linear, sum a = 1, and it is held
/// exactly: each step of the solver minimises the objective over a for the other factor fixed,
/// a separable quadratic with the linear constraint and bounds, solved in closed form up to one
/// multiplier (found by bisection). On grids of n >= 512 a solve on 2 x 2 aggregated cells gives
/// the start. The weights depend on n, k and b only and are cached (the last two), so the three
/// channels of a material share them. info: constraint_error (relative), iterations,
/// last_change, objective.
ModelResult guided(const Kernel2D& k, const GuideParams& g);

// ---- Manual two-Gaussian model [Freude14 §5.4, Eq. 5.21, Table A.1] -------------------------

/// a_m(x) = w G(x, tau_n) + (1 - w) G(x, tau_f) with 1D Gaussians of unit integral; widths
/// sqrt(tau) in mm. Cell masses are exact integrals of the Gaussians over the cells; with
/// `normalise` (the thesis's energy conservation) each Gaussian is scaled to unit mass on the
/// grid, so the kernel has unit L1 whatever leaves the grid. info: mass_outside_grid (of the
/// unnormalised mixture), l1.
ModelResult manual_two_gaussian(const Kernel2D& k, double sqrt_tau_near_mm, double sqrt_tau_far_mm,
                                double w, bool normalise = true);

/// The manual model's "close fit": sqrt(tau_n), sqrt(tau_f) and w of one channel minimising the
/// image-space RMS of the separable convolution of `signal` against `exact` (the exact 2D
/// convolution of the same signal, channel `channel`) under the conventions of convolve.h. The
/// error is a quartic in w for fixed widths, minimised exactly; the widths are found by a
/// log-spaced grid search refined by Nelder-Mead. info: fit_rms, sqrt_tau_near_mm,
/// sqrt_tau_far_mm, w, evaluations (image-space evaluations of a width pair).
ModelResult fit_manual_two_gaussian(const Kernel2D& k, const ImageRGB& signal,
                                    const ImageRGB& exact, int channel);

// ---- d'Eon's sum of Gaussians [d'Eon & Luebke 2007; Freude14 Eq. 4.15] ----------------------

struct GaussianMixture {
    std::vector<double> weights;    ///< sum to the profile's L1 (1)
    std::vector<double> variances;  ///< mm^2, ascending
};

/// Fit N 2D Gaussians to the radial profile of the kernel: minimise the 2D L2 error
/// sum over cells of (K - A_g)^2 with sum w = ||K||_1 (energy) and w >= 0; variances by a
/// derivative-free search in log space, weights by constrained least squares for each trial.
GaussianMixture fit_gaussian_mixture(const Kernel2D& k, int count);
/// The mixture as N separable terms (2 N 1D convolutions). info: variances, weights.
ModelResult sum_of_gaussians(const Kernel2D& k, int count);

// ---- The original SSSS skin kernel [Freude14 Eq. 4.8; Jimenez et al., separable-sss demo] ----

/// The separable-sss demo's kernel parameters: strength t and falloff f per channel, the width w
/// scales offsets at render time.
struct SsssSkinParams {
    std::array<double, 3> strength = {0.48, 0.41, 0.28};
    std::array<double, 3> falloff = {1.0, 0.37, 0.3};
};

/// One tap of a sampled 1D kernel: offset (in the kernel's unit) and weight per channel.
struct Tap {
    double offset;
    std::array<double, 3> weight;
};

/// The SSSS skin kernel as a model on a kernel grid (offsets in mm, w = 1): a_s(x) =
/// t p(x / (0.001 + f)) / ||p|| + (1 - t) delta(x) with the demo's profile p (d'Eon's skin
/// Gaussians, red weights) and the demo's strength t and falloff f of `channel`; the delta's mass
/// is split between the two cells next to x = 0. Unit L1.
ModelResult ssss_skin_kernel(const Kernel2D& k, int channel, const SsssSkinParams& p = {});

/// SeparableSSS::calculateKernel() of the demo, operation for operation in single precision:
/// `samples` offsets in [-range, range] (range 2, or 3 for more than 20 samples) by the quadratic
/// mapping, weights (area x profile), normalised, then the strength lerp with the centre delta.
/// The centre tap comes first, as in the demo. Its shipped 11/17/25-tap presets are this function.
std::vector<Tap> ssss_demo_kernel(int samples, const SsssSkinParams& p = {});

}  // namespace ssslab::approx
