// The image-space pipeline: test signals, exact (FFT) and separable convolutions with the common
// resampling and clamp-to-edge conventions, and tap kernels [Freude14 ch. 6; JimenezSupp §C].
#include "approx/convolve.h"
#include "approx/image.h"
#include "approx/models.h"

#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

namespace ssslab {
namespace {

using approx::convolve_exact;
using approx::convolve_separable;
using approx::convolve_taps;
using approx::ImageRGB;
using approx::Kernel2D;
using approx::KernelGrid;
using approx::make_signal;
using approx::make_taps;
using approx::SeparableKernel;
using approx::Signal;
using approx::SignalParams;

// The skin-like analytic profile (testing.h): exp(-r / l1) / r plus exp(-r / l2) / l2 per
// channel, lengths stretched by `scale`.
using testing::analytic_profile;

struct Kernels {
    std::vector<Kernel2D> k;  // one per channel
    std::array<const Kernel2D*, 3> ptr() const { return {&k[0], &k[1], &k[2]}; }
};

Kernels skin_kernels(double dr_mm, int nr, double scale = 1.0) {
    const RadialProfile p = analytic_profile(dr_mm, nr, scale);
    Kernels ks;
    for (int c = 0; c < 3; ++c) ks.k.emplace_back(p, c, KernelGrid::from_profile(p));
    return ks;
}

ImageRGB random_image(int w, int h, double pixel_mm, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    ImageRGB img(w, h, pixel_mm);
    for (auto& ch : img.c)
        for (double& v : ch) v = u(rng);
    return img;
}

// ---- Brute force reference: resampling cell by cell on the full grid, direct summation ------

// Kpix(dx, dy) for |dx| <= W - 1, |dy| <= H - 1, every full-grid cell's mass split over the pixel
// bins [(d - 1/2) p, (d + 1/2) p) by the product of its x and y overlaps, offsets folded.
std::vector<double> brute_pixel_kernel(const Kernel2D& k, double p, int w, int h) {
    const int n = k.n();
    const double hc = k.h_mm();
    const int mx = 2 * w - 1, my = 2 * h - 1;
    std::vector<double> kp(static_cast<size_t>(mx) * my, 0.0);
    auto overlaps = [&](int i, int fold) {
        std::vector<std::pair<int, double>> o;
        const double a = i * hc, b = (i + 1) * hc;
        const int dmax = static_cast<int>(std::ceil(std::max(std::fabs(a), std::fabs(b)) / p)) + 1;
        for (int d = -dmax; d <= dmax; ++d) {
            const double len = std::min(b, (d + 0.5) * p) - std::max(a, (d - 0.5) * p);
            if (len > 0) o.emplace_back(std::clamp(d, -fold, fold), len / hc);
        }
        return o;
    };
    for (int i = -n; i < n; ++i) {
        const auto ox = overlaps(i, w - 1);
        for (int j = -n; j < n; ++j) {
            const auto oy = overlaps(j, h - 1);
            const double m = k.at(i, j);
            for (const auto& [dx, fx] : ox)
                for (const auto& [dy, fy] : oy)
                    kp[static_cast<size_t>(dy + h - 1) * mx + static_cast<size_t>(dx + w - 1)] +=
                        m * fx * fy;
        }
    }
    return kp;
}

ImageRGB brute_convolve(const ImageRGB& e, const std::array<const Kernel2D*, 3>& k) {
    const int w = e.width, h = e.height, mx = 2 * w - 1;
    ImageRGB out(w, h, e.pixel_mm);
    for (int ch = 0; ch < 3; ++ch) {
        const std::vector<double> kp = brute_pixel_kernel(*k[ch], e.pixel_mm, w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double s = 0;
                for (int dy = -(h - 1); dy <= h - 1; ++dy)
                    for (int dx = -(w - 1); dx <= w - 1; ++dx)
                        s += kp[static_cast<size_t>(dy + h - 1) * mx +
                                static_cast<size_t>(dx + w - 1)] *
                             e.at(ch, std::clamp(x - dx, 0, w - 1), std::clamp(y - dy, 0, h - 1));
                out.at(ch, x, y) = s;
            }
    }
    return out;
}

double max_abs_diff(const ImageRGB& a, const ImageRGB& b) {
    double m = 0;
    for (int ch = 0; ch < 3; ++ch)
        for (size_t i = 0; i < a.c[ch].size(); ++i)
            m = std::max(m, std::fabs(a.c[ch][i] - b.c[ch][i]));
    return m;
}

double max_abs(const ImageRGB& a) {
    double m = 0;
    for (const auto& ch : a.c)
        for (double v : ch) m = std::max(m, std::fabs(v));
    return m;
}

// RMS of (a - b) over all channels, relative to the RMS of b.
double relative_rms(const ImageRGB& a, const ImageRGB& b) {
    double num = 0, den = 0;
    for (int ch = 0; ch < 3; ++ch)
        for (size_t i = 0; i < a.c[ch].size(); ++i) {
            const double d = a.c[ch][i] - b.c[ch][i];
            num += d * d;
            den += b.c[ch][i] * b.c[ch][i];
        }
    return std::sqrt(num / den);
}

double rms_all(const ImageRGB& a, const ImageRGB& b) {
    const approx::ImageErrors e = approx::image_errors(a, b);
    return std::sqrt((e.rms[0] * e.rms[0] + e.rms[1] * e.rms[1] + e.rms[2] * e.rms[2]) / 3.0);
}

double mean(const ImageRGB& a, int ch) {
    double s = 0;
    for (double v : a.c[ch]) s += v;
    return s / static_cast<double>(a.c[ch].size());
}

ImageRGB transpose(const ImageRGB& a) {
    ImageRGB t(a.height, a.width, a.pixel_mm);
    for (int ch = 0; ch < 3; ++ch)
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) t.at(ch, y, x) = a.at(ch, x, y);
    return t;
}

Eigen::MatrixXd random_quadrant(int n, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.1, 1.0);
    Eigen::MatrixXd q(n, n);  // deliberately not symmetric: catches swapped axes
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) q(i, j) = u(rng) * std::exp(-0.3 * i - 0.1 * j);
    return q;
}

