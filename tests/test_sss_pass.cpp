// The separable screen-space SSS pass (realtime/sss_pass.h) [Freude14 §4.4, Algorithm 4.1,
// Eqs. 4.11, 4.12; JimenezSupp §E, Figs. S.6, S.7]: constant irradiance through every kernel
// model, agreement with approx::convolve_taps and approx::convolve_separable on a flat G-buffer,
// follow-surface and rejection at a depth step and a material edge, kernels narrower than a pixel
// and wider than the image, signed SVD terms, bit-identical results for 1 and 2 threads, and the
// per-pixel rotation of the axes (SssParams::rotate): constants kept, a Gaussian's result
// unchanged (square and non-square pixels), the cross of a non-Gaussian kernel turned into an
// isotropic blur, determinism.
#include "approx/convolve.h"
#include "approx/image.h"
#include "approx/models.h"
#include "realtime/sss_pass.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace ssslab {
namespace {

using approx::ImageRGB;
using approx::Kernel2D;
using approx::KernelGrid;
using approx::ModelResult;
using approx::SeparableKernel;
using realtime::SssEdgeMode;
using realtime::SssGBuffer;
using realtime::SssMaterialKernel;
using realtime::SssParams;
using testing::analytic_profile;
using testing::edge_mode_name;
using testing::flat_gbuffer;
using testing::kSssEdgeModes;
using testing::pixel_mm;
using testing::random_image;
using testing::rel_diff;
using testing::skin_kernels;
using testing::sss_camera;

struct Model {
    std::string name;
    std::array<ModelResult, 3> r;
    std::array<const SeparableKernel*, 3> ptr() const {
        return {&r[0].kernel, &r[1].kernel, &r[2].kernel};
    }
};

// Every model family of approx/models.h, built per channel.
std::vector<Model> all_models(const std::vector<Kernel2D>& k) {
    std::vector<Model> m;
    auto add = [&](const std::string& name, auto&& build) {
        Model x;
        x.name = name;
        for (int c = 0; c < 3; ++c) x.r[c] = build(c);
        m.push_back(std::move(x));
    };
    add("svd1_l1", [&](int c) { return approx::svd_rank_n(k[c], 1, true); });
    add("svd2", [&](int c) { return approx::svd_rank_n(k[c], 2, false); });
    add("preintegration", [&](int c) { return approx::preintegration(k[c]); });
    add("guided_k1", [&](int c) { return approx::guided(k[c], {1.0, 0.0}); });
    add("manual", [&](int c) { return approx::manual_two_gaussian(k[c], 0.05, 0.3, 0.5); });
    add("deon2", [&](int c) { return approx::sum_of_gaussians(k[c], 2); });
    add("ssss_skin", [&](int c) { return approx::ssss_skin_kernel(k[c], c); });
    return m;
}

// ---- 1. Constant irradiance on a flat, camera-facing medium ---------------------------------

TEST(SssPass, ConstantIrradianceThroughEveryModel) {
    const std::vector<Kernel2D> k = skin_kernels();
    const int w = 40, h = 32;
    const double c = 0.37, z = h;
    for (const Model& m : all_models(k)) {
        const SssMaterialKernel mk = realtime::make_material_kernel(m.ptr(), 17);
        // The pass maps c to c sum_k sign_k (sum of term k's tap weights)^2 = c sum A: the taps
        // hold each term's whole 1D mass.
        std::array<double, 3> sum{};
        for (int ch = 0; ch < 3; ++ch) {
            double s = 0;
            for (const realtime::SssTerm& t : mk.terms) {
                double ws = 0;
                for (double v : t.taps.weight[ch]) ws += v;
                s += t.sign[ch] * ws * ws;
            }
            sum[ch] = s;
            EXPECT_NEAR(s, m.r[ch].kernel.sum(), 1e-12) << m.name;
        }
        std::printf("  %-15s rank %zu  sum of weights (R, G, B) = %.9f %.9f %.9f\n", m.name.c_str(),
                    mk.terms.size(), sum[0], sum[1], sum[2]);
        // The energy-conserving models keep a constant exactly.
        if (m.name != "svd2" && m.name != "deon2" && m.name != "ssss_skin") {
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sum[ch], 1.0, 1e-9) << m.name;
        }
        const ImageRGB e(w, h, 0.05, c);
        for (SssEdgeMode mode : kSssEdgeModes)
            for (double jitter : {0.0, 0.33}) {
                SssParams p = sss_camera(w, h, mode);
                p.jitter = jitter;
                const std::vector<float> out = realtime::sss_pass(flat_gbuffer(e, z), {mk}, p);
                double worst = 0;
                for (size_t i = 0; i < out.size(); ++i)
                    worst = std::max(worst, std::fabs(out[i] / (c * sum[i % 3]) - 1));
                EXPECT_LT(worst, 1e-6) << m.name << " " << edge_mode_name(mode) << " " << jitter;
            }
    }
}

