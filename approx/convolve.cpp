#include "approx/convolve.h"

#include "approx/fft.h"
#include "core/hash.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>

namespace ssslab::approx {

namespace {

using detail::Fft2D;
using detail::fft_size;

// ---- Resampling of a half-grid kernel to pixel offsets ---------------------------------------

// The resampling operator of an even 1D kernel as a sparse matrix: column i (half cell i, the
// cells [i h, (i + 1) h] and its mirror [-(i + 1) h, -i h]) lists the pixel offsets (index d + r)
// that receive its mass, with the fraction each receives; the fractions of a column sum to 2
// (both cells). Offsets beyond +-fold are folded onto +-fold.
struct Resampler {
    int r = 0;
    std::vector<std::vector<std::pair<int, double>>> cols;
};

Resampler make_resampler(int n, double h, double p, int fold) {
    if (n < 0) throw std::invalid_argument("resample: negative cell count");
    if (!(h > 0) || !(p > 0)) throw std::invalid_argument("resample: h and pixel must be > 0");
    if (fold < 0) throw std::invalid_argument("resample: fold < 0");
    Resampler rs;
    const double extent = std::ceil(static_cast<double>(n) * h / p);
    rs.r = static_cast<int>(std::min(extent, static_cast<double>(fold)));
    rs.cols.resize(static_cast<size_t>(n));
    const int r = rs.r;
    // Bins beyond r hold nothing: r >= ceil(n h / p) >= round(n h / p) holds the whole grid
    // unless folded, and folding sends [(r - 1/2) p, inf) to bin r.
    const double cut = (r - 0.5) * p;
    std::vector<std::pair<int, double>> bins;
    for (int i = 0; i < n; ++i) {
        const double a = i * h, b = (i + 1) * h;
        bins.clear();
        const double top = std::min(b, cut);
        if (top > a) {
            const double d0 = std::floor(a / p + 0.5);
            const double d1 = std::min(std::floor(top / p + 0.5), static_cast<double>(r) - 1);
            for (double d = d0; d <= d1; d += 1) {
                const double len = std::min(top, (d + 0.5) * p) - std::max(a, (d - 0.5) * p);
                if (len > 0) bins.emplace_back(static_cast<int>(d), len);
            }
        }
        if (b > cut) bins.emplace_back(r, b - std::max(a, cut));
        double total = 0;
        for (const auto& x : bins) total += x.second;
        auto& col = rs.cols[static_cast<size_t>(i)];
        for (const auto& [d, len] : bins) {
            const double f = len / total;
            if (d == 0) {
                col.emplace_back(r, 2 * f);
            } else {
                col.emplace_back(r + d, f);
                col.emplace_back(r - d, f);
            }
        }
    }
    return rs;
}

void check_image(const ImageRGB& e, const char* what) {
    if (e.width < 1 || e.height < 1)
        throw std::invalid_argument(std::string(what) + ": empty image");
    if (!(e.pixel_mm > 0)) throw std::invalid_argument(std::string(what) + ": pixel_mm <= 0");
    const size_t n = static_cast<size_t>(e.width) * static_cast<size_t>(e.height);
    for (int ch = 0; ch < 3; ++ch)
        if (e.c[ch].size() != n)
            throw std::invalid_argument(std::string(what) + ": channel size mismatch");
}

// The kernel resampled to pixel offsets: Kpix(dx + rx, dy + ry) = (Rx q Ry^T)(dx, dy), dx along x.
struct PixelKernel {
    int rx = 0, ry = 0;
    Eigen::MatrixXd k;  // (2 rx + 1) x (2 ry + 1)
};

PixelKernel pixel_kernel(const Kernel2D& kernel, double p, int fold_x, int fold_y) {
    const Eigen::MatrixXd& q = kernel.quadrant();
    const int n = kernel.n();
    const Resampler sx = make_resampler(n, kernel.h_mm(), p, fold_x);
    const Resampler sy = make_resampler(n, kernel.h_mm(), p, fold_y);
    PixelKernel pk;
    pk.rx = sx.r;
    pk.ry = sy.r;
    const int mx = 2 * sx.r + 1, my = 2 * sy.r + 1;
    // Ry by rows: for each pixel offset dy, the half cells j feeding it.
    std::vector<std::vector<std::pair<int, double>>> ry_rows(static_cast<size_t>(my));
    for (int j = 0; j < n; ++j)
        for (const auto& [d, w] : sy.cols[static_cast<size_t>(j)])
            ry_rows[static_cast<size_t>(d)].emplace_back(j, w);
    // T = q Ry^T (n x my), then Kpix = Rx T: both products only touch the nonzeros of R.
    pk.k = Eigen::MatrixXd::Zero(mx, my);
    tbb::parallel_for(tbb::blocked_range<int>(0, my), [&](const tbb::blocked_range<int>& range) {
        Eigen::VectorXd col(n);  // column d of T
        for (int d = range.begin(); d < range.end(); ++d) {
            col.setZero();
            for (const auto& [j, w] : ry_rows[static_cast<size_t>(d)])
                col.noalias() += w * q.col(j);
            auto out = pk.k.col(d);
            for (int i = 0; i < n; ++i) {
                const double v = col(i);
                if (v == 0) continue;
                for (const auto& [dx, w] : sx.cols[static_cast<size_t>(i)]) out(dx) += w * v;
            }
        }
    });
    return pk;
}

// 1D clamp-to-edge convolutions with a resampled kernel k (offsets -r..r at index d + r):
// out(x) = sum_d k(d) in(clamp(x - d)).
void convolve_rows(const std::vector<double>& in, std::vector<double>& out, int w, int h,
                   const std::vector<double>& k) {
    const int r = static_cast<int>(k.size() / 2);
    std::vector<double> krev(k.rbegin(), k.rend());
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        std::vector<double> pad(static_cast<size_t>(w + 2 * r));
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const double* src = in.data() + static_cast<size_t>(y) * w;
            for (int u = 0; u < w + 2 * r; ++u)
                pad[static_cast<size_t>(u)] = src[std::clamp(u - r, 0, w - 1)];
            double* dst = out.data() + static_cast<size_t>(y) * w;
            // out(x) = sum_m k[m] pad[x + 2r - m] = sum_m krev[m] pad[x + m]
            for (int x = 0; x < w; ++x) {
                const double* pp = pad.data() + x;
                double s = 0;
                for (int m = 0; m <= 2 * r; ++m) s += krev[static_cast<size_t>(m)] * pp[m];
                dst[x] = s;
            }
        }
    });
}