// ---- 1. convolve_exact against brute force --------------------------------------------------

TEST(ImageSpace, ExactConvolutionMatchesBruteForce) {
    const ImageRGB e = random_image(13, 11, 0.1, 7);
    const Kernel2D normal(random_quadrant(8, 1), 0.037);  // extent 0.30 mm: 3 pixels
    const Kernel2D wide(random_quadrant(45, 2), 0.07);    // extent 3.15 mm: 32 pixels > 12
    const Kernel2D narrow(random_quadrant(3, 3), 0.01);   // extent 0.03 mm < p / 2
    const std::vector<std::pair<const char*, std::array<const Kernel2D*, 3>>> cases = {
        {"normal", {&normal, &normal, &normal}},
        {"wide", {&wide, &wide, &wide}},
        {"mixed", {&normal, &wide, &narrow}}};
    for (const auto& [name, ks] : cases) {
        const ImageRGB fast = convolve_exact(e, ks);
        const ImageRGB slow = brute_convolve(e, ks);
        const double rel = max_abs_diff(fast, slow) / max_abs(slow);
        std::printf("  %-7s max |fft - brute| / max = %.3g\n", name, rel);
        EXPECT_LT(rel, 1e-12) << name;
    }
    // A kernel within the centre pixel leaves the image as it is.
    const ImageRGB same = convolve_exact(e, {&narrow, &narrow, &narrow});
    const double d = max_abs_diff(same, e);
    std::printf("  narrow: max |out - in| = %.3g\n", d);
    EXPECT_LT(d, 1e-12);
    // Blurring does change an image (the comparison above can fail).
    EXPECT_GT(max_abs_diff(convolve_exact(e, {&wide, &wide, &wide}), e), 0.05);
}

// ---- 2. Pre-integration is exact for straight edges ----------------------------------------

