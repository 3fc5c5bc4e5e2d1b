// The separable screen-space SSS pass (passes 2-3 of [Freude14 §4.2, Algorithm 4.1]; Jimenez et
// al. 2015), the CPU reference a GPU backend is held to. Its inputs are plain arrays and numbers
// (G-buffer, taps, parameters) that a GL backend can upload as they are.
//
// For every separable term k of a pixel's material kernel, a horizontal then a vertical 1D pass
// with that term's taps; the terms are summed with their signs per channel (SVD rank N: 2N passes
// [Freude14 §5.1]). Tap offsets are in mm; a tap at o mm lands o / unit_mm world units, and
// at view depth z one world unit covers H / (2 tan_half z) pixels vertically [Freude14 Eq. 4.11,
// k_sc = 1 / (tan(f_y / 2) p_d) in units of the half image height] and W / (2 tan_half aspect z)
// horizontally: the aspect enters through the projection only, and for square pixels (aspect =
// W / H, as RasterCamera builds it) both scales are the same. The scale is taken at the centre
// pixel's depth, as the shader does (the kernel is not re-scaled per sample).
//
// Sampling: linear interpolation between the two texels around a tap's position, clamp-to-edge,
// taps optionally jittered per pixel within their cells [JimenezSupp Figs. S.6, S.7]: the rules of
// approx::convolve_taps, whose helpers are used, so that on a flat, single-material G-buffer of
// constant depth term 0 of this pass is approx::convolve_taps (for a kernel over half a pixel
// wide: see below).
//
// Edges are handled per texel (each of the two texels of a tap is treated on its own, with its
// own depth and material, weights (1 - t) and t):
//   - kFollowSurface [Freude14 Eq. 4.12; separable-sss demo]: a texel's value o is replaced by
//     o (1 - s) + c s, c the pass input at the centre pixel, s = min(1, strength |z_c - z_o| /
//     tan_half); material indices are not looked at (a texel with no medium has depth +inf in a
//     raster frame, so s = 1).
//   - kReject [as Unreal's and Godot's screen-space SSS]: texels whose material differs from the
//     centre's or whose depth differs by more than reject_depth are dropped, and the kept sum is
//     rescaled per channel by (sum of all weights) / (sum of kept weights), so that a normalised
//     kernel stays normalised. With nothing dropped the result is that of kNone to the last bit.
//   - kNone: every texel counts (light bleeds across silhouettes; the reference for the others).
// A kernel whose support covers less than half a pixel along an axis (support_mm times the scale
// < 1/2) makes that 1D pass the centre value times the sum of its weights: the kernel lies within
// the centre pixel's bin, the convention of approx/convolve.h (convolve_exact and
// convolve_separable do the same), so a kernel narrower than a pixel is the identity.
//
// Rotation (SssParams::rotate) [JimenezSupp Figs. S.6, S.7]: the product of two 1D kernels is
// a 2D kernel with a cross along the pass axes wherever the 1D profile is not a Gaussian; with
// rotate on, each pixel runs its two passes along its own pair of perpendicular axes, at an
// angle a in [0, pi) hashed from the pixel and the seed (deterministic), so that the cross
// turns with the pixel and averages out into noise. The axes are (cos a, sin a) and
// (-sin a, cos a) on the medium's plane in mm, so in pixels (cos a px, sin a py) and
// (-sin a px, cos a py) per mm, px and py the horizontal and vertical scales above (the aspect
// enters as without rotation). A tap's position along its axis is sampled bilinearly in 2D
// (approx::tap_texels along x and along y: clamp-to-edge), and the edge rule above is applied
// per texel to each of the four (weights (1 - t_x)(1 - t_y), t_x (1 - t_y), (1 - t_x) t_y,
// t_x t_y). The second pass of a pixel reads the first pass's results of its neighbours, each
// along that neighbour's own axis (as the shader does). The narrow-kernel rule above takes the
// larger of the axis's two pixel components. With rotate off the pass is the x, y one above,
// to the bit.
//
// Pixels with material -1 (no medium) pass their input through. Between the two passes of a term
// they hold their input too, which is what kNone then bleeds into the medium.
//
// Threads: rows (horizontal pass) and columns (vertical pass) in parallel (oneTBB); each output
// pixel is computed on its own from the previous pass, so results are bit-identical for any
// thread count (with rotate: rows in parallel for both passes, the same). The pass keeps its
// scratch images (16 bytes a pixel: a small process-wide pool, and per worker thread a row and
// a block of rows) between calls, so that a frame's pass neither page-faults nor zero-fills
// them; without rotate it touches only the medium's bounding box and the rows and columns its
// taps reach.
#pragma once

#include "core/enum_names.h"

