#include "realtime/sss_reference.h"

#include "core/rng.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ssslab::realtime {

SssExactKernel SssExactKernel::from_kernels(const std::array<const approx::Kernel2D*, 3>& k) {
    for (int ch = 0; ch < 3; ++ch)
        if (!k[ch]) throw std::invalid_argument("SssExactKernel: null kernel");
    SssExactKernel e{{*k[0], *k[1], *k[2]}, k[0]->h_mm(), k[0]->n(), {}, {}, {}};
    for (int ch = 1; ch < 3; ++ch)
        if (k[ch]->n() != e.n || std::fabs(k[ch]->h_mm() - e.h_mm) > 1e-12 * e.h_mm)
            throw std::invalid_argument(
                "SssExactKernel: the channels' kernels are on different grids");
    const int n = e.n;
    const size_t n1 = static_cast<size_t>(n) + 1;
    for (int ch = 0; ch < 3; ++ch)
        if (!(e.channel[ch].quadrant().minCoeff() >= 0))
            throw std::invalid_argument("SssExactKernel: channel " + std::to_string(ch) +
                                        " has a negative (or NaN) cell");
    // Summed-area tables: sat(i, j) = mass of the quadrant's cells [0, i) x [0, j).
    e.sat.assign(3 * n1 * n1, 0.0);
    for (int ch = 0; ch < 3; ++ch) {
        const Eigen::MatrixXd& q = e.channel[ch].quadrant();
        double* s = e.sat.data() + ch;
        for (int i = 0; i < n; ++i) {
            double row = 0;  // cells [i, i + 1) x [0, j)
            for (int j = 0; j < n; ++j) {
                row += q(i, j);
                s[3 * ((i + 1) * n1 + j + 1)] = s[3 * (i * n1 + j + 1)] + row;
            }
        }
    }
    // The sampling density: the mean of the channels, m(i, j) = 4 mean_c q_c(i, j) (sum 1).
    e.cum_y.assign(static_cast<size_t>(n) * n1, 0.0);
    e.cdf_x.assign(n1, 0.0);
    for (int i = 0; i < n; ++i) {
        double* row = &e.cum_y[static_cast<size_t>(i) * n1];
        for (int j = 0; j < n; ++j) {
            const double m = 4.0 / 3.0 *
                             (e.channel[0].quadrant()(i, j) + e.channel[1].quadrant()(i, j) +
                              e.channel[2].quadrant()(i, j));
            row[j + 1] = row[j] + m;
        }
        e.cdf_x[i + 1] = e.cdf_x[i] + row[n];
    }
    const double total = e.cdf_x[n];
    if (!(total > 0) || !std::isfinite(total))
        throw std::invalid_argument("SssExactKernel: the kernel has no mass");
    for (double& v : e.cdf_x) v /= total;
    e.cdf_x[n] = 1.0;
    return e;
}

