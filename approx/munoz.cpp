#include "approx/munoz.h"

#include "approx/option_list.h"

#include "approx/fft.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace ssslab::approx {

namespace {

using detail::Fft2D;
using detail::fft_size;

// MunozKernel::pixel_average: the pixels within this many of the centre averaged over
// kSub x kSub points (beyond, the profile is smooth over a pixel or negligible).
constexpr int kAveragedRing = 4;
constexpr int kSub = 16;

/// The options' ranges (munoz_exitance and parse_munoz; the config key of the threshold is t).
void check_options(const MunozOptions& o) {
    auto fail = [](const std::string& what) { throw std::invalid_argument("munoz: " + what); };
    if (o.layers < 1 || o.layers > 16)
        fail("layers must be in 1..16, got " + std::to_string(o.layers));
    if (!(o.threshold >= 0 && o.threshold < 1))
        fail("threshold t must be in [0, 1), got " + std::to_string(o.threshold));
    if (o.downsample < 1 || o.downsample > 8)
        fail("downsample must be in 1..8, got " + std::to_string(o.downsample));
}

void check(const MunozView& v, const MunozOptions& o) {
    auto fail = [](const std::string& what) { throw std::invalid_argument("munoz: " + what); };
    check_options(o);
    if (v.width < 1 || v.height < 1) fail("the view has no pixels");
    const size_t n = static_cast<size_t>(v.width) * static_cast<size_t>(v.height);
    if (v.front_z.size() != n || v.back_z.size() != n) fail("front_z or back_z: wrong size");
    for (int c = 0; c < 3; ++c)
        if (v.front_irradiance[c].size() != n || v.back_irradiance[c].size() != n)
            fail("front_irradiance or back_irradiance: wrong size");
    if (!std::isfinite(v.pixel_mm) || !std::isfinite(v.pixel_mm_per_depth))
        fail("pixel_mm and pixel_mm_per_depth must be finite");
    for (size_t i = 0; i < n; ++i) {
        const float f = v.front_z[i], b = v.back_z[i];
        if (std::isnan(f) || std::isnan(b)) fail("a NaN depth at pixel " + std::to_string(i));
        if (std::isinf(f) && !std::isinf(b))
            fail("pixel " + std::to_string(i) + " has a back sample and no front one");
        if (std::isfinite(b) && b < f)
            fail("pixel " + std::to_string(i) + ": the back sample is nearer than the front one");
        for (float z : {f, b})
            if (std::isfinite(z) && !(v.pixel_mm + v.pixel_mm_per_depth * z > 0))
                fail("the pixel size at depth " + std::to_string(z) + " mm is not positive");
        for (int c = 0; c < 3; ++c)
            for (float e : {v.front_irradiance[c][i], v.back_irradiance[c][i]})
                if (!std::isfinite(e) || e < 0)
                    fail("irradiance must be finite and >= 0 (pixel " + std::to_string(i) + ")");
    }
}

/// Where a depth falls between the layers: the lower layer and the fraction towards the next.
struct LayerPos {
    int l0 = 0;
    double s = 0;
};

LayerPos layer_of(double z, double z_min, double dz, int layers) {
    if (layers == 1 || !(dz > 0)) return {0, 0};
    const double u = std::clamp((z - z_min) / dz, 0.0, static_cast<double>(layers - 1));
    const int l0 = std::min(static_cast<int>(std::floor(u)), layers - 2);
    return {l0, u - l0};
}

}  // namespace

const char* split_name(MunozSplit s) {
    return s == MunozSplit::equal ? "equal" : s == MunozSplit::linear ? "linear" : "nearest";
}

MunozOptions parse_munoz(const std::string& spec) {
    MunozOptions o;
    const OptionList list("munoz", spec);
    for (const auto& [key, v] : list.items()) {
        if (key == "layers")
            o.layers = list.whole(key, v);
        else if (key == "t")
            o.threshold = list.number(key, v);
        else if (key == "downsample")
            o.downsample = list.whole(key, v);
        else if (key == "split" && (v == "equal" || v == "linear" || v == "nearest"))
            o.split = v == "equal"    ? MunozSplit::equal
                      : v == "linear" ? MunozSplit::linear
                                      : MunozSplit::nearest;
        else if (key == "visible" && (v == "skip" || v == "all"))
            o.skip_invisible = v == "skip";
        else if (key == "kernel" && (v == "point" || v == "average"))
            o.kernel = v == "point" ? MunozKernel::point : MunozKernel::pixel_average;
        else if (key == "split" || key == "visible" || key == "kernel")
            throw std::invalid_argument("munoz \"" + key + "\": unknown value \"" + v + "\"");
        else
            throw std::invalid_argument(
                "munoz: unknown key \"" + key +
                "\" (known: layers, t, downsample, split, visible, kernel)");
    }
    check_options(o);
    return o;
}

