// The screen-space 2D reference (realtime/sss_reference.h) [Freude14 §6.1, §6.2, Eqs. 4.11, 4.12]:
// constant irradiance in every mode and method, the exact method against approx::convolve_exact
// and a plain 2D loop on a flat G-buffer, a separable kernel against realtime::sss_pass, the
// sampled method against the exact one (per-pixel z-scores, the standard error over replicas,
// its decrease with the sample count), depth steps and material edges, kernels narrower than a
// pixel and wider than the image, 1 vs 2 threads, bad input, and a timing print.
#include "approx/convolve.h"
#include "approx/image.h"
#include "approx/models.h"
#include "realtime/sss_pass.h"
#include "realtime/sss_reference.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace ssslab {
namespace {

using approx::ImageRGB;
using approx::Kernel2D;
using approx::KernelGrid;
using realtime::SssEdgeMode;
using realtime::SssExactKernel;
using realtime::SssGBuffer;
using realtime::SssParams;
using realtime::SssReferenceOptions;
using realtime::SssReferenceResult;
using Method = SssReferenceOptions::Method;
// The helpers this file shares with test_sss_pass.cpp (testing.h).
using testing::analytic_profile;
using testing::edge_mode_name;
using testing::flat_gbuffer;
using testing::kSssEdgeModes;
using testing::pixel_mm;
using testing::random_image;
using testing::rel_diff;
using testing::skin_kernels;
using testing::sss_camera;

SssExactKernel exact_kernel(const std::vector<Kernel2D>& k) {
    return SssExactKernel::from_kernels({&k[0], &k[1], &k[2]});
}

// A lit disc of radius r px about (cx, cy), 1 inside, 0.1 outside, channels scaled apart.
SssGBuffer lit_disc(int w, int h, double cx, double cy, double r, double z) {
    SssGBuffer g(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const bool in = (x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r;
            for (int ch = 0; ch < 3; ++ch)
                g.irradiance[3 * i + ch] = static_cast<float>((in ? 1.0 : 0.1) * (1 - 0.2 * ch));
            g.view_z[i] = static_cast<float>(z);
        }
    return g;
}

SssReferenceOptions method(Method m, int samples = 256, std::uint64_t seed = 1) {
    SssReferenceOptions o;
    o.method = m;
    o.samples = samples;
    o.seed = seed;
    return o;
}

// ---- 1. Constant irradiance ------------------------------------------------------------------

TEST(SssReference, ConstantStaysConstantInEveryModeAndMethod) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 40, h = 32;
    const std::array<float, 3> c = {0.37f, 0.81f, 0.05f};
    // A depth step (the right half 0.2 units behind: follow-surface blends, rejection drops and
    // renormalises with reject_depth 0.1) and a flat buffer.
    for (double step : {0.0, 0.2}) {
        SssGBuffer g(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                g.view_z[i] = static_cast<float>(h + (x < w / 2 ? 0 : step));
                for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = c[ch];
            }
        for (SssEdgeMode mode : kSssEdgeModes)
            for (Method m : {Method::kExact, Method::kSampled, Method::kAuto}) {
                SssParams p = sss_camera(w, h, mode);
                p.reject_depth = 0.1;
                const SssReferenceResult r = realtime::sss_reference(g, k, p, method(m, 64));
                double worst = 0, se = 0;
                for (size_t i = 0; i < r.irradiance.size(); ++i) {
                    worst = std::max(
                        worst, std::fabs(static_cast<double>(r.irradiance[i]) / c[i % 3] - 1));
                    se = std::max(se, static_cast<double>(r.standard_error[i]));
                }
                EXPECT_LT(worst, 1e-6) << edge_mode_name(mode) << " " << static_cast<int>(m);
                EXPECT_EQ(se, 0.0) << edge_mode_name(mode) << " " << static_cast<int>(m);
                EXPECT_EQ(r.exact_pixels + r.sampled_pixels, static_cast<std::int64_t>(w * h));
                if (m == Method::kAuto) {
                    EXPECT_EQ(r.exact_pixels, w * h);  // 61 x 61 taps
                }
            }
    }
}

// ---- 2. Flat G-buffer: the exact method is the 2D convolution --------------------------------

TEST(SssReference, FlatExactEqualsConvolveExact) {
    const std::vector<Kernel2D> kk = skin_kernels();
    const std::vector<SssExactKernel> k = {exact_kernel(kk)};
    const int w = 40, h = 32;  // not square: the aspect enters the horizontal scale
    for (double z : {32.0, 23.3, 9.1}) {
        const SssParams p0 = sss_camera(w, h, SssEdgeMode::kNone);
        const ImageRGB e = random_image(w, h, pixel_mm(p0, h, z), 3);
        const ImageRGB ref = approx::convolve_exact(e, {&kk[0], &kk[1], &kk[2]});
        for (SssEdgeMode mode : kSssEdgeModes) {
            const SssReferenceResult r = realtime::sss_reference(
                flat_gbuffer(e, z), k, sss_camera(w, h, mode), method(Method::kExact));
            const double d = rel_diff(r.irradiance, ref);
            std::printf(
                "  z %g (pixel %.4f mm), %-6s: max |reference - convolve_exact| / max = "
                "%.3g\n",
                z, e.pixel_mm, edge_mode_name(mode), d);
            EXPECT_LT(d, 1e-6);
        }
    }
}

// Pixels of an even number k of cells along an axis: pixel offset d holds cells k d - k / 2 to
// k d + k / 2 - 1, so W is a sum of whole cell masses and the reference is a plain loop over
// Kernel2D::at. Square pixels of 2 x 2 cells, and non-square ones of 4 x 2 (aspect 2.4 on a
// 24 x 20 image: the x scale follows the projection).
TEST(SssReference, FlatExactEqualsAPlainLoopOverTheCells) {
    const std::vector<Kernel2D> kk = skin_kernels();
    const std::vector<SssExactKernel> k = {exact_kernel(kk)};
    const int w = 24, h = 20, n = kk[0].n();
    for (int kx : {2, 4}) {
        SssParams p = sss_camera(w, h, SssEdgeMode::kNone);
        p.unit_mm = 0.04;
        // Pixel height 2 tan_half z unit_mm / h = 0.02 mm = 2 cells; width 2 tan_half aspect z
        // unit_mm / w = kx cells.
        const double z = 10;
        p.aspect = kx * 0.01 * w / (2 * p.tan_half * z * p.unit_mm);
        const ImageRGB e = random_image(w, h, 0.02, 4);
        ImageRGB ref(w, h, 0.02, 0.0);
        // The pixel offset holding cell c for pixels of m cells (m even): floor((c + m/2) / m).
        auto pix = [](int c, int m) {
            const int t = c + m / 2;
            return t >= 0 ? t / m : -((-t + m - 1) / m);
        };
        for (int ch = 0; ch < 3; ++ch)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    double s = 0;
                    for (int j = -n; j < n; ++j) {
                        const int qy = std::clamp(y + pix(j, 2), 0, h - 1);
                        for (int i = -n; i < n; ++i)
                            s += kk[ch].at(i, j) *
                                 e.at(ch, std::clamp(x + pix(i, kx), 0, w - 1), qy);
                    }
                    ref.at(ch, x, y) = s;
                }
        const SssReferenceResult r =
            realtime::sss_reference(flat_gbuffer(e, z), k, p, method(Method::kExact));
        const double d = rel_diff(r.irradiance, ref);
        std::printf("  pixel = %d x 2 cells: max |reference - plain loop| / max = %.3g\n", kx, d);
        EXPECT_LT(d, 1e-6);
    }
}