TEST(ImageSpace, PreintegrationIsExactForEdges) {
    const Kernels ks = skin_kernels(0.01, 300);  // extent 3 mm = 60 pixels
    std::array<approx::ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(ks.k[c]);
    const std::array<const SeparableKernel*, 3> sep = {&pre[0].kernel, &pre[1].kernel,
                                                       &pre[2].kernel};
    SignalParams sp;
    sp.size = 96;
    sp.pixel_mm = 0.05;
    const ImageRGB edge = make_signal(Signal::kEdge, sp);
    const ImageRGB hedge = transpose(edge);  // a horizontal edge
    for (const auto& [name, img] : {std::pair<const char*, const ImageRGB&>{"vertical", edge},
                                    std::pair<const char*, const ImageRGB&>{"horizontal", hedge}}) {
        const ImageRGB exact = convolve_exact(img, ks.ptr());
        const ImageRGB s = convolve_separable(img, sep);
        const double d = max_abs_diff(s, exact);
        std::printf("  %s edge: max |preint - exact| = %.3g\n", name, d);
        EXPECT_LT(d, 1e-12) << name;
        // The kernel does blur the edge: not a trivial identity.
        EXPECT_GT(max_abs_diff(exact, img), 0.1) << name;
    }
    // Negative control: a dot is not additively separable, pre-integration is not exact.
    const ImageRGB dot = make_signal(Signal::kDot, sp);
    const double d = max_abs_diff(convolve_separable(dot, sep), convolve_exact(dot, ks.ptr()));
    std::printf("  dot: max |preint - exact| = %.3g\n", d);
    EXPECT_GT(d, 1e-6);
}

// ---- 3. A constant image stays constant under every normalised kernel -----------------------

TEST(ImageSpace, ConstantImageStaysConstant) {
    const Kernels ks = skin_kernels(0.01, 300);  // extent 3 mm = 60 pixels
    const double c = 0.37;
    const ImageRGB e(160, 120, 0.05, c);
    auto check = [&](const ImageRGB& out, const char* what) {
        double m = 0;
        for (const auto& ch : out.c)
            for (double v : ch) m = std::max(m, std::fabs(v - c));
        std::printf("  %-22s max |out - c| = %.3g\n", what, m);
        EXPECT_LT(m, 1e-12) << what;
    };
    check(convolve_exact(e, ks.ptr()), "exact");
    std::array<approx::ModelResult, 3> pre, svd;
    for (int ch = 0; ch < 3; ++ch) {
        pre[ch] = approx::preintegration(ks.k[ch]);
        svd[ch] = approx::svd_rank_n(ks.k[ch], 1, true);
    }
    const std::array<const SeparableKernel*, 3> p = {&pre[0].kernel, &pre[1].kernel,
                                                     &pre[2].kernel};
    const std::array<const SeparableKernel*, 3> s = {&svd[0].kernel, &svd[1].kernel,
                                                     &svd[2].kernel};
    check(convolve_separable(e, p), "separable preint");
    check(convolve_separable(e, s), "separable svd1 (L1)");
    for (int count : {3, 25}) {
        const approx::TapKernel taps = make_taps(p, count);
        check(convolve_taps(e, taps), count == 3 ? "taps 3" : "taps 25");
        check(convolve_taps(e, taps, 0.33), count == 3 ? "taps 3 jittered" : "taps 25 jittered");
    }
    // Not normalised (plain rank-1 SVD): the constant is not kept, so the check can fail.
    const approx::ModelResult raw = approx::svd_rank_n(ks.k[0], 1, false);
    const ImageRGB r = convolve_separable(e, {&raw.kernel, &raw.kernel, &raw.kernel});
    EXPECT_GT(std::fabs(r.at(0, 80, 60) - c), 1e-6);
}

