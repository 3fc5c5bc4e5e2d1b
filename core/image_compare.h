// Statistical comparison of two Monte Carlo images of the same scene (e.g. ssslab's path tracer
// against Blender's Cycles): is their difference at the noise level? In the manner of Mitsuba's
// render tests (reference mean and standard error, per-pixel z), but on blocks of pixels so that
// each test statistic is close to Gaussian even where single pixels are not.
//
// An image estimate is a per-pixel RGB mean with the variance of that mean, from either
//  - one image with a standard-error layer (ssslab's "<layer>" and "<layer>.stderr", from the
//    batch statistics of core/stats.h), or
//  - K >= 2 independent runs (different seeds) of a renderer that reports no variance: the
//    per-pixel mean of the runs and its variance s^2 / K (K - 1 degrees of freedom per pixel).
// Pixels are independent samples in both (each pixel has its own random numbers), so the
// variance of a mean over n pixels is the sum of their variances over n^2; a block's variance
// estimate thus has about n (K - 1) degrees of freedom and its z is close to standard normal.
//
// Per channel: the whole-image mean of both and their z; per block the difference of block means
// over its standard error, summed over the blocks into a chi-square with its p-value. The three
// channels are tested apart: their noise is strongly correlated (one path carries RGB, grey
// surfaces scatter all three alike), so a sum over channels would not be chi-square distributed.
// Blocks without noise on either side (unlit, or a constant background seen directly; their SE
// is rounding) are left out and counted when they agree, and make p = 0 when they differ.
#pragma once

#include "core/film_image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace ssslab {

struct ImageEstimate {
    int width = 0, height = 0;
    std::vector<double> mean;  ///< (y * width + x) * 3 + c
    std::vector<double> var;   ///< variance of `mean`, same layout
    std::string source;        ///< for messages: file names
};

/// `layer` and `<layer>.stderr` of one image (RGB). Throws std::invalid_argument naming the
/// layer if either is missing or not RGB.
ImageEstimate estimate_with_stderr(const LayeredImage& image, const std::string& layer,
                                   const std::string& source);
/// The mean and variance of the mean of K >= 2 independent runs, from their `layer` (RGB;
/// "" is the default layer, as Blender writes it). Throws std::invalid_argument on fewer than two
/// runs, missing layers or different sizes.
ImageEstimate estimate_from_runs(const std::vector<LayeredImage>& runs, const std::string& layer,
                                 const std::string& source);

struct BlockDifference {
    int x0 = 0, y0 = 0, channel = 0;
    double a = 0, b = 0, se = 0, z = 0;  ///< block means, SE of a - b, z = (a - b) / se
};

struct ImageComparison {
    int block = 16;
    std::array<double, 3> mean_a{}, se_a{}, mean_b{}, se_b{}, z_mean{};
    std::vector<BlockDifference> blocks;
    std::array<double, 3> chi2{};  ///< per channel, over its blocks
    std::array<int, 3> dof{};      ///< blocks that entered, per channel
    std::array<double, 3> p{1, 1, 1};
    double max_abs_z = 0;
    int skipped = 0;  ///< block-channels without noise on either side that agree
    /// Block-channels without noise that differ (beyond float precision): the images are not
    /// the same, whatever the noise elsewhere (p is then 0).
    int deterministic_differences = 0;
    /// The smallest per-channel p-value times 3 (Bonferroni), capped at 1.
    double p_min_corrected() const;
    /// Relative RMS difference of block means, and what noise alone would give:
    /// sqrt(sum (a - b)^2 / sum b^2) and sqrt(sum se^2 / sum b^2).
    double rel_rms_diff = 0, rel_rms_noise = 0;
};

/// The mean over all pixels of one channel of an estimate, and its standard error (the pixels
/// independent: the root of the summed variances over the pixel count).
struct ImageMean {
    double mean = 0, se = 0;
};
ImageMean image_mean(const ImageEstimate& e, int channel);

/// The mean over pixels of the variance of an estimate's pixel means in one channel: its mean
/// squared error if unbiased. Times the seconds it took, the inverse is the efficiency
/// 1 / (MSE x time) that compares renderers independently of how long each ran.
double mean_pixel_variance(const ImageEstimate& e, int channel);

/// Compare two estimates of the same size (std::invalid_argument otherwise) on square blocks of
/// `block` pixels (partial blocks at the right and bottom edges included).
ImageComparison compare_images(const ImageEstimate& a, const ImageEstimate& b, int block);

/// The RMS difference between an image a and a noisy estimate b of what it is compared with,
/// over n values (pixel channels; the caller picks the pixels), with the noise taken out
/// [the bias of a squared difference is the variance of the difference]: for independent a_i, b_i
/// with variances va_i, vb_i,
///     E[(a_i - b_i)^2] = (E a_i - E b_i)^2 + va_i + vb_i,
/// so D^2 = mean_i ((a_i - b_i)^2 - va_i - vb_i) is an unbiased estimate of the mean squared
/// difference of the expectations, whatever the noise: a noisy reference adds no error and
/// ranks no model. Its standard error assumes Gaussian noise: Var((d + e)^2 - v) = 4 d^2 v +
/// 2 v^2 per value (v = va + vb; d^2 v estimated by the term times v), the values independent;
/// with
/// `dof` > 0 the variances are taken as estimates on that many degrees of freedom (batch
/// statistics: batches - 1), whose own spread the standard error then includes.
struct NoiseCorrectedRms {
    double rms = 0;        ///< sqrt(max(0, D^2)): the noise-corrected RMS difference
    double rms_se = 0;     ///< its standard error (delta method; at D = 0: sqrt(SE(D^2)))
    double ms = 0;         ///< D^2 (may be negative when the difference is within the noise)
    double ms_se = 0;      ///< standard error of D^2
    double raw_rms = 0;    ///< sqrt(mean (a - b)^2), the uncorrected RMS
    double noise_rms = 0;  ///< sqrt(mean (va + vb)): what noise alone adds to raw_rms^2
    std::size_t n = 0;
};
/// `va` and `vb` may be empty (that side has no noise); otherwise all four have n entries
/// (std::invalid_argument otherwise). Variances, not standard errors.
NoiseCorrectedRms noise_corrected_rms(const std::vector<double>& a, const std::vector<double>& va,
                                      const std::vector<double>& b, const std::vector<double>& vb,
                                      double dof = 0);

/// The largest difference of a from b relative to b, over all values: |a - b| / |b|, with |b|
/// taken at least floor_fraction times b's largest magnitude (so that near-zero values are
/// judged against the image's scale). Equal sizes; two backends' parity (realtime/gl).
double max_relative_difference(const std::vector<float>& a, const std::vector<float>& b,
                               double floor_fraction = 1e-6);

/// PSNR of image a against image b in dB, the peak b's largest magnitude (999 where they are
/// equal): two backends' parity (realtime/gl: the tests, `ssslab bench --realtime --backend gl`).
/// Any indexable float or double sequences of one size.
template <class A, class B>
double psnr(const A& a, const B& b) {
    double peak = 0, se = 0;
    for (std::size_t i = 0; i < b.size(); ++i) {
        const double x = static_cast<double>(a[i]), y = static_cast<double>(b[i]);
        peak = std::max(peak, std::fabs(y));
        se += (x - y) * (x - y);
    }
    const double mse = se / static_cast<double>(b.size());
    return mse > 0 ? 10 * std::log10(peak * peak / mse) : 999.0;
}

}  // namespace ssslab
