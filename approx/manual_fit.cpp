// The manual two-Gaussian model's "close fit" [Freude14 §5.4]: the parameters an artist would
// find by tuning the model in image space, found by minimising the image-space RMS against the
// exact 2D convolution of a test signal.
//
// For fixed widths the separable result is a quadratic form in w:
//   a_m (x) a_m = w^2 P_nn + w (1 - w) (P_nf + P_fn) + (1 - w)^2 P_ff,
// with P_ij the image convolved horizontally with G_i and vertically with G_j, so the squared
// error is a quartic in w, minimised exactly on [0, 1]. The two widths are searched on a
// log-spaced grid (row passes cached per width) and refined by Nelder-Mead in log space.
#include "approx/convolve.h"
#include "approx/models.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab::approx {

namespace {

using Plane = std::vector<double>;

// out(x, y) = sum_d k[d + r] in(clamp(x - d), y): the convolution of convolve.h along x.
Plane conv_rows(const Plane& in, int w, int h, const std::vector<double>& k) {
    const int r = static_cast<int>(k.size() / 2);
    Plane out(in.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        std::vector<double> pad(static_cast<size_t>(w + 2 * r));
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const double* src = in.data() + static_cast<size_t>(y) * w;
            for (int u = 0; u < w + 2 * r; ++u)
                pad[static_cast<size_t>(u)] = src[std::clamp(u - r, 0, w - 1)];
            double* dst = out.data() + static_cast<size_t>(y) * w;
            // out(x) = sum_j k[j] pad[x + 2 r - j], j = d + r.
            for (int x = 0; x < w; ++x) {
                double s = 0;
                const double* p = pad.data() + x + 2 * r;
                for (int j = 0; j <= 2 * r; ++j) s += k[static_cast<size_t>(j)] * p[-j];
                dst[x] = s;
            }
        }
    });
    return out;
}

// The same along y.
Plane conv_cols(const Plane& in, int w, int h, const std::vector<double>& k) {
    const int r = static_cast<int>(k.size() / 2);
    Plane out(in.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            double* dst = out.data() + static_cast<size_t>(y) * w;
            for (int j = 0; j <= 2 * r; ++j) {
                const int src_y = std::clamp(y - (j - r), 0, h - 1);
                const double kj = k[static_cast<size_t>(j)];
                const double* src = in.data() + static_cast<size_t>(src_y) * w;
                for (int x = 0; x < w; ++x) dst[x] += kj * src[x];
            }
        }
    });
    return out;
}

struct Quartic {
    std::array<double, 5> c{};  // E(w) = sum c_i w^i
    double at(double w) const { return (((c[4] * w + c[3]) * w + c[2]) * w + c[1]) * w + c[0]; }
    double slope(double w) const { return ((4 * c[4] * w + 3 * c[3]) * w + 2 * c[2]) * w + c[1]; }
    double curvature(double w) const { return (12 * c[4] * w + 6 * c[3]) * w + 2 * c[2]; }
};

// argmin of a quartic on [0, 1]: the best of a fine scan, polished by safeguarded Newton steps.
double minimise_quartic(const Quartic& q, double& best) {
    double wb = 0;
    best = q.at(0);
    for (int i = 1; i <= 400; ++i) {
        const double w = i / 400.0, e = q.at(w);
        if (e < best) best = e, wb = w;
    }
    for (int it = 0; it < 30; ++it) {
        const double g = q.slope(wb), c = q.curvature(wb);
        if (!(c > 0)) break;
        const double next =
            std::clamp(wb - g / c, std::max(0.0, wb - 0.0025), std::min(1.0, wb + 0.0025));
        const double e = q.at(next);
        if (!(e < best)) break;
        best = e, wb = next;
    }
    return wb;
}

class Fitter {
  public:
    Fitter(const Kernel2D& k, const ImageRGB& signal, const ImageRGB& exact, int channel)
        : k_(k),
          w_(signal.width),
          h_(signal.height),
          p_(signal.pixel_mm),
          e_(signal.c[static_cast<size_t>(channel)]),
          t_(exact.c[static_cast<size_t>(channel)]) {}

