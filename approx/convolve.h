// Convolution of images with kernels, in physical units.
//
// Convention (the same for every method, so that they compare exactly): the output at pixel
// (x, y) is sum over pixel offsets (dx, dy) of Kpix(dx, dy) E(clamp(x - dx), clamp(y - dy)),
// with clamp-to-edge boundaries; a normalised kernel therefore maps a constant image to itself.
// A kernel on its grid of cells (side h, centres at (i + 1/2) h) is resampled to the pixel grid
// (side p, pixel offsets centred on integer multiples of p) by distributing each cell's mass over
// the pixel bins [(d - 1/2) p, (d + 1/2) p) in proportion to the overlap, along each axis (the
// cell is taken as uniform). Offsets beyond +-(W - 1) pixels are folded onto +-(W - 1): under
// clamp-to-edge they read the same pixel, so a kernel wider than the image is handled exactly,
// and one narrower than a pixel lands in the centre pixel.
#pragma once

#include "approx/image.h"
#include "approx/kernel2d.h"
#include "approx/separable.h"

#include <array>
#include <vector>

namespace ssslab::approx {

/// Resample an even 1D kernel (half cell masses a[i] at (i + 1/2) h, i in [0, n)) to pixel
/// offsets -r..r (2 r + 1 values, index d + r), r = min(ceil(n h / p), fold) with mass beyond
/// +-fold pixels folded onto +-fold.
std::vector<double> resample_1d(const std::vector<double>& half, double h_mm, double pixel_mm,
                                int fold);

/// The exact 2D convolution (FFT, FFTW) of each channel with that channel's kernel.
ImageRGB convolve_exact(const ImageRGB& e, const std::array<const Kernel2D*, 3>& k);

/// The same by separable passes: for each term, a horizontal then a vertical 1D convolution with
/// the resampled a_k, summed with the terms' signs (full resolution: every pixel offset).
ImageRGB convolve_separable(const ImageRGB& e, const std::array<const SeparableKernel*, 3>& a);

/// A 1D kernel discretised into taps: offsets in mm, weights per channel.
struct TapKernel {
    std::vector<double> offset_mm;              ///< ascending, symmetric about 0
    std::array<std::vector<double>, 3> weight;  ///< per channel, parallel to offset_mm
    double support_mm = 0;                      ///< the range the offsets span
};

/// Importance-sampled taps of term `term` of a separable kernel (every channel's term `term`; the
/// channels must have the same rank), its sign left out: the caller applies it (rank N: N tap
/// kernels, as realtime/sss_pass.h builds them). The range R is taken from |a_term| (an SVD term
/// past the first changes sign); the weights are the signed masses of a_term over the cells.
TapKernel make_term_taps(const std::array<const SeparableKernel*, 3>& a, int term, int count,
                         double support_mass = 0.995);

/// Importance-sampled taps of a rank-1 separable kernel (one term per channel; the kernel's
/// single term is used) [Freude14 §4.4]: `count` (odd) offsets by the SSSS quadratic mapping
/// o = R sign(u) u^2, u uniform in [-1, 1], with the range R the radius holding `support_mass` of
/// the widest channel's 1D mass (from the kernel, not fixed for skin); each tap's weight is the
/// kernel's mass integrated over the tap's cell (between the midpoints to its neighbours, the
/// outer cells reaching to infinity), so the weights of a normalised kernel sum to 1 exactly.
TapKernel make_taps(const std::array<const SeparableKernel*, 3>& a, int count,
                    double support_mass = 0.995);

/// Separable convolution with taps: a horizontal then a vertical pass, each sampling the image at
/// offsets (in pixels, fractional) with linear interpolation between pixels and clamp-to-edge.
/// With jitter > 0, every pixel moves each tap within its cell by up to `jitter` times the cell's
/// half width (stratified jitter from a hash of pixel, pass and tap: deterministic), turning the
/// banding of few taps into noise [JimenezSupp Figs. S.6, S.7: "33 % jittered" is jitter = 0.33].
ImageRGB convolve_taps(const ImageRGB& e, const TapKernel& taps, double jitter = 0.0);

// ---- Tap sampling, shared by convolve_taps and realtime's SSS pass (one rule, one place) ------

/// A hash of (x, y, pass, tap, seed) to a uniform value in [-1, 1] (deterministic; seed 0 is the
/// hash convolve_taps uses).
double jitter_hash(int x, int y, int pass, int tap, unsigned seed = 0);

/// How far each tap may move towards either neighbour under jitter, in mm: `jitter` times the
/// distance to its cell's boundary (the midpoint) on that side; the outer cells are taken as
/// mirror images of their inner half.
struct TapJitterRange {
    std::vector<double> left_mm, right_mm;
};
TapJitterRange tap_jitter_range(const TapKernel& taps, double jitter);

/// Offset of tap i in mm, moved by xi in [-1, 1] (a jitter_hash) within its range.
inline double jittered_offset_mm(const TapKernel& taps, const TapJitterRange& r, size_t i,
                                 double xi) {
    return taps.offset_mm[i] + xi * (xi < 0 ? r.left_mm[i] : r.right_mm[i]);
}

/// Linear interpolation at position s (in pixels, along an axis of `len` pixels) with
/// clamp-to-edge: the value is (1 - t) v[i0] + t v[i1].
struct TapTexels {
    int i0 = 0, i1 = 0;
    double t = 0;
};
inline TapTexels tap_texels(double s, int len) {
    TapTexels r;
    // Clamped in double first: offsets far beyond the image never reach an int conversion.
    const double c = s < 0 ? 0.0 : (s > len - 1 ? static_cast<double>(len - 1) : s);
    r.i0 = static_cast<int>(c);
    if (r.i0 > len - 1) r.i0 = len - 1;
    r.i1 = r.i0 + 1 < len ? r.i0 + 1 : len - 1;
    r.t = c - r.i0;
    return r;
}

}  // namespace ssslab::approx