std::string munoz_label(const MunozOptions& o) {
    std::ostringstream s;
    s << "layers=" << o.layers << ",t=" << o.threshold << ",downsample=" << o.downsample
      << ",split=" << split_name(o.split) << ",visible=" << (o.skip_invisible ? "skip" : "all")
      << ",kernel=" << (o.kernel == MunozKernel::point ? "point" : "average");
    return s.str();
}

namespace {

using Spectrum = std::vector<std::complex<double>>;

/// The forward transform of fft's real buffer into `out`.
void to_spectrum(Fft2D& fft, size_t nspec, Spectrum& out) {
    fft.forward();
    out.resize(nspec);
    const fftw_complex* s = fft.spec();
    for (size_t k = 0; k < nspec; ++k) out[k] = {s[k][0], s[k][1]};
}

/// One evaluation of Munoz11's layered convolution: the depth layers, the coarse irradiance
/// maps per layer and channel (e), their convolutions (m) and the result.
struct LayeredConvolution {
    LayeredConvolution(const MunozView& view, const RadialFunction& profile,
                       const MunozOptions& options, MunozResult& result)
        : v(view), rd(profile), o(options), res(result) {}

    const MunozView& v;
    const RadialFunction& rd;
    const MunozOptions& o;
    MunozResult& res;
    const int w = v.width, h = v.height, nl = o.layers, d = o.downsample;
    const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
    const int wc = (w + d - 1) / d, hc = (h + d - 1) / d;
    const size_t nc = static_cast<size_t>(wc) * static_cast<size_t>(hc);
    double z_min = 0, dz = 0;
    std::vector<std::array<std::vector<double>, 3>> e, m;
    std::vector<char> seen;

    double layer_z(int l) const { return z_min + l * dz; }
    double pixel_at(double z) const { return v.pixel_mm + v.pixel_mm_per_depth * z; }
    bool find_layers();
    void deposit_irradiance();
    void convolve();
    void convolve_channel(int c, Fft2D& fft, int nx, int ny, size_t nspec, size_t nreal,
                          const std::array<double, 3>& r0);
    void interpolate();
};

/// The layers over the depths of every sample; false when no object is in view.
bool LayeredConvolution::find_layers() {
    // [Munoz11 §4.2]
    z_min = std::numeric_limits<double>::infinity();
    double z_max = -z_min;
    for (size_t i = 0; i < n; ++i)
        for (float z : {v.front_z[i], v.back_z[i]})
            if (std::isfinite(z)) {
                z_min = std::min(z_min, static_cast<double>(z));
                z_max = std::max(z_max, static_cast<double>(z));
            }
    if (!std::isfinite(z_min)) return false;  // no object in view
    dz = nl > 1 ? (z_max - z_min) / (nl - 1) : 0.0;
    res.stats.dz_mm = dz;
    return true;
}

/// Irradiance maps per layer and channel on the coarse grid, and the layers Eq. 7 reads.
void LayeredConvolution::deposit_irradiance() {
    // Irradiance maps per layer and channel on the coarse grid: each sample's irradiance split
    // between its two nearest layers, averaged over the downsampling block (power conserved).
    e.resize(static_cast<size_t>(nl));
    for (auto& layer : e)
        for (auto& c : layer) c.assign(nc, 0.0);
    const double block = 1.0 / (static_cast<double>(d) * d);
    auto deposit = [&](size_t i, double z, const std::array<std::vector<float>, 3>& irr) {
        const LayerPos p = layer_of(z, z_min, dz, nl);
        double w0 = 1, w1 = 0;
        if (nl > 1 && dz > 0) {
            w1 = o.split == MunozSplit::equal    ? 0.5
                 : o.split == MunozSplit::linear ? p.s
                                                 : (p.s >= 0.5 ? 1.0 : 0.0);
            w0 = 1 - w1;
        }
        const size_t x = i % static_cast<size_t>(w), y = i / static_cast<size_t>(w);
        const size_t j = (y / d) * static_cast<size_t>(wc) + x / d;
        for (int c = 0; c < 3; ++c) {
            const double ec = irr[c][i] * block;
            e[p.l0][c][j] += w0 * ec;
            if (w1 > 0) e[p.l0 + 1][c][j] += w1 * ec;
        }
    };
    seen.assign(static_cast<size_t>(nl), 0);
    for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v.front_z[i])) continue;
        deposit(i, v.front_z[i], v.front_irradiance);
        if (std::isfinite(v.back_z[i])) deposit(i, v.back_z[i], v.back_irradiance);
        // Eq. 7 reads the two layers about the visible depth.
        const LayerPos p = layer_of(v.front_z[i], z_min, dz, nl);
        seen[p.l0] = 1;
        if (nl > 1 && dz > 0) seen[p.l0 + 1] = 1;
    }
    for (int l = 0; l < nl; ++l) res.stats.layers_used += seen[l] || !o.skip_invisible;
}