// out(x, y) += sign * sum_d k(d) in(x, clamp(y - d))
void convolve_cols_add(const std::vector<double>& in, std::vector<double>& out, int w, int h,
                       const std::vector<double>& k, double sign) {
    const int r = static_cast<int>(k.size() / 2);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
        std::vector<double> acc(static_cast<size_t>(w));
        for (int y = rows.begin(); y < rows.end(); ++y) {
            std::fill(acc.begin(), acc.end(), 0.0);
            for (int m = 0; m <= 2 * r; ++m) {
                const double km = k[static_cast<size_t>(m)];
                if (km == 0) continue;
                const int sy = std::clamp(y - (m - r), 0, h - 1);
                const double* src = in.data() + static_cast<size_t>(sy) * w;
                for (int x = 0; x < w; ++x) acc[static_cast<size_t>(x)] += km * src[x];
            }
            double* dst = out.data() + static_cast<size_t>(y) * w;
            for (int x = 0; x < w; ++x) dst[x] += sign * acc[static_cast<size_t>(x)];
        }
    });
}

}  // namespace

double jitter_hash(int x, int y, int pass, int tap, unsigned seed) {
    uint32_t v = hash32(static_cast<uint32_t>(x) * 0x9e3779b1U + 0x632be5abU +
                        static_cast<uint32_t>(seed) * 0x27d4eb2fU);
    v = hash32(v ^ (static_cast<uint32_t>(y) * 0x85ebca77U));
    v = hash32(v ^ (static_cast<uint32_t>(pass) * 0xc2b2ae3dU + static_cast<uint32_t>(tap)));
    return (v >> 8) * (2.0 / 16777216.0) - 1.0;
}

