// Images in physical units and the test signals of the kernel comparisons [Freude14 Figs. 6.3-6.10,
// 5.10, 5.12; JimenezSupp Fig. S.5]. An image is an irradiance (or radiant exitance) per RGB
// channel on a grid of square pixels of side pixel_mm; pixel (x, y) covers
// [x p, (x + 1) p) x [y p, (y + 1) p), x to the right, y down.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace ssslab::approx {

struct ImageRGB {
    int width = 0, height = 0;
    double pixel_mm = 0;
    std::array<std::vector<double>, 3> c;  ///< row-major, c[ch][y * width + x]

    ImageRGB() = default;
    ImageRGB(int w, int h, double pixel_mm, double fill = 0.0);
    double& at(int ch, int x, int y) { return c[ch][static_cast<size_t>(y) * width + x]; }
    double at(int ch, int x, int y) const { return c[ch][static_cast<size_t>(y) * width + x]; }
};

/// The test signals. All are deterministic; values in [0, 1]; anti-aliased by averaging 4 x 4
/// sub-pixel samples where they have edges. `size` pixels square, `pixel_mm` per pixel.
enum class Signal {
    kEdge,           ///< white left half, black right half: a vertical edge (Figs. 6.3-6.5)
    kCircleSquares,  ///< a disk beside two tilted, adjacent squares (Figs. 6.6-6.10)
    kDot,            ///< a small white disk in the centre, radius dot_radius_mm (Fig. S.5)
    kSkinShaded,     ///< procedural skin-like albedo under shading with a sharp shadow (Fig. 5.10)
    kSkinUniform,    ///< the same albedo, uniformly lit (Fig. 5.12)
};
const char* signal_name(Signal s);
/// Parse a name ("edge", "circle_squares", "dot", "skin_shaded", "skin_uniform").
bool parse_signal(const std::string& name, Signal& out);

struct SignalParams {
    int size = 256;
    double pixel_mm = 0.05;
    double dot_radius_mm = 0.25;
    unsigned seed = 1;  ///< procedural texture of the skin patches
};
ImageRGB make_signal(Signal s, const SignalParams& p);

/// Per-channel comparison of an approximation with the exact result.
struct ImageErrors {
    std::array<double, 3> rms{};      ///< sqrt(mean (approx - exact)^2)
    std::array<double, 3> max_abs{};  ///< max |approx - exact|
    std::array<double, 3> energy{};   ///< (sum approx - sum exact) / sum exact
};
ImageErrors image_errors(const ImageRGB& approx, const ImageRGB& exact);

/// 8-bit PNG-ready RGB bytes (clamped to [0, 1], gamma 2.2 when `srgb`), and a difference
/// image |a - b| scaled so that `scale` maps to white.
std::vector<unsigned char> to_rgb8(const ImageRGB& img, bool srgb = true);
std::vector<unsigned char> difference_rgb8(const ImageRGB& a, const ImageRGB& b, double scale);

}  // namespace ssslab::approx