// ---- 3. A separable kernel: the reference is sss_pass with full-resolution taps -------------

TEST(SssReference, SeparableKernelAgreesWithSssPass) {
    // Rank-1 quadrants u u^T, u(i) = exp(-(i + 1/2) h / l), a different l per channel.
    const int n = 40;
    const double hmm = 0.05, ls[3] = {0.4, 0.25, 0.15};
    std::vector<Kernel2D> kk;
    for (int ch = 0; ch < 3; ++ch) {
        Eigen::VectorXd u(n);
        for (int i = 0; i < n; ++i) u(i) = std::exp(-(i + 0.5) * hmm / ls[ch]);
        kk.emplace_back(u * u.transpose(), hmm);
    }
    const std::vector<SssExactKernel> k = {exact_kernel(kk)};
    const int w = 36, h = 30;
    for (double z : {30.0, 17.0}) {
        const SssParams p = sss_camera(w, h, SssEdgeMode::kNone);
        const double pmm = pixel_mm(p, h, z);
        const SssGBuffer g = flat_gbuffer(random_image(w, h, pmm, 6), z);
        // Full resolution: a tap at every pixel offset, weights the 1D kernel resampled to the
        // pixel bins (a = u / (2 sum u): half cell masses), folded at w - 1 as clamp-to-edge does.
        realtime::SssMaterialKernel mk;
        realtime::SssTerm term;
        for (int ch = 0; ch < 3; ++ch) {
            std::vector<double> a(static_cast<size_t>(n));
            for (int i = 0; i < n; ++i) a[static_cast<size_t>(i)] = 2 * kk[ch].quadrant()(i, 0);
            double s = 0;
            for (double v : a) s += v;
            for (double& v : a) v /= 2 * s;
            const std::vector<double> kx = approx::resample_1d(a, hmm, pmm, w - 1);
            const int r = static_cast<int>(kx.size() / 2);
            if (ch == 0)
                for (int d = -r; d <= r; ++d) term.taps.offset_mm.push_back(d * pmm);
            ASSERT_EQ(kx.size(), term.taps.offset_mm.size());
            term.taps.weight[ch] = kx;
        }
        term.taps.support_mm = term.taps.offset_mm.back();
        mk.terms.push_back(term);
        const std::vector<float> pass = realtime::sss_pass(g, {mk}, p);
        const SssReferenceResult ref = realtime::sss_reference(g, k, p, method(Method::kExact));
        const double d = rel_diff(pass, ref.irradiance);
        // 17 importance-sampled taps of the same (exact rank-1) kernel: the pass's sampling error.
        std::array<approx::ModelResult, 3> svd;
        for (int ch = 0; ch < 3; ++ch) svd[ch] = approx::svd_rank_n(kk[ch], 1, true);
        const std::vector<float> pass17 = realtime::sss_pass(
            g,
            {realtime::make_material_kernel({&svd[0].kernel, &svd[1].kernel, &svd[2].kernel}, 17)},
            p);
        const double d17 = rel_diff(pass17, ref.irradiance);
        std::printf(
            "  z %g: max |sss_pass - reference| / max: full-resolution taps %.3g, 17 "
            "taps %.3g\n",
            z, d, d17);
        EXPECT_LT(d, 1e-6);
        EXPECT_LT(d17, 0.2);  // tap sampling of a random image (no tight bound claimed)
    }
}