TapJitterRange tap_jitter_range(const TapKernel& taps, double jitter) {
    if (!(jitter >= 0)) throw std::invalid_argument("tap_jitter_range: jitter must be >= 0");
    const std::vector<double>& off = taps.offset_mm;
    TapJitterRange r;
    for (size_t i = 0; i < off.size(); ++i) {
        const double l = i > 0 ? 0.5 * (off[i] - off[i - 1]) : -1;
        const double rr = i + 1 < off.size() ? 0.5 * (off[i + 1] - off[i]) : -1;
        r.left_mm.push_back(jitter * (l >= 0 ? l : std::max(rr, 0.0)));
        r.right_mm.push_back(jitter * (rr >= 0 ? rr : std::max(l, 0.0)));
    }
    return r;
}

std::vector<double> resample_1d(const std::vector<double>& half, double h_mm, double pixel_mm,
                                int fold) {
    const Resampler rs = make_resampler(static_cast<int>(half.size()), h_mm, pixel_mm, fold);
    std::vector<double> out(static_cast<size_t>(2 * rs.r + 1), 0.0);
    for (size_t i = 0; i < half.size(); ++i)
        for (const auto& [d, w] : rs.cols[i]) out[static_cast<size_t>(d)] += w * half[i];
    return out;
}

ImageRGB convolve_exact(const ImageRGB& e, const std::array<const Kernel2D*, 3>& k) {
    check_image(e, "convolve_exact");
    const int w = e.width, h = e.height;
    // The distinct kernels (channels often share one).
    std::vector<const Kernel2D*> kernels;
    std::array<size_t, 3> which{};
    for (int ch = 0; ch < 3; ++ch) {
        if (!k[ch]) throw std::invalid_argument("convolve_exact: null kernel");
        const auto it = std::find(kernels.begin(), kernels.end(), k[ch]);
        which[ch] = static_cast<size_t>(it - kernels.begin());
        if (it == kernels.end()) kernels.push_back(k[ch]);
    }
    std::vector<PixelKernel> pk(kernels.size());
    for (size_t i = 0; i < kernels.size(); ++i)
        pk[i] = pixel_kernel(*kernels[i], e.pixel_mm, w - 1, h - 1);
    int rx = 0, ry = 0;
    for (const auto& p : pk) {
        rx = std::max(rx, p.rx);
        ry = std::max(ry, p.ry);
    }
    // Replicate-pad by (rx, ry): P(u, v) = E(clamp(u - rx), clamp(v - ry)), size wp x hp. With
    // the kernel at index (dx + rx, dy + ry), the circular convolution C of size nx >= wp holds
    // out(x, y) = C(x + 2 rx, y + 2 ry) without wrap-around: the image indices it reads,
    // x + 2 rx - (dx + rx) - ..., stay in [0, wp).
    const int wp = w + 2 * rx, hp = h + 2 * ry;
    const int nx = fft_size(wp), ny = fft_size(hp);
    const size_t nreal = static_cast<size_t>(nx) * static_cast<size_t>(ny);
    const size_t ncplx = static_cast<size_t>(nx / 2 + 1) * static_cast<size_t>(ny);

    std::vector<std::vector<std::complex<double>>> khat(kernels.size());
    tbb::parallel_for(size_t{0}, kernels.size(), [&](size_t i) {
        Fft2D fft(nx, ny);
        std::fill(fft.real(), fft.real() + nreal, 0.0);
        const PixelKernel& p = pk[i];
        for (int dy = -p.ry; dy <= p.ry; ++dy)
            for (int dx = -p.rx; dx <= p.rx; ++dx)
                fft.real()[static_cast<size_t>(dy + ry) * nx + static_cast<size_t>(dx + rx)] =
                    p.k(dx + p.rx, dy + p.ry);
        fft.forward();
        khat[i].resize(ncplx);
        for (size_t j = 0; j < ncplx; ++j) khat[i][j] = {fft.spec()[j][0], fft.spec()[j][1]};
    });

    ImageRGB out(w, h, e.pixel_mm, 0.0);
    const double norm = 1.0 / static_cast<double>(nreal);
    tbb::parallel_for(0, 3, [&](int ch) {
        Fft2D fft(nx, ny);
        double* buf = fft.real();
        std::fill(buf, buf + nreal, 0.0);
        for (int v = 0; v < hp; ++v) {
            const int sy = std::clamp(v - ry, 0, h - 1);
            for (int u = 0; u < wp; ++u)
                buf[static_cast<size_t>(v) * nx + static_cast<size_t>(u)] =
                    e.at(ch, std::clamp(u - rx, 0, w - 1), sy);
        }
        fft.forward();
        const auto& kh = khat[which[ch]];
        for (size_t j = 0; j < ncplx; ++j) {
            const std::complex<double> z =
                std::complex<double>(fft.spec()[j][0], fft.spec()[j][1]) * kh[j];
            fft.spec()[j][0] = z.real();
            fft.spec()[j][1] = z.imag();
        }
        fft.inverse();
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                out.at(ch, x, y) =
                    buf[static_cast<size_t>(y + 2 * ry) * nx + static_cast<size_t>(x + 2 * rx)] *
                    norm;
    });
    return out;
}