// The size the experiments use: 256 x 256 pixels, a kernel of n = 1236 (extent 8.65 mm = 173
// pixels). Kernel2D's own normalisation holds its mass to ~1e-12 only at this n, so the output
// is compared with the constant times the kernel's mass.
TEST(ImageSpace, ExactConvolutionTiming) {
    const Kernels ks = skin_kernels(0.007, 1236);
    const double c = 0.37;
    const ImageRGB e(256, 256, 0.05, c);
    const auto t0 = std::chrono::steady_clock::now();
    const ImageRGB out = convolve_exact(e, ks.ptr());
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  convolve_exact 256 x 256, n = 1236, 3 kernels: %.3f s\n", secs);
    for (int ch = 0; ch < 3; ++ch) {
        const Eigen::MatrixXd& q = ks.k[static_cast<size_t>(ch)].quadrant();
        long double sum = 0;  // the kernel's mass, accurately
        for (Eigen::Index j = 0; j < q.cols(); ++j)
            for (Eigen::Index i = 0; i < q.rows(); ++i) sum += q(i, j);
        const double mass = static_cast<double>(4 * sum);
        double m = 0;
        for (double v : out.c[ch]) m = std::max(m, std::fabs(v - c * mass));
        std::printf("  channel %d: kernel mass - 1 = %.3g, max |out - c mass| = %.3g\n", ch,
                    mass - 1.0, m);
        EXPECT_LT(m, 1e-13) << ch;
    }
}

// ---- 4. Resampling and taps -----------------------------------------------------------------

TEST(ImageSpace, ResampleConventions) {
    // One cell [0, 1] (and its mirror [-1, 0]) on pixels of side 1: half of each cell lands in
    // the centre bin [-1/2, 1/2), half in the bin beside it.
    const std::vector<double> one = approx::resample_1d({1.0}, 1.0, 1.0, 10);
    ASSERT_EQ(one.size(), 3u);
    EXPECT_DOUBLE_EQ(one[0], 0.5);
    EXPECT_DOUBLE_EQ(one[1], 1.0);
    EXPECT_DOUBLE_EQ(one[2], 0.5);

    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> half(157);
    double sum = 0;
    for (double& v : half) sum += (v = u(rng));
    for (int fold : {0, 3, 40, 1000}) {
        const std::vector<double> r = approx::resample_1d(half, 0.037, 0.05, fold);
        const int expect_r = std::min(static_cast<int>(std::ceil(157 * 0.037 / 0.05)), fold);
        EXPECT_EQ(static_cast<int>(r.size()), 2 * expect_r + 1) << fold;
        double s = 0;
        for (double v : r) s += v;
        EXPECT_NEAR(s, 2 * sum, 1e-12 * sum) << fold;
        for (size_t i = 0; i < r.size(); ++i) EXPECT_EQ(r[i], r[r.size() - 1 - i]) << fold;
    }
    // Folding: the mass beyond fold pixels ends on the outermost bin.
    const std::vector<double> full = approx::resample_1d(half, 0.037, 0.05, 1000);
    const std::vector<double> folded = approx::resample_1d(half, 0.037, 0.05, 40);
    const int rf = static_cast<int>(full.size() / 2);
    double beyond = 0;
    for (int d = 40; d <= rf; ++d) beyond += full[static_cast<size_t>(rf + d)];
    EXPECT_NEAR(folded.back(), beyond, 1e-12);
    EXPECT_NEAR(folded[40], full[static_cast<size_t>(rf)], 1e-15);
}

TEST(ImageSpace, TapKernels) {
    const Kernels narrow = skin_kernels(0.005, 300);
    const Kernels wide = skin_kernels(0.02, 300, 4.0);  // the same kernel, 4x wider
    std::array<approx::ModelResult, 3> pn, pw;
    for (int c = 0; c < 3; ++c) {
        pn[c] = approx::preintegration(narrow.k[c]);
        pw[c] = approx::preintegration(wide.k[c]);
    }
    const std::array<const SeparableKernel*, 3> an = {&pn[0].kernel, &pn[1].kernel, &pn[2].kernel};
    const std::array<const SeparableKernel*, 3> aw = {&pw[0].kernel, &pw[1].kernel, &pw[2].kernel};
    for (int count : {3, 17, 101}) {
        const approx::TapKernel t = make_taps(an, count);
        ASSERT_EQ(static_cast<int>(t.offset_mm.size()), count);
        for (int ch = 0; ch < 3; ++ch) {
            double s = 0;
            for (double v : t.weight[ch]) {
                EXPECT_GE(v, 0.0);
                s += v;
            }
            EXPECT_NEAR(s, 1.0, 1e-12) << count << " " << ch;
        }
        for (int i = 0; i < count; ++i) {
            const size_t a = static_cast<size_t>(i), b = static_cast<size_t>(count - 1 - i);
            EXPECT_EQ(t.offset_mm[a], -t.offset_mm[b]);
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(t.weight[ch][a], t.weight[ch][b], 1e-15);
            if (i > 0) {
                EXPECT_LT(t.offset_mm[a - 1], t.offset_mm[a]);
            }
        }
        EXPECT_EQ(t.offset_mm[static_cast<size_t>(count / 2)], 0.0);
        EXPECT_DOUBLE_EQ(t.offset_mm.back(), t.support_mm);
    }
    // The range follows the kernel's width.
    const double rn = make_taps(an, 17).support_mm, rw = make_taps(aw, 17).support_mm;
    std::printf("  support R: narrow %.4f mm, wide %.4f mm\n", rn, rw);
    EXPECT_NEAR(rw / rn, 4.0, 1e-9);
    // And with the mass it must hold.
    EXPECT_LT(make_taps(an, 17, 0.9).support_mm, rn);
    EXPECT_THROW(make_taps(an, 16), std::invalid_argument);
    EXPECT_THROW(make_taps(an, 1), std::invalid_argument);
}