// ---- 2. Flat G-buffer of constant depth: the pass is convolve_taps / convolve_separable ------

TEST(SssPass, FlatEqualsConvolveTaps) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(k[c]);
    const std::array<const SeparableKernel*, 3> a = {&pre[0].kernel, &pre[1].kernel,
                                                     &pre[2].kernel};
    const int w = 40, h = 32;  // not square: the aspect enters the horizontal scale
    for (double z : {32.0, 20.0}) {
        const SssParams p0 = sss_camera(w, h, SssEdgeMode::kNone);
        const ImageRGB e = random_image(w, h, pixel_mm(p0, h, z), 3);
        for (int count : {9, 17})
            for (double jitter : {0.0, 0.33}) {
                const approx::TapKernel taps = approx::make_taps(a, count);
                const ImageRGB ref = approx::convolve_taps(e, taps, jitter);
                const SssMaterialKernel mk = realtime::make_material_kernel(a, count);
                for (SssEdgeMode mode : kSssEdgeModes) {
                    SssParams p = sss_camera(w, h, mode);
                    p.jitter = jitter;
                    const double d = rel_diff(realtime::sss_pass(flat_gbuffer(e, z), {mk}, p), ref);
                    std::printf(
                        "  z %g, %d taps, jitter %.2f, %-6s: max |pass - taps| / max = "
                        "%.3g\n",
                        z, count, jitter, edge_mode_name(mode), d);
                    EXPECT_LT(d, 1e-6);
                }
            }
    }
}

// Taps at every pixel offset with the resampled kernel's weights: the pass is convolve_separable
// (a rank-2 SVD with signed terms).
TEST(SssPass, FullResolutionTapsEqualConvolveSeparable) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> svd;
    for (int c = 0; c < 3; ++c) svd[c] = approx::svd_rank_n(k[c], 2, false);
    const int w = 24, h = 24;  // square: the same fold along both axes
    const SssParams p = sss_camera(w, h, SssEdgeMode::kNone);
    const double z = 24, pmm = pixel_mm(p, h, z);
    const ImageRGB e = random_image(w, h, pmm, 5);
    SssMaterialKernel mk;
    for (int t = 0; t < 2; ++t) {
        realtime::SssTerm term;
        for (int ch = 0; ch < 3; ++ch) {
            const SeparableKernel& s = svd[ch].kernel;
            const std::vector<double> kx = approx::resample_1d(s.terms[t].a, s.h_mm, pmm, w - 1);
            const int r = static_cast<int>(kx.size() / 2);
            if (ch == 0)
                for (int d = -r; d <= r; ++d) term.taps.offset_mm.push_back(d * pmm);
            term.taps.weight[ch] = kx;
            term.sign[ch] = s.terms[t].sign;
            ASSERT_EQ(kx.size(), term.taps.offset_mm.size());
        }
        term.taps.support_mm = term.taps.offset_mm.back();
        mk.terms.push_back(term);
    }
    const ImageRGB ref =
        approx::convolve_separable(e, {&svd[0].kernel, &svd[1].kernel, &svd[2].kernel});
    const double d = rel_diff(realtime::sss_pass(flat_gbuffer(e, z), {mk}, p), ref);
    std::printf("  max |pass - convolve_separable| / max = %.3g (signs %g %g %g)\n", d,
                mk.terms[1].sign[0], mk.terms[1].sign[1], mk.terms[1].sign[2]);
    EXPECT_LT(d, 1e-6);
}

// ---- 3. Depth step and material edge ---------------------------------------------------------