#include "approx/convolve.h"
#include "approx/separable.h"

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace ssslab::realtime {

/// What the pass reads per pixel (row-major, y down, width x height; the layout of RasterFrame).
struct SssGBuffer {
    int width = 0, height = 0;
    /// Irradiance transmitted into the medium, RGB interleaved (3 floats a pixel).
    std::vector<float> irradiance;
    /// View depth: distance along the camera's forward axis (RasterFrame::view_z), world units,
    /// > 0 and finite where there is a medium. Eq. 4.11 scales by it, not by the ray distance.
    std::vector<float> view_z;
    /// Index into the material kernels, -1: no medium (the input passes through).
    std::vector<int32_t> material;

    SssGBuffer() = default;
    SssGBuffer(int w, int h);  ///< zero irradiance, depth 1, material 0
    size_t pixels() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
};

/// One separable term of a material's kernel: 1D taps (offsets in mm, weights per channel) and
/// the term's sign per channel (an SVD term of a negative eigenvalue: -1).
struct SssTerm {
    approx::TapKernel taps;
    std::array<double, 3> sign = {1, 1, 1};
};

/// A material's kernel: rank N, N terms (each a horizontal and a vertical pass).
struct SssMaterialKernel {
    std::vector<SssTerm> terms;
};

/// The kernel of a material from any model's result (one SeparableKernel per channel, the same
/// rank in all three): per term k, `count` importance-sampled taps of term k
/// (approx::make_term_taps) and its signs.
SssMaterialKernel make_material_kernel(const std::array<const approx::SeparableKernel*, 3>& a,
                                       int count, double support_mass = 0.995);

enum class SssEdgeMode {
    kNone,           ///< no geometry awareness
    kFollowSurface,  ///< blend toward the centre by depth difference [Freude14 Eq. 4.12]
    kReject,         ///< drop samples across depth or material edges, renormalise per channel
};
}  // namespace ssslab::realtime
template <>
struct ssslab::EnumNames<ssslab::realtime::SssEdgeMode> {
    using E = ssslab::realtime::SssEdgeMode;
    static constexpr std::array<std::pair<E, std::string_view>, 3> table = {
        {{E::kFollowSurface, "follow"}, {E::kReject, "reject"}, {E::kNone, "none"}}};
};
namespace ssslab::realtime {

/// Parameters of the pass. Units: world units unless stated.
struct SssParams {
    double tan_half = 1;  ///< tan(fov_y / 2) of the camera
    double aspect = 1;    ///< image width / height (RasterCamera::aspect)
    double unit_mm = 1;   ///< one world unit in mm (Scene::unit_mm)
    SssEdgeMode mode = SssEdgeMode::kFollowSurface;
    /// C SSS_w of Eq. 4.12, per world unit of depth difference (the demo's C = 300 times its
    /// sssWidth = 0.012 gives 3.6 in its scene's units; scale it with the scene's unit).
    double follow_strength = 3.6;
    double reject_depth = 1;  ///< kReject: largest depth difference kept
    double jitter = 0;        ///< fraction of a tap's half cell it may move (0.33: "33 %")
    uint32_t seed = 0;        ///< of the jitter and rotation hashes (0: convolve_taps's)
    /// Per-pixel rotation of the pass axes against the cross pattern of separable kernels
    /// [JimenezSupp Figs. S.6, S.7]: each pixel's two 1D passes run along its own pair of
    /// perpendicular axes (see the file comment). false: the axes are x and y.
    bool rotate = false;
};

/// The checks of sss_pass's inputs (every backend's): throws std::invalid_argument on
/// inconsistent sizes, taps without weights or bad parameters.
void check_sss_inputs(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                      const SssParams& p);

/// Whether the pass takes a pixel of material m at view depth z (materials: how many kernels).
inline bool sss_pixel_ok(int32_t m, float z, size_t materials) {
    return m == -1 || (m >= 0 && m < static_cast<int32_t>(materials) && z > 0 &&
                       z <= std::numeric_limits<float>::max());
}
/// Throws the pass's std::invalid_argument for pixel i, one that sss_pixel_ok refuses.
[[noreturn]] void refuse_sss_pixel(const SssGBuffer& g, size_t materials, size_t i);

/// The pass: output irradiance after subsurface scattering, RGB interleaved as the input.
/// Throws std::invalid_argument on inconsistent sizes, a material index without a kernel, a
/// medium pixel of non-positive or non-finite depth, or bad parameters.
std::vector<float> sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                            const SssParams& p);
/// The same into `out`, whose storage is reused when the size is unchanged.
void sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
              const SssParams& p, std::vector<float>& out);

}  // namespace ssslab::realtime
