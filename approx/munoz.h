// Convolution-based layered subsurface scattering [Munoz11: Munoz, Echevarria, Seron, Gutierrez,
// Convolution-based simulation of homogeneous subsurface scattering, CGF 30(8) 2011; the seed
// 003_*.txt in ../shared/papers, an OCR text whose equations (4)-(7) are read as below].
//
// The object seen from the camera is cut into n_l layers parallel to the image plane,
//     z^l = z_min + l dz,  dz = (z_max - z_min) / (n_l - 1),  l = 0 .. n_l - 1   [Munoz11 §4.2]
// over the view depths of its front and back surface samples. Each pixel has two samples, the
// nearest surface (front) and the farthest (back), each with the irradiance that entered there;
// a sample's irradiance goes to the two layers nearest its depth, half to each ("equally
// distributed ... half of the irradiance to each of them", §4.2; `MunozSplit::linear` splits in
// proportion to the distance instead). Per layer distance e = |i - l| a kernel
//     R_d^e(x, y) = R_d(sqrt((k_x x)^2 + (k_y y)^2 + (e dz)^2))                 [Munoz11 Eq. 5]
// at pixel offsets (x, y) (point-sampled at pixel centres, as the paper writes it), times the
// source pixel's area k_x k_y so that the discrete sum is the surface integral (the pixel's
// projected area: like the paper, no 1 / cos for surfaces seen at an angle); the radiant
// exitance of layer l is
//     M_l = sum over i of E_i * R_d^{|i - l|}                                   [Munoz11 Eq. 6]
// (2D linear convolutions by FFT, FFTW, zero outside the image: the object's irradiance is zero
// beyond its outline, unlike approx/convolve.h's clamp-to-edge images). At a visible front
// sample of depth z between layers l0 and l0 + 1, M = (1 - s) M_l0 + s M_l0+1 with
// s = (z - z^l0) / dz (Eq. 7's interpolation); the outgoing radiance is then
// L_o = F_t(w_o) M / pi [Munoz11 Eq. 7], or M times the real-time renderer's exit weight: the
// caller's, so that every approximation is scored with one exit rule (as approx/hierarchical.h).
//
// Pixel size: k(z) = pixel_mm + pixel_mm_per_depth z (an orthographic camera: the first; a
// perspective one: 2 tan(fov / 2) / H as the second). The paper has one k for the object; a
// perspective view spans several, so the kernel from layer i into layer l measures in-plane
// distances at k((z^i + z^l) / 2) and weighs a source pixel by its area at its own layer,
// k(z^i)^2 (one kernel per distance e when the camera is orthographic).
//
// Optimisations [Munoz11 §5]: the threshold t of Eq. 8 drops layer i's contribution to layer l,
// per channel, where t R_d(0) > R_d(|z^i - z^l|); layer maps down-sampled by an integer factor per
// axis (irradiance averaged over the block, kernels on the coarse pixels, M_l interpolated back
// bilinearly: "100/50/25 %" are factors 1, 2, 4); layers no visible sample interpolates from are
// not convolved (their irradiance still feeds the others).
#pragma once

#include "approx/radial_function.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ssslab::approx {

/// The object as the camera sees it, per pixel (row-major, width x height).
struct MunozView {
    int width = 0, height = 0;
    /// Pixel side [mm] at view depth z [mm]: pixel_mm + pixel_mm_per_depth z; > 0 on the object.
    double pixel_mm = 0, pixel_mm_per_depth = 0;
    /// View depth [mm] of the nearest and the farthest surface sample; +infinity where none (a
    /// pixel with a front sample and no back one has a single sample).
    std::vector<float> front_z, back_z;
    /// Irradiance that entered at each sample, per channel; 0 where there is none.
    std::array<std::vector<float>, 3> front_irradiance, back_irradiance;
};

enum class MunozSplit {
    equal,   ///< half to each of the two nearest layers [Munoz11 §4.2]
    linear,  ///< in proportion to the distance to each (the layers' linear interpolation)
    /// all to the nearest layer, and Eq. 7 reads the nearest layer only: a medium between far
    /// layers keeps its light (equal keeps half, linear (1 - s)^2 + s^2), at the price of depth
    /// steps where the visible depth crosses a layer midpoint (not in the paper)
    nearest,
};

enum class MunozKernel {
    point,          ///< R_d at the pixel's centre [Munoz11 Eq. 5 as written]
    pixel_average,  ///< R_d averaged over the pixel's square (near the centre)
};

struct MunozOptions {
    int layers = 4;        ///< n_l, 1..16 (the paper recommends 4..8)
    double threshold = 0;  ///< t of Eq. 8, in [0, 1); 0 convolves every pair
    int downsample = 1;    ///< layer maps at 1/downsample per axis, 1..8
    bool skip_invisible = true;
    MunozSplit split = MunozSplit::equal;
    /// Eq. 5 point-samples R_d at pixel centres, which overestimates where a pixel is not small
    /// against the profile's peak (1 / sigma_t'): +23 % on a flat medium at pixels of 2 z_r,
    /// worse on down-sampled layers. pixel_average takes each kernel pixel's mean over its
    /// square instead (16 x 16 points within 4 pixels of the centre).
    MunozKernel kernel = MunozKernel::point;
};

struct MunozStats {
    int layers_used = 0;                 ///< layers some visible sample interpolates from
    std::int64_t convolutions = 0;       ///< (layer pair, channel) products computed
    std::int64_t skipped_threshold = 0;  ///< (pair, channel) dropped by Eq. 8
    std::int64_t skipped_invisible = 0;  ///< (pair, channel) of layers no one sees
    double dz_mm = 0;                    ///< layer spacing
    double seconds = 0;                  ///< wall time of the call
};

struct MunozResult {
    /// M at the visible front samples, per channel (0 where there is no object).
    std::array<std::vector<float>, 3> exitance;
    MunozStats stats;
};

/// A variant named in an experiment config: "layers=4", "layers=8,t=0.001,downsample=2",
/// "layers=4,split=linear,visible=all,kernel=average" (keys layers, t, downsample, split =
/// equal | linear, visible = skip | all, kernel = point | average); unset keys keep MunozOptions'
/// defaults. Throws std::invalid_argument naming the key for an unknown key, a repeated one or a
/// value out of range.
MunozOptions parse_munoz(const std::string& spec);
/// The canonical text of a variant (every key), as parse_munoz reads it.
std::string munoz_label(const MunozOptions& o);
/// "equal", "linear", "nearest".
const char* split_name(MunozSplit s);

/// Throws std::invalid_argument naming the option or field for layers outside 1..16, a
/// threshold outside [0, 1), downsample outside 1..8, layer maps of mismatched sizes, a
/// non-positive pixel size on the object, negative or non-finite irradiance, or a back sample
/// nearer than the front one.
MunozResult munoz_exitance(const MunozView& view, const RadialFunction& rd, const MunozOptions& o);

}  // namespace ssslab::approx
