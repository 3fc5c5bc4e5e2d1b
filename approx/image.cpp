#include "approx/image.h"

#include "core/hash.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace ssslab::approx {

ImageRGB::ImageRGB(int w, int h, double pixel, double fill) : width(w), height(h), pixel_mm(pixel) {
    if (w < 0 || h < 0) throw std::invalid_argument("ImageRGB: negative size");
    for (auto& ch : c) ch.assign(static_cast<size_t>(w) * static_cast<size_t>(h), fill);
}

const char* signal_name(Signal s) {
    switch (s) {
        case Signal::kEdge:
            return "edge";
        case Signal::kCircleSquares:
            return "circle_squares";
        case Signal::kDot:
            return "dot";
        case Signal::kSkinShaded:
            return "skin_shaded";
        case Signal::kSkinUniform:
            return "skin_uniform";
    }
    return "unknown";
}

bool parse_signal(const std::string& name, Signal& out) {
    for (Signal s : {Signal::kEdge, Signal::kCircleSquares, Signal::kDot, Signal::kSkinShaded,
                     Signal::kSkinUniform}) {
        if (name == signal_name(s)) {
            out = s;
            return true;
        }
    }
    return false;
}

namespace {

constexpr int kSuper = 4;  // 4 x 4 sub-pixel samples

// Value in [0, 1] attached to lattice point (ix, iy) of noise layer `layer`.
double lattice(int ix, int iy, uint32_t layer) {
    const uint32_t h = hash32(static_cast<uint32_t>(ix) * 0x8da6b343U ^
                              hash32(static_cast<uint32_t>(iy) * 0xd8163841U ^ hash32(layer)));
    return (h >> 8) * (1.0 / 16777216.0);
}

struct NoiseSample {
    double v = 0, dx = 0, dy = 0;  // value and its gradient (per lattice unit)
};

// Value noise: lattice values blended with the quintic fade, with its analytic gradient.
NoiseSample value_noise(double x, double y, uint32_t layer) {
    const double fx = std::floor(x), fy = std::floor(y);
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
    const double tx = x - fx, ty = y - fy;
    auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    auto dfade = [](double t) { return 30 * t * t * (t * (t - 2) + 1); };
    const double sx = fade(tx), sy = fade(ty), dsx = dfade(tx), dsy = dfade(ty);
    const double v00 = lattice(ix, iy, layer), v10 = lattice(ix + 1, iy, layer);
    const double v01 = lattice(ix, iy + 1, layer), v11 = lattice(ix + 1, iy + 1, layer);
    const double a = v00 + sx * (v10 - v00);  // along x at y = iy
    const double b = v01 + sx * (v11 - v01);  // along x at y = iy + 1
    NoiseSample s;
    s.v = a + sy * (b - a);
    s.dx = dsx * ((v10 - v00) + sy * ((v11 - v01) - (v10 - v00)));
    s.dy = dsy * (b - a);
    return s;
}

// Fractal sum of value noise over the given feature scales (mm), normalised to [0, 1], with the
// gradient per mm. Each octave has its own hashed layer and lattice offset.
NoiseSample fbm(double xmm, double ymm, const std::vector<double>& scales, double persistence,
                uint32_t layer) {
    NoiseSample out;
    double amp = 1, total = 0;
    for (size_t o = 0; o < scales.size(); ++o) {
        const uint32_t l = hash32(layer * 131U + static_cast<uint32_t>(o));
        const double ox = (hash32(l ^ 0x1234567U) >> 8) * (1.0 / 16777216.0) * 97.0;
        const double oy = (hash32(l ^ 0x7654321U) >> 8) * (1.0 / 16777216.0) * 89.0;
        const NoiseSample s = value_noise(xmm / scales[o] + ox, ymm / scales[o] + oy, l);
        out.v += amp * s.v;
        out.dx += amp * s.dx / scales[o];
        out.dy += amp * s.dy / scales[o];
        total += amp;
        amp *= persistence;
    }
    out.v /= total;
    out.dx /= total;
    out.dy /= total;
    return out;
}

double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

// The skin patch at a point (mm); `u`, `v` are the coordinates relative to the patch, in [0, 1].
std::array<double, 3> skin(double xmm, double ymm, double u, double v, bool shaded, unsigned seed) {
    static const std::vector<double> kAlbedoScales = {2.0, 1.0, 0.5, 0.25, 0.12};
    static const std::vector<double> kRednessScales = {1.5, 0.7, 0.35};
    static const std::vector<double> kPoreScales = {0.1};
    static const std::vector<double> kHeightScales = {3.0, 1.5, 0.7, 0.3, 0.15};
    const uint32_t s = hash32(seed * 0x9e3779b9U + 0x5bd1e995U);
    const double t1 = fbm(xmm, ymm, kAlbedoScales, 0.6, s ^ 0x11U).v;
    const double t2 = fbm(xmm, ymm, kRednessScales, 0.6, s ^ 0x22U).v;
    const double pore = smoothstep(0.72, 0.92, fbm(xmm, ymm, kPoreScales, 1.0, s ^ 0x33U).v);
    const std::array<double, 3> base = {0.85, 0.62, 0.50};
    std::array<double, 3> a{};
    const double m = 0.8 + 0.35 * t1;
    a[0] = base[0] * m;
    a[1] = base[1] * m * (1 - 0.25 * (t2 - 0.5));
    a[2] = base[2] * m * (1 - 0.15 * (t2 - 0.5));
    for (double& x : a) x = std::clamp(x * (1 - 0.3 * pore), 0.0, 1.0);
    if (!shaded) return a;
    // Lambert shading of a procedural height field (amplitude 0.35 mm), light from the upper
    // left, and a straight shadow boundary across the patch where only ambient light arrives.
    double irradiance = 0.05;
    if (u + v < 1.2) {
        const NoiseSample hgt = fbm(xmm, ymm, kHeightScales, 0.55, s ^ 0x44U);
        const double amp = 0.35;
        double nx = -amp * hgt.dx, ny = -amp * hgt.dy, nz = 1;
        const double nn = std::sqrt(nx * nx + ny * ny + nz * nz);
        nx /= nn;
        ny /= nn;
        nz /= nn;
        const double lx = -0.45, ly = -0.4, lz = 0.8;
        const double ln = std::sqrt(lx * lx + ly * ly + lz * lz);
        const double cosine = std::max(0.0, (nx * lx + ny * ly + nz * lz) / ln);
        irradiance = 0.05 + 0.95 * cosine;
    }
    for (double& x : a) x = std::clamp(x * irradiance, 0.0, 1.0);
    return a;
}

}  // namespace