// ---- 5. SVD rank-N converges to the exact convolution ---------------------------------------

TEST(ImageSpace, SvdRankNApproachesExact) {
    const Kernels ks = skin_kernels(0.01, 300);
    SignalParams sp;
    sp.size = 96;
    sp.pixel_mm = 0.05;
    const ImageRGB e = make_signal(Signal::kCircleSquares, sp);
    const ImageRGB exact = convolve_exact(e, ks.ptr());
    std::vector<double> rms;
    for (int rank = 1; rank <= 6; ++rank) {
        std::array<approx::ModelResult, 3> m;
        for (int c = 0; c < 3; ++c) m[c] = approx::svd_rank_n(ks.k[c], rank, false);
        const ImageRGB s = convolve_separable(e, {&m[0].kernel, &m[1].kernel, &m[2].kernel});
        rms.push_back(rms_all(s, exact));
        std::printf("  rank %d: image RMS %.3e\n", rank, rms.back());
    }
    for (size_t i = 1; i < rms.size(); ++i) EXPECT_LT(rms[i], rms[i - 1]) << "rank " << i + 1;
    EXPECT_LT(rms.back(), 0.1 * rms.front());
}

// ---- 6. Taps against the full-resolution separable convolution ------------------------------

TEST(ImageSpace, TapsApproachSeparable) {
    const Kernels ks = skin_kernels(0.01, 300);
    std::array<approx::ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(ks.k[c]);
    const std::array<const SeparableKernel*, 3> a = {&pre[0].kernel, &pre[1].kernel,
                                                     &pre[2].kernel};
    SignalParams sp;
    sp.size = 96;
    sp.pixel_mm = 0.05;
    const ImageRGB e = make_signal(Signal::kCircleSquares, sp);
    const ImageRGB ref = convolve_separable(e, a);
    const double e101 = relative_rms(convolve_taps(e, make_taps(a, 101)), ref);
    const double e17 = relative_rms(convolve_taps(e, make_taps(a, 17)), ref);
    std::printf("  relative RMS vs separable: 17 taps %.3e, 101 taps %.3e\n", e17, e101);
    EXPECT_LT(e101, 1e-2);
    EXPECT_GT(e17, e101);

    // Jitter turns banding into noise without biasing a smooth signal.
    const ImageRGB skin = make_signal(Signal::kSkinUniform, sp);
    const approx::TapKernel t = make_taps(a, 17);
    const ImageRGB plain = convolve_taps(skin, t);
    const ImageRGB jit = convolve_taps(skin, t, 0.33);
    const double change = max_abs_diff(plain, jit);
    std::printf("  jitter 0.33: max change %.3e, mean shift", change);
    EXPECT_GT(change, 1e-4);
    for (int ch = 0; ch < 3; ++ch) {
        const double shift = mean(jit, ch) - mean(plain, ch);
        std::printf(" %.2e", shift);
        EXPECT_LT(std::fabs(shift), 1e-3) << ch;
    }
    std::printf("\n");
    // Deterministic.
    EXPECT_EQ(max_abs_diff(jit, convolve_taps(skin, t, 0.33)), 0.0);
}