// ---- 4. Sampled against exact ----------------------------------------------------------------

// Per-pixel z-scores (sampled - exact) / SE of one seed (20261201) on a smooth image (a Gaussian
// spot) and on a lit disc with a hard edge, at 64 to 4096 samples, with 2 (the default) and 16
// points per stratum. The standard error is unbiased in the mean square at any count (the test over
// seeds below), but where the kernel's tail crosses a bright region that few samples reach (the
// spot seen from the image corners: about 0.3 of 64 samples) it is itself very noisy, and so are
// the z-scores: their variance is 15 to 200 at 64 samples and tends to 1 as the samples resolve
// the tail. Asserted at 4096 samples: mean, variance and median |z| of N(0, 1) (0.674).
TEST(SssReference, SampledAgreesWithExactByZScores) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 32, h = 32;
    SssGBuffer spot(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const double r2 = (x - 15.3) * (x - 15.3) + (y - 16.6) * (y - 16.6);
            for (int ch = 0; ch < 3; ++ch)
                spot.irradiance[3 * i + ch] =
                    static_cast<float>((0.1 + std::exp(-r2 / (2 * 3.0 * 3.0))) * (1 - 0.2 * ch));
            spot.view_z[i] = static_cast<float>(h);  // 0.05 mm pixels
        }
    const SssGBuffer disc = lit_disc(w, h, 15.5, 16.3, 7.5, h);
    const SssParams p = sss_camera(w, h, SssEdgeMode::kNone);
    const int counts[4] = {64, 256, 1024, 4096};
    for (int per : {2, 16})
        for (int img = 0; img < 2; ++img) {
            const SssGBuffer& g = img == 0 ? spot : disc;
            const char* name = img == 0 ? "spot" : "disc";
            const SssReferenceResult ex = realtime::sss_reference(g, k, p, method(Method::kExact));
            double rms_se[4] = {0, 0, 0, 0};
            for (int t = 0; t < 4; ++t) {
                SssReferenceOptions o = method(Method::kSampled, counts[t], 20261201);
                o.samples_per_stratum = per;
                const SssReferenceResult s = realtime::sss_reference(g, k, p, o);
                EXPECT_EQ(s.sampled_pixels, w * h);
                double sum = 0, sum2 = 0, se2 = 0;
                int m = 0, within2 = 0;
                std::vector<double> zabs;
                for (size_t i = 0; i < s.irradiance.size(); ++i) {
                    se2 += static_cast<double>(s.standard_error[i]) * s.standard_error[i];
                    // A z-score needs an SE above the float outputs' resolution.
                    if (!(s.standard_error[i] > 1e-6f * std::fabs(ex.irradiance[i]))) continue;
                    const double zsc = (s.irradiance[i] - ex.irradiance[i]) / s.standard_error[i];
                    sum += zsc;
                    sum2 += zsc * zsc;
                    within2 += std::fabs(zsc) < 2;
                    zabs.push_back(std::fabs(zsc));
                    ++m;
                }
                rms_se[t] = std::sqrt(se2 / static_cast<double>(s.irradiance.size()));
                const double mean = sum / m, var = sum2 / m - mean * mean;
                std::nth_element(zabs.begin(), zabs.begin() + m / 2, zabs.end());
                const double med = zabs[static_cast<size_t>(m / 2)];
                std::printf(
                    "  %2d a stratum, %s, %4d samples: %d z, mean %7.4f, variance %9.4f, "
                    "median |z| %.3f, |z| < 2: %.4f, RMS SE %.3g\n",
                    per, name, counts[t], m, mean, var, med, static_cast<double>(within2) / m,
                    rms_se[t]);
                EXPECT_GT(m, static_cast<int>(s.irradiance.size()) / 2);
                if (counts[t] == 4096) {
                    // About 5 standard deviations of the mean and variance of m independent
                    // N(0, 1) values; neighbouring pixels share their error, which widens both.
                    EXPECT_LT(std::fabs(mean), 5 / std::sqrt(m)) << per << " " << name;
                    EXPECT_GT(var, 0.8) << per << " " << name;
                    EXPECT_LT(var, 1.25) << per << " " << name;
                    EXPECT_GT(med, 0.6) << per << " " << name;
                    EXPECT_LT(med, 0.75) << per << " " << name;
                }
            }
            const double slope = std::log(rms_se[0] / rms_se[3]) / std::log(64.0);
            std::printf(
                "  %2d a stratum, %s: RMS SE 64 -> 4096 samples: SE ~ N^-%.3f (iid: "
                "N^-0.5)\n",
                per, name, slope);
            EXPECT_GT(slope, 0.45);  // at least 1 / sqrt(N); stratification makes it faster
        }
}