namespace {

using Method = SssReferenceOptions::Method;

void check(const SssGBuffer& g, const std::vector<SssExactKernel>& kernels, const SssParams& p,
           const SssReferenceOptions& o) {
    if (g.width < 1 || g.height < 1) throw std::invalid_argument("sss_reference: empty G-buffer");
    const size_t n = g.pixels();
    if (g.irradiance.size() != 3 * n || g.view_z.size() != n || g.material.size() != n)
        throw std::invalid_argument("sss_reference: G-buffer arrays differ from width x height");
    if (!(p.tan_half > 0) || !std::isfinite(p.tan_half))
        throw std::invalid_argument("sss_reference: tan_half must be > 0");
    if (!(p.aspect > 0) || !std::isfinite(p.aspect))
        throw std::invalid_argument("sss_reference: aspect must be > 0");
    if (!(p.unit_mm > 0) || !std::isfinite(p.unit_mm))
        throw std::invalid_argument("sss_reference: unit_mm must be > 0");
    if (!(p.follow_strength >= 0))
        throw std::invalid_argument("sss_reference: follow_strength < 0");
    if (!(p.reject_depth >= 0)) throw std::invalid_argument("sss_reference: reject_depth < 0");
    if (o.method != Method::kAuto && o.method != Method::kExact && o.method != Method::kSampled)
        throw std::invalid_argument("sss_reference: unknown method");
    if (o.method != Method::kExact && o.samples_per_stratum < 2)
        throw std::invalid_argument("sss_reference: samples_per_stratum must be >= 2");
    if (o.method != Method::kExact && o.samples < o.samples_per_stratum)
        throw std::invalid_argument("sss_reference: samples must be >= samples_per_stratum");
    if (o.method == Method::kAuto && o.max_exact_taps < 1)
        throw std::invalid_argument("sss_reference: max_exact_taps must be >= 1");
    for (const SssExactKernel& k : kernels) {
        const size_t n1 = static_cast<size_t>(k.n) + 1;
        if (k.n < 1 || !(k.h_mm > 0) || k.cdf_x.size() != n1 ||
            k.cum_y.size() != n1 * static_cast<size_t>(k.n))
            throw std::invalid_argument(
                "sss_reference: a kernel was not built by SssExactKernel::from_kernels");
        if (k.sat.size() != 3 * n1 * n1)
            throw std::invalid_argument(
                "sss_reference: a kernel was not built by SssExactKernel::from_kernels");
    }
    for (size_t i = 0; i < n; ++i) {
        const int32_t m = g.material[i];
        if (m < -1 || m >= static_cast<int32_t>(kernels.size()))
            throw std::invalid_argument("sss_reference: material index " + std::to_string(m) +
                                        " without a kernel");
        if (m >= 0 && !(g.view_z[i] > 0 && std::isfinite(g.view_z[i])))
            throw std::invalid_argument(
                "sss_reference: a medium pixel has no positive finite depth");
    }
}

// One axis of a pixel's footprint: the screen pixels [lo, hi] it covers (clamped to the image)
// and, for each of their hi - lo + 2 boundaries, its place on the kernel's grid: C(u) factors as
// sign * (bilinear weights of cells i0, i0 + 1 of the summed-area table at fraction f).
struct Axis {
    int lo = 0, hi = 0;
    std::vector<int> i0;
    std::vector<double> f, sign;
    int count() const { return hi - lo + 1; }
};

// The window of pixels of an axis of `len` pixels whose squares overlap the kernel's support
// [-extent, extent] mm about pixel `pos`, at `s` pixels per mm.
void axis_window(Axis& a, int pos, int len, double s, double extent_mm) {
    // Pixel pos + d overlaps iff |d| - 1/2 < extent s: |d| <= ceil(extent s + 1/2) - 1.
    const double r = std::ceil(extent_mm * s + 0.5) - 1;
    a.lo = static_cast<int>(std::max(0.0, pos - r));
    a.hi = static_cast<int>(std::min(static_cast<double>(len - 1), pos + r));
}

// Fill an axis's boundaries. Boundary k lies at (lo + k - pos - 1/2) / s mm; the outer ones of
// an edge pixel lie at -+infinity (clamp-to-edge: the edge pixel takes the kernel's mass out to
// infinity); all are clamped to the grid, [0, n] cells from the centre.
void axis_boundaries(Axis& a, int pos, int len, double s, double h_mm, int n) {
    const int nb = a.count() + 1;
    a.i0.resize(static_cast<size_t>(nb));
    a.f.resize(static_cast<size_t>(nb));
    a.sign.resize(static_cast<size_t>(nb));
    for (int k = 0; k < nb; ++k) {
        double b = (a.lo + k - pos - 0.5) / s;
        if (k == 0 && a.lo == 0) b = -std::numeric_limits<double>::infinity();
        if (k == nb - 1 && a.hi == len - 1) b = std::numeric_limits<double>::infinity();
        const double u = std::min(static_cast<double>(n), std::fabs(b) / h_mm);
        const int i = std::min(static_cast<int>(u), n - 1);
        a.i0[static_cast<size_t>(k)] = i;
        a.f[static_cast<size_t>(k)] = u - i;
        a.sign[static_cast<size_t>(k)] = b < 0 ? -1.0 : 1.0;
    }
}

// The stratification of kSampled: `m` cells of the unit square (u_x, u_y), `rows` rows of
// height 1 / rows, row r split into cols(r) cells of width 1 / cols(r) (cell areas within a factor
// (1 + 1 / (m / rows)) of each other); two points per cell, a third in the first samples mod 2.
struct Strata {
    int m = 0, rows = 0;
    Strata(int samples, int per) : m(samples / per), rows(static_cast<int>(std::sqrt(m))) {
        rows = std::max(1, rows);
        while (rows * rows > m) --rows;  // std::sqrt rounding
    }
    int cols(int r) const { return m / rows + (r < m % rows ? 1 : 0); }
};

// One kSampled sample, per channel: w_c (E'(q) - E(c)) if q is kept, w_c if it is dropped.
struct Sample {
    std::array<double, 3> y{}, d{};
};

// Per-channel accumulation of a stratified estimate: sum over strata of A_h mean_h(y) and of
// A_h^2 var_h(y) / n_h (the unbiased variance of the stratified mean).
struct StratAcc {
    std::array<double, 3> mean{}, var{};
    void add(double area, int count, const std::array<double, 3>* y) {
        for (int ch = 0; ch < 3; ++ch) {
            double sum = 0;
            for (int s = 0; s < count; ++s) sum += y[s][ch];
            const double ybar = sum / count;
            double ss = 0;
            for (int s = 0; s < count; ++s) ss += (y[s][ch] - ybar) * (y[s][ch] - ybar);
            mean[ch] += area * ybar;
            var[ch] += area * area * ss / (count - 1) / count;
        }
    }
};

// The per-thread buffers of a block of rows.
struct Scratch {
    Axis ax, ay;
    std::vector<Sample> samples;
    std::vector<double> c0, c1;  // corner values of two boundary rows, 3 per corner
    std::vector<std::array<double, 3>> ys, zs;
};

// kSampled's strata: (area, points) in the order they are drawn.
using StrataList = std::vector<std::pair<double, int>>;

// One medium pixel: its kernel, the kernel's scale there (pixels per mm along x and y), its
// irradiance E(c), and the edge rule against it.
struct MediumPixel {
    const SssGBuffer& g;
    const SssParams& p;
    const SssExactKernel& k;
    int x = 0, y = 0;
    size_t c = 0;
    int32_t mat = 0;
    double zc = 0, sx = 0, sy = 0;
    std::array<double, 3> ec{};

