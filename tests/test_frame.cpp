// The real-time frame (realtime/frame.h): the passes wired together, the composite against the
// G-buffer it is made of, the SSS pass left out where it has nothing to do, kernels only for the
// media in view, the separable pass against the 2D reference on a separable kernel, determinism,
// and `ssslab raster`.
#include "approx/model_spec.h"
#include "core/build_info.h"
#include "core/film_image.h"
#include "core/image_compare.h"
#include "core/profile.h"
#include "core/scene.h"
#include "realtime/frame.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <filesystem>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using realtime::FrameMaterial;
using realtime::FrameOptions;
using realtime::SssMethod;

// A medium sphere on a diffuse floor under a sphere light and a dim environment, in mm.
const std::string kScene = testing::ball_scene(30, 48, 40);

Scene scene_of(const std::string& text) {
    return parse_scene(text, "ball.toml", ".");
}

// A radial profile R(r) = A exp(-r^2 / (2 s^2)) per channel (widths s_mm), on `nr` bins of
// `dr_mm`: a 2D Gaussian, which is separable, so a rank-1 SVD of it is exact.
RadialProfile gaussian_profile(std::array<double, 3> s_mm, double dr_mm, int nr) {
    RadialProfile p;
    p.name = "gauss";
    p.dr_cm = dr_mm / 10;
    p.nr = nr;
    for (int c = 0; c < 3; ++c) {
        const double s = s_mm[static_cast<size_t>(c)] / 10;  // cm
        for (int i = 0; i < nr; ++i) {
            const double r = (i + 0.5) * p.dr_cm;
            p.rd_per_cm2[static_cast<size_t>(c)].push_back(0.5 * std::exp(-r * r / (2 * s * s)) /
                                                           (2 * M_PI * s * s));
            p.se_per_cm2[static_cast<size_t>(c)].push_back(0);
        }
        p.rd_total[static_cast<size_t>(c)] = 0.5;
        p.rsp[static_cast<size_t>(c)] = 0.02;
    }
    return p;
}

std::map<int, FrameMaterial> materials_for(const Scene& s, const realtime::RasterizedFrame& f,
                                           const RadialProfile& p, const std::string& model,
                                           int taps, bool exact) {
    std::map<int, FrameMaterial> m;
    for (int i : f.media_in_view)
        m[i] = realtime::make_frame_material(p, approx::parse_model(model), taps, exact);
    (void)s;
    return m;
}

// Small shadow maps and few light samples: the tests are about the wiring, not the lighting.
FrameOptions small() {
    FrameOptions o;
    o.lighting.shadow_map_size = 256;
    o.lighting.light_samples = 4;
    o.lighting.environment_samples = 8;
    return o;
}

const float* layer(const LayeredImage& im, const std::string& name) {
    return im.layer(name).pixels().data();
}

TEST(Frame, WithoutMediaTheSssPassDoesNotRun) {
    std::string text = kScene;
    text.replace(text.find("preset = \"Skin1\"\nroughness = 0.3"),
                 std::string("preset = \"Skin1\"\nroughness = 0.3").size(),
                 "type = \"diffuse\"\nalbedo = [0.8, 0.2, 0.1]");
    const Scene s = scene_of(text);
    FrameOptions o = small();
    const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
    EXPECT_TRUE(f.media_in_view.empty());
    EXPECT_EQ(f.lit_in_view.size(), 2u);
    const realtime::FrameResult r = realtime::render_frame(s, f, {}, o);
    for (const auto& p : r.times) {
        if (p.pass == "sss") {
            EXPECT_EQ(p.ms, 0.0);
        }
    }
    const size_t n = 3u * 48u * 40u;
    double lit = 0;
    for (size_t i = 0; i < n; ++i) {
        EXPECT_EQ(layer(r.image, "subsurface")[i], 0.0f);
        EXPECT_FLOAT_EQ(layer(r.image, "radiance")[i],
                        layer(r.image, "surface")[i] + layer(r.image, "specular")[i]);
        lit += layer(r.image, "radiance")[i];
    }
    EXPECT_GT(lit, 0.0);
}