// Over independent seeds: the mean over seeds agrees with the exact value within its standard
// error, and the mean of the reported variance equals the variance over seeds (the stratified
// estimate of the variance is unbiased). Every mode; kReject's delta-method SE too.
TEST(SssReference, StandardErrorMatchesTheSpreadOverSeeds) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 24, h = 24, seeds = 100, samples = 32;
    SssGBuffer g = lit_disc(w, h, 11.5, 12.2, 6.5, h);
    for (int y = 0; y < h; ++y)
        for (int x = 16; x < w; ++x) g.view_z[static_cast<size_t>(y) * w + x] = h + 0.5f;
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.follow_strength = 0.5;  // s = 0.5 across the step: a blend
        p.reject_depth = 0.2;
        const SssReferenceResult ex = realtime::sss_reference(g, k, p, method(Method::kExact));
        const size_t nv = ex.irradiance.size();
        std::vector<double> sum(nv, 0.0), sum2(nv, 0.0), se2(nv, 0.0);
        for (int s = 0; s < seeds; ++s) {
            const SssReferenceResult r = realtime::sss_reference(
                g, k, p, method(Method::kSampled, samples, 1000 + static_cast<unsigned>(s)));
            for (size_t i = 0; i < nv; ++i) {
                sum[i] += r.irradiance[i];
                sum2[i] += static_cast<double>(r.irradiance[i]) * r.irradiance[i];
                se2[i] += static_cast<double>(r.standard_error[i]) * r.standard_error[i];
            }
        }
        double chi2 = 0, var_tot = 0, se2_tot = 0;
        int dof = 0;
        for (size_t i = 0; i < nv; ++i) {
            const double mean = sum[i] / seeds;
            const double var = (sum2[i] - seeds * mean * mean) / (seeds - 1);
            var_tot += var;
            se2_tot += se2[i] / seeds;
            if (!(var > 1e-14)) continue;
            const double t = (mean - ex.irradiance[i]) / std::sqrt(var / seeds);
            chi2 += t * t;
            ++dof;
        }
        const double ratio = se2_tot / var_tot;
        std::printf(
            "  %-6s: sum of t^2 over seeds = %.1f for %d pixel channels (z = %.2f); "
            "mean SE^2 / variance over seeds = %.4f\n",
            edge_mode_name(mode), chi2, dof, (chi2 - dof) / std::sqrt(2.0 * dof), ratio);
        ASSERT_GT(dof, 100);
        // t^2 of 99 degrees of freedom has mean 99 / 97: the sum is within 5 sigma of that.
        const double mean_t2 = (seeds - 1.0) / (seeds - 3.0);
        EXPECT_LT(std::fabs(chi2 - dof * mean_t2), 5 * std::sqrt(2.0 * dof) * mean_t2);
        // The pooled variance over 100 seeds holds to a few per cent; the delta method's to
        // its linearisation.
        EXPECT_NEAR(ratio, 1.0, mode == SssEdgeMode::kReject ? 0.15 : 0.1);
    }
}