ImageRGB convolve_separable(const ImageRGB& e, const std::array<const SeparableKernel*, 3>& a) {
    check_image(e, "convolve_separable");
    const int w = e.width, h = e.height;
    ImageRGB out(w, h, e.pixel_mm, 0.0);
    std::vector<double> tmp(static_cast<size_t>(w) * static_cast<size_t>(h));
    for (int ch = 0; ch < 3; ++ch) {
        const SeparableKernel* s = a[ch];
        if (!s) throw std::invalid_argument("convolve_separable: null kernel");
        for (const SeparableTerm& t : s->terms) {
            const std::vector<double> kx = resample_1d(t.a, s->h_mm, e.pixel_mm, w - 1);
            const std::vector<double> ky = resample_1d(t.a, s->h_mm, e.pixel_mm, h - 1);
            convolve_rows(e.c[ch], tmp, w, h, kx);
            convolve_cols_add(tmp, out.c[ch], w, h, ky, t.sign);
        }
    }
    return out;
}

TapKernel make_taps(const std::array<const SeparableKernel*, 3>& a, int count,
                    double support_mass) {
    for (int ch = 0; ch < 3; ++ch) {
        if (!a[ch]) throw std::invalid_argument("make_taps: null kernel");
        if (a[ch]->rank() != 1 || a[ch]->terms[0].sign < 0)
            throw std::invalid_argument("make_taps: the kernel must be one positive rank-1 term");
    }
    return make_term_taps(a, 0, count, support_mass);
}