// The composite holds the G-buffer's terms together as the header says: with a kernel far
// narrower than a pixel the pass is the identity, so subsurface = exit_weight (albedo E +
// translucency) per sample, computed here from realtime::shade's own G-buffer.
TEST(Frame, CompositeIsTheGBufferTermsAndANarrowKernelIsTheIdentity) {
    const Scene s = scene_of(kScene);
    FrameOptions o = small();
    const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
    ASSERT_EQ(f.media_in_view, std::vector<int>{0});
    const RadialProfile p = gaussian_profile({1e-4, 1e-4, 1e-4}, 1e-5, 200);  // 0.1 um wide
    // L1-normalised, so that the pass's weights sum to 1 (the rank-1 SVD of this discrete,
    // nearly separable kernel alone holds 99.98 % of it).
    const auto mats = materials_for(s, f, p, "svd:rank=1,l1", 17, false);
    const realtime::FrameResult sep = realtime::render_frame(s, f, mats, o);
    o.method = SssMethod::kNone;
    const realtime::FrameResult none = realtime::render_frame(s, f, mats, o);
    const realtime::GBuffer g = realtime::shade(s, f.camera, f.raster, o.lighting);
    const std::array<double, 3> a = mats.at(0).albedo;
    size_t medium = 0;
    for (size_t i = 0; i < g.samples(); ++i)
        for (size_t c = 0; c < 3; ++c) {
            const double expect = g.material[i] == 0
                                      ? g.exit_weight[i] * (a[c] * g.irradiance[3 * i + c] +
                                                            g.translucency[3 * i + c])
                                      : 0.0;
            EXPECT_NEAR(layer(none.image, "subsurface")[3 * i + c], expect, 1e-6 * (1 + expect));
            EXPECT_NEAR(layer(sep.image, "subsurface")[3 * i + c],
                        layer(none.image, "subsurface")[3 * i + c], 1e-6 * (1 + expect));
            medium += g.material[i] == 0 && c == 0;
        }
    EXPECT_GT(medium, 50u);
    // The albedo: the grid's share of R_d over 1 - R_sp (here all of 0.5 within the grid).
    EXPECT_NEAR(a[0], 0.5 / 0.98, 1e-3);
}

// A medium slab filling the view from above, lit by a small sphere light just beside the view:
// a peaked irradiance, and a medium in every pixel of the kernels' footprints.
constexpr const char* kSlab = R"(
[scene]
name = "slab"
[camera]
position = [0, 40, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 30
width = 64
height = 56
[[lights]]
type = "sphere"
position = [13, 1.5, 0]
radius = 0.5
radiance = [3000, 3000, 3000]
[[materials]]
name = "slab"
preset = "Skin1"
roughness = 0.3
[[shapes]]
type = "box"
size = [200, 20, 200]
translate = [0, -10, 0]
material = "slab"
)";