// ---- 5. Depth step and material edge ---------------------------------------------------------

double right_half_energy(const std::vector<float>& out, int w, int h) {
    double s = 0;
    for (int y = 0; y < h; ++y)
        for (int x = w / 2; x < w; ++x)
            for (int ch = 0; ch < 3; ++ch) s += out[3 * (static_cast<size_t>(y) * w + x) + ch];
    return s;
}

TEST(SssReference, FollowSurfaceAndRejectStopBleeding) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 48, h = 32;
    const double z = 32, step = 100;  // the right half 100 world units (5 mm) behind
    SssGBuffer g(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            g.view_z[i] = static_cast<float>(x < w / 2 ? z : z + step);
            for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = x < w / 2 ? 1.0f : 0.0f;
        }
    const double lit = 3.0 * (w / 2) * h;
    for (Method m : {Method::kExact, Method::kSampled}) {
        std::array<double, 3> bleed{};
        for (int mi = 0; mi < 3; ++mi) {
            SssParams p = sss_camera(w, h, kSssEdgeModes[mi]);
            p.reject_depth = 1.0;
            bleed[mi] = right_half_energy(
                            realtime::sss_reference(g, k, p, method(m, 64)).irradiance, w, h) /
                        lit;
            std::printf("  %-7s %-6s: fraction of the lit half's energy across the step = %.3g\n",
                        m == Method::kExact ? "exact" : "sampled",
                        edge_mode_name(kSssEdgeModes[mi]), bleed[mi]);
        }
        EXPECT_GT(bleed[0], 1e-3);             // mode none bleeds
        EXPECT_LT(bleed[1], 1e-3 * bleed[0]);  // follow-surface: s = 1 across a 100-unit step
        EXPECT_LT(bleed[2], 1e-3 * bleed[0]);  // reject: every pixel across is dropped

        // A material edge at constant depth: rejection drops the other material's pixels.
        SssGBuffer me = g;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                me.view_z[i] = static_cast<float>(z);
                me.material[i] = x < w / 2 ? 0 : 1;
            }
        const std::vector<SssExactKernel> k2 = {k[0], k[0]};
        const double none = right_half_energy(
            realtime::sss_reference(me, k2, sss_camera(w, h, SssEdgeMode::kNone), method(m, 64))
                .irradiance,
            w, h);
        const double rej = right_half_energy(
            realtime::sss_reference(me, k2, sss_camera(w, h, SssEdgeMode::kReject), method(m, 64))
                .irradiance,
            w, h);
        std::printf("  %-7s material edge: none %.3g, reject %.3g\n",
                    m == Method::kExact ? "exact" : "sampled", none / lit, rej / lit);
        EXPECT_GT(none / lit, 1e-3);
        EXPECT_EQ(rej, 0.0);
    }
}

