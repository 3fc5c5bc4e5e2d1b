// Munoz11's layered convolution (approx/munoz.h) against a direct implementation of its
// equations written here without FFTs (Eqs. 5-7: layers, the split of each sample, per-distance
// kernels, the interpolation of the visible depth): one layer on a flat slab is the direct 2D
// sum; several layers, front and back samples, a perspective pixel size and every split rule
// agree with the direct sum to rounding; a constant irradiance on a large flat medium converges
// to E R_dr at second order in the pixel size (the midpoint rule of a smooth profile); the
// threshold of Eq. 8 and the skipping of invisible layers; bad input.
#include "approx/diffusion.h"
#include "approx/model_spec.h"
#include "approx/munoz.h"
#include "core/rng.h"
#include "core/scene.h"
#include "experiments/runner/surface_frames.h"
#include "realtime/frame.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

namespace ssslab::approx {
namespace {

const double kInf = std::numeric_limits<double>::infinity();

std::shared_ptr<const DiffusionProfile> dipole(double sigma_a, double sigma_s) {
    DiffusionMedium m;
    m.sigma_a = sigma_a;
    m.sigma_s = sigma_s;
    m.eta = 1.3;
    return make_diffusion_profile("dipole", m);
}

std::array<std::shared_ptr<const DiffusionProfile>, 3> media() {
    return {dipole(0.05, 2.0), dipole(0.2, 2.0), dipole(0.02, 1.5)};
}

MunozView empty_view(int w, int h, double pixel_mm, double per_depth) {
    MunozView v;
    v.width = w;
    v.height = h;
    v.pixel_mm = pixel_mm;
    v.pixel_mm_per_depth = per_depth;
    const size_t n = static_cast<size_t>(w) * h;
    v.front_z.assign(n, static_cast<float>(kInf));
    v.back_z.assign(n, static_cast<float>(kInf));
    for (int c = 0; c < 3; ++c) {
        v.front_irradiance[c].assign(n, 0.0f);
        v.back_irradiance[c].assign(n, 0.0f);
    }
    return v;
}

/// The paper's equations summed directly: every sample's irradiance to its layers (equal halves
/// or linear), every pair of layers with its kernel (in-plane distance at the mean depth's pixel
/// size, the source pixel's area at its layer), Eq. 7 at the visible depth.
std::array<std::vector<double>, 3> direct(const MunozView& v, const RadialFunction& rd,
                                          const MunozOptions& o) {
    const int w = v.width, h = v.height, nl = o.layers;
    const size_t n = static_cast<size_t>(w) * h;
    double z0 = kInf, z1 = -kInf;
    for (size_t i = 0; i < n; ++i)
        for (float z : {v.front_z[i], v.back_z[i]})
            if (std::isfinite(z)) z0 = std::min(z0, double(z)), z1 = std::max(z1, double(z));
    const double dz = nl > 1 ? (z1 - z0) / (nl - 1) : 0;
    auto pos = [&](double z, int& l0, double& s) {
        l0 = 0;
        s = 0;
        if (nl == 1 || dz == 0) return;
        const double u = (z - z0) / dz;
        l0 = std::min(int(std::floor(u)), nl - 2);
        s = u - l0;
    };
    auto k = [&](double z) { return v.pixel_mm + v.pixel_mm_per_depth * z; };
    // Layer maps E_l(q), full resolution.
    std::vector<std::array<std::vector<double>, 3>> e(nl);
    for (auto& l : e)
        for (auto& c : l) c.assign(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v.front_z[i])) continue;
        for (int side = 0; side < 2; ++side) {
            const double z = side == 0 ? v.front_z[i] : v.back_z[i];
            if (!std::isfinite(z)) continue;
            const auto& irr = side == 0 ? v.front_irradiance : v.back_irradiance;
            int l0;
            double s;
            pos(z, l0, s);
            const double w1 = (nl == 1 || dz == 0) ? 0 : (o.split == MunozSplit::equal ? 0.5 : s);
            for (int c = 0; c < 3; ++c) {
                e[l0][c][i] += (1 - w1) * irr[c][i];
                if (w1 > 0) e[l0 + 1][c][i] += w1 * irr[c][i];
            }
        }
    }
    std::array<std::vector<double>, 3> out;
    for (auto& c : out) c.assign(n, 0.0);
    for (size_t p = 0; p < n; ++p) {
        if (!std::isfinite(v.front_z[p])) continue;
        int l0;
        double s;
        pos(v.front_z[p], l0, s);
        const int px = int(p % w), py = int(p / w);
        for (int l : {l0, l0 + 1}) {
            const double wl = l == l0 ? 1 - s : s;
            if (wl == 0 || l >= nl) continue;
            for (int i = 0; i < nl; ++i) {
                const double zi = z0 + i * dz, zl = z0 + l * dz;
                const double side = k(0.5 * (zi + zl)), area = k(zi) * k(zi);
                const double ez = std::abs(i - l) * dz;
                for (size_t q = 0; q < n; ++q) {
                    const double dx = side * (px - int(q % w)), dy = side * (py - int(q / w));
                    const auto r = rd(std::sqrt(dx * dx + dy * dy + ez * ez));
                    for (int c = 0; c < 3; ++c) out[c][p] += wl * area * r[c] * e[i][c][q];
                }
            }
        }
    }
    return out;
}