// Left half lit (1), right half dark; returns the light that reached the right half.
double right_half_energy(const std::vector<float>& out, int w, int h) {
    double s = 0;
    for (int y = 0; y < h; ++y)
        for (int x = w / 2; x < w; ++x)
            for (int ch = 0; ch < 3; ++ch) s += out[3 * (static_cast<size_t>(y) * w + x) + ch];
    return s;
}

TEST(SssPass, FollowSurfaceAndRejectStopBleedingAcrossADepthStep) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(k[c]);
    const SssMaterialKernel mk =
        realtime::make_material_kernel({&pre[0].kernel, &pre[1].kernel, &pre[2].kernel}, 17);
    const int w = 48, h = 32;
    const double z = 32, step = 100;  // the right half 100 world units (5 mm) behind
    SssGBuffer g(w, h), ones(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            g.view_z[i] = ones.view_z[i] = static_cast<float>(x < w / 2 ? z : z + step);
            for (int ch = 0; ch < 3; ++ch) {
                g.irradiance[3 * i + ch] = x < w / 2 ? 1.0f : 0.0f;
                ones.irradiance[3 * i + ch] = 1.0f;
            }
        }
    const double lit = 3.0 * (w / 2) * h;
    std::array<double, 3> bleed{};
    for (int m = 0; m < 3; ++m) {
        SssParams p = sss_camera(w, h, kSssEdgeModes[m]);
        p.jitter = 0.33;
        p.reject_depth = 1.0;  // 0.05 mm
        bleed[m] = right_half_energy(realtime::sss_pass(g, {mk}, p), w, h) / lit;
        std::printf("  %-6s: fraction of the lit half's energy across the step = %.3g\n",
                    edge_mode_name(kSssEdgeModes[m]), bleed[m]);
        // With rejection the kept weights are renormalised: a constant stays constant on both
        // sides of the step.
        if (kSssEdgeModes[m] == SssEdgeMode::kReject) {
            const std::vector<float> o = realtime::sss_pass(ones, {mk}, p);
            for (float v : o) EXPECT_NEAR(v, 1.0, 1e-6);
        }
    }
    EXPECT_GT(bleed[0], 1e-3);             // mode none bleeds
    EXPECT_LT(bleed[1], 1e-3 * bleed[0]);  // follow-surface: t = 1 across a 100-unit step
    EXPECT_LT(bleed[2], 1e-3 * bleed[0]);  // reject: every sample across is dropped

    // A material edge at constant depth: rejection drops the other material's samples.
    SssGBuffer me = g;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            me.view_z[i] = static_cast<float>(z);
            me.material[i] = x < w / 2 ? 0 : 1;
        }
    const double none = right_half_energy(
        realtime::sss_pass(me, {mk, mk}, sss_camera(w, h, SssEdgeMode::kNone)), w, h);
    const double rej = right_half_energy(
        realtime::sss_pass(me, {mk, mk}, sss_camera(w, h, SssEdgeMode::kReject)), w, h);
    std::printf("  material edge: none %.3g, reject %.3g\n", none / lit, rej / lit);
    EXPECT_GT(none / lit, 1e-3);
    EXPECT_EQ(rej, 0.0);
}

// ---- 4. Stiff cases: narrower than a pixel, wider than the image ----------------------------

TEST(SssPass, KernelNarrowerThanAPixelIsTheIdentity) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(k[c]);
    const SssMaterialKernel mk =
        realtime::make_material_kernel({&pre[0].kernel, &pre[1].kernel, &pre[2].kernel}, 17);
    const int w = 32, h = 24;
    // At depth 100 h a pixel is 5 mm: the kernel's support is under 0.3 px.
    const double z = 100.0 * h;
    const SssGBuffer g = flat_gbuffer(random_image(w, h, 1.0, 9), z);
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.jitter = 0.33;
        const std::vector<float> out = realtime::sss_pass(g, {mk}, p);
        const double d = rel_diff(out, g.irradiance);
        std::printf("  %-6s: max |out - in| / max = %.3g\n", edge_mode_name(mode), d);
        EXPECT_LT(d, 1e-6);
    }
}