// ---- 7. Signals -----------------------------------------------------------------------------

TEST(ImageSpace, Signals) {
    SignalParams sp;
    sp.size = 90;
    sp.pixel_mm = 0.05;
    for (Signal s : {Signal::kEdge, Signal::kCircleSquares, Signal::kDot, Signal::kSkinShaded,
                     Signal::kSkinUniform}) {
        const ImageRGB a = make_signal(s, sp), b = make_signal(s, sp);
        const char* name = approx::signal_name(s);
        Signal parsed{};
        ASSERT_TRUE(approx::parse_signal(name, parsed));
        EXPECT_EQ(parsed, s);
        ASSERT_EQ(a.width, 90);
        ASSERT_EQ(a.height, 90);
        EXPECT_EQ(a.pixel_mm, 0.05);
        double lo = 1, hi = 0;
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_EQ(a.c[ch], b.c[ch]) << name;
            for (double v : a.c[ch]) {
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
        }
        std::printf("  %-15s values in [%.3f, %.3f]\n", name, lo, hi);
        EXPECT_GE(lo, 0.0) << name;
        EXPECT_LE(hi, 1.0) << name;
        EXPECT_GT(hi - lo, 0.2) << name;  // not blank
        const std::vector<unsigned char> rgb = approx::to_rgb8(a);
        EXPECT_EQ(rgb.size(), 90u * 90u * 3u);
    }
    Signal dummy{};
    EXPECT_FALSE(approx::parse_signal("no_such_signal", dummy));

    const ImageRGB edge = make_signal(Signal::kEdge, sp);
    for (int ch = 0; ch < 3; ++ch)
        for (int y = 0; y < 90; ++y) {
            for (int x = 0; x < 30; ++x) EXPECT_EQ(edge.at(ch, x, y), 1.0);
            for (int x = 60; x < 90; ++x) EXPECT_EQ(edge.at(ch, x, y), 0.0);
        }
    // The texture depends on the seed.
    SignalParams other = sp;
    other.seed = 2;
    EXPECT_GT(max_abs_diff(make_signal(Signal::kSkinUniform, sp),
                           make_signal(Signal::kSkinUniform, other)),
              0.01);
    // The dot's area is pi r^2 (anti-aliased coverage).
    const ImageRGB dot = make_signal(Signal::kDot, sp);
    const double area = mean(dot, 0) * 90 * 90 * 0.05 * 0.05;
    EXPECT_NEAR(area, std::numbers::pi * 0.25 * 0.25, 0.03 * std::numbers::pi * 0.25 * 0.25);
}

TEST(ImageSpace, ErrorsAndBytes) {
    ImageRGB a(4, 2, 0.1, 0.5), b(4, 2, 0.1, 0.5);
    a.at(1, 3, 1) = 0.8;
    const approx::ImageErrors e = approx::image_errors(a, b);
    EXPECT_EQ(e.max_abs[0], 0.0);
    EXPECT_NEAR(e.max_abs[1], 0.3, 1e-15);
    EXPECT_NEAR(e.rms[1], std::sqrt(0.09 / 8), 1e-15);
    EXPECT_NEAR(e.energy[1], 0.3 / 4.0, 1e-15);
    const std::vector<unsigned char> lin = approx::to_rgb8(a, false);
    ASSERT_EQ(lin.size(), 24u);
    EXPECT_EQ(lin[0], 128);                       // 0.5 * 255 = 127.5, rounded
    EXPECT_EQ(lin[(1 * 4 + 3) * 3 + 1], 204);     // 0.8 * 255
    EXPECT_EQ(approx::to_rgb8(a, true)[0], 186);  // 0.5^(1/2.2) * 255 = 186.0
    const std::vector<unsigned char> d = approx::difference_rgb8(a, b, 0.3);
    EXPECT_EQ(d[(1 * 4 + 3) * 3 + 1], 255);
    EXPECT_EQ(d[(1 * 4 + 3) * 3 + 0], 0);
    EXPECT_THROW(approx::image_errors(a, ImageRGB(3, 2, 0.1)), std::invalid_argument);
}

}  // namespace
}  // namespace ssslab