double worst_relative(const MunozResult& a, const std::array<std::vector<double>, 3>& b) {
    double peak = 0, worst = 0;
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < b[c].size(); ++i) peak = std::max(peak, std::fabs(b[c][i]));
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < b[c].size(); ++i)
            worst = std::max(worst, std::fabs(a.exitance[c][i] - b[c][i]) / peak);
    return worst;
}

TEST(Munoz, OneLayerOnAFlatSlabIsTheDirect2DSum) {
    const RadialFunction rd = RadialFunction::from_diffusion(media());
    MunozView v = empty_view(24, 20, 0.1, 0);
    RngStream rng(1, rng_domain::kTest + 310, 0);
    for (size_t i = 0; i < v.front_z.size(); ++i) {
        v.front_z[i] = 100;
        for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = static_cast<float>(rng.uniform());
    }
    for (int layers : {1, 4}) {  // a flat object: every sample in layer 0 whatever n_l
        MunozOptions o;
        o.layers = layers;
        const MunozResult r = munoz_exitance(v, rd, o);
        const double err = worst_relative(r, direct(v, rd, o));
        std::printf("layers %d: worst difference from the direct sum %.2g of the peak\n", layers,
                    err);
        EXPECT_LT(err, 1e-6) << layers;  // float output: 6e-8 relative rounding
        EXPECT_EQ(r.stats.convolutions, 3);
    }
}

TEST(Munoz, LayersFrontAndBackAndPerspectiveFollowTheEquations) {
    const RadialFunction rd = RadialFunction::from_diffusion(media());
    MunozView v = empty_view(18, 14, 0.02, 0.002);  // pixel 0.22-0.24 mm at 100-110 mm
    RngStream rng(2, rng_domain::kTest + 311, 0);
    for (size_t i = 0; i < v.front_z.size(); ++i) {
        if (rng.uniform() < 0.15) continue;  // outside the object
        v.front_z[i] = static_cast<float>(100 + 4 * rng.uniform());
        if (rng.uniform() < 0.8) v.back_z[i] = static_cast<float>(106 + 4 * rng.uniform());
        for (int c = 0; c < 3; ++c) {
            v.front_irradiance[c][i] = static_cast<float>(rng.uniform());
            v.back_irradiance[c][i] = static_cast<float>(0.3 * rng.uniform());
        }
    }
    for (MunozSplit split : {MunozSplit::equal, MunozSplit::linear})
        for (int layers : {2, 3, 6}) {
            MunozOptions o;
            o.layers = layers;
            o.split = split;
            o.skip_invisible = false;
            const MunozResult r = munoz_exitance(v, rd, o);
            const double err = worst_relative(r, direct(v, rd, o));
            std::printf(
                "%s split, %d layers: worst difference %.2g of the peak, %lld "
                "convolutions\n",
                split_name(split), layers, err, static_cast<long long>(r.stats.convolutions));
            EXPECT_LT(err, 1e-6) << layers;
            EXPECT_EQ(r.stats.convolutions, 3 * layers * layers);
            // Skipping the layers no visible sample reads changes nothing.
            o.skip_invisible = true;
            const MunozResult s = munoz_exitance(v, rd, o);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(s.exitance[c], r.exitance[c]);
            EXPECT_EQ(s.stats.convolutions + s.stats.skipped_invisible, r.stats.convolutions);
        }
}