// ---- 6. Stiff cases, determinism, bad input --------------------------------------------------

TEST(SssReference, KernelNarrowerThanAPixelIsTheIdentity) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 32, h = 24;
    const double z = 100.0 * h;  // a pixel is 5 mm: the kernel's support is under 0.3 px
    const SssGBuffer g = flat_gbuffer(random_image(w, h, 1.0, 9), z);
    for (SssEdgeMode mode : kSssEdgeModes)
        for (Method m : {Method::kExact, Method::kSampled, Method::kAuto}) {
            const SssReferenceResult r =
                realtime::sss_reference(g, k, sss_camera(w, h, mode), method(m, 16));
            EXPECT_EQ(std::memcmp(r.irradiance.data(), g.irradiance.data(),
                                  g.irradiance.size() * sizeof(float)),
                      0)
                << edge_mode_name(mode) << " " << static_cast<int>(m);
        }
}

TEST(SssReference, KernelWiderThanTheImage) {
    const std::vector<SssExactKernel> k = {exact_kernel(skin_kernels())};
    const int w = 24, h = 20;
    const double z = h / 50.0;  // a pixel is 0.001 mm: the kernel spans 1500 px
    for (SssEdgeMode mode : kSssEdgeModes)
        for (Method m : {Method::kExact, Method::kSampled, Method::kAuto}) {
            const SssReferenceResult c =
                realtime::sss_reference(flat_gbuffer(ImageRGB(w, h, 1.0, 0.6), z), k,
                                        sss_camera(w, h, mode), method(m, 16));
            for (float v : c.irradiance) EXPECT_NEAR(v, 0.6, 1e-6) << edge_mode_name(mode);
            if (m == Method::kAuto) {
                EXPECT_EQ(c.exact_pixels, w * h);  // clamped: 480 taps
            }
        }
    // An interior impulse: the exact method conserves its energy only up to the mass that
    // clamp-to-edge sends to the edge pixels (which then hold it); it stays finite, >= 0.
    ImageRGB dot(w, h, 1.0, 0.0);
    for (int ch = 0; ch < 3; ++ch) dot.at(ch, 11, 9) = 1.0;
    const SssReferenceResult o = realtime::sss_reference(
        flat_gbuffer(dot, z), k, sss_camera(w, h, SssEdgeMode::kNone), method(Method::kExact));
    double energy = 0;
    for (float v : o.irradiance) {
        EXPECT_TRUE(std::isfinite(v) && v >= -1e-7f);
        energy += v;
    }
    std::printf("  impulse energy out / in = %.3g\n", energy / 3);
    EXPECT_LE(energy, 3.0 * (1 + 1e-6));
}

