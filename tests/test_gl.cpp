// The GL twin of the real-time renderer (realtime/gl, issue 15): headless contexts through OSMesa
// and EGL, and the separable SSS pass in GLSL held to the CPU pass (realtime/sss_pass.h) on
// identical inputs, every edge mode with and without jitter and rotation, two materials (one of
// SVD rank 2, signed terms), a depth step, pixels without medium, kernels narrower than a pixel
// and wider than the image. Tests skip (with the reason) where no context can be made.
#include "approx/model_spec.h"
#include "approx/models.h"
#include "core/image_compare.h"
#include "core/scene.h"
#include "realtime/gl/context.h"
#include "realtime/gl/frame_gl.h"
#include "realtime/gl/lighting_gl.h"
#include "realtime/gl/raster_gl.h"
#include "realtime/gl/sss_pass_gl.h"
#include "realtime/lighting.h"
#include "realtime/sss_pass.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ssslab {
namespace {

using approx::Kernel2D;
using approx::ModelResult;
using realtime::SssEdgeMode;
using realtime::SssGBuffer;
using realtime::SssMaterialKernel;
using realtime::SssParams;
using realtime::gl::GlContext;
using realtime::gl::GlPlatform;
using testing::edge_mode_name;
using testing::flat_gbuffer;
using testing::kSssEdgeModes;
using testing::random_image;
using testing::skin_kernels;
using testing::sss_camera;

// One context per platform for the whole test program (made once: llvmpipe's start-up is not
// free).
GlContext* context(GlPlatform platform, std::string& why) {
    static std::map<GlPlatform, std::pair<std::unique_ptr<GlContext>, std::string>> made;
    auto it = made.find(platform);
    if (it == made.end()) {
        std::string reason;
        auto c = realtime::gl::try_gl_context(platform, reason);
        it = made.emplace(platform, std::make_pair(std::move(c), reason)).first;
    }
    why = it->second.second;
    if (it->second.first) it->second.first->make_current();
    return it->second.first.get();
}

// The tests of the pass run on every platform of the build that gives a context.
class GlSssPassTest : public ::testing::TestWithParam<std::string> {
  protected:
    GlContext* ctx = nullptr;
    void SetUp() override {
        std::string why;
        ctx = context(realtime::gl::parse_gl_platform(GetParam()), why);
        if (!ctx) GTEST_SKIP() << "no OpenGL context on " << GetParam() << ": " << why;
    }
};
INSTANTIATE_TEST_SUITE_P(Platforms, GlSssPassTest,
                         ::testing::ValuesIn(realtime::gl::gl_platforms_built()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

TEST(Gl, ContextsOfEveryPlatformBuilt) {
    const std::vector<std::string> built = realtime::gl::gl_platforms_built();
    ASSERT_FALSE(built.empty());
    int made = 0;
    for (const std::string& name : built) {
        std::string why;
        auto c = realtime::gl::try_gl_context(realtime::gl::parse_gl_platform(name), why);
        if (!c) {
            std::printf("%s: no context (%s)\n", name.c_str(), why.c_str());
            continue;
        }
        ++made;
        std::printf("%s: %s, %s, OpenGL %s\n", name.c_str(), c->platform().c_str(),
                    c->renderer().c_str(), c->version().c_str());
        EXPECT_NE(c->version().find("Core"), std::string::npos) << c->version();
    }
    if (made == 0) GTEST_SKIP() << "no platform gave a context";
    EXPECT_THROW(realtime::gl::parse_gl_platform("glx"), std::invalid_argument);
}

// Two materials (pre-integration, 17 taps; SVD rank 2 with signed terms, 11 taps), a random
// irradiance over a depth ramp with a 20-unit step, a disc without medium.
struct Case {
    std::vector<SssMaterialKernel> mats;
    SssGBuffer g;
};
Case two_materials(int w, int h) {
    const std::vector<Kernel2D> k = skin_kernels();
    std::array<ModelResult, 3> pre, svd;
    for (int c = 0; c < 3; ++c) {
        pre[c] = approx::preintegration(k[c]);
        svd[c] = approx::svd_rank_n(k[c], 2, false);
    }
    Case d;
    d.mats = {realtime::make_material_kernel({&pre[0].kernel, &pre[1].kernel, &pre[2].kernel}, 17),
              realtime::make_material_kernel({&svd[0].kernel, &svd[1].kernel, &svd[2].kernel}, 11)};
    d.g = flat_gbuffer(random_image(w, h, 1.0, 13), 1.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            d.g.view_z[i] = static_cast<float>(30 + 0.3 * x + (x > w * 0.6 ? 20 : 0));
            const int dx = x - w / 2, dy = y - h / 2;
            d.g.material[i] = dx * dx + dy * dy < (h / 5) * (h / 5) ? -1 : (y < h / 2 ? 0 : 1);
        }
    return d;
}

// The CPU pass on inputs perturbed at rounding level: every irradiance by up to 1.2e-7 relative
// and the kernel scale by 2.4e-7 (the GL pass computes tap positions in float, the CPU pass in
// double). How far that moves the CPU's own result is what float arithmetic can promise.
std::vector<float> perturbed_cpu(const SssGBuffer& g, const std::vector<SssMaterialKernel>& mats,
                                 SssParams p) {
    SssGBuffer q = g;
    uint32_t st = 1;
    for (float& v : q.irradiance) {
        st = st * 1664525u + 1013904223u;
        v *= 1.0f + ((st >> 8) * (1.0f / 16777216.0f) - 0.5f) * 2.4e-7f;
    }
    p.unit_mm *= 1 + 2.4e-7;
    return realtime::sss_pass(q, mats, p);
}

// The values of the pixels of material m.
std::vector<float> of_material(const Case& c, const std::vector<float>& v, int m) {
    std::vector<float> r;
    for (size_t i = 0; i < c.g.pixels(); ++i)
        if (c.g.material[i] == m)
            for (int ch = 0; ch < 3; ++ch) r.push_back(v[3 * i + ch]);
    return r;
}

TEST_P(GlSssPassTest, EqualsTheCpuPassOnIdenticalInputs) {
    realtime::gl::GlSssPass pass(*ctx);
    const Case c = two_materials(97, 61);
    for (SssEdgeMode mode : kSssEdgeModes)
        for (double jitter : {0.0, 0.33})
            for (bool rotate : {false, true}) {
                SssParams p = sss_camera(c.g.width, c.g.height, mode);
                p.jitter = jitter;
                p.seed = 7;
                p.rotate = rotate;
                const std::string what = std::string(edge_mode_name(mode)) + " jitter " +
                                         std::to_string(jitter) + " rotate " +
                                         std::to_string(rotate);
                const std::vector<float> cpu = realtime::sss_pass(c.g, c.mats, p);
                std::vector<float> gl;
                pass.run(c.g, c.mats, p, gl);
                ASSERT_EQ(gl.size(), cpu.size());
                const std::vector<float> self = perturbed_cpu(c.g, c.mats, p);
                // Material 0 (one term, positive weights) in every mode, and everything without
                // rejection: 1e-5 relative, pixel by pixel.
                const double m0 =
                    max_relative_difference(of_material(c, gl, 0), of_material(c, cpu, 0));
                const double m1 =
                    max_relative_difference(of_material(c, gl, 1), of_material(c, cpu, 1));
                const double m1_self =
                    max_relative_difference(of_material(c, self, 1), of_material(c, cpu, 1));
                std::printf(
                    "%-30s GL vs CPU, worst relative difference: material 0 %.2g, "
                    "material 1 (SVD rank 2) %.2g (CPU vs itself perturbed: %.2g)\n",
                    what.c_str(), m0, m1, m1_self);
                EXPECT_LT(m0, 1e-5) << what;
                if (mode != SssEdgeMode::kReject) {
                    EXPECT_LT(m1, 1e-5) << what;
                } else {
                    // Rejection rescales each term by (its weight sum) / (its kept weight sum);
                    // the signed second SVD term's sums are near 0, so the result is
                    // ill-conditioned: rounding-level changes move the CPU pass itself by
                    // percents there. The GL pass must stay within that.
                    EXPECT_LT(m1, std::max(1e-5, 4 * m1_self)) << what;
                }
                // Pixels without medium pass their input through, bit for bit.
                for (size_t i = 0; i < c.g.pixels(); ++i) {
                    if (c.g.material[i] >= 0) continue;
                    for (int ch = 0; ch < 3; ++ch)
                        ASSERT_EQ(gl[3 * i + ch], c.g.irradiance[3 * i + ch]);
                }
            }
}

TEST_P(GlSssPassTest, NarrowAndWideKernels) {
    realtime::gl::GlSssPass pass(*ctx);
    Case c = two_materials(64, 48);
    // Far away (kernels narrower than a pixel: the identity times the mass) and close (wider
    // than the image: clamp-to-edge everywhere).
    for (float z : {5000.0f, 0.5f}) {
        for (float& v : c.g.view_z) v = z;
        for (SssEdgeMode mode : kSssEdgeModes) {
            const SssParams p = sss_camera(c.g.width, c.g.height, mode);
            const std::vector<float> cpu = realtime::sss_pass(c.g, c.mats, p);
            std::vector<float> gl;
            pass.run(c.g, c.mats, p, gl);
            const double worst = max_relative_difference(gl, cpu);
            std::printf("z %g %s: worst relative difference %.3g\n", z, edge_mode_name(mode),
                        worst);
            EXPECT_LT(worst, 1e-5) << "z " << z << " " << edge_mode_name(mode);
        }
    }
}

TEST_P(GlSssPassTest, RefusesWhatTheCpuPassRefuses) {
    realtime::gl::GlSssPass pass(*ctx);
    const Case c = two_materials(20, 16);
    const SssParams p = sss_camera(20, 16, SssEdgeMode::kNone);
    std::vector<float> out;
    SssGBuffer bad = c.g;
    bad.material[0] = 2;
    EXPECT_THROW(pass.run(bad, c.mats, p, out), std::invalid_argument);
    bad = c.g;
    bad.material[21] = 0;
    bad.view_z[21] = -1;
    EXPECT_THROW(pass.run(bad, c.mats, p, out), std::invalid_argument);
    SssParams q = p;
    q.tan_half = 0;
    EXPECT_THROW(pass.run(c.g, c.mats, q, out), std::invalid_argument);
}

// ---- The G-buffer's geometry (realtime/gl/raster_gl.h) against the software rasterizer ----

TEST_P(GlSssPassTest, RasterOfTheBuiltInScenesMatchesTheSoftwareRasterizer) {
    realtime::gl::GlRaster raster(*ctx);
    // The five scenes, then two of them supersampled (3 x 3 samples a pixel).
    const std::vector<std::pair<const char*, int>> cases = {
        {"skin", 1},    {"marble", 1}, {"wholemilk", 1}, {"apple", 1},
        {"ketchup", 1}, {"skin", 3},   {"apple", 3}};
    for (const auto& [name, ss] : cases) {
        const Scene scene =
            read_scene(testing::source_path("experiments/scenes/") + name + ".toml");
        const int w = 320 / ss, h = 240 / ss;
        realtime::RasterOptions o;
        o.supersample = ss;
        const realtime::RasterFrame sw = realtime::rasterize(scene, o, w, h);
        realtime::RasterFrame gl;
        realtime::gl::GlRasterTimes t;
        raster.rasterize(scene, o, w, h, gl, &t);
        ASSERT_EQ(gl.shape.size(), sw.shape.size());
        ASSERT_EQ(gl.supersample, ss);
        ASSERT_EQ(gl.coverage.size(), sw.coverage.size());
        size_t same_shape = 0, same_triangle = 0, covered = 0;
        double worst_z = 0;
        for (size_t i = 0; i < sw.shape.size(); ++i) {
            covered += sw.shape[i] >= 0;
            if (gl.shape[i] != sw.shape[i]) continue;
            ++same_shape;
            if (gl.triangle[i] != sw.triangle[i]) continue;
            ++same_triangle;
            if (sw.shape[i] >= 0)
                worst_z = std::max(worst_z, std::fabs(gl.view_z[i] - sw.view_z[i]) / sw.view_z[i]);
        }
        const double n = static_cast<double>(sw.shape.size());
        const double p = psnr(gl.depth, sw.depth);
        std::printf(
            "%-10s x%d: %zu of %zu samples covered; same shape %.5f, same triangle %.5f, "
            "view z within %.2g; depth layer PSNR %.1f dB; GL draws %.2f ms (timer "
            "query %.2f), call %.1f ms\n",
            name, ss, covered, sw.shape.size(), same_shape / n, same_triangle / n, worst_z, p,
            t.draw_ms, t.gpu_ms, t.wall_ms);
        EXPECT_GT(same_shape / n, 0.999) << name;
        EXPECT_GT(same_triangle / n, 0.99) << name;
        EXPECT_LT(worst_z, 1e-5) << name;
        EXPECT_GT(p, 45.0) << name;
    }
}

// ---- Pass 1 (realtime/gl/lighting_gl.h) against realtime::shade on the same raster frame ----

// Translucency through a slab table of every medium (any table: the two backends read the same
// one): T falling from 0.6 to 1e-4 over 0.1 to 20 mm.
std::vector<realtime::SlabTransmittance> synthetic_slabs(const Scene& scene) {
    std::vector<realtime::SlabTransmittance> slabs(scene.materials.size());
    for (size_t m = 0; m < scene.materials.size(); ++m)
        if (scene.materials[m].kind == SceneMaterial::Kind::kMedium)
            for (double d : {0.1, 0.5, 2.0, 5.0, 20.0}) {
                slabs[m].thickness_mm.push_back(d);
                slabs[m].transmittance.push_back(
                    {0.6 * std::exp(-d / 1.5), 0.6 * std::exp(-d / 2.5), 0.6 * std::exp(-d / 4.0)});
            }
    return slabs;
}

TEST_P(GlSssPassTest, LightingOfTheBuiltInScenesMatchesTheCpuPass) {
    realtime::gl::GlLighting lighting(*ctx);
    for (const char* name : {"skin", "marble", "wholemilk", "apple", "ketchup"}) {
        const Scene scene =
            read_scene(testing::source_path("experiments/scenes/") + name + ".toml");
        const int w = 320, h = 240;
        const realtime::RasterFrame frame = realtime::rasterize(scene, {}, w, h);
        const realtime::RasterCamera camera =
            realtime::RasterCamera::from_scene(scene.camera, w, h);
        realtime::LightingOptions o;
        o.thickness_layer = true;
        o.shadow_map_size = 1024;  // half the default: llvmpipe draws 80-150 maps a frame here
        const std::vector<realtime::SlabTransmittance> slabs = synthetic_slabs(scene);
        realtime::LightingStats cs, gs;
        const realtime::GBuffer cpu = realtime::shade(scene, camera, frame, o, slabs, &cs);
        realtime::GBuffer gpu;
        realtime::gl::GlLightingTimes t;
        lighting.shade(scene, camera, frame, o, slabs, &gs, gpu, &t);
        ASSERT_EQ(gpu.irradiance.size(), cpu.irradiance.size());
        EXPECT_EQ(gpu.material, cpu.material) << name;
        const std::vector<
            std::pair<const char*, std::pair<const std::vector<float>*, const std::vector<float>*>>>
            layers = {{"irradiance", {&gpu.irradiance, &cpu.irradiance}},
                      {"specular", {&gpu.specular, &cpu.specular}},
                      {"surface", {&gpu.surface, &cpu.surface}},
                      {"translucency", {&gpu.translucency, &cpu.translucency}},
                      {"thickness", {&gpu.thickness, &cpu.thickness}},
                      {"exit_weight", {&gpu.exit_weight, &cpu.exit_weight}},
                      {"normal", {&gpu.normal, &cpu.normal}}};
        std::printf(
            "%-10s maps %d (CPU %d), GL draws: maps %.1f ms, shading %.1f ms; call %.1f ms; PSNR "
            "dB:",
            name, gs.shadow_maps, cs.shadow_maps, t.shadow_wall_ms, t.shading_wall_ms, t.wall_ms);
        for (const auto& [layer, ab] : layers) {
            const double p = psnr(*ab.first, *ab.second);
            const auto mm = std::minmax_element(ab.second->begin(), ab.second->end());
            const size_t nonzero = static_cast<size_t>(std::count_if(
                ab.second->begin(), ab.second->end(), [](float v) { return v != 0; }));
            std::printf(" %s %.1f [%.3g..%.3g, %zu nonzero]", layer, p, *mm.first, *mm.second,
                        nonzero);
            EXPECT_GT(p, 45.0) << name << " " << layer;
        }
        std::printf("\n");
    }
}

// A spot light (core/light.h: KHR_lights_punctual's cone, the emitter's angular profile) lights
// a diffuse floor and a rough medium: the GL pass's layers against the CPU pass's, and the cone
// is there (lit floor inside it, none far outside).
TEST_P(GlSssPassTest, ASpotLightIsLitAsTheCpuPassLightsIt) {
    const Scene scene = parse_scene(R"(
[scene]
name = "spot"
[camera]
position = [0, 6, 5]
target = [0, 0.5, 0]
fov_y_deg = 55
width = 160
height = 120
[[lights]]
type = "spot"
position = [0.5, 4, 0.5]
direction = [-0.1, -1, -0.1]
intensity = [20, 15, 10]
inner_cone_angle_deg = 12
outer_cone_angle_deg = 30
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.7, 0.6, 0.5]
[[materials]]
name = "skin"
preset = "Skin1"
roughness = 0.3
[[shapes]]
type = "plane"
size_x = 10
size_z = 10
material = "floor"
[[shapes]]
type = "sphere"
radius = 0.8
subdivisions = 4
translate = [0, 0.85, 0]
material = "skin"
)",
                                    "spot.toml", ".");
    const int w = 160, h = 120;
    const realtime::RasterFrame frame = realtime::rasterize(scene, {}, w, h);
    const realtime::RasterCamera camera = realtime::RasterCamera::from_scene(scene.camera, w, h);
    realtime::LightingOptions o;
    o.thickness_layer = true;
    o.shadow_map_size = 512;
    const std::vector<realtime::SlabTransmittance> slabs = synthetic_slabs(scene);
    const realtime::GBuffer cpu = realtime::shade(scene, camera, frame, o, slabs);
    realtime::gl::GlLighting lighting(*ctx);
    realtime::GBuffer gpu;
    lighting.shade(scene, camera, frame, o, slabs, nullptr, gpu);
    for (const auto& [name, a, b] : {std::tuple{"surface", &gpu.surface, &cpu.surface},
                                     std::tuple{"irradiance", &gpu.irradiance, &cpu.irradiance},
                                     std::tuple{"specular", &gpu.specular, &cpu.specular}}) {
        const double p = psnr(*a, *b);
        std::printf("  [measured] spot, %s: PSNR %.1f dB\n", name, p);
        EXPECT_GT(p, 45.0) << name;
    }
    // The floor's radiance under the cone's axis and at the image's corner (far outside it).
    int lit = 0, dark = 0;
    for (std::size_t i = 0; i < cpu.shape.size(); ++i) {
        if (cpu.shape[i] != 0) continue;
        (cpu.surface[3 * i] > 0.1f ? lit : dark) += 1;
        if (cpu.surface[3 * i] == 0.0f) {
            EXPECT_LT(gpu.surface[3 * i], 1e-4f);
        }
    }
    EXPECT_GT(lit, 500);
    EXPECT_GT(dark, 500);
}

// ---- Whole frames (realtime/gl/frame_gl.h): every layer of the GL twin's image against the
// software renderer's, each backend from its own raster ----

TEST_P(GlSssPassTest, FramesOfTheBuiltInScenesMatchTheSoftwareRenderer) {
    realtime::gl::GlFrameBackend gl(*ctx);
    const RadialProfile profile = testing::analytic_profile(0.01, 600);
    for (const char* name : {"skin", "marble", "wholemilk", "apple", "ketchup"}) {
        const Scene scene =
            read_scene(testing::source_path("experiments/scenes/") + name + ".toml");
        const std::vector<realtime::SlabTransmittance> slabs = synthetic_slabs(scene);
        realtime::FrameOptions so;
        so.width = 320;
        so.height = 240;
        so.sss.follow_strength = realtime::default_follow_strength(scene);
        so.sss.reject_depth = realtime::default_reject_depth(scene);
        so.lighting.shadow_map_size = 1024;
        realtime::FrameOptions go = so;
        gl.install(go);
        const realtime::RasterizedFrame sf = realtime::rasterize_frame(scene, so);
        const realtime::RasterizedFrame gf = realtime::rasterize_frame(scene, go);
        EXPECT_EQ(gf.media_in_view, sf.media_in_view) << name;
        std::map<int, realtime::FrameMaterial> materials;
        for (int m : sf.media_in_view)
            materials[m] = realtime::make_frame_material(profile, approx::parse_model("svd:rank=2"),
                                                         17, false);
        const realtime::FrameResult sr = realtime::render_frame(scene, sf, materials, so, slabs);
        const realtime::FrameResult gr = realtime::render_frame(scene, gf, materials, go, slabs);
        std::printf("%-10s PSNR dB:", name);
        for (const ImageLayer& sl : sr.image.layers()) {
            ASSERT_TRUE(gr.image.has_layer(sl.name())) << name << " " << sl.name();
            const auto a = gr.image.layer(sl.name()).pixels(), b = sl.pixels();
            const double p = psnr(a, b);
            std::printf(" %s %.1f", sl.name().c_str(), p);
            EXPECT_GT(p, 45.0) << name << " " << sl.name();
        }
        std::printf("\n");
    }
}

}  // namespace
}  // namespace ssslab