// A flat medium of 100 x 100 mm under E = (1, 0.5, 2): M at the centre converges to E R_dr. The
// kernel is the midpoint rule of a profile smooth in (x, y) (the dipole is a function of
// r^2 + z_r^2): its error falls at least as the square of the pixel size (faster for a smooth,
// decaying integrand), down to the part of R_dr beyond the image (50 mm from the centre: below
// 16 e^-15 = 5e-6 for the widest medium, sigma_tr = 0.30 / mm).
TEST(Munoz, AConstantIrradianceOnALargeFlatMediumConvergesToTheTotalDiffuseReflectance) {
    const auto m = media();
    const RadialFunction rd = RadialFunction::from_diffusion(m);
    const std::array<float, 3> e = {1, 0.5f, 2};
    std::array<double, 3> last{};
    for (int pass = 0; pass < 2; ++pass) {
        const int size = pass == 0 ? 101 : 201;
        const double pixel = 100.0 / size;
        MunozView v = empty_view(size, size, pixel, 0);
        for (size_t i = 0; i < v.front_z.size(); ++i) {
            v.front_z[i] = 50;
            for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = e[c];
        }
        const MunozResult r = munoz_exitance(v, rd, MunozOptions{});
        const size_t centre = static_cast<size_t>(size / 2) * size + size / 2;
        for (int c = 0; c < 3; ++c) {
            const double expected = e[c] * m[c]->total_rd();
            const double err = std::fabs(r.exitance[c][centre] - expected) / expected;
            std::printf("pixel %.3f mm, channel %d: M %.6g, E R_dr %.6g, relative error %.2g\n",
                        pixel, c, r.exitance[c][centre], expected, err);
            if (pass == 1) {
                // Halving the pixel divides the error by 4 or more, until the truncation.
                EXPECT_TRUE(err < 0.3 * last[c] || err < 1e-5) << c << ": " << err;
            }
            last[c] = err;
            // The kernel averaged over each pixel: the coarse pixels' error mostly gone.
            MunozOptions avg;
            avg.kernel = MunozKernel::pixel_average;
            const double ea =
                std::fabs(munoz_exitance(v, rd, avg).exitance[c][centre] - expected) / expected;
            std::printf("  averaged over the pixel: relative error %.2g\n", ea);
            // Within 0.3 % at both sizes (beyond 4 pixels the kernel is point-sampled again: a
            // midpoint rule, second order in the pixel), far below the point kernel's error at
            // the coarse pixels.
            EXPECT_LT(ea, 3e-3) << c;
            if (pass == 0) {
                EXPECT_LT(ea, 0.2 * err) << c;
            }
        }
    }
}