ImageRGB make_signal(Signal s, const SignalParams& p) {
    if (p.size < 1) throw std::invalid_argument("make_signal: size < 1");
    if (!(p.pixel_mm > 0)) throw std::invalid_argument("make_signal: pixel_mm must be > 0");
    const int n = p.size;
    const double w = n;  // image side in pixels
    ImageRGB img(n, n, p.pixel_mm, 0.0);

    // Circle and squares, in pixel units: a disk at (0.3 W, 0.5 H), radius W / 6, and two squares
    // of side W / 5 rotated by 30 degrees, sharing an edge, centred at (0.7 W, 0.5 H).
    const double disk_cx = 0.3 * w, disk_cy = 0.5 * w, disk_r = w / 6.0;
    const double side = w / 5.0, ang = 30.0 * 3.14159265358979323846 / 180.0;
    const double e1x = std::cos(ang), e1y = std::sin(ang);  // the squares' local axes
    const double e2x = -std::sin(ang), e2y = std::cos(ang);
    const double pair_cx = 0.7 * w, pair_cy = 0.5 * w;
    // The squares are stacked along e2: centres at the pair's centre -+ side / 2 e2.
    const double sq_c[2][2] = {{pair_cx - 0.5 * side * e2x, pair_cy - 0.5 * side * e2y},
                               {pair_cx + 0.5 * side * e2x, pair_cy + 0.5 * side * e2y}};
    const double dot_r = p.dot_radius_mm / p.pixel_mm;

    auto inside_shape = [&](double x, double y) -> double {
        const double dx = x - disk_cx, dy = y - disk_cy;
        if (dx * dx + dy * dy <= disk_r * disk_r) return 1.0;
        for (const auto& c : sq_c) {
            const double rx = x - c[0], ry = y - c[1];
            if (std::fabs(rx * e1x + ry * e1y) <= 0.5 * side &&
                std::fabs(rx * e2x + ry * e2y) <= 0.5 * side)
                return 1.0;
        }
        return 0.0;
    };

    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
        for (int py = rows.begin(); py < rows.end(); ++py)
            for (int px = 0; px < n; ++px) {
                std::array<double, 3> acc{};
                for (int sy = 0; sy < kSuper; ++sy)
                    for (int sx = 0; sx < kSuper; ++sx) {
                        // Sub-sample position in pixel units (pixel (x, y) covers [x, x + 1)).
                        const double x = px + (sx + 0.5) / kSuper;
                        const double y = py + (sy + 0.5) / kSuper;
                        std::array<double, 3> v{};
                        switch (s) {
                            case Signal::kEdge:
                                v.fill(x < 0.5 * w ? 1.0 : 0.0);
                                break;
                            case Signal::kCircleSquares:
                                v.fill(inside_shape(x, y));
                                break;
                            case Signal::kDot: {
                                const double dx = x - 0.5 * w, dy = y - 0.5 * w;
                                v.fill(dx * dx + dy * dy <= dot_r * dot_r ? 1.0 : 0.0);
                                break;
                            }
                            case Signal::kSkinShaded:
                            case Signal::kSkinUniform:
                                v = skin(x * p.pixel_mm, y * p.pixel_mm, x / w, y / w,
                                         s == Signal::kSkinShaded, p.seed);
                                break;
                        }
                        for (int ch = 0; ch < 3; ++ch) acc[ch] += v[ch];
                    }
                for (int ch = 0; ch < 3; ++ch)
                    img.at(ch, px, py) = std::clamp(acc[ch] / (kSuper * kSuper), 0.0, 1.0);
            }
    });
    return img;
}