TEST(SssReference, BitIdenticalForOneAndTwoThreadsAndPassThrough) {
    const std::vector<Kernel2D> kk = skin_kernels();
    const RadialProfile wide = analytic_profile(0.02, 100, 1.0);  // 2 mm, another material
    std::vector<Kernel2D> kw;
    for (int c = 0; c < 3; ++c) kw.emplace_back(wide, c, KernelGrid::from_profile(wide));
    const std::vector<SssExactKernel> k = {exact_kernel(kk), exact_kernel(kw)};
    const int w = 53, h = 37;
    SssGBuffer g = flat_gbuffer(random_image(w, h, 1.0, 13), 1.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            g.view_z[i] = static_cast<float>(30 + 0.3 * x + (x > 30 ? 20 : 0));
            g.material[i] =
                (x - 26) * (x - 26) + (y - 18) * (y - 18) < 64 ? -1 : (y < h / 2 ? 0 : 1);
        }
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.reject_depth = 3;
        SssReferenceOptions o = method(Method::kAuto, 32, 7);
        o.max_exact_taps = 1200;  // some pixels exact, some sampled
        SssReferenceResult one, two;
        tbb::task_arena(1).execute([&] { one = realtime::sss_reference(g, k, p, o); });
        tbb::task_arena(2).execute([&] { two = realtime::sss_reference(g, k, p, o); });
        std::printf("  %-6s: %lld exact, %lld sampled pixels\n", edge_mode_name(mode),
                    static_cast<long long>(one.exact_pixels),
                    static_cast<long long>(one.sampled_pixels));
        EXPECT_GT(one.exact_pixels, 0);
        EXPECT_GT(one.sampled_pixels, 0);
        EXPECT_EQ(one.exact_pixels, two.exact_pixels);
        EXPECT_EQ(std::memcmp(one.irradiance.data(), two.irradiance.data(),
                              one.irradiance.size() * sizeof(float)),
                  0)
            << edge_mode_name(mode);
        EXPECT_EQ(std::memcmp(one.standard_error.data(), two.standard_error.data(),
                              one.standard_error.size() * sizeof(float)),
                  0)
            << edge_mode_name(mode);
        size_t through = 0;
        for (size_t i = 0; i < g.pixels(); ++i)
            if (g.material[i] < 0)
                for (int ch = 0; ch < 3; ++ch) {
                    EXPECT_EQ(one.irradiance[3 * i + ch], g.irradiance[3 * i + ch]);
                    EXPECT_EQ(one.standard_error[3 * i + ch], 0.0f);
                    ++through;
                }
        EXPECT_GT(through, 0u);
        EXPECT_EQ(one.exact_pixels + one.sampled_pixels,
                  static_cast<std::int64_t>(g.pixels() - through / 3));
    }
}

TEST(SssReference, BadInputIsRefused) {
    const std::vector<Kernel2D> kk = skin_kernels();
    const std::vector<SssExactKernel> k = {exact_kernel(kk)};
    const int w = 12, h = 10;
    const SssGBuffer g(w, h);
    const SssParams p = sss_camera(w, h, SssEdgeMode::kNone);
    EXPECT_NO_THROW(realtime::sss_reference(g, k, p));
    SssGBuffer bad = g;
    bad.irradiance.pop_back();
    EXPECT_THROW(realtime::sss_reference(bad, k, p), std::invalid_argument);
    bad = g;
    bad.material[3] = 1;  // no kernel 1
    EXPECT_THROW(realtime::sss_reference(bad, k, p), std::invalid_argument);
    EXPECT_THROW(realtime::sss_reference(g, {}, p), std::invalid_argument);
    bad = g;
    bad.view_z[5] = 0;
    EXPECT_THROW(realtime::sss_reference(bad, k, p), std::invalid_argument);
    SssParams bp = p;
    bp.tan_half = 0;
    EXPECT_THROW(realtime::sss_reference(g, k, bp), std::invalid_argument);
    EXPECT_THROW(realtime::sss_reference(g, k, p, method(Method::kSampled, 1)),
                 std::invalid_argument);
    SssExactKernel broken = k[0];
    broken.sat.pop_back();
    EXPECT_THROW(realtime::sss_reference(g, {broken}, p), std::invalid_argument);
    EXPECT_THROW(SssExactKernel::from_kernels({&kk[0], nullptr, &kk[2]}), std::invalid_argument);
    const Kernel2D other(Eigen::MatrixXd::Ones(4, 4), 0.01);
    EXPECT_THROW(SssExactKernel::from_kernels({&kk[0], &other, &kk[2]}), std::invalid_argument);
    Eigen::MatrixXd neg = Eigen::MatrixXd::Ones(4, 4);
    neg(3, 3) = -0.5;
    const Kernel2D negk(neg, 0.01);
    EXPECT_THROW(SssExactKernel::from_kernels({&negk, &negk, &negk}), std::invalid_argument);
}