TEST(SssPass, KernelWiderThanTheImage) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre;
    for (int c = 0; c < 3; ++c) pre[c] = approx::preintegration(k[c]);
    const SssMaterialKernel mk =
        realtime::make_material_kernel({&pre[0].kernel, &pre[1].kernel, &pre[2].kernel}, 17);
    const int w = 24, h = 20;
    // At depth h / 50 a pixel is 0.001 mm: the kernel spans 1500 px on a 24 px image.
    const double z = h / 50.0;
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.jitter = 0.33;
        const std::vector<float> c =
            realtime::sss_pass(flat_gbuffer(ImageRGB(w, h, 1.0, 0.6), z), {mk}, p);
        for (float v : c) EXPECT_NEAR(v, 0.6, 1e-6) << edge_mode_name(mode);
        ImageRGB dot(w, h, 1.0, 0.0);
        for (int ch = 0; ch < 3; ++ch) dot.at(ch, 11, 9) = 1.0;
        const std::vector<float> o = realtime::sss_pass(flat_gbuffer(dot, z), {mk}, p);
        double energy = 0;
        bool finite = true;
        for (float v : o) {
            finite = finite && std::isfinite(v) && v >= -1e-7f;
            energy += v;
        }
        std::printf("  %-6s: impulse energy out / in = %.3g\n", edge_mode_name(mode), energy / 3);
        EXPECT_TRUE(finite) << edge_mode_name(mode);
        EXPECT_LE(energy, 3.0 * (1 + 1e-6)) << edge_mode_name(mode);
    }
}

// ---- 5. Signed terms: the rank-2 pass is the sum of its single-term passes -------------------

TEST(SssPass, Rank2IsTheSumOfItsTerms) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> svd;
    for (int c = 0; c < 3; ++c) svd[c] = approx::svd_rank_n(k[c], 2, false);
    const SssMaterialKernel both =
        realtime::make_material_kernel({&svd[0].kernel, &svd[1].kernel, &svd[2].kernel}, 17);
    ASSERT_EQ(both.terms.size(), 2u);
    std::printf("  term 2 signs: %g %g %g\n", both.terms[1].sign[0], both.terms[1].sign[1],
                both.terms[1].sign[2]);
    const int w = 40, h = 32;
    SssGBuffer g = flat_gbuffer(random_image(w, h, 1.0, 11), h);
    for (int x = w / 2; x < w; ++x)
        for (int y = 0; y < h; ++y) g.view_z[static_cast<size_t>(y) * w + x] = 1.5f * h;
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.jitter = 0.33;
        p.reject_depth = 1.0;
        const std::vector<float> all = realtime::sss_pass(g, {both}, p);
        const std::vector<float> t0 =
            realtime::sss_pass(g, {SssMaterialKernel{{both.terms[0]}}}, p);
        // Without jitter: alone, term 2 would take term 1's jitter (pass indices 2k + dir).
        SssParams p0 = p;
        p0.jitter = 0;
        const std::vector<float> all0 = realtime::sss_pass(g, {both}, p0);
        const std::vector<float> a0 =
            realtime::sss_pass(g, {SssMaterialKernel{{both.terms[0]}}}, p0);
        const std::vector<float> a1 =
            realtime::sss_pass(g, {SssMaterialKernel{{both.terms[1]}}}, p0);
        std::vector<float> sum(a0.size());
        for (size_t i = 0; i < sum.size(); ++i) sum[i] = a0[i] + a1[i];
        double d = rel_diff(all0, sum);
        // A negative term (as an SVD term of a negative eigenvalue) is subtracted.
        SssMaterialKernel neg = both;
        neg.terms[1].sign = {-1, -1, -1};
        const std::vector<float> diff = realtime::sss_pass(g, {neg}, p0);
        for (size_t i = 0; i < sum.size(); ++i) sum[i] = a0[i] - a1[i];
        d = std::max(d, rel_diff(diff, sum));
        std::printf("  %-6s: max |both - (term 1 +- term 2)| / max = %.3g\n", edge_mode_name(mode),
                    d);
        EXPECT_LT(d, 1e-6) << edge_mode_name(mode);
        EXPECT_GT(rel_diff(all, t0), 1e-4) << edge_mode_name(mode);  // term 2 matters
    }
}

// ---- 6. Determinism and pass-through ---------------------------------------------------------