// What the paper's split costs [Munoz11 §4.2: "equally distributed between the corresponding
// pixels of the two closest layers (half of the irradiance to each of them)"]: a flat medium
// under constant light with two layers 60 mm apart (two dark patches set the depth range) keeps
// half its light wherever it lies, the other half reaching it only through the kernel across
// 60 mm (nothing); split=linear keeps it all on a layer and (1 - s)^2 + s^2 of it at s between
// them; split=nearest (ours) keeps it all. Where the layers are far apart against the mean free
// path, the equal split halves the exitance; the point-sampled kernels' overestimate at coarse
// pixels can hide that.
TEST(Munoz, TheEqualSplitHalvesTheLightOfAMediumBetweenFarLayers) {
    const auto m = media();
    const RadialFunction rd = RadialFunction::from_diffusion(m);
    const int size = 201;
    const double pixel = 100.0 / size;
    const size_t centre = static_cast<size_t>(size / 2) * size + size / 2;
    for (const double z : {20.0, 35.0, 50.0}) {
        MunozView v = empty_view(size, size, pixel, 0);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const size_t i = static_cast<size_t>(y) * size + x;
                const bool patch = x < 2 && y < 2;  // dark, at depth 20 and 80
                v.front_z[i] = static_cast<float>(patch ? (x == 0 ? 20.0 : 80.0) : z);
                for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = patch ? 0.0f : 1.0f;
            }
        for (const MunozSplit split :
             {MunozSplit::equal, MunozSplit::linear, MunozSplit::nearest}) {
            MunozOptions o;
            o.layers = 2;
            o.kernel = MunozKernel::pixel_average;
            o.split = split;
            const MunozResult r = munoz_exitance(v, rd, o);
            const double s = (z - 20.0) / 60.0;
            const double kept = split == MunozSplit::equal    ? 0.5
                                : split == MunozSplit::linear ? (1 - s) * (1 - s) + s * s
                                                              : 1.0;
            for (int c = 0; c < 3; ++c) {
                const double ratio = r.exitance[c][centre] / m[c]->total_rd();
                std::printf(
                    "  z %.0f mm, %s split, channel %d: M / (E R_dr) %.4f (expected %.4f)\n", z,
                    split_name(split), c, ratio, kept);
                EXPECT_NEAR(ratio, kept, 5e-3) << z << " " << c;
            }
        }
    }
}

TEST(Munoz, TheThresholdDropsFarLayersAndDownsamplingKeepsThePower) {
    const RadialFunction rd = RadialFunction::from_diffusion(media());
    MunozView v = empty_view(40, 40, 0.25, 0);
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
            const size_t i = static_cast<size_t>(y) * 40 + x;
            v.front_z[i] = static_cast<float>(100 + 0.2 * x);  // a slanted face, 8 mm deep
            v.back_z[i] = 120;
            for (int c = 0; c < 3; ++c) {
                v.front_irradiance[c][i] = 1;
                v.back_irradiance[c][i] = 0.5;
            }
        }
    // Layers 0-3 hold the front (100-107.8 mm), 6-7 the back (120 mm): 6 sources per target.
    const std::int64_t pairs = 3 * 8 * 6;
    MunozOptions o;
    o.layers = 8;
    o.skip_invisible = false;
    std::int64_t last = -1;
    for (double t : {0.0, 1e-3, 0.05, 0.9}) {
        o.threshold = t;
        const MunozResult r = munoz_exitance(v, rd, o);
        std::printf("t %.3g: %lld convolutions, %lld skipped, %.3f s\n", t,
                    static_cast<long long>(r.stats.convolutions),
                    static_cast<long long>(r.stats.skipped_threshold), r.stats.seconds);
        EXPECT_EQ(r.stats.convolutions + r.stats.skipped_threshold, pairs);
        if (t == 0) {
            EXPECT_EQ(r.stats.skipped_threshold, 0);
        }
        // The layer itself (e = 0) is never dropped: t R_d(0) < R_d(0).
        EXPECT_LE(r.stats.skipped_threshold, pairs - 3 * 6);
        EXPECT_GE(r.stats.skipped_threshold, last);
        last = r.stats.skipped_threshold;
    }
    EXPECT_GT(last, 0);
    // Downsampled by 2: the coarse maps hold the same power, so the exitance of a smooth input
    // stays close (the kernels' quadrature is coarser: a second-order change).
    o.threshold = 0;
    const MunozResult full = munoz_exitance(v, rd, o);
    o.downsample = 2;
    const MunozResult half = munoz_exitance(v, rd, o);
    double sf = 0, sh = 0;
    for (size_t i = 0; i < full.exitance[0].size(); ++i) {
        sf += full.exitance[0][i];
        sh += half.exitance[0][i];
    }
    std::printf("downsample 2: mean exitance %.5g against %.5g at full resolution\n", sh / 1600,
                sf / 1600);
    EXPECT_NEAR(sh / sf, 1.0, 0.05);
}