// ---- Timing (printed, not asserted) ---------------------------------------------------------

// A Skin1-like kernel [Freude14 Table 6.2, the thesis grid of Table 6.1: dr = min MFP / 20 =
// 0.034 mm, extent 32 max MFP = 41 mm, n = 1233]: per channel exp(-sigma_tr r) / r with
// sigma_tr = sqrt(3 sigma_a (sigma_a + sigma_s)) in mm^-1, at the cell centres.
TEST(SssReference, TimingPrint) {
    const double sa[3] = {0.032, 0.17, 0.48}, ss[3] = {0.74, 0.88, 1.01};  // mm^-1
    const double mfp_min = 1 / (sa[2] + ss[2]), mfp_max = 1 / (sa[0] + ss[0]);
    const double hmm = mfp_min / 20;
    const int n = static_cast<int>(std::ceil(32 * mfp_max / hmm));
    std::vector<Kernel2D> kk;
    for (int ch = 0; ch < 3; ++ch) {
        const double st = std::sqrt(3 * sa[ch] * (sa[ch] + ss[ch]));
        Eigen::MatrixXd q(n, n);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const double r = std::hypot(i + 0.5, j + 0.5) * hmm;
                q(i, j) = std::exp(-st * r) / r;
            }
        kk.emplace_back(std::move(q), hmm);
    }
    auto t0 = std::chrono::steady_clock::now();
    const std::vector<SssExactKernel> k = {exact_kernel(kk)};
    auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    const double t_build = secs(t0, std::chrono::steady_clock::now());
    // 1 mm pixels (a head and shoulders 256 mm across at 256 x 256): the footprint is 83 x 83
    // pixels. 128 x 128 unless SSSLAB_REFERENCE_TIMING_SIZE says otherwise, to keep the test fast.
    const char* size_env = std::getenv("SSSLAB_REFERENCE_TIMING_SIZE");
    const int w = size_env ? std::max(16, std::atoi(size_env)) : 128, h = w;
    SssParams p = sss_camera(w, h, SssEdgeMode::kFollowSurface);
    p.unit_mm = 1;
    const double z = h;
    const SssGBuffer g = lit_disc(w, h, w / 2 - 0.5, h / 2 + 0.5, 0.23 * w, z);
    std::printf("  Skin1-like kernel: n = %d, h = %.4f mm, tables built in %.3f s\n", n, hmm,
                t_build);
    SssReferenceResult ex, sm;
    for (Method m : {Method::kExact, Method::kSampled}) {
        t0 = std::chrono::steady_clock::now();
        SssReferenceResult r = realtime::sss_reference(g, k, p, method(m, 256));
        const double t = secs(t0, std::chrono::steady_clock::now());
        // One thread: the cost a pixel, less sensitive to other work on the machine.
        t0 = std::chrono::steady_clock::now();
        tbb::task_arena(1).execute([&] { realtime::sss_reference(g, k, p, method(m, 256)); });
        const double t1 = secs(t0, std::chrono::steady_clock::now());
        std::printf("  %d x %d, 1 mm pixels, %s: %.3f s (%.2f us a pixel; one thread %.2f us)\n", w,
                    h, m == Method::kExact ? "exact (83 x 83 taps)" : "sampled (256 samples)", t,
                    1e6 * t / (w * h), 1e6 * t1 / (w * h));
        (m == Method::kExact ? ex : sm) = std::move(r);
    }
    double err = 0, se = 0, ref = 0;
    for (size_t i = 0; i < ex.irradiance.size(); ++i) {
        err += std::pow(sm.irradiance[i] - ex.irradiance[i], 2);
        se += std::pow(sm.standard_error[i], 2);
        ref += std::pow(ex.irradiance[i], 2);
    }
    std::printf("  sampled - exact: RMS %.3g, RMS SE %.3g (RMS value %.3g)\n",
                std::sqrt(err / ex.irradiance.size()), std::sqrt(se / ex.irradiance.size()),
                std::sqrt(ref / ex.irradiance.size()));
}

}  // namespace
}  // namespace ssslab