// The determinism tests' case: two materials (pre-integration with 17 taps, SVD rank 2 with 11),
// a random 53 x 37 irradiance over a depth ramp with a step, and a disc of no medium.
struct DeterminismCase {
    std::vector<SssMaterialKernel> mats;
    SssGBuffer g;
};
DeterminismCase determinism_case() {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre, svd;
    for (int c = 0; c < 3; ++c) {
        pre[c] = approx::preintegration(k[c]);
        svd[c] = approx::svd_rank_n(k[c], 2, false);
    }
    DeterminismCase d;
    d.mats = {realtime::make_material_kernel({&pre[0].kernel, &pre[1].kernel, &pre[2].kernel}, 17),
              realtime::make_material_kernel({&svd[0].kernel, &svd[1].kernel, &svd[2].kernel}, 11)};
    const int w = 53, h = 37;
    d.g = flat_gbuffer(random_image(w, h, 1.0, 13), 1.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            d.g.view_z[i] = static_cast<float>(30 + 0.3 * x + (x > 30 ? 20 : 0));
            d.g.material[i] =
                (x - 26) * (x - 26) + (y - 18) * (y - 18) < 64 ? -1 : (y < h / 2 ? 0 : 1);
        }
    return d;
}

TEST(SssPass, BitIdenticalForOneAndTwoThreadsAndPassThrough) {
    const DeterminismCase dc = determinism_case();
    const std::vector<SssMaterialKernel>& mats = dc.mats;
    const SssGBuffer& g = dc.g;
    const int w = dc.g.width, h = dc.g.height;
    for (SssEdgeMode mode : kSssEdgeModes) {
        SssParams p = sss_camera(w, h, mode);
        p.jitter = 0.33;
        p.seed = 7;
        std::vector<float> one, two;
        tbb::task_arena(1).execute([&] { one = realtime::sss_pass(g, mats, p); });
        tbb::task_arena(2).execute([&] { two = realtime::sss_pass(g, mats, p); });
        ASSERT_EQ(one.size(), two.size());
        EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(float)), 0)
            << edge_mode_name(mode);
        size_t through = 0, changed = 0;
        for (size_t i = 0; i < g.pixels(); ++i)
            for (int ch = 0; ch < 3; ++ch) {
                if (g.material[i] < 0) {
                    EXPECT_EQ(one[3 * i + ch], g.irradiance[3 * i + ch]);
                    ++through;
                } else if (one[3 * i + ch] != g.irradiance[3 * i + ch]) {
                    ++changed;
                }
            }
        EXPECT_GT(through, 0u);
        EXPECT_GT(changed, g.pixels());  // the medium is blurred
    }
    // Bad input is refused.
    SssGBuffer bad = g;
    bad.material[0] = 2;
    EXPECT_THROW(realtime::sss_pass(bad, mats, sss_camera(w, h, SssEdgeMode::kNone)),
                 std::invalid_argument);
    bad = g;
    bad.view_z[static_cast<size_t>(w) + 1] = 0;
    bad.material[static_cast<size_t>(w) + 1] = 0;
    EXPECT_THROW(realtime::sss_pass(bad, mats, sss_camera(w, h, SssEdgeMode::kNone)),
                 std::invalid_argument);
}

// ---- 7. Per-pixel rotation of the axes [JimenezSupp Figs. S.6, S.7] -------------------------

TEST(SssPassRotate, ConstantIrradianceStaysConstant) {
    const std::vector<Kernel2D> k = skin_kernels();
    const int w = 40, h = 32;
    const double c = 0.37, z = h;
    for (const Model& m : all_models(k)) {
        const SssMaterialKernel mk = realtime::make_material_kernel(m.ptr(), 17);
        // c sum_k sign_k (sum of term k's weights)^2, summed here from the taps.
        std::array<double, 3> sum{};
        for (int ch = 0; ch < 3; ++ch)
            for (const realtime::SssTerm& t : mk.terms) {
                double ws = 0;
                for (double v : t.taps.weight[ch]) ws += v;
                sum[ch] += t.sign[ch] * ws * ws;
            }
        const ImageRGB e(w, h, 0.05, c);
        for (SssEdgeMode mode : kSssEdgeModes)
            for (double jitter : {0.0, 0.33}) {
                SssParams p = sss_camera(w, h, mode);
                p.jitter = jitter;
                p.rotate = true;
                const std::vector<float> out = realtime::sss_pass(flat_gbuffer(e, z), {mk}, p);
                double worst = 0;
                for (size_t i = 0; i < out.size(); ++i)
                    worst = std::max(worst, std::fabs(out[i] / (c * sum[i % 3]) - 1));
                EXPECT_LT(worst, 1e-6) << m.name << " " << edge_mode_name(mode) << " " << jitter;
            }
    }
}