TEST(Munoz, BadInputIsRefusedNamingTheOption) {
    const RadialFunction rd = RadialFunction::from_diffusion(media());
    MunozView v = empty_view(4, 4, 0.1, 0);
    v.front_z[5] = 10;
    auto refused = [&](const MunozView& view, const MunozOptions& o, const char* word) {
        try {
            munoz_exitance(view, rd, o);
            ADD_FAILURE() << "accepted: " << word;
        } catch (const std::invalid_argument& ex) {
            EXPECT_NE(std::string(ex.what()).find(word), std::string::npos) << ex.what();
        }
    };
    MunozOptions o;
    o.layers = 0;
    refused(v, o, "layers");
    o.layers = 17;
    refused(v, o, "layers");
    o = {};
    o.threshold = -0.1;
    refused(v, o, "threshold");
    o.threshold = 1;
    refused(v, o, "threshold");
    o = {};
    o.downsample = 0;
    refused(v, o, "downsample");
    MunozView b = v;
    b.back_z[5] = 5;
    refused(b, {}, "back sample");
    b = v;
    b.back_z[6] = 5;
    refused(b, {}, "no front");
    b = v;
    b.front_irradiance[1][5] = -1;
    refused(b, {}, "irradiance");
    b = v;
    b.front_z.pop_back();
    refused(b, {}, "front_z");
    b = v;
    b.pixel_mm = 0;
    refused(b, {}, "pixel size");
    // Nothing in view: zeros, no error.
    const MunozResult none = munoz_exitance(empty_view(3, 3, 0.1, 0), rd, {});
    EXPECT_EQ(none.exitance[0], std::vector<float>(9, 0.0f));
}

// The wholemilk scene's frame at w x h with a cheap pass 1, its one medium material m, an
// analytic profile for it (R_sp per channel set) and the FrameMaterial the composite reads.
struct SmallFrame {
    Scene scene;
    realtime::FrameOptions fo;
    realtime::RasterizedFrame frame;
    realtime::LitFrame lit;
    int m = -1;
    RadialProfile prof;
    std::map<int, RadialProfile> profiles;
    std::map<int, realtime::FrameMaterial> materials;

    SmallFrame(int w, int h)
        : scene(read_scene(testing::source_path("experiments/scenes/wholemilk.toml"))) {
        fo.width = w;
        fo.height = h;
        fo.lighting.light_samples = 1;
        fo.lighting.environment_samples = 4;
        fo.lighting.shadow_map_size = 256;
        frame = realtime::rasterize_frame(scene, fo);
        lit = realtime::light_frame(scene, frame, fo);
        if (frame.media_in_view.size() != 1u) return;
        m = frame.media_in_view[0];
        prof = testing::analytic_profile(0.02, 400, 4.0);
        prof.rsp = {0.02, 0.03, 0.04};
        profiles = {{m, prof}};
        materials = {
            {m, realtime::make_frame_material(prof, approx::parse_model("svd:rank=1"), 17, false)}};
    }
};