/// Eq. 6, every channel.
void LayeredConvolution::convolve() {
    // Eq. 6 by FFT: zero-padded to a linear convolution of the coarse maps with kernels over
    // every offset -(wc - 1)..(wc - 1), -(hc - 1)..(hc - 1).
    const int nx = fft_size(2 * wc - 1), ny = fft_size(2 * hc - 1);
    const size_t nspec = static_cast<size_t>(nx / 2 + 1) * static_cast<size_t>(ny);
    const size_t nreal = static_cast<size_t>(nx) * static_cast<size_t>(ny);
    Fft2D fft(nx, ny);
    const std::array<double, 3> r0 = rd(0.0);
    m.resize(static_cast<size_t>(nl));

    for (int c = 0; c < 3; ++c) convolve_channel(c, fft, nx, ny, nspec, nreal, r0);
}

/// Eq. 6 in channel c: every visible layer's map, the sum over the source layers of their
/// spectra times the kernel's.
void LayeredConvolution::convolve_channel(int c, Fft2D& fft, int nx, int ny, size_t nspec,
                                          size_t nreal, const std::array<double, 3>& r0) {
    // Spectra of the layers that hold irradiance in this channel.
    std::vector<Spectrum> es(static_cast<size_t>(nl));
    for (int i = 0; i < nl; ++i) {
        const auto& ei = e[i][c];
        if (std::all_of(ei.begin(), ei.end(), [](double x) { return x == 0; })) continue;
        double* r = fft.real();
        std::fill(r, r + nreal, 0.0);
        for (int y = 0; y < hc; ++y)
            for (int x = 0; x < wc; ++x)
                r[static_cast<size_t>(y) * nx + x] = ei[static_cast<size_t>(y) * wc + x];
        to_spectrum(fft, nspec, es[i]);
    }
    // Kernel spectra by (in-plane pixel side, layer distance e) [Eq. 5].
    std::map<std::pair<double, int>, Spectrum> kernels;
    auto kernel = [&](double side, int dist) -> const Spectrum& {
        auto it = kernels.find({side, dist});
        if (it != kernels.end()) return it->second;
        double* r = fft.real();
        const double ez = dist * dz;
        tbb::parallel_for(tbb::blocked_range<int>(0, ny), [&](const auto& range) {
            for (int y = range.begin(); y < range.end(); ++y) {
                // Wrapped offsets: rows/columns past half the size are negative offsets;
                // offsets beyond the maps' reach never meet a pixel and stay 0.
                const int oy = y <= ny / 2 ? y : y - ny;
                for (int x = 0; x < nx; ++x) {
                    const int ox = x <= nx / 2 ? x : x - nx;
                    double k = 0;
                    if (std::abs(ox) < wc && std::abs(oy) < hc) {
                        if (o.kernel == MunozKernel::pixel_average &&
                            std::max(std::abs(ox), std::abs(oy)) <= kAveragedRing) {
                            // The mean over the pixel's square, kSub x kSub midpoints.
                            for (int j = 0; j < kSub; ++j)
                                for (int i = 0; i < kSub; ++i) {
                                    const double px = side * (ox + (i + 0.5) / kSub - 0.5);
                                    const double py = side * (oy + (j + 0.5) / kSub - 0.5);
                                    k += rd(std::sqrt(px * px + py * py + ez * ez))[c];
                                }
                            k /= kSub * kSub;
                        } else {
                            const double px = side * ox, py = side * oy;
                            k = rd(std::sqrt(px * px + py * py + ez * ez))[c];
                        }
                    }
                    r[static_cast<size_t>(y) * nx + x] = k;
                }
            }
        });
        Spectrum s;
        to_spectrum(fft, nspec, s);
        return kernels.emplace(std::make_pair(side, dist), std::move(s)).first->second;
    };
    for (int l = 0; l < nl; ++l) {
        m[l][c].assign(nc, 0.0);
        Spectrum acc(nspec, {0.0, 0.0});
        bool any = false;
        for (int i = 0; i < nl; ++i) {
            if (es[i].empty()) continue;
            const int dist = std::abs(i - l);
            if (o.skip_invisible && !seen[l]) {
                ++res.stats.skipped_invisible;
                continue;
            }
            // Eq. 8: contributions below t R_d(0) are dropped.
            if (o.threshold > 0 && o.threshold * r0[c] > rd(dist * dz)[c]) {
                ++res.stats.skipped_threshold;
                continue;
            }
            const double side = d * pixel_at(0.5 * (layer_z(i) + layer_z(l)));
            const double source = d * pixel_at(layer_z(i));
            const double area = source * source;
            const Spectrum& k = kernel(side, dist);
            const Spectrum& ei = es[i];
            for (size_t q = 0; q < nspec; ++q) acc[q] += area * ei[q] * k[q];
            ++res.stats.convolutions;
            any = true;
        }
        if (!any) continue;
        fftw_complex* s = fft.spec();
        for (size_t q = 0; q < nspec; ++q) {
            s[q][0] = acc[q].real();
            s[q][1] = acc[q].imag();
        }
        fft.inverse();
        const double norm = 1.0 / static_cast<double>(nreal);
        const double* r = fft.real();
        for (int y = 0; y < hc; ++y)
            for (int x = 0; x < wc; ++x)
                m[l][c][static_cast<size_t>(y) * wc + x] =
                    r[static_cast<size_t>(y) * nx + x] * norm;
    }
}