// A rank-1 term of 1D taps every `step_px` pixels (at pixel size pmm mm) over [-reach, reach]
// pixels, the weights of f(d) (d in pixels) normalised to 1, the same in all channels.
template <class F>
SssMaterialKernel taps_from_profile(F&& f, double reach_px, double step_px, double pmm) {
    realtime::SssTerm t;
    const int n = static_cast<int>(std::lround(reach_px / step_px));
    double total = 0;
    for (int i = -n; i <= n; ++i) total += f(i * step_px);
    for (int i = -n; i <= n; ++i) {
        t.taps.offset_mm.push_back(i * step_px * pmm);
        for (int ch = 0; ch < 3; ++ch) t.taps.weight[ch].push_back(f(i * step_px) / total);
    }
    t.taps.support_mm = n * step_px * pmm;
    return SssMaterialKernel{{t}};
}

// The mean of the pass over seeds 0 .. n - 1 (rotation on): what a temporal filter sees.
std::vector<float> mean_over_seeds(const SssGBuffer& g, const SssMaterialKernel& mk, SssParams p,
                                   int n) {
    std::vector<double> sum(g.irradiance.size(), 0.0);
    for (int s = 0; s < n; ++s) {
        p.seed = static_cast<uint32_t>(s);
        const std::vector<float> o = realtime::sss_pass(g, {mk}, p);
        for (size_t i = 0; i < o.size(); ++i) sum[i] += o[i];
    }
    std::vector<float> m(sum.size());
    for (size_t i = 0; i < m.size(); ++i) m[i] = static_cast<float>(sum[i] / n);
    return m;
}

