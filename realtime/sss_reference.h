// The screen-space 2D reference of the SSS pass: the pipeline of realtime/sss_pass.h (same
// G-buffer, parameters, kernel scale, edge modes, clamp-to-edge) with the exact, non-separable 2D
// kernel of the material [Freude14 §6.1, "simple rotation"; the ground truth the separable models
// approximate, §6.2] instead of a separable model. A separable model against this reference
// measures the model's approximation and the pass's sampling only; this reference against the path
// tracer measures the screen-space diffusion assumption itself (docs/architecture.md, "The
// real-time renderer").
//
// The kernel of a channel is approx::Kernel2D (cell masses on the thesis grid, unit L1), taken as a
// piecewise-constant density: cell mass / h^2 over each cell of side h (mm). For the pixel c being
// shaded, with Eq. 4.11's scale at c's view depth (s_x = W / (2 tan_half aspect z_c unit_mm),
// s_y = H / (2 tan_half z_c unit_mm) pixels per mm), screen pixel q receives the weight
//     W(q) = integral of the density over q's square mapped to mm about c's centre,
// an exact area integral (the density is piecewise constant), and the output is
//     out(c) = sum_q W(q) E'(q),
// E' the G-buffer irradiance after the edge rule. Clamp-to-edge: a pixel square beyond the image
// reads the edge pixel, so the edge row or column of the image receives the kernel's mass out to
// infinity. A kernel narrower than a pixel lands in the centre pixel: the identity, as sss_pass.
//
// Edge rules, per screen pixel q (those of sss_pass, which applies them per texel):
//   - kNone: E'(q) = E(q).
//   - kFollowSurface [Freude14 Eq. 4.12]: E'(q) = E(q) (1 - s) + E(c) s,
//     s = min(1, follow_strength |z_c - z_q| / tan_half); materials are not looked at.
//   - kReject: q is dropped if its material differs from c's or |z_c - z_q| > reject_depth; the
//     kept sum is rescaled per channel by (all weights) / (kept weights). With nothing dropped the
//     result is that of kNone.
// Since the kernel has unit mass, out(c) = E(c) + sum_q W(q) (E'(q) - E(c)) (with the kept
// weights' renormalisation in kReject): both methods below evaluate this form, so a constant stays
// constant exactly and the centre pixel adds no noise.
//
// Methods:
//   - kExact: the sum over every pixel of the footprint (the pixels the kernel's grid overlaps,
//     clamped to the image), W from a summed-area table of the cell masses evaluated at the pixel
//     square's corners in grid coordinates with bilinear interpolation: exact for a piecewise
//     constant density.
//   - kSampled: per pixel, `samples` points drawn from the mean of the three channels' densities
//     (marginal in x, conditional in y, both by inverse CDF of the piecewise-constant density; the
//     signs of x and y from the same uniforms), the weights K_c / p per channel, E' of the pixel
//     holding the point (box reconstruction: an unbiased estimate of the exact sum). The unit
//     square of the two uniforms is stratified into samples / samples_per_stratum cells of
//     (nearly) equal area with samples_per_stratum (default 2) independent points each, so the
//     standard error is estimated from the within-stratum differences without bias (in the mean
//     square: per pixel it is noisy where few samples reach a bright region, see realtime/README).
//     kReject: a ratio estimator (kept numerator over 1 - dropped mass, both from the same
//     samples), its standard error by the delta method; its bias is O(1 / samples), below the
//     standard error (see sss_reference.cpp).
//   - kAuto: kExact where the footprint holds at most max_exact_taps pixels, kSampled elsewhere.
//
// Random numbers: Philox streams keyed by (seed, rng_domain::kSssReference, pixel index), drawn in
// sample order: results are bit-identical for any thread count. Rows run in parallel (oneTBB).
#pragma once

#include "approx/kernel2d.h"
#include "realtime/sss_pass.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ssslab::realtime {

/// A material's exact 2D kernel, per channel (approx::Kernel2D of the thesis grid, unit L1), with
/// the tables both methods read. The three channels share the grid (cell size and count) and have
/// non-negative cells.
struct SssExactKernel {
    std::array<approx::Kernel2D, 3> channel;
    double h_mm = 0;  ///< cell side
    int n = 0;        ///< cells per half side (the quadrant is n x n)
    /// Summed-area tables of the channels' quadrants, (n + 1) x (n + 1) x 3, index
    /// 3 (i (n + 1) + j) + channel (interleaved: one cache line serves the three channels): the
    /// mass in cells [0, i) x [0, j) of the quadrant (x along i).
    std::vector<double> sat;
    /// The sampling density, the mean of the three channels (quadrant masses m(i, j), sum 1):
    /// marginal CDF over i (n + 1 values, the last 1) and, per i, the cumulative sums over j
    /// (n + 1 values per row, row i at i (n + 1), the last the row's mass).
    std::vector<double> cdf_x, cum_y;

    /// Throws std::invalid_argument for a null kernel, channels on different grids or a negative
    /// cell.
    static SssExactKernel from_kernels(const std::array<const approx::Kernel2D*, 3>& k);
    double extent_mm() const { return n * h_mm; }
};

struct SssReferenceOptions {
    enum class Method {
        kAuto,     ///< kExact where the footprint holds <= max_exact_taps pixels, else kSampled
        kExact,    ///< the exact sum over the footprint, every pixel
        kSampled,  ///< Monte Carlo, every pixel
    };
    Method method = Method::kAuto;
    /// kAuto's budget: pixels summed per output pixel (footprint clamped to the image).
    std::int64_t max_exact_taps = 4096;
    int samples = 256;  ///< kSampled: kernel samples per pixel (>= samples_per_stratum)
    /// kSampled: points per stratum (>= 2; samples / samples_per_stratum strata).
    int samples_per_stratum = 2;
    std::uint64_t seed = 1;
};

struct SssReferenceResult {
    std::vector<float> irradiance;      ///< RGB interleaved, as sss_pass's output
    std::vector<float> standard_error;  ///< RGB: per pixel and channel, 0 where computed exactly
    std::int64_t exact_pixels = 0;      ///< medium pixels computed exactly
    std::int64_t sampled_pixels = 0;    ///< medium pixels sampled (no-medium pixels: neither)
};

/// The reference: every medium pixel through its material's exact kernel; pixels of material -1
/// pass through. p.jitter and p.seed (the separable pass's tap jitter) are not used. Throws
/// std::invalid_argument on the errors sss_pass refuses (sizes, a material without a kernel, a
/// medium pixel without a positive finite depth, bad parameters) and on bad options.
SssReferenceResult sss_reference(const SssGBuffer& g, const std::vector<SssExactKernel>& kernels,
                                 const SssParams& p, const SssReferenceOptions& o = {});

}  // namespace ssslab::realtime