/// Eq. 7 into the result.
void LayeredConvolution::interpolate() {
    // Eq. 7: each visible sample interpolates the two layers about its depth, the coarse maps
    // read bilinearly at the pixel's centre.
    auto coarse = [&](const std::vector<double>& map, int x, int y) {
        if (d == 1) return map[static_cast<size_t>(y) * wc + x];
        const double u = std::clamp((x + 0.5) / d - 0.5, 0.0, wc - 1.0);
        const double t = std::clamp((y + 0.5) / d - 0.5, 0.0, hc - 1.0);
        const int x0 = std::min(static_cast<int>(u), wc - 1),
                  y0 = std::min(static_cast<int>(t), hc - 1);
        const int x1 = std::min(x0 + 1, wc - 1), y1 = std::min(y0 + 1, hc - 1);
        const double fx = u - x0, fy = t - y0;
        auto at = [&](int xx, int yy) { return map[static_cast<size_t>(yy) * wc + xx]; };
        return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) +
               fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
    };
    for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v.front_z[i])) continue;
        const int x = static_cast<int>(i % static_cast<size_t>(w));
        const int y = static_cast<int>(i / static_cast<size_t>(w));
        LayerPos p = layer_of(v.front_z[i], z_min, dz, nl);
        if (o.split == MunozSplit::nearest && p.s > 0)
            p = p.s >= 0.5 ? LayerPos{p.l0 + 1, 0.0} : LayerPos{p.l0, 0.0};
        for (int c = 0; c < 3; ++c) {
            double val = (1 - p.s) * coarse(m[p.l0][c], x, y);
            if (p.s > 0) val += p.s * coarse(m[p.l0 + 1][c], x, y);
            res.exitance[c][i] = static_cast<float>(std::max(val, 0.0));
        }
    }
}

}  // namespace

MunozResult munoz_exitance(const MunozView& v, const RadialFunction& rd, const MunozOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    check(v, o);
    MunozResult res;
    LayeredConvolution lc(v, rd, o, res);
    for (auto& map : res.exitance) map.assign(lc.n, 0.0f);
    if (!lc.find_layers()) return res;
    lc.deposit_irradiance();
    lc.convolve();
    lc.interpolate();
    res.stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
}

}  // namespace ssslab::approx