TapKernel make_term_taps(const std::array<const SeparableKernel*, 3>& a, int term, int count,
                         double support_mass) {
    if (count < 3 || count % 2 == 0)
        throw std::invalid_argument("make_taps: the tap count must be odd and >= 3");
    if (!(support_mass > 0 && support_mass <= 1))
        throw std::invalid_argument("make_taps: support_mass must be in (0, 1]");
    for (int ch = 0; ch < 3; ++ch) {
        if (!a[ch]) throw std::invalid_argument("make_taps: null kernel");
        if (term < 0 || term >= a[ch]->rank())
            throw std::invalid_argument("make_taps: term " + std::to_string(term) +
                                        " beyond the kernel's rank " +
                                        std::to_string(a[ch]->rank()));
        if (!(a[ch]->h_mm > 0)) throw std::invalid_argument("make_taps: kernel h_mm <= 0");
    }
    const size_t tk = static_cast<size_t>(term);
    // The range R: the radius at which the cumulative 1D mass (cells taken as uniform) reaches
    // support_mass of the whole, for the widest channel.
    double range = 0;
    for (int ch = 0; ch < 3; ++ch) {
        const std::vector<double>& half = a[ch]->terms[tk].a;
        const double h = a[ch]->h_mm;
        double total = 0;
        for (double v : half) total += std::fabs(v);
        const double target = support_mass * total;
        double cum = 0, rc = static_cast<double>(half.size()) * h;
        for (size_t i = 0; i < half.size(); ++i) {
            const double m = std::fabs(half[i]);
            if (m > 0 && cum + m >= target) {
                const double f = std::clamp((target - cum) / m, 0.0, 1.0);
                rc = (static_cast<double>(i) + f) * h;
                break;
            }
            cum += m;
        }
        range = std::max(range, rc);
    }
    if (!(range > 0)) throw std::invalid_argument("make_taps: the kernel has no extent");

    TapKernel taps;
    taps.support_mm = range;
    const int m = count - 1;
    taps.offset_mm.resize(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) {
        const double u = static_cast<double>(2 * i - m) / m;  // exactly antisymmetric
        taps.offset_mm[static_cast<size_t>(i)] = range * (u < 0 ? -u * u : u * u);
    }
    // Cell bounds: midpoints between consecutive offsets, +-infinity outside.
    std::vector<double> bound(static_cast<size_t>(count + 1));
    bound[0] = -std::numeric_limits<double>::infinity();
    bound[static_cast<size_t>(count)] = std::numeric_limits<double>::infinity();
    for (int i = 1; i < count; ++i)
        bound[static_cast<size_t>(i)] = 0.5 * (taps.offset_mm[static_cast<size_t>(i - 1)] +
                                               taps.offset_mm[static_cast<size_t>(i)]);
    for (int ch = 0; ch < 3; ++ch) {
        const std::vector<double>& half = a[ch]->terms[tk].a;
        const double h = a[ch]->h_mm;
        // Cumulative mass from 0 to x >= 0 of the piecewise-constant kernel, odd in x.
        std::vector<double> cum(half.size() + 1, 0.0);
        for (size_t i = 0; i < half.size(); ++i) cum[i + 1] = cum[i] + half[i];
        auto mass_to = [&](double x) {
            const double ax = std::fabs(x);
            double v;
            if (!(ax < static_cast<double>(half.size()) * h)) {
                v = cum.back();
            } else {
                const size_t i = static_cast<size_t>(ax / h);
                const double f = ax / h - static_cast<double>(i);
                v = cum[i] + f * half[i];
            }
            return x < 0 ? -v : v;
        };
        auto& wt = taps.weight[ch];
        wt.resize(static_cast<size_t>(count));
        for (int i = 0; i < count; ++i)
            wt[static_cast<size_t>(i)] =
                mass_to(bound[static_cast<size_t>(i + 1)]) - mass_to(bound[static_cast<size_t>(i)]);
    }
    return taps;
}

ImageRGB convolve_taps(const ImageRGB& e, const TapKernel& taps, double jitter) {
    check_image(e, "convolve_taps");
    const int count = static_cast<int>(taps.offset_mm.size());
    if (count < 1) throw std::invalid_argument("convolve_taps: no taps");
    for (int ch = 0; ch < 3; ++ch)
        if (taps.weight[ch].size() != taps.offset_mm.size())
            throw std::invalid_argument("convolve_taps: weights and offsets differ in length");
    if (!(jitter >= 0)) throw std::invalid_argument("convolve_taps: jitter must be >= 0");
    const int w = e.width, h = e.height;
    const double p = e.pixel_mm;
    const TapJitterRange range = tap_jitter_range(taps, jitter);

    // One pass along x (pass 0) or y (pass 1): out(x, y) = sum_i w_i in(pos + offset_i), linear
    // interpolation, positions clamped to the image (clamp-to-edge).
    auto pass = [&](const ImageRGB& in, int dir) {
        ImageRGB out(w, h, p, 0.0);
        const int len = dir == 0 ? w : h;
        tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y < rows.end(); ++y)
                for (int x = 0; x < w; ++x) {
                    const int pos = dir == 0 ? x : y;
                    std::array<double, 3> acc{};
                    for (int i = 0; i < count; ++i) {
                        const size_t si = static_cast<size_t>(i);
                        const double xi = jitter > 0 ? jitter_hash(x, y, dir, i) : 0.0;
                        const double o = jittered_offset_mm(taps, range, si, xi) / p;
                        const TapTexels s = tap_texels(pos + o, len);
                        for (int ch = 0; ch < 3; ++ch) {
                            const double v0 = dir == 0 ? in.at(ch, s.i0, y) : in.at(ch, x, s.i0);
                            const double v1 = dir == 0 ? in.at(ch, s.i1, y) : in.at(ch, x, s.i1);
                            acc[ch] += taps.weight[ch][si] * ((1 - s.t) * v0 + s.t * v1);
                        }
                    }
                    for (int ch = 0; ch < 3; ++ch) out.at(ch, x, y) = acc[ch];
                }
        });
        return out;
    };
    return pass(pass(e, 0), 1);
}

}  // namespace ssslab::approx