    // E'(q) - E(c) per channel under the edge rule; false: q is dropped (kReject).
    bool edge(size_t q, std::array<double, 3>& d) const {
        const float* e = &g.irradiance[3 * q];
        switch (p.mode) {
            case SssEdgeMode::kNone:
                for (int ch = 0; ch < 3; ++ch) d[ch] = e[ch] - ec[ch];
                return true;
            case SssEdgeMode::kFollowSurface: {
                // [Freude14 Eq. 4.12]: E' = E (1 - s) + E(c) s.
                const double dz = std::fabs(static_cast<double>(g.view_z[q]) - zc);
                const double s = std::min(1.0, p.follow_strength * dz / p.tan_half);
                for (int ch = 0; ch < 3; ++ch) d[ch] = (1 - s) * (e[ch] - ec[ch]);
                return true;
            }
            case SssEdgeMode::kReject: {
                const double dz = std::fabs(static_cast<double>(g.view_z[q]) - zc);
                if (g.material[q] != mat || !(dz <= p.reject_depth)) return false;
                for (int ch = 0; ch < 3; ++ch) d[ch] = e[ch] - ec[ch];
                return true;
            }
        }
        return true;
    }
};

// Corner values C(b_kx, b_ly) = sign_x sign_y F(|b_kx|, |b_ly|) of boundary l of ay and every
// boundary of ax, F the quadrant's cumulative mass: bilinear in the summed-area table, exact for
// a piecewise-constant density.
void corner_row(const SssExactKernel& k, const Axis& ax, const Axis& ay, int l,
                std::vector<double>& row) {
    const size_t n1 = static_cast<size_t>(k.n) + 1;
    const int nbx = ax.count() + 1;
    const size_t jl = static_cast<size_t>(l);
    const int j = ay.i0[jl];
    const double fy = ay.f[jl], sgy = ay.sign[jl];
    for (int kx = 0; kx < nbx; ++kx) {
        const size_t kk = static_cast<size_t>(kx);
        const size_t i = static_cast<size_t>(ax.i0[kk]);
        const double fx = ax.f[kk], sg = ax.sign[kk] * sgy;
        const double* r0 = k.sat.data() + 3 * (i * n1 + static_cast<size_t>(j));
        const double* r1 = r0 + 3 * n1;
        const double a00 = (1 - fx) * (1 - fy), a01 = (1 - fx) * fy;
        const double a10 = fx * (1 - fy), a11 = fx * fy;
        for (int ch = 0; ch < 3; ++ch)
            row[3 * kk + ch] =
                sg * (a00 * r0[ch] + a01 * r0[3 + ch] + a10 * r1[ch] + a11 * r1[3 + ch]);
    }
}

// kExact: E(c) plus the sum over the pixels of the window (s.ax, s.ay) of the kernel's mass over
// each pixel's square times E' - E(c).
std::array<double, 3> exact_pixel(const MediumPixel& px, Scratch& s) {
    const int w = px.g.width, h = px.g.height;
    Axis& ax = s.ax;
    Axis& ay = s.ay;
    axis_boundaries(ax, px.x, w, px.sx, px.k.h_mm, px.k.n);
    axis_boundaries(ay, px.y, h, px.sy, px.k.h_mm, px.k.n);
    const int nbx = ax.count() + 1;
    s.c0.resize(3 * static_cast<size_t>(nbx));
    s.c1.resize(3 * static_cast<size_t>(nbx));
    std::array<double, 3> sum{}, kept{};
    bool dropped = false;
    std::array<double, 3> d{};
    corner_row(px.k, ax, ay, 0, s.c0);
    for (int ly = 0; ly < ay.count(); ++ly) {
        corner_row(px.k, ax, ay, ly + 1, s.c1);
        const std::vector<double>& c0 = s.c0;
        const std::vector<double>& c1 = s.c1;
        const size_t row = static_cast<size_t>(ay.lo + ly) * w;
        for (int kx = 0; kx < ax.count(); ++kx) {
            const size_t kk = 3 * static_cast<size_t>(kx);
            std::array<double, 3> wq;
            for (int ch = 0; ch < 3; ++ch)
                wq[ch] = c1[kk + 3 + ch] - c1[kk + ch] - c0[kk + 3 + ch] + c0[kk + ch];
            if (wq[0] == 0 && wq[1] == 0 && wq[2] == 0) continue;
            const size_t q = row + static_cast<size_t>(ax.lo + kx);
            if (!px.edge(q, d)) {
                dropped = true;
                continue;
            }
            for (int ch = 0; ch < 3; ++ch) {
                sum[ch] += wq[ch] * d[ch];
                kept[ch] += wq[ch];
            }
        }
        std::swap(s.c0, s.c1);
    }
    std::array<double, 3> out{};
    for (int ch = 0; ch < 3; ++ch) {
        double v = sum[ch];
        // kReject: (all weights) / (kept weights), all = the kernel's unit mass.
        if (dropped) v = kept[ch] != 0 ? v / kept[ch] : 0.0;
        out[ch] = px.ec[ch] + v;
    }
    return out;
}

// One kSampled point in stratum cell (r, col) of a row of nc cells, drawn from the kernel's
// density: per channel w_c (E'(q) - E(c)), or w_c where q is dropped (keep false).
Sample draw_sample(const MediumPixel& px, const Strata& st, int r, int col, int nc, RngStream& rng,
                   bool& keep) {
    const SssExactKernel& k = px.k;
    const int n = k.n;
    const size_t n1 = static_cast<size_t>(n) + 1;
    const double hk = k.h_mm;
    const int w = px.g.width, h = px.g.height;
    const double ux = (r + rng.uniform()) / st.rows;
    const double uy = (col + rng.uniform()) / nc;
    // x: the sign from the half of [0, 1), |x| by the marginal's inverse CDF (piecewise linear:
    // uniform within the cell).
    const double sgx = ux < 0.5 ? -1.0 : 1.0;
    const double vx = std::fabs(2 * ux - 1);
    int i =
        static_cast<int>(std::upper_bound(k.cdf_x.begin(), k.cdf_x.end(), vx) - k.cdf_x.begin()) -
        1;
    i = std::clamp(i, 0, n - 1);
    const double pi = k.cdf_x[i + 1] - k.cdf_x[i];
    const double fx = std::clamp((vx - k.cdf_x[i]) / pi, 0.0, 1.0);
    // y given the column, the same way.
    const double* cum = &k.cum_y[static_cast<size_t>(i) * n1];
    const double sgy = uy < 0.5 ? -1.0 : 1.0;
    const double t = std::fabs(2 * uy - 1) * cum[n];
    int j = static_cast<int>(std::upper_bound(cum, cum + n1, t) - cum) - 1;
    j = std::clamp(j, 0, n - 1);
    const double pj = cum[j + 1] - cum[j];
    const double fy = std::clamp((t - cum[j]) / pj, 0.0, 1.0);
    // Probability of the full-grid cell: pi pj / row mass / 4 (signs).
    const double prob = pi * pj / cum[n] / 4;
    // The pixel holding the point (box reconstruction), clamped.
    const double qx = px.x + sgx * (i + fx) * hk * px.sx;
    const double qy = px.y + sgy * (j + fy) * hk * px.sy;
    const int ix = static_cast<int>(std::clamp(std::floor(qx + 0.5), 0.0, w - 1.0));
    const int iy = static_cast<int>(std::clamp(std::floor(qy + 0.5), 0.0, h - 1.0));
    const size_t q = static_cast<size_t>(iy) * w + static_cast<size_t>(ix);
    Sample smp{};
    std::array<double, 3> d{};
    keep = px.edge(q, d);
    for (int ch = 0; ch < 3; ++ch) {
        const double wc = k.channel[ch].quadrant()(i, j) / prob;
        if (keep)
            smp.y[ch] = wc * d[ch];
        else
            smp.d[ch] = wc;
    }
    return smp;
}

// Adds value(sample) of the samples, stratum by stratum, to acc (buf: a stratum's values).
template <class Value>
void add_strata(const StrataList& strata, const std::vector<Sample>& samples, Value&& value,
                StratAcc& acc, std::vector<std::array<double, 3>>& buf) {
    size_t at = 0;
    for (const auto& [area, cnt] : strata) {
        buf.resize(static_cast<size_t>(cnt));
        for (int s = 0; s < cnt; ++s)
            buf[static_cast<size_t>(s)] = value(samples[at + static_cast<size_t>(s)]);
        acc.add(area, cnt, buf.data());
        at += static_cast<size_t>(cnt);
    }
}

// The kernel's exact weight of the centre pixel in channel ch, (ax, ay) holding its boundaries.
double centre_weight(const SssExactKernel& k, const Axis& ax, const Axis& ay, int ch) {
    const size_t n1 = static_cast<size_t>(k.n) + 1;
    auto f = [&](size_t kx, size_t ly) {
        const size_t i = static_cast<size_t>(ax.i0[kx]);
        const size_t j = static_cast<size_t>(ay.i0[ly]);
        const double fx = ax.f[kx], fy = ay.f[ly];
        const double* r0 = k.sat.data() + 3 * (i * n1 + j) + ch;
        const double* r1 = r0 + 3 * n1;
        return ax.sign[kx] * ay.sign[ly] *
               ((1 - fx) * ((1 - fy) * r0[0] + fy * r0[3]) + fx * ((1 - fy) * r1[0] + fy * r1[3]));
    };
    return f(1, 1) - f(0, 1) - f(1, 0) + f(0, 0);
}

// kReject's ratio estimate from the samples in s.samples and their stratified means acc_y,
// acc_d: the pixel's value and its standard error.
void reject_ratio(const MediumPixel& px, const StrataList& strata, const StratAcc& acc_y,
                  const StratAcc& acc_d, Scratch& s, std::array<double, 3>& out,
                  std::array<double, 3>& se) {
    // kReject: R = Y / D, D = 1 - (dropped mass), both from the samples; D is kept above the
    // centre pixel's exact weight (the centre is never dropped, so the true D is at least
    // that). A ratio of unbiased estimates: its bias, (R Var(D) - Cov(Y, D)) / D^2 to first
    // order, is O(1 / samples) against a standard error O(1 / sqrt(samples)); over 100 seeds of
    // 32 samples test_sss_reference does not detect it. Without a dropped sample D = 1 exactly
    // and the estimate is kNone's.
    Axis& ax = s.ax;
    Axis& ay = s.ay;
    ax.lo = ax.hi = px.x;  // the centre pixel only
    ay.lo = ay.hi = px.y;
    axis_boundaries(ax, px.x, px.g.width, px.sx, px.k.h_mm, px.k.n);
    axis_boundaries(ay, px.y, px.g.height, px.sy, px.k.h_mm, px.k.n);
    std::array<double, 3> rr{}, dd{};
    for (int ch = 0; ch < 3; ++ch) {
        const double wc = centre_weight(px.k, ax, ay, ch);
        dd[ch] = std::max(1.0 - acc_d.mean[ch], wc);
        rr[ch] = dd[ch] > 0 ? acc_y.mean[ch] / dd[ch] : 0.0;
        out[ch] = px.ec[ch] + rr[ch];
    }
    // Delta method: Var(Y / D) ~ Var(mean of y + R d) / D^2.
    StratAcc acc_z;
    add_strata(
        strata, s.samples,
        [&](const Sample& smp) {
            std::array<double, 3> z;
            for (int ch = 0; ch < 3; ++ch) z[ch] = smp.y[ch] + rr[ch] * smp.d[ch];
            return z;
        },
        acc_z, s.zs);
    for (int ch = 0; ch < 3; ++ch) se[ch] = dd[ch] > 0 ? std::sqrt(acc_z.var[ch]) / dd[ch] : 0.0;
}

// One sss_reference call: its input, the kernel scale and kSampled's strata.
struct Reference {
    const SssGBuffer& g;
    const std::vector<SssExactKernel>& kernels;
    const SssParams& p;
    const SssReferenceOptions& o;
    // Kernel scale [Freude14 Eq. 4.11]: pixels per mm at view depth z, along x and along y.
    const double px_per_mm_z, py_per_mm_z;
    const int per;  // kSampled's points per stratum
    const Strata st;
    StrataList strata;