// In a real-time frame (experiments/runner/surface_frames.h): the far sides seen behind the near
// ones, and the subsurface layer equal to the exit weight times the layered exitance of the
// G-buffer's near samples and the back frame's far ones, computed here from the two G-buffers
// (the units: R_d per entered irradiance, the albedo the composite applies cancelled).
TEST(MunozFrame, TheSubsurfaceLayerIsTheExitWeightTimesTheLayeredExitance) {
    const SmallFrame sf(64, 48);
    ASSERT_EQ(sf.frame.media_in_view.size(), 1u);
    const realtime::LitFrame back = runner::light_back_frame(sf.scene, sf.fo);
    MunozOptions mo;
    mo.layers = 4;
    const runner::MunozFrame mf = runner::render_munoz_frame(sf.scene, sf.frame, sf.lit, back,
                                                             sf.materials, sf.profiles, mo, sf.fo);
    EXPECT_GT(mf.stats.convolutions, 0);

    const realtime::GBuffer& fg = sf.lit.gbuffer;
    const realtime::GBuffer& bg = back.gbuffer;
    const size_t n = fg.view_z.size();
    MunozView v = empty_view(fg.width, fg.height, 0, 2 * sf.frame.camera.tan_half / fg.height);
    size_t medium = 0, with_back = 0;
    for (size_t i = 0; i < n; ++i) {
        if (fg.material[i] != sf.m) continue;
        ++medium;
        v.front_z[i] = static_cast<float>(fg.view_z[i] * sf.scene.unit_mm);
        for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = fg.irradiance[3 * i + c];
        if (bg.material[i] != sf.m) continue;
        ++with_back;
        EXPECT_GT(bg.view_z[i], fg.view_z[i]) << i;
        v.back_z[i] = static_cast<float>(bg.view_z[i] * sf.scene.unit_mm);
        for (int c = 0; c < 3; ++c) v.back_irradiance[c][i] = bg.irradiance[3 * i + c];
    }
    // A closed medium: every ray that enters it leaves it.
    EXPECT_GT(medium, 300u);
    EXPECT_GT(static_cast<double>(with_back), 0.98 * static_cast<double>(medium));
    const RadialFunction per_incident = RadialFunction::from_profile(sf.prof);
    const RadialFunction rd([&](double r) {
        auto x = per_incident(r);
        for (int c = 0; c < 3; ++c) x[c] /= 1 - sf.prof.rsp[c];
        return x;
    });
    const MunozResult r = munoz_exitance(v, rd, mo);
    const ImageLayer& sub = mf.frame.image.layer("subsurface");
    double worst = 0, peak = 0;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const double want = fg.material[i] == sf.m ? fg.exit_weight[i] * r.exitance[c][i] : 0.0;
            peak = std::max(peak, want);
            worst = std::max(worst, std::fabs(sub.pixels()[3 * i + c] - want));
        }
    EXPECT_GT(peak, 0);
    EXPECT_LT(worst, 1e-5 * peak);
}