// On a Gaussian profile, which is separable, the separable pass with many taps and the exact 2D
// reference agree up to the taps' sampling and the pass's linear interpolation; a wrong kernel
// scale in either would not. (Where the footprint reaches pixels without a medium the two
// differ by design: between its passes the separable pass leaves those pixels unblurred.)
TEST(Frame, SeparablePassMatchesTheReferenceOnASeparableKernel) {
    const Scene s = scene_of(kSlab);
    FrameOptions o = small();
    o.width = 64;
    o.height = 56;
    o.sss.mode = realtime::SssEdgeMode::kNone;
    o.reference.method = realtime::SssReferenceOptions::Method::kExact;
    const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
    // 3 to 6 pixels wide (sigma): the separable pass interpolates linearly between texels (a
    // tent of variance 1/6 px^2 on top of the kernel's), the reference integrates boxes exactly.
    const RadialProfile p = gaussian_profile({2.4, 1.8, 1.2}, 0.02, 600);
    const auto mats = materials_for(s, f, p, "svd:rank=1", 201, true);
    const realtime::FrameResult sep = realtime::render_frame(s, f, mats, o);
    o.method = SssMethod::kReference;
    const realtime::FrameResult ref = realtime::render_frame(s, f, mats, o);
    o.method = SssMethod::kNone;
    const realtime::FrameResult none = realtime::render_frame(s, f, mats, o);
    double d2 = 0, r2 = 0, blur2 = 0;
    const ImageLayer& mat = ref.image.layer("material");
    for (int y = 0; y < 56; ++y)
        for (int x = 0; x < 64; ++x) {
            ASSERT_EQ(mat.at(x, y), 0) << "the slab fills the view";
            for (int c = 0; c < 3; ++c) {
                const double a = sep.image.layer("subsurface").at(x, y, c);
                const double b = ref.image.layer("subsurface").at(x, y, c);
                const double n = none.image.layer("subsurface").at(x, y, c);
                d2 += (a - b) * (a - b);
                r2 += b * b;
                blur2 += (n - b) * (n - b);
            }
        }
    ASSERT_GT(r2, 0);
    std::printf("separable vs reference: %.3g %% RMS; no pass vs reference: %.3g %%\n",
                100 * std::sqrt(d2 / r2), 100 * std::sqrt(blur2 / r2));
    EXPECT_LT(std::sqrt(d2 / r2), 0.005);
    // The pass does something here: without it the difference is far larger.
    EXPECT_GT(std::sqrt(blur2 / r2), 5 * std::sqrt(d2 / r2));
}

TEST(Frame, KernelsOnlyForMediaInViewAndAMissingOneIsNamed) {
    std::string text = kScene;
    // A second medium behind the camera.
    text += R"(
[[materials]]
name = "hidden"
preset = "Marble"
roughness = 0.3
[[shapes]]
type = "sphere"
radius = 2
subdivisions = 2
translate = [0, 4, 80]
material = "hidden"
)";
    const Scene s = scene_of(text);
    FrameOptions o = small();
    const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
    EXPECT_EQ(f.media_in_view, std::vector<int>{0});
    try {
        realtime::render_frame(s, f, {}, o);
        FAIL() << "no kernel for an visible medium must be refused";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("jelly"), std::string::npos) << e.what();
    }
}

TEST(Frame, BitIdenticalForOneAndTwoThreadsWithSupersampling) {
    const Scene s = scene_of(kScene);
    FrameOptions o = small();
    o.raster.supersample = 2;
    o.sss.jitter = 0.33;
    const RadialProfile p = gaussian_profile({0.8, 0.5, 0.3}, 0.01, 400);
    LayeredImage im[2] = {LayeredImage(1, 1), LayeredImage(1, 1)};
    for (int t = 1; t <= 2; ++t) {
        tbb::task_arena arena(t);
        arena.execute([&] {
            const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
            im[t - 1] =
                realtime::render_frame(s, f, materials_for(s, f, p, "preintegration", 17, false), o)
                    .image;
        });
    }
    ASSERT_EQ(im[0].layers().size(), im[1].layers().size());
    for (const ImageLayer& l : im[0].layers()) {
        const ImageLayer& m = im[1].layer(l.name());
        for (size_t i = 0; i < l.pixels().size(); ++i)
            ASSERT_EQ(l.pixels()[i], m.pixels()[i]) << l.name() << " " << i;
    }
    // Volpath's layer names, plus the real-time renderer's own.
    for (const char* n : {"radiance", "subsurface", "specular", "depth", "normal", "irradiance",
                          "material", "surface", "translucency"})
        EXPECT_TRUE(im[0].has_layer(n)) << n;
}