    // One Gaussian of width sigma (mm) resampled to pixel offsets along x and along y; the
    // Gaussian is cut at 8 sigma (the mass beyond, below 1e-15, is folded onto the last offset).
    std::vector<double> pixels(double sigma, int image_side) const {
        const ModelResult g = manual_two_gaussian(k_, sigma, sigma, 1.0);
        const int fold =
            std::min(image_side - 1, static_cast<int>(std::ceil(8.0 * sigma / p_)) + 1);
        return resample_1d(g.kernel.terms[0].a, k_.h_mm(), p_, fold);
    }

    // The error quartic of a width pair from the row passes of each width.
    Quartic quartic(const Plane& rows_n, const Plane& rows_f, const std::vector<double>& yn,
                    const std::vector<double>& yf) {
        ++evaluations;
        const Plane a = conv_cols(rows_n, w_, h_, yn);
        const Plane c = conv_cols(rows_f, w_, h_, yf);
        const Plane b1 = conv_cols(rows_n, w_, h_, yf);
        const Plane b2 = conv_cols(rows_f, w_, h_, yn);
        // E(w) = |U + w V + w^2 W|^2, U = C - T, V = B - 2C, W = A - B + C.
        double uu = 0, uv = 0, vv = 0, uw = 0, vw = 0, ww = 0;
        for (size_t i = 0; i < t_.size(); ++i) {
            const double b = b1[i] + b2[i];
            const double u = c[i] - t_[i], v = b - 2 * c[i], x = a[i] - b + c[i];
            uu += u * u, uv += u * v, vv += v * v, uw += u * x, vw += v * x, ww += x * x;
        }
        Quartic q;
        q.c = {uu, 2 * uv, vv + 2 * uw, 2 * vw, ww};
        return q;
    }

    // Squared error and the best w for a width pair (log widths).
    double evaluate(double log_near, double log_far, double& w) {
        const double sn = std::exp(log_near), sf = std::exp(log_far);
        const Plane rn = conv_rows(e_, w_, h_, pixels(sn, w_));
        const Plane rf = conv_rows(e_, w_, h_, pixels(sf, w_));
        const Quartic q = quartic(rn, rf, pixels(sn, h_), pixels(sf, h_));
        double best = 0;
        w = minimise_quartic(q, best);
        return std::max(best, 0.0);
    }

    const Kernel2D& k_;
    int w_, h_;
    double p_;
    const Plane& e_;
    const Plane& t_;
    int evaluations = 0;
};

}  // namespace