// Jensen-Buhler in a real-time frame (experiments/runner/surface_frames.h): at a threshold of 0
// the subsurface layer is the exit weight times the brute-force sum over the cloud's points at
// each medium pixel's surface point (the camera ray at its view depth), with the points lit as
// pass 1 lights (realtime::boundary_irradiance, tested in test_lighting); a positive threshold
// stays within a few per cent of it; an analytic profile is integrated in the same frame.
TEST(JensenBuhlerFrame, TheSubsurfaceLayerIsTheExitWeightTimesTheBruteForceSum) {
    const SmallFrame sf(48, 36);
    ASSERT_EQ(sf.frame.media_in_view.size(), 1u);
    JensenBuhlerOptions jo = parse_jensen_buhler("density=1,threshold=0");
    const runner::JensenBuhlerCloud cloud =
        runner::build_jensen_buhler_cloud(sf.scene, sf.frame.media_in_view, jo, sf.fo, 1);
    ASSERT_EQ(cloud.trees.size(), 1u);
    const PointOctree& tree = cloud.trees.at(sf.m);
    EXPECT_EQ(cloud.points, tree.points().size());
    size_t lit_points = 0;
    for (const SurfacePoint& p : tree.points()) lit_points += p.irradiance[0] > 0;
    // Lit from above and around: more than a third of the sphere's points, not all of them.
    EXPECT_GT(3 * lit_points, tree.points().size());
    EXPECT_LT(lit_points, tree.points().size());

    const runner::JensenBuhlerFrame f0 = runner::render_jensen_buhler_frame(
        sf.scene, sf.frame, sf.lit, sf.materials, sf.profiles, cloud, jo, sf.fo);
    jo.max_solid_angle = 0.05;
    const runner::JensenBuhlerFrame f1 = runner::render_jensen_buhler_frame(
        sf.scene, sf.frame, sf.lit, sf.materials, sf.profiles, cloud, jo, sf.fo);
    EXPECT_EQ(f0.stats.clusters, 0u);
    EXPECT_GT(f1.stats.clusters, 0u);
    EXPECT_LT(f1.stats.points, f0.stats.points);

    const RadialFunction rd = runner::per_entered(sf.prof);
    const realtime::GBuffer& g = sf.lit.gbuffer;
    const realtime::RasterCamera cam =
        realtime::RasterCamera::from_scene(sf.scene.camera, g.width, g.height);
    const auto rays = cam.sample_rays(1);
    const ImageLayer& s0 = f0.frame.image.layer("subsurface");
    const ImageLayer& s1 = f1.frame.image.layer("subsurface");
    double worst = 0, worst1 = 0, peak = 0;
    size_t medium = 0;
    for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
            const size_t i = static_cast<size_t>(y * g.width + x);
            std::array<double, 3> want{};
            if (g.material[i] == sf.m) {
                ++medium;
                const Vec3 p =
                    (cam.position + rays.unnormalized(x, y) *
                                        static_cast<double>(static_cast<float>(g.view_z[i]))) *
                    sf.scene.unit_mm;
                want = tree.brute_force(rd, p);
                for (double& v : want) v *= g.exit_weight[i];
            }
            for (int c = 0; c < 3; ++c) {
                peak = std::max(peak, want[c]);
                worst = std::max(worst, std::fabs(s0.pixels()[3 * i + c] - want[c]));
                worst1 = std::max(worst1, std::fabs(s1.pixels()[3 * i + c] - want[c]));
            }
        }
    std::printf(
        "  [measured] %zu points (%zu sf.lit), %zu medium pixels: threshold 0 within %.2e of "
        "the peak, threshold 0.05 within %.2e\n",
        tree.points().size(), lit_points, medium, worst / peak, worst1 / peak);
    EXPECT_GT(medium, 200u);
    EXPECT_GT(peak, 0);
    EXPECT_LT(worst, 1e-5 * peak);
    EXPECT_LT(worst1, 0.05 * peak);

    // The dipole for the material's coefficients through the same cloud: finite, positive.
    jo.profile = "dipole";
    const runner::JensenBuhlerFrame fd = runner::render_jensen_buhler_frame(
        sf.scene, sf.frame, sf.lit, sf.materials, sf.profiles, cloud, jo, sf.fo);
    double sum = 0;
    for (float v : fd.frame.image.layer("subsurface").pixels()) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0);
}

TEST(MunozSpec, NamesVariantsAndRefusesBadOnes) {
    const MunozOptions o = parse_munoz("layers=8,t=0.001,downsample=2,split=linear,visible=all");
    EXPECT_EQ(o.layers, 8);
    EXPECT_EQ(o.threshold, 0.001);
    EXPECT_EQ(o.downsample, 2);
    EXPECT_EQ(o.split, MunozSplit::linear);
    EXPECT_FALSE(o.skip_invisible);
    EXPECT_EQ(parse_munoz(munoz_label(o)).layers, 8);
    EXPECT_EQ(munoz_label(parse_munoz("layers=4")),
              "layers=4,t=0,downsample=1,split=equal,visible=skip,kernel=point");
    EXPECT_EQ(parse_munoz("kernel=average").kernel, MunozKernel::pixel_average);
    EXPECT_EQ(parse_munoz("split=nearest").split, MunozSplit::nearest);
    EXPECT_EQ(munoz_label(parse_munoz("split=nearest")),
              "layers=4,t=0,downsample=1,split=nearest,visible=skip,kernel=point");
    for (const char* bad :
         {"layers=0", "layers=17", "layers=2.5", "t=-1", "t=1", "t=x", "downsample=9", "split=odd",
          "kernel=cell", "colour=red", "layers", "layers=4,layers=5"})
        EXPECT_THROW(parse_munoz(bad), std::invalid_argument) << bad;
}

}  // namespace
}  // namespace ssslab::approx