    Reference(const SssGBuffer& g_, const std::vector<SssExactKernel>& kernels_,
              const SssParams& p_, const SssReferenceOptions& o_)
        : g(g_),
          kernels(kernels_),
          p(p_),
          o(o_),
          px_per_mm_z(g.width / (2.0 * p.tan_half * p.aspect * p.unit_mm)),
          py_per_mm_z(g.height / (2.0 * p.tan_half * p.unit_mm)),
          per(o.method == Method::kExact ? 2 : o.samples_per_stratum),
          st(o.method == Method::kExact ? 2 : o.samples, per) {
        for (int r = 0; r < st.rows; ++r)
            for (int col = 0; col < st.cols(r); ++col) {
                const int cnt = per + (static_cast<int>(strata.size()) < o.samples % per ? 1 : 0);
                strata.emplace_back(1.0 / (static_cast<double>(st.rows) * st.cols(r)), cnt);
            }
    }

    // kSampled: the stratified estimate of the pixel's value and its standard error.
    void sampled_pixel(const MediumPixel& px, Scratch& s, std::array<double, 3>& out,
                       std::array<double, 3>& se) const {
        RngStream rng(o.seed, rng_domain::kSssReference, px.c);
        StratAcc acc_y, acc_d;
        // The samples are kept: kReject's delta method makes a second pass over them at the
        // ratio.
        s.samples.clear();
        bool any_dropped = false;
        int stratum = 0;
        for (int r = 0; r < st.rows; ++r) {
            const int nc = st.cols(r);
            for (int col = 0; col < nc; ++col, ++stratum) {
                const int cnt = strata[static_cast<size_t>(stratum)].second;
                for (int k = 0; k < cnt; ++k) {
                    bool keep = true;
                    s.samples.push_back(draw_sample(px, st, r, col, nc, rng, keep));
                    any_dropped = any_dropped || !keep;
                }
            }
        }
        // Stratified means and variances.
        add_strata(
            strata, s.samples, [](const Sample& smp) { return smp.y; }, acc_y, s.ys);
        add_strata(
            strata, s.samples, [](const Sample& smp) { return smp.d; }, acc_d, s.zs);
        if (!any_dropped) {
            for (int ch = 0; ch < 3; ++ch) {
                out[ch] = px.ec[ch] + acc_y.mean[ch];
                se[ch] = std::sqrt(acc_y.var[ch]);
            }
        } else {
            reject_ratio(px, strata, acc_y, acc_d, s, out, se);
        }
    }