TEST(RasterCommand, WritesTheLayersThePassTimesAndRefusesBadInput) {
    testing::TempDir dir;
    const fs::path scene = dir.write("ball.toml", kScene);
    const auto r = testing::run_ssslab(
        {"raster", scene.string(), "--photons", "2000", "--cache", (dir / "res").string(), "--out",
         (dir / "ball.exr").string(), "--no-translucency"},
        dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* pass : {"raster", "shadow maps", "lighting", "sss", "composite", "frame"})
        EXPECT_NE(r.out.find(pass), std::string::npos) << pass << "\n" << r.out;
    const LayeredImage im = read_exr((dir / "ball.exr").string());
    for (const char* n :
         {"radiance", "subsurface", "specular", "depth", "normal", "irradiance", "material"})
        EXPECT_TRUE(im.has_layer(n)) << n;
    EXPECT_EQ(im.metadata().at("ssslab.model"), "svd:rank=1");
    EXPECT_TRUE(fs::exists(dir / "ball.png"));
    EXPECT_TRUE(fs::exists(dir / "ball.exr.toml"));
    // The profile is cached: a second run with another model computes no MCML run.
    const auto again = testing::run_ssslab(
        {"raster", scene.string(), "--photons", "2000", "--cache", (dir / "res").string(), "--out",
         (dir / "b2.exr").string(), "--no-translucency", "--model", "deon:n=2", "--shadow-map",
         "256", "--env-samples", "8"},
        dir.path());
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_NE(again.out.find("0 MCML runs computed"), std::string::npos) << again.out;
    // The header names the kernel that ran: with --sss reference the exact 2D one, not --model.
    const auto ref = testing::run_ssslab(
        {"raster", scene.string(), "--photons", "2000", "--cache", (dir / "res").string(), "--out",
         (dir / "b3.exr").string(), "--no-translucency", "--sss", "reference", "--shadow-map",
         "256", "--env-samples", "8"},
        dir.path());
    ASSERT_EQ(ref.exit_code, 0) << ref.err;
    EXPECT_EQ(read_exr((dir / "b3.exr").string()).metadata().at("ssslab.model"), "reference:2d");

    // Bad input: exit 2, a message naming the option, no output.
    const auto bad = testing::run_ssslab(
        {"raster", scene.string(), "--model", "svd:rnak=2", "--out", (dir / "x.exr").string()},
        dir.path());
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("--model"), std::string::npos) << bad.err;
    const auto fit = testing::run_ssslab(
        {"raster", scene.string(), "--model", "manual:fit=edge", "--out", (dir / "x.exr").string()},
        dir.path());
    EXPECT_EQ(fit.exit_code, 2);
    EXPECT_NE(fit.err.find("kernel study"), std::string::npos) << fit.err;
    EXPECT_FALSE(fs::exists(dir / "x.exr"));
    EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(RasterCommand, TheGlBackendDrawsTheSameImage) {
    testing::TempDir dir;
    const fs::path scene = dir.write("ball.toml", kScene);
    const std::vector<std::string> common = {
        "--photons", "2000", "--cache", (dir / "res").string(), "--shadow-map", "512"};
    auto args = [&](std::vector<std::string> a) {
        a.insert(a.begin(), {"raster", scene.string()});
        a.insert(a.end(), common.begin(), common.end());
        return a;
    };
    // Bad input first (exit 2, the option named, nothing written), in every build.
    const auto platform = testing::run_ssslab(
        args({"--platform", "egl", "--out", (dir / "x.exr").string()}), dir.path());
    EXPECT_EQ(platform.exit_code, 2);
    EXPECT_NE(platform.err.find("--platform"), std::string::npos) << platform.err;
    EXPECT_FALSE(fs::exists(dir / "x.exr"));
    if (!SSSLAB_HAVE_GL) GTEST_SKIP() << "built without the GL twin";

    const auto sw = testing::run_ssslab(args({"--out", (dir / "sw.exr").string()}), dir.path());
    ASSERT_EQ(sw.exit_code, 0) << sw.err;
    const auto gl = testing::run_ssslab(
        args({"--backend", "gl", "--out", (dir / "gl.exr").string()}), dir.path());
    if (gl.exit_code != 0 && gl.err.find("no OpenGL context") != std::string::npos)
        GTEST_SKIP() << gl.err;
    ASSERT_EQ(gl.exit_code, 0) << gl.err;
    for (const char* what : {"backend gl", "sss_gpu", "lighting_draw", "shadow maps", "frame"})
        EXPECT_NE(gl.out.find(what), std::string::npos) << what << "\n" << gl.out;
    EXPECT_NE(testing::read_text(dir / "gl.exr.toml").find("backend = 'gl'"), std::string::npos);
    // Every layer within 45 dB PSNR of the software image (peak: the software layer's).
    const LayeredImage a = read_exr((dir / "gl.exr").string()),
                       b = read_exr((dir / "sw.exr").string());
    for (const ImageLayer& l : b.layers()) {
        ASSERT_TRUE(a.has_layer(l.name())) << l.name();
        EXPECT_GT(psnr(a.layer(l.name()).pixels(), l.pixels()), 45.0) << l.name();
    }
    // Supersampled (2 x 2 samples a pixel) on both backends: the same.
    const auto sw2 = testing::run_ssslab(
        args({"--supersample", "2", "--out", (dir / "sw2.exr").string()}), dir.path());
    ASSERT_EQ(sw2.exit_code, 0) << sw2.err;
    const auto gl2 = testing::run_ssslab(
        args({"--backend", "gl", "--supersample", "2", "--out", (dir / "gl2.exr").string()}),
        dir.path());
    ASSERT_EQ(gl2.exit_code, 0) << gl2.err;
    const LayeredImage a2 = read_exr((dir / "gl2.exr").string()),
                       b2 = read_exr((dir / "sw2.exr").string());
    for (const ImageLayer& l : b2.layers()) {
        ASSERT_TRUE(a2.has_layer(l.name())) << l.name();
        EXPECT_GT(psnr(a2.layer(l.name()).pixels(), l.pixels()), 45.0) << l.name();
    }
}

}  // namespace
}  // namespace ssslab