// A Gaussian's product kernel is rotation-invariant, so on a Gaussian blob (a smooth irradiance)
// rotation on and off both give the analytic convolution, a Gaussian of the summed variances,
// to within the error of linear interpolation. With rotation a pixel's second pass reads its
// neighbours' first passes, which ran along their own axes: one frame differs from the
// analytic result to first order in sigma_k^2 (bounded below), the mean over seeds only to the
// interpolation error and a fourth-order residue. Non-square pixels too, where the kernel is
// 1 px wide along x and 2 px along y (the aspect must enter each rotated axis).
TEST(SssPassRotate, GaussianKernelIsUnchangedByRotation) {
    const int w = 64, h = 64;
    const double z = h, sf = 7.0, cx = 31.5, cy = 30.25;  // blob sigma in px
    for (double stretch : {1.0, 2.0}) {
        SssParams p = sss_camera(w, h, SssEdgeMode::kFollowSurface);
        p.aspect *= stretch;                   // pixels `stretch` times as wide as high
        const double pmm = pixel_mm(p, h, z);  // mm per pixel vertically
        const double sk = 2.0;                 // kernel sigma in vertical pixels
        const SssMaterialKernel mk = taps_from_profile(
            [&](double d) { return std::exp(-d * d / (2 * sk * sk)); }, 5 * sk, 0.25, pmm);
        const double skx = sk / stretch, sky = sk;
        SssGBuffer g(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                const double v =
                    std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * sf * sf));
                for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = static_cast<float>(v);
                g.view_z[i] = static_cast<float>(z);
            }
        const std::vector<float> off = realtime::sss_pass(g, {mk}, p);
        p.rotate = true;
        const std::vector<float> one = realtime::sss_pass(g, {mk}, p);
        const std::vector<float> mean = mean_over_seeds(g, mk, p, 16);
        // The analytic result: variances sf^2 + sk^2 along each axis.
        const double vx = sf * sf + skx * skx, vy = sf * sf + sky * sky;
        const double amp = std::sqrt(sf * sf / vx) * std::sqrt(sf * sf / vy);
        double d_one = 0, d_mean = 0, d_off = 0, d_mean_off = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                const double ref = amp * std::exp(-(x - cx) * (x - cx) / (2 * vx) -
                                                  (y - cy) * (y - cy) / (2 * vy));
                for (int ch = 0; ch < 3; ++ch) {
                    const size_t j = 3 * i + ch;
                    d_one = std::max(d_one, std::fabs(one[j] - ref));
                    d_mean = std::max(d_mean, std::fabs(mean[j] - ref));
                    d_off = std::max(d_off, std::fabs(off[j] - ref));
                    d_mean_off =
                        std::max(d_mean_off, std::fabs(static_cast<double>(mean[j]) - off[j]));
                }
            }
        // Linear interpolation at fraction t adds t (1 - t) / 2 f'' <= f'' / 8 per axis it
        // interpolates along, max |f''| <= peak / sf^2 (the input, the sharper of the two
        // passes' inputs; peak 1); two passes, each interpolating along up to two axes:
        // 4 / 8 / sf^2. The taps (every quarter pixel over 5 sigma): under 1e-5.
        const double interp = 0.5 / (sf * sf) + 1e-5;
        // Rotation, one frame: a neighbour's first pass along u' instead of u changes the blur
        // by sk^2 / 2 (d_u'^2 - d_u^2) f, at most sk^2 / 2 * 2 / (e sf^2) for a Gaussian f
        // (max of r^2 exp(-r^2 / 2 sf^2) / sf^4).
        const double mixing = sk * sk / (std::exp(1.0) * sf * sf);
        // The mean over angles: the covariance sk^2 (u u^T + v v^T) of random u, v has the
        // determinant of the exact one less sk^4 cos^2; the peak's excess, averaged, is
        // sk^4 / (4 (sf^2 + sk^2)^2).
        const double residue = std::pow(sk, 4) / (4 * std::pow(sf * sf + sk * sk, 2));
        std::printf(
            "  stretch %.1f: max |off - analytic| = %.2e (bound %.2e), |one seed - analytic| = "
            "%.2e (bound %.2e), |mean of 16 seeds - analytic| = %.2e, |mean - off| = %.2e "
            "(bound %.2e; a wrong aspect: %.2e)\n",
            stretch, d_off, interp, d_one, interp + mixing, d_mean, d_mean_off, interp + residue,
            amp * (1 - std::sqrt(vx / vy)));
        EXPECT_LT(d_off, interp) << stretch;
        EXPECT_LT(d_one, interp + mixing) << stretch;
        EXPECT_LT(d_mean, interp + residue) << stretch;
        EXPECT_LT(d_mean_off, interp + residue) << stretch;
    }
}

// The ratio of the mean output on the axes to that on the diagonals, over an annulus around
// (cx, cy): pixels within `half_deg` degrees of the directions 0, 90, 180, 270 degrees or of
// 45, 135, 225, 315 degrees.
double axis_to_diagonal(const std::vector<float>& out, int w, int h, double cx, double cy,
                        double r0, double r1, double half_deg) {
    double axis = 0, diag = 0;
    int na = 0, nd = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double dx = x - cx, dy = y - cy, r = std::hypot(dx, dy);
            if (r < r0 || r > r1) continue;
            const double deg = std::fmod(std::atan2(dy, dx) * 180 / std::acos(-1.0) + 360, 90);
            const double v = out[3 * (static_cast<size_t>(y) * w + x)];
            if (std::min(deg, 90 - deg) < half_deg) {
                axis += v;
                ++na;
            } else if (std::fabs(deg - 45) < half_deg) {
                diag += v;
                ++nd;
            }
        }
    EXPECT_GT(na, 20);
    EXPECT_GT(nd, 20);
    return (axis / na) / (diag / nd);
}