ModelResult fit_manual_two_gaussian(const Kernel2D& k, const ImageRGB& signal,
                                    const ImageRGB& exact, int channel) {
    const auto t0 = std::chrono::steady_clock::now();
    if (channel < 0 || channel > 2)
        throw std::invalid_argument("fit_manual_two_gaussian: channel must be 0, 1 or 2");
    if (signal.width < 2 || signal.height < 2 || signal.width != exact.width ||
        signal.height != exact.height || signal.pixel_mm != exact.pixel_mm ||
        !(signal.pixel_mm > 0))
        throw std::invalid_argument(
            "fit_manual_two_gaussian: the signal and its exact convolution must be images of the "
            "same size and pixel size");
    Fitter f(k, signal, exact, channel);
    const double npix = static_cast<double>(signal.width) * signal.height;

    // Grid phase: widths log-spaced from an eighth of a pixel (narrower ones are all a delta on
    // the pixel grid) to the smaller of the kernel's extent and twice the image.
    const double lo = f.p_ / 8.0;
    const double hi = std::max(2.0 * lo, std::min(k.n() * k.h_mm(), 2.0 * signal.width * f.p_));
    constexpr int kGrid = 9;
    std::array<double, kGrid> logs{};
    std::vector<Plane> rows(kGrid);
    std::vector<std::vector<double>> ys(kGrid);
    for (int i = 0; i < kGrid; ++i) {
        logs[static_cast<size_t>(i)] =
            std::log(lo) + (std::log(hi) - std::log(lo)) * i / (kGrid - 1);
        const double s = std::exp(logs[static_cast<size_t>(i)]);
        rows[static_cast<size_t>(i)] = conv_rows(f.e_, f.w_, f.h_, f.pixels(s, f.w_));
        ys[static_cast<size_t>(i)] = f.pixels(s, f.h_);
    }
    double best = INFINITY, best_w = 0.5;
    double x0 = logs[0], y0 = logs[0];
    for (int i = 0; i < kGrid; ++i)
        for (int j = i; j < kGrid; ++j) {
            const Quartic q = f.quartic(rows[static_cast<size_t>(i)], rows[static_cast<size_t>(j)],
                                        ys[static_cast<size_t>(i)], ys[static_cast<size_t>(j)]);
            double e = 0;
            const double w = minimise_quartic(q, e);
            if (e < best)
                best = e, best_w = w, x0 = logs[static_cast<size_t>(i)],
                y0 = logs[static_cast<size_t>(j)];
        }
    rows.clear();

    // Nelder-Mead in (log sigma_n, log sigma_f), started at the grid optimum with steps of half a
    // grid spacing; the widths are kept in [lo / 8, 4 hi].
    const double step = 0.5 * (logs[1] - logs[0]);
    const double bound_lo = std::log(lo / 8.0), bound_hi = std::log(4.0 * hi);
    struct Vertex {
        double x, y, f, w;
    };
    auto eval = [&](double x, double y) {
        x = std::clamp(x, bound_lo, bound_hi);
        y = std::clamp(y, bound_lo, bound_hi);
        double w = 0;
        const double e = f.evaluate(x, y, w);
        return Vertex{x, y, e, w};
    };
    std::array<Vertex, 3> s = {Vertex{x0, y0, best, best_w}, eval(x0 + step, y0),
                               eval(x0, y0 + step)};
    for (int it = 0; it < 60; ++it) {
        std::sort(s.begin(), s.end(), [](const Vertex& a, const Vertex& b) { return a.f < b.f; });
        const double size = std::max(std::fabs(s[1].x - s[0].x) + std::fabs(s[1].y - s[0].y),
                                     std::fabs(s[2].x - s[0].x) + std::fabs(s[2].y - s[0].y));
        if (size < 2e-3 || s[2].f - s[0].f <= 1e-12 * (s[0].f + 1e-300)) break;
        const double cx = 0.5 * (s[0].x + s[1].x), cy = 0.5 * (s[0].y + s[1].y);
        const Vertex r = eval(2 * cx - s[2].x, 2 * cy - s[2].y);
        if (r.f < s[0].f) {
            const Vertex e = eval(3 * cx - 2 * s[2].x, 3 * cy - 2 * s[2].y);
            s[2] = e.f < r.f ? e : r;
        } else if (r.f < s[1].f) {
            s[2] = r;
        } else {
            const Vertex c = r.f < s[2].f ? eval(1.5 * cx - 0.5 * s[2].x, 1.5 * cy - 0.5 * s[2].y)
                                          : eval(0.5 * (cx + s[2].x), 0.5 * (cy + s[2].y));
            if (c.f < std::min(r.f, s[2].f)) {
                s[2] = c;
            } else {
                for (int i = 1; i < 3; ++i)
                    s[static_cast<size_t>(i)] = eval(0.5 * (s[0].x + s[static_cast<size_t>(i)].x),
                                                     0.5 * (s[0].y + s[static_cast<size_t>(i)].y));
            }
        }
    }
    std::sort(s.begin(), s.end(), [](const Vertex& a, const Vertex& b) { return a.f < b.f; });
    // The near Gaussian is the narrower one (the model is symmetric under the swap with 1 - w).
    double sn = std::exp(s[0].x), sf = std::exp(s[0].y), w = s[0].w;
    if (sn > sf) std::swap(sn, sf), w = 1.0 - w;

    ModelResult r = manual_two_gaussian(k, sn, sf, w);
    r.info["fit_rms"] = std::sqrt(s[0].f / npix);
    r.info["sqrt_tau_near_mm"] = sn;
    r.info["sqrt_tau_far_mm"] = sf;
    r.info["w"] = w;
    r.info["evaluations"] = f.evaluations;
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