namespace ssslab {
namespace {

using realtime::SssEdgeMode;

double layer_sum(const LayeredImage& im, const std::string& name, bool& finite, bool& nonneg) {
    double s = 0;
    for (float v : im.layer(name).pixels()) {
        finite = finite && std::isfinite(v);
        nonneg = nonneg && v >= 0;
        s += v;
    }
    return s;
}

// Stiff views: the slab seen at grazing incidence (the kernel's footprint foreshortened to a
// sliver, depth changing fast along it) and the ball far away, a medium seen through nothing but
// its silhouette (a few pixels, every neighbour another surface). The pass stays finite and
// non-negative and keeps the subsurface light within what the no-pass frame has.
TEST(FrameStiff, GrazingViewAndASilhouetteOnly) {
    std::string grazing = kSlab;
    grazing.replace(grazing.find("position = [0, 40, 0]"), 21, "position = [0, 0.8, 30]");
    grazing.replace(grazing.find("up = [0, 0, -1]"), 15, "up = [0, 1, 0]");
    std::string far = kScene;
    far.replace(far.find("position = [0, 8, 40]"), 21, "position = [0, 8, 300]");
    const RadialProfile p = gaussian_profile({2.4, 1.8, 1.2}, 0.02, 600);
    for (const std::string* text : {&grazing, &far}) {
        SCOPED_TRACE(text == &grazing ? "grazing" : "silhouette");
        const Scene s = scene_of(*text);
        for (SssEdgeMode mode :
             {SssEdgeMode::kNone, SssEdgeMode::kFollowSurface, SssEdgeMode::kReject}) {
            FrameOptions o = small();
            o.sss.mode = mode;
            const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
            ASSERT_EQ(f.media_in_view.size(), 1u);
            if (text == &far) {  // a silhouette: a few pixels, each of them partly the floor
                const auto n = std::count(f.raster.shape.begin(), f.raster.shape.end(), 0);
                EXPECT_GT(n, 0);
                EXPECT_LT(n, 12);
            }
            const auto mats = materials_for(s, f, p, "svd:rank=1,l1", 17, true);
            const realtime::LitFrame lit = realtime::light_frame(s, f, o);
            const realtime::FrameResult sep = realtime::render_frame(s, f, lit, mats, o);
            o.method = SssMethod::kReference;
            const realtime::FrameResult ref = realtime::render_frame(s, f, lit, mats, o);
            o.method = SssMethod::kNone;
            const realtime::FrameResult none = realtime::render_frame(s, f, lit, mats, o);
            bool finite = true, nonneg = true;
            const double a = layer_sum(sep.image, "subsurface", finite, nonneg);
            const double b = layer_sum(ref.image, "subsurface", finite, nonneg);
            const double c = layer_sum(none.image, "subsurface", finite, nonneg);
            EXPECT_TRUE(finite);
            EXPECT_TRUE(nonneg);
            ASSERT_GT(c, 0);
            // Normalised kernels and clamp-to-edge: light is moved, not made. (With mode none
            // some leaves the medium's pixels, which then show none of it.)
            EXPECT_LE(a, 1.02 * c);
            EXPECT_LE(b, 1.02 * c);
            if (mode != SssEdgeMode::kNone) {
                EXPECT_GT(a, 0.5 * c);
                EXPECT_GT(b, 0.5 * c);
            }
        }
    }
}

// A depth step between two media: a Skin1 box in front of a Marble slab. Where the pass follows
// the surface or rejects across the step, the slab's pixels do not depend on what the box is:
// the same with the box a diffuse surface of the same shape (same shadows), to the last bit.
// With no edge handling the box's light bleeds into them.
TEST(FrameStiff, ADepthStepBetweenTwoMediaDoesNotBleed) {
    const std::string base = R"(
[scene]
name = "step"
[camera]
position = [0, 40, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 30
width = 64
height = 56
[[lights]]
type = "directional"
direction = [0.3, 1, 0.2]
irradiance = [3, 3, 3]
angular_radius_deg = 2
[[materials]]
name = "slab"
preset = "Marble"
roughness = 0.3
[[materials]]
name = "box"
BOX
[[shapes]]
type = "box"
size = [200, 20, 200]
translate = [0, -10, 0]
material = "slab"
[[shapes]]
type = "box"
size = [8, 6, 30]
translate = [-2, 8, 0]
material = "box"
)";
    auto with = [&](const std::string& box) {
        std::string t = base;
        t.replace(t.find("BOX"), 3, box);
        return scene_of(t);
    };
    const Scene media = with("preset = \"Skin1\"\nroughness = 0.3");
    const Scene diffuse = with("type = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]");
    const RadialProfile p = gaussian_profile({2.4, 1.8, 1.2}, 0.02, 600);
    for (SssEdgeMode mode :
         {SssEdgeMode::kNone, SssEdgeMode::kFollowSurface, SssEdgeMode::kReject}) {
        FrameOptions o = small();
        o.sss.mode = mode;
        o.sss.follow_strength = realtime::default_follow_strength(media);
        o.sss.reject_depth = realtime::default_reject_depth(media);
        std::array<LayeredImage, 2> im = {LayeredImage(1, 1), LayeredImage(1, 1)};
        for (int k = 0; k < 2; ++k) {
            const Scene& s = k == 0 ? media : diffuse;
            const realtime::RasterizedFrame f = realtime::rasterize_frame(s, o);
            im[static_cast<size_t>(k)] =
                realtime::render_frame(s, f, materials_for(s, f, p, "svd:rank=1,l1", 17, false), o)
                    .image;
        }
        double diff = 0, total = 0;
        int slab = 0;
        const ImageLayer& mat = im[1].layer("material");
        for (int y = 0; y < 56; ++y)
            for (int x = 0; x < 64; ++x) {
                if (mat.at(x, y) != 0) continue;  // the slab's pixels
                ++slab;
                for (int c = 0; c < 3; ++c) {
                    const double a = im[0].layer("subsurface").at(x, y, c);
                    const double b = im[1].layer("subsurface").at(x, y, c);
                    diff += std::abs(a - b);
                    total += b;
                }
            }
        ASSERT_GT(slab, 1000);
        std::printf("depth step, mode %d: the box's light in the slab's pixels %.3g %%\n",
                    static_cast<int>(mode), 100 * diff / total);
        if (mode == SssEdgeMode::kNone)
            EXPECT_GT(diff, 1e-3 * total);
        else
            EXPECT_EQ(diff, 0.0);
    }
}

}  // namespace
}  // namespace ssslab