// The cross pattern [JimenezSupp Fig. S.6]: a 1D profile that is the sum of a narrow and a wide
// Gaussian (one rank-1 term, as a 1-term fit of a two-lobed profile) makes the product kernel
// k(x) k(y) a cross: on a circle of radius 10 px its value on an axis, k(10) k(0), is about 7
// times that on a diagonal, k(7.1)^2. Rotating each pixel's axes spreads the cross over all
// directions: the output on the circle is nearly isotropic. Energy is kept either way.
TEST(SssPassRotate, RotationRemovesTheCrossPattern) {
    const int w = 96, h = 96;
    const double z = h, cx = 48, cy = 48;
    const SssParams p0 = sss_camera(w, h, SssEdgeMode::kNone);
    const double pmm = pixel_mm(p0, h, z);
    const double s1 = 1.0, s2 = 6.0;  // px
    const SssMaterialKernel mk = taps_from_profile(
        [&](double d) {
            return 0.5 * std::exp(-d * d / (2 * s1 * s1)) / s1 +
                   0.5 * std::exp(-d * d / (2 * s2 * s2)) / s2;
        },
        4 * s2, 0.5, pmm);
    // A small bright disc (radius 1.5 px) at (cx, cy).
    SssGBuffer g(w, h);
    double in = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (std::hypot(x - cx, y - cy) <= 1.5) {
                const size_t i = static_cast<size_t>(y) * w + x;
                for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = 1.0f;
                in += 1;
            }
    for (auto& v : g.view_z) v = static_cast<float>(z);
    double ratio[2] = {0, 0};
    for (int rotate = 0; rotate < 2; ++rotate)
        for (SssEdgeMode mode : {SssEdgeMode::kNone, SssEdgeMode::kFollowSurface}) {
            SssParams p = sss_camera(w, h, mode);
            p.rotate = rotate != 0;
            // With rotation, the mean over 16 seeds (one frame is noisy: see above).
            const std::vector<float> out =
                rotate ? mean_over_seeds(g, mk, p, 16) : realtime::sss_pass(g, {mk}, p);
            const double a = axis_to_diagonal(out, w, h, cx, cy, 8.5, 11.5, 12);
            double energy = 0;
            for (size_t i = 0; i < g.pixels(); ++i) energy += out[3 * i];
            std::printf(
                "  rotate %d, %-6s: axis / diagonal on r = 8.5..11.5 px: %.3f, energy "
                "out / in = %.6f\n",
                rotate, edge_mode_name(mode), a, energy / in);
            // A gather whose kernel turns from pixel to pixel keeps energy on average only.
            EXPECT_NEAR(energy / in, 1.0, rotate ? 1e-2 : 1e-5);
            if (mode == SssEdgeMode::kNone) ratio[rotate] = a;
        }
    EXPECT_GT(ratio[0], 3.0);                                  // the cross
    EXPECT_LT(std::fabs(ratio[1] - 1), 0.1 * (ratio[0] - 1));  // gone, to the noise
}

TEST(SssPassRotate, BitIdenticalForOneAndTwoThreads) {
    const DeterminismCase dc = determinism_case();
    const std::vector<SssMaterialKernel>& mats = dc.mats;
    const SssGBuffer& g = dc.g;
    const int w = dc.g.width, h = dc.g.height;
    for (SssEdgeMode mode : kSssEdgeModes)
        for (double jitter : {0.0, 0.33}) {
            SssParams p = sss_camera(w, h, mode);
            p.jitter = jitter;
            p.seed = 7;
            p.rotate = true;
            std::vector<float> one, two, unrotated, other_seed;
            tbb::task_arena(1).execute([&] { one = realtime::sss_pass(g, mats, p); });
            tbb::task_arena(2).execute([&] { two = realtime::sss_pass(g, mats, p); });
            ASSERT_EQ(one.size(), two.size());
            EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(float)), 0)
                << edge_mode_name(mode) << " " << jitter;
            for (size_t i = 0; i < g.pixels(); ++i) {
                if (g.material[i] >= 0) continue;
                for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(one[3 * i + ch], g.irradiance[3 * i + ch]);
            }
            SssParams q = p;
            q.rotate = false;
            unrotated = realtime::sss_pass(g, mats, q);
            q = p;
            q.seed = 8;
            other_seed = realtime::sss_pass(g, mats, q);
            // Rotation changes the result, and the angles follow the seed.
            EXPECT_GT(rel_diff(one, unrotated), 1e-4) << edge_mode_name(mode) << " " << jitter;
            EXPECT_GT(rel_diff(one, other_seed), 1e-4) << edge_mode_name(mode) << " " << jitter;
        }
}

}  // namespace
}  // namespace ssslab