namespace {
void check_same_shape(const ImageRGB& a, const ImageRGB& b, const char* what) {
    if (a.width != b.width || a.height != b.height)
        throw std::invalid_argument(std::string(what) + ": images of different sizes");
    const size_t n = static_cast<size_t>(a.width) * static_cast<size_t>(a.height);
    for (int ch = 0; ch < 3; ++ch)
        if (a.c[ch].size() != n || b.c[ch].size() != n)
            throw std::invalid_argument(std::string(what) + ": channel size mismatch");
}
}  // namespace

ImageErrors image_errors(const ImageRGB& approx, const ImageRGB& exact) {
    check_same_shape(approx, exact, "image_errors");
    ImageErrors e;
    for (int ch = 0; ch < 3; ++ch) {
        const auto& a = approx.c[ch];
        const auto& x = exact.c[ch];
        double sq = 0, mx = 0, sa = 0, sx = 0;
        for (size_t i = 0; i < a.size(); ++i) {
            const double d = a[i] - x[i];
            sq += d * d;
            mx = std::max(mx, std::fabs(d));
            sa += a[i];
            sx += x[i];
        }
        e.rms[ch] = a.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(a.size()));
        e.max_abs[ch] = mx;
        // A black exact image has no relative energy error: report the absolute one then.
        e.energy[ch] = sx != 0 ? (sa - sx) / sx : sa - sx;
    }
    return e;
}

namespace {
unsigned char to_byte(double v) {
    if (!(v > 0)) return 0;  // also NaN
    if (v >= 1) return 255;
    return static_cast<unsigned char>(std::lround(v * 255.0));
}
}  // namespace

std::vector<unsigned char> to_rgb8(const ImageRGB& img, bool srgb) {
    const size_t n = static_cast<size_t>(img.width) * static_cast<size_t>(img.height);
    std::vector<unsigned char> out(3 * n);
    for (size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch) {
            double v = std::clamp(img.c[ch][i], 0.0, 1.0);
            if (srgb) v = std::pow(v, 1.0 / 2.2);
            out[3 * i + static_cast<size_t>(ch)] = to_byte(v);
        }
    return out;
}

std::vector<unsigned char> difference_rgb8(const ImageRGB& a, const ImageRGB& b, double scale) {
    check_same_shape(a, b, "difference_rgb8");
    if (!(scale > 0)) throw std::invalid_argument("difference_rgb8: scale must be > 0");
    const size_t n = static_cast<size_t>(a.width) * static_cast<size_t>(a.height);
    std::vector<unsigned char> out(3 * n);
    for (size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch)
            out[3 * i + static_cast<size_t>(ch)] =
                to_byte(std::fabs(a.c[ch][i] - b.c[ch][i]) / scale);
    return out;
}

}  // namespace ssslab::approx