    // Pixel (x, y) into res; how[c]: 0 no medium, 1 exact, 2 sampled.
    void pixel(int x, int y, Scratch& s, SssReferenceResult& res,
               std::vector<unsigned char>& how) const {
        const int w = g.width, h = g.height;
        const size_t c = static_cast<size_t>(y) * w + static_cast<size_t>(x);
        const int32_t mat = g.material[c];
        const float* ec_f = &g.irradiance[3 * c];
        if (mat < 0) {
            for (int ch = 0; ch < 3; ++ch) res.irradiance[3 * c + ch] = ec_f[ch];
            return;
        }
        const SssExactKernel& k = kernels[static_cast<size_t>(mat)];
        const double zc = g.view_z[c];
        const MediumPixel px{g,
                             p,
                             k,
                             x,
                             y,
                             c,
                             mat,
                             zc,
                             px_per_mm_z / zc,
                             py_per_mm_z / zc,
                             {ec_f[0], ec_f[1], ec_f[2]}};
        const double extent = k.extent_mm();
        axis_window(s.ax, x, w, px.sx, extent);
        axis_window(s.ay, y, h, px.sy, extent);
        const double taps = static_cast<double>(s.ax.count()) * s.ay.count();
        const bool exact =
            o.method == Method::kExact ||
            (o.method == Method::kAuto && taps <= static_cast<double>(o.max_exact_taps));
        std::array<double, 3> out{}, se{};
        if (exact) {
            how[c] = 1;
            out = exact_pixel(px, s);
        } else {
            how[c] = 2;
            sampled_pixel(px, s, out, se);
        }
        for (int ch = 0; ch < 3; ++ch) {
            res.irradiance[3 * c + ch] = static_cast<float>(out[ch]);
            res.standard_error[3 * c + ch] = static_cast<float>(se[ch]);
        }
    }
};

}  // namespace

SssReferenceResult sss_reference(const SssGBuffer& g, const std::vector<SssExactKernel>& kernels,
                                 const SssParams& p, const SssReferenceOptions& o) {
    check(g, kernels, p, o);
    const size_t npix = g.pixels();
    const Reference ref(g, kernels, p, o);

    SssReferenceResult res;
    res.irradiance.assign(3 * npix, 0.0f);
    res.standard_error.assign(3 * npix, 0.0f);
    // 0: no medium, 1: exact, 2: sampled (counted after the loop: deterministic).
    std::vector<unsigned char> how(npix, 0);

    tbb::parallel_for(tbb::blocked_range<int>(0, g.height),
                      [&](const tbb::blocked_range<int>& rows) {
                          Scratch s;
                          for (int y = rows.begin(); y < rows.end(); ++y)
                              for (int x = 0; x < g.width; ++x) ref.pixel(x, y, s, res, how);
                      });

    for (unsigned char v : how) {
        res.exact_pixels += v == 1;
        res.sampled_pixels += v == 2;
    }
    return res;
}

}  // namespace ssslab::realtime
