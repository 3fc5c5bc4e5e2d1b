// The real-time renderer's lighting pass (realtime/lighting.h) and shadow maps
// (realtime/shadow_map.h): diffuse direct lighting against volpath at max_depth = 1 with
// per-pixel z-scores as the light and environment sample counts grow; the shadow boundary of
// a square occluder against its closed form; the irradiance transmitted through a smooth and a
// rough boundary against 1 - F and the GGX table, the table against volpath's own GGX sampling,
// exit weights normalised; first-surface specular against volpath; translucency of a slab lit
// from behind; bit-identical G-buffers for 1 and 2 threads.
#include "realtime/lighting.h"

#include "core/dielectric.h"
#include "core/rng.h"
#include "core/scene.h"
#include "realtime/raster.h"
#include "realtime/shadow_map.h"
#include "testing.h"
#include "volpath/microfacet.h"
#include "volpath/render.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

namespace ssslab::realtime {
namespace {

constexpr double kPi = std::numbers::pi;

struct Rendered {
    RasterFrame frame;
    GBuffer g;
    LightingStats stats;
    double ms = 0;
};

Rendered render_rt(const Scene& s, int w, int h, int ss, const LightingOptions& o,
                   const std::vector<SlabTransmittance>& slabs = {}) {
    Rendered r;
    RasterOptions ro;
    ro.supersample = ss;
    r.frame = rasterize(s, ro, w, h);
    const RasterCamera cam = RasterCamera::from_scene(s.camera, w, h);
    const auto t0 = std::chrono::steady_clock::now();
    r.g = shade(s, cam, r.frame, o, slabs, &r.stats);
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

// Box filter of a 3-channel per-sample layer to pixel (x, y), channel c.
double pixel(const Rendered& r, const std::vector<float>& layer, int x, int y, int c) {
    const int s = r.frame.supersample;
    double sum = 0;
    for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i)
            sum += layer[3 * r.frame.sample_index(x * s + i, y * s + j) + static_cast<size_t>(c)];
    return sum / (s * s);
}

// A pixel whose samples all see the same shape with facet normals within 12 degrees of each
// other (no silhouette, no box edge), and whose realtime radiance (surface + specular) varies
// over its samples by less than `max_spread` of its mean (no sharp shadow edge, where the
// shadow maps' texels show): there volpath's box filter and the samples' mean agree.
bool interior_one(const Rendered& r, int x, int y, double max_spread) {
    const int s = r.frame.supersample;
    const std::size_t i0 = r.frame.sample_index(x * s, y * s);
    const int shape = r.g.shape[i0];
    if (shape < 0) return false;
    double lo = 1e300, hi = -1e300, sum = 0;
    for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i) {
            const std::size_t k = r.frame.sample_index(x * s + i, y * s + j);
            const double v = r.g.surface[3 * k] + r.g.specular[3 * k];
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            sum += v;
        }
    if (hi - lo > max_spread * sum / (s * s)) return false;
    for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i) {
            const std::size_t k = r.frame.sample_index(x * s + i, y * s + j);
            if (r.g.shape[k] != shape) return false;
            double d = 0;
            for (std::size_t c = 0; c < 3; ++c) d += r.g.normal[3 * k + c] * r.g.normal[3 * i0 + c];
            if (shape >= 0 && d < std::cos(12 * kPi / 180)) return false;
        }
    return true;
}

constexpr double kMaxSpread = 0.2;
// ... and so are its four neighbours (away from the edges, not only off them).
bool interior(const Rendered& r, int x, int y, double max_spread = kMaxSpread) {
    if (x < 1 || y < 1 || x + 1 >= r.frame.width || y + 1 >= r.frame.height) return false;
    return interior_one(r, x, y, max_spread) && interior_one(r, x - 1, y, max_spread) &&
           interior_one(r, x + 1, y, max_spread) && interior_one(r, x, y - 1, max_spread) &&
           interior_one(r, x, y + 1, max_spread);
}

volpath::RenderResult render_vp(const Scene& s, int w, int h, double spp, std::uint64_t seed) {
    volpath::RenderOptions o;
    o.seed = seed;
    o.width = w;
    o.height = h;
    o.max_depth = 1;
    o.budget.samples = static_cast<std::int64_t>(spp * testing::test_scale());
    return volpath::render(s, o);
}

// Sum of z^2 of the realtime layer against volpath's radiance (scaled by `scale`) over the
// interior pixels, their count, and the RMS relative error.
struct Agreement {
    double chi2 = 0, max_z = 0;
    double mean_z = 0, median_abs_z = 0;
    double bias = 0;  ///< sqrt(max(0, sum (v - ref)^2 - se^2) / sum ref^2): error beyond the noise
    int n = 0;
};
Agreement agree(const Rendered& r, const std::vector<float>& layer, const LayeredImage& vp,
                double scale = 1, double max_spread = kMaxSpread) {
    const ImageLayer& L = vp.layer("radiance");
    const ImageLayer& E = vp.layer("radiance.stderr");
    Agreement a;
    double e2 = 0, l2 = 0;
    std::vector<double> abs_z;
    for (int y = 0; y < r.frame.height; ++y)
        for (int x = 0; x < r.frame.width; ++x) {
            if (!interior(r, x, y, max_spread)) continue;
            for (int c = 0; c < 3; ++c) {
                const double se = E.at(x, y, c), ref = L.at(x, y, c);
                if (!(se > 0) || !(ref > 0)) continue;
                const double v = scale * pixel(r, layer, x, y, c);
                const double z = (v - ref) / se;
                a.chi2 += z * z;
                a.max_z = std::max(a.max_z, std::abs(z));
                a.mean_z += z;
                abs_z.push_back(std::abs(z));
                ++a.n;
                e2 += (v - ref) * (v - ref) - se * se;
                l2 += ref * ref;
            }
        }
    a.bias = std::sqrt(std::max(0.0, e2) / l2);
    if (a.n > 0) {
        a.mean_z /= a.n;
        std::sort(abs_z.begin(), abs_z.end());
        a.median_abs_z = abs_z[abs_z.size() / 2];
    }
    return a;
}

const char* kDiffuseScene = R"(
[scene]
name = "diffuse"
[camera]
position = [0, 4.5, 5.5]
target = [0, 0.3, 0]
fov_y_deg = 40
width = 32
height = 32
[[lights]]
type = "sphere"
position = [3.5, 3.5, 2.5]
radius = 0.8
radiance = [3.0, 2.5, 2.0]
[[lights]]
type = "environment"
radiance = [0.15, 0.2, 0.3]
[[lights]]
type = "directional"
direction = [-1, 1.5, 0.8]
angular_radius_deg = 6
irradiance = [0.6, 0.6, 0.5]
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.7, 0.6, 0.5]
[[materials]]
name = "white"
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[[shapes]]
type = "plane"
size_x = 5
size_z = 5
material = "floor"
[[shapes]]
type = "sphere"
radius = 0.7
subdivisions = 4
translate = [-0.8, 0.7, -0.3]
material = "white"
[[shapes]]
type = "box"
size = [1, 1, 1]
rotate_deg = [0, 30, 0]
translate = [1.0, 0.5, 0.4]
material = "floor"
)";

TEST(Lighting, DiffuseDirectLightingAgainstVolpath) {
    const Scene s = parse_scene(kDiffuseScene, "diffuse.toml", ".");
    const int w = 32, h = 32;
    const double spp = 300;
    const volpath::RenderResult vp = render_vp(s, w, h, spp, 7);
    const int counts[3][2] = {{2, 4}, {16, 64}, {1024, 1024}};
    std::vector<Agreement> res;
    Rendered last;
    for (const auto& cnt : counts) {
        LightingOptions o;
        o.light_samples = cnt[0];
        o.environment_samples = cnt[1];
        o.shadow_map_size = 256;
        Rendered r = render_rt(s, w, h, 4, o);
        const Agreement a = agree(r, r.g.surface, vp.image);
        std::printf(
            "  [measured] light %d env %d: %d maps (%.0f ms shadow, %.0f ms shading): %d pixel-"
            "channels, chi2/n %.3f, mean z %.3f, median |z| %.3f, max |z| %.2f, bias (RMS beyond "
            "the noise) %.4f\n",
            cnt[0], cnt[1], r.stats.shadow_maps, r.stats.shadow_ms, r.stats.shading_ms, a.n,
            a.chi2 / a.n, a.mean_z, a.median_abs_z, a.max_z, a.bias);
        res.push_back(a);
        last = std::move(r);
    }
    ASSERT_GT(res[2].n, 800);
    // The error beyond volpath's noise shrinks as the counts grow (8 %, 1.3 %, 0.26 % measured).
    // The largest count was 256 / 256 until volpath-render-6, whose NEE samples the environment
    // by cos(theta) at a surface: volpath's noise on these diffuse surfaces fell (~1.6x in SE)
    // and the real-time image's own sampling error at 256 samples showed (chi2/n 1.47, median
    // |z| 0.79, its RMS beyond the noise 0.45 %); at 1024 it is 0.26 %.
    EXPECT_GT(res[0].bias, 2 * res[1].bias);
    EXPECT_GT(res[1].bias, res[2].bias);
    // At the largest count the realtime image is volpath's within its noise: no systematic
    // offset (the mean z within 4 / sqrt(n)) and the |z| distributed as for a standard normal
    // (median 0.674; its standard deviation 1 / (2 * 2 phi(0.674) sqrt(n)) = 0.025 here).
    // Robust statistics: volpath's SEs come from 100 batches and a few pixels underestimate
    // theirs (the chi-square over the same pixels is 1.18 n with seed 7, 1.03 and 1.06 with
    // seeds 8 and 9; the mean z is within +-0.04 for all three).
    const double zsd = 1 / (4 * 0.3178 * std::sqrt(res[2].n));
    EXPECT_LT(std::abs(res[2].mean_z), 4 / std::sqrt(res[2].n));
    EXPECT_GT(res[2].median_abs_z, 0.674 - 4 * zsd);
    EXPECT_LT(res[2].median_abs_z, 0.674 * 1.01 + 4 * zsd);  // t with 99 dof: 1 % wider
    // At the smallest count it is measurably off.
    EXPECT_GT(res[0].median_abs_z, 1.5);
    EXPECT_GT(std::abs(res[0].mean_z), 10 / std::sqrt(res[0].n));
    // The test can fail: lights 3 % too bright are detected.
    const Agreement off = agree(last, last.g.surface, vp.image, 1.03);
    std::printf("  [measured] 3 %% too bright: mean z %.2f, median |z| %.2f\n", off.mean_z,
                off.median_abs_z);
    EXPECT_GT(off.mean_z, 4 / std::sqrt(off.n));
    // Normals: volpath's "normal" layer holds the facet normal outward for the winding (not
    // turned towards the camera); the G-buffer's is the same. Pixels inside one box face.
    int faces = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!interior(last, x, y, 1e300) ||
                last.g.shape[last.frame.sample_index(4 * x, 4 * y)] != 2)
                continue;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(pixel(last, last.g.normal, x, y, c),
                            vp.image.layer("normal").at(x, y, c), 1e-5);
            ++faces;
        }
    EXPECT_GT(faces, 5);
    // The background is the environment.
    EXPECT_NEAR(last.g.surface[0], 0.15f, 1e-6);
}

const char* kSpotScene = R"(
[scene]
name = "spot"
[camera]
position = [0, 5, 3]
target = [0.4, 0, -0.3]
fov_y_deg = 45
width = 32
height = 32
[[lights]]
type = "spot"
position = [0.5, 3, -0.3]
direction = [-0.2, -1, 0.15]
intensity = [4, 3, 2]
inner_cone_angle_deg = 25
outer_cone_angle_deg = 50
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.7, 0.6, 0.5]
[[shapes]]
type = "plane"
size_x = 8
size_z = 8
material = "floor"
)";

// A spot light (core/light.h, KHR_lights_punctual's cone) over a diffuse plane: every sample of
// the real-time G-buffer against the closed form albedo / pi * I f(cos theta) cos(theta_n) / d^2
// (f written here from the extension's text), inside the inner cone, on the ramp and outside; then
// the frame with its shadow map against volpath by per-pixel z-scores (the path tracer's NEE of
// the same light), and a spot 3 % too bright is detected.
TEST(Lighting, ASpotLightOnAPlaneAgainstItsClosedFormAndVolpath) {
    const Scene s = parse_scene(kSpotScene, "spot.toml", ".");
    const int w = 32, h = 32, ss = 2;
    LightingOptions o;
    o.shadows = false;
    const Rendered r = render_rt(s, w, h, ss, o);
    const RasterCamera cam = RasterCamera::from_scene(s.camera, w, h);
    const RasterCamera::SampleRays rays = cam.sample_rays(ss);
    const SceneLight& sp = s.lights[0];
    const double ci = std::cos(25 * kPi / 180), co = std::cos(50 * kPi / 180);
    int inside = 0, ramp = 0, outside = 0;
    double max_rel = 0;
    for (int sy = 0; sy < h * ss; ++sy)
        for (int sx = 0; sx < w * ss; ++sx) {
            const std::size_t i = r.frame.sample_index(sx, sy);
            if (r.g.shape[i] != 0) continue;
            const Vec3 p = cam.position + rays.unnormalized(sx, sy) * r.frame.view_z[i];
            const Vec3 d = sp.position - p;
            const double d2 = dot(d, d);
            const Vec3 wi = d * (1 / std::sqrt(d2));
            const double c = -dot(wi, sp.direction);
            const double f = c >= ci ? 1.0 : (c <= co ? 0.0 : std::pow((c - co) / (ci - co), 2));
            (f == 1 ? inside : (f == 0 ? outside : ramp))++;
            for (std::size_t k = 0; k < 3; ++k) {
                const double want =
                    s.materials[0].albedo[k] / kPi * sp.color[k] * f * std::max(0.0, wi.y) / d2;
                const double got = r.g.surface[3 * i + k];
                EXPECT_NEAR(got, want, 1e-5 * want + 1e-9) << sx << " " << sy;
                if (want > 0) max_rel = std::max(max_rel, std::abs(got / want - 1));
            }
        }
    std::printf(
        "  [measured] spot: %d samples inside the inner cone, %d on the ramp, %d outside; "
        "largest relative difference %.2g\n",
        inside, ramp, outside, max_rel);
    EXPECT_GT(inside, 100);
    EXPECT_GT(ramp, 100);
    EXPECT_GT(outside, 100);

    // With its shadow map, against the path tracer.
    const volpath::RenderResult vp = render_vp(s, w, h, 200, 11);
    const Rendered rs = render_rt(s, w, h, 4, LightingOptions{});
    const Agreement a = agree(rs, rs.g.surface, vp.image);
    std::printf(
        "  [measured] spot against volpath: %d pixel-channels, chi2/n %.3f, mean z %.3f, "
        "median |z| %.3f, max |z| %.2f\n",
        a.n, a.chi2 / a.n, a.mean_z, a.median_abs_z, a.max_z);
    ASSERT_GT(a.n, 600);
    EXPECT_LT(std::abs(a.mean_z), 4 / std::sqrt(a.n));
    const double zsd = 1 / (4 * 0.3178 * std::sqrt(a.n));
    EXPECT_GT(a.median_abs_z, 0.674 - 4 * zsd);
    EXPECT_LT(a.median_abs_z, 0.674 * 1.01 + 4 * zsd);
    const Agreement off = agree(rs, rs.g.surface, vp.image, 1.03);
    EXPECT_GT(off.mean_z, 4 / std::sqrt(off.n));
}

TEST(Lighting, ShadowBoundaryOfASquareOccluder) {
    // A directional delta light over a 2 x 2 square at height 1 above a plane: a ground point
    // p is in shadow iff p + t w (t = 1 / w_y) lies in the square. Every mismatch must lie
    // within 1.5 texel footprints of that boundary.
    const Vec3 w = normalize(Vec3{1, 1, 0.5});
    const std::string text = R"(
[scene]
name = "shadow"
[camera]
position = [0, 10, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 40
width = 64
height = 64
[[lights]]
type = "directional"
direction = [1, 1, 0.5]
irradiance = 1
[[materials]]
name = "d"
type = "diffuse"
albedo = 0.5
[[shapes]]
type = "plane"
size_x = 20
size_z = 20
material = "d"
[[shapes]]
type = "plane"
size_x = 2
size_z = 2
translate = [0, 1, 0]
material = "d"
)";
    const Scene s = parse_scene(text, "shadow.toml", ".");
    for (int size : {128, 512, 2048}) {
        LightingOptions o;
        o.shadow_map_size = size;
        const Rendered r = render_rt(s, 64, 64, 2, o);
        ASSERT_EQ(r.stats.shadow_maps, 1);
        const Vec3 shift = w * (1 / w.y);
        const double lit_value = 0.5 / kPi * w.y;
        // Texel footprint on the ground: the map covers the receivers' box seen along w.
        const ShadowView v = [&] {
            Box b, c;
            for (std::size_t i = 0; i < r.g.samples(); ++i)
                if (r.g.shape[i] >= 0) {
                    const int sx = static_cast<int>(i % static_cast<std::size_t>(r.g.width));
                    const int sy = static_cast<int>(i / static_cast<std::size_t>(r.g.width));
                    const RasterCamera cam = RasterCamera::from_scene(s.camera, 64, 64);
                    b.add(cam.position +
                          cam.ray_direction((sx + 0.5) / 2, (sy + 0.5) / 2) * r.g.ray_t[i]);
                }
            c.add({-10, 0, -10});
            c.add({10, 1, 10});
            return fit_directional(w, b, c, size);
        }();
        // Drawn in bands of any size, the map is the same.
        if (size == 512) {
            const ShadowMap whole = render_shadow_map(s, v), bands = render_shadow_map(s, v, 5000);
            EXPECT_EQ(whole.depth, bands.depth);
            EXPECT_EQ(whole.shape, bands.shape);
        }
        const double footprint = v.texel_size(0) / w.y;
        int ground = 0, shadowed = 0, mismatches = 0;
        double worst = 0;
        const RasterCamera cam = RasterCamera::from_scene(s.camera, 64, 64);
        for (int sy = 0; sy < r.g.height; ++sy)
            for (int sx = 0; sx < r.g.width; ++sx) {
                const std::size_t i = static_cast<std::size_t>(sy * r.g.width + sx);
                if (r.g.shape[i] != 0) continue;
                ++ground;
                const Vec3 p = cam.position + cam.ray_direction((sx + 0.5) / 2, (sy + 0.5) / 2) *
                                                  static_cast<double>(r.g.ray_t[i]);
                const Vec3 q = p + shift;
                const bool in = std::abs(q.x) < 1 && std::abs(q.z) < 1;
                // Distance of q to the square's boundary.
                const double dx = std::abs(q.x) - 1, dz = std::abs(q.z) - 1;
                const double dist =
                    in ? std::min(-dx, -dz) : std::hypot(std::max(dx, 0.0), std::max(dz, 0.0));
                const double L = r.g.surface[3 * i];
                const bool lit = L > 0.5 * lit_value;
                shadowed += !lit;
                if (lit) {
                    EXPECT_NEAR(L, lit_value, 1e-6);
                }
                if (lit == !in) continue;
                ++mismatches;
                worst = std::max(worst, dist / footprint);
                EXPECT_LT(dist, 1.5 * footprint) << sx << "," << sy;
            }
        std::printf(
            "  [measured] shadow map %d: %d ground samples, %d shadowed, %d mismatches, farthest "
            "%.2f texel footprints (%.4f units) from the boundary\n",
            size, ground, shadowed, mismatches, worst, footprint);
        EXPECT_GT(shadowed, 500);
    }
}

std::string medium_box(const char* roughness, const char* lights) {
    return std::string(R"(
[scene]
name = "slab"
[camera]
position = [0, 8, 3]
target = [0, 0, 0]
fov_y_deg = 30
width = 24
height = 24
)") + lights +
           R"(
[[materials]]
name = "m"
sigma_a_per_mm = 0.1
sigma_s_per_mm = 1.0
g = 0
eta = 1.4
roughness = )" +
           roughness + R"(
[[shapes]]
type = "box"
size = [8, 1, 8]
translate = [0, -0.5, 0]
material = "m"
)";
}

TEST(Lighting, IrradianceThroughTheBoundary) {
    // The top of a medium box under a delta directional light: (1 - F(cos, eta)) E cos for a
    // smooth boundary, T_ggx(cos) E cos for alpha = 0.3, with exit weight T(cos_o) / (pi c).
    const Vec3 w = normalize(Vec3{0.5, 1, 0.3});
    const char* light =
        "[[lights]]\ntype = \"directional\"\ndirection = [0.5, 1, 0.3]\n"
        "irradiance = [1, 2, 3]\n";
    for (const char* rough : {"0", "0.3"}) {
        const Scene s = parse_scene(medium_box(rough, light), "m.toml", ".");
        const Rendered r = render_rt(s, 24, 24, 1, LightingOptions{});
        const BoundaryTransmittance T(1.4, std::atof(rough));
        int n = 0;
        double worst = 0;
        const RasterCamera cam = RasterCamera::from_scene(s.camera, 24, 24);
        for (std::size_t i = 0; i < r.g.samples(); ++i) {
            if (r.g.material[i] != 0 || r.g.normal[3 * i + 1] < 0.99f) continue;
            const double mu = w.y;
            const double t =
                std::atof(rough) == 0 ? 1 - dielectric::fresnel_dielectric(mu, 1.4) : T(mu);
            for (int c = 0; c < 3; ++c) {
                const double e = t * (c + 1) * mu;
                worst = std::max(worst, std::abs(r.g.irradiance[3 * i + c] - e) / e);
            }
            const int sx = static_cast<int>(i % 24), sy = static_cast<int>(i / 24);
            const Vec3 wo = -cam.ray_direction(sx + 0.5, sy + 0.5);
            EXPECT_NEAR(r.g.exit_weight[i], T(wo.y) / (kPi * T.hemispherical()), 1e-6);
            EXPECT_EQ(r.g.surface[3 * i], 0.f);
            ++n;
        }
        std::printf("  [measured] roughness %s: %d top samples, worst relative error %.2e\n", rough,
                    n, worst);
        EXPECT_GT(n, 300);
        EXPECT_LT(worst, 1e-6);
    }
}

// Points off the G-buffer (a point cloud on the media, Jensen-Buhler) are lit as pass 1 lights
// its medium samples: at the G-buffer's own medium samples, without shadows, the same irradiance
// to float rounding, and with shadows too where the lights are planned for the frame's
// receivers (ketchup: a sun and the environment, whose samples do not depend on the receivers'
// box as a sphere light's do); with the maps fitted to the points' own box instead, the same
// on most of them (the maps' texels differ at shadow edges); a smooth boundary's top face under a
// delta light gets (1 - F(cos, eta)) E cos and its bottom face nothing.
TEST(Lighting, BoundaryPointsAreLitAsPassOneLightsMediumSamples) {
    const Scene scene = read_scene(testing::source_path("experiments/scenes/ketchup.toml"));
    for (bool shadows : {false, true}) {
        LightingOptions o;
        o.light_samples = 4;
        o.environment_samples = 8;
        o.shadow_map_size = 1024;
        o.environment_map_size = 512;
        o.shadows = shadows;
        const Rendered r = render_rt(scene, 64, 48, 1, o);
        const RasterCamera cam = RasterCamera::from_scene(scene.camera, 64, 48);
        std::vector<BoundaryPoint> pts;
        std::vector<std::size_t> at;
        Box receivers;  // as shade() gathers it: diffuse samples and media seen from outside
        const RasterCamera::SampleRays rays = cam.sample_rays(1);
        for (std::size_t i = 0; i < r.g.samples(); ++i) {
            if (r.g.shape[i] < 0) continue;
            const int sx = static_cast<int>(i % 64), sy = static_cast<int>(i / 64);
            const Vec3 p = cam.position + rays.unnormalized(sx, sy) * r.frame.view_z[i];
            const bool medium = scene.materials[static_cast<std::size_t>(r.g.material[i])].kind ==
                                SceneMaterial::Kind::kMedium;
            if (medium && !(r.g.exit_weight[i] > 0)) continue;  // seen from inside
            receivers.add(p);
            if (!medium) continue;
            pts.push_back({p,
                           {r.g.normal[3 * i], r.g.normal[3 * i + 1], r.g.normal[3 * i + 2]},
                           r.g.material[i]});
            at.push_back(i);
        }
        ASSERT_GT(pts.size(), 300u);
        for (bool own_box : {false, true}) {
            const std::vector<std::array<double, 3>> E =
                boundary_irradiance(scene, pts, o, own_box ? Box{} : receivers);
            std::size_t agree = 0, lit = 0;
            double worst = 0;
            for (std::size_t k = 0; k < pts.size(); ++k) {
                bool same = true;
                for (int c = 0; c < 3; ++c) {
                    const double g = r.g.irradiance[3 * at[k] + c];
                    const double d = std::abs(E[k][c] - g) / std::max(g, 1e-3);
                    worst = std::max(worst, d);
                    same = same && d < 1e-5;
                }
                agree += same;
                lit += E[k][1] > 0;
            }
            std::printf(
                "  [measured] shadows %d, %s box: %zu points, %zu lit, %.4f agree, worst %.2e\n",
                shadows, own_box ? "points'" : "frame's", pts.size(), lit,
                static_cast<double>(agree) / pts.size(), worst);
            EXPECT_GT(lit, pts.size() / 2);
            if (shadows && own_box)
                EXPECT_GT(static_cast<double>(agree), 0.85 * static_cast<double>(pts.size()));
            else
                EXPECT_EQ(agree, pts.size());
        }
    }
    // The closed form on a box's top and bottom faces.
    const char* light =
        "[[lights]]\ntype = \"directional\"\ndirection = [0.5, 1, 0.3]\n"
        "irradiance = [1, 2, 3]\n";
    const Scene box = parse_scene(medium_box("0", light), "m.toml", ".");
    const Vec3 w = normalize(Vec3{0.5, 1, 0.3});
    std::vector<BoundaryPoint> faces;
    for (int k = 0; k < 20; ++k) {
        const double x = -0.9 + 0.09 * k, z = 0.8 - 0.08 * k;
        faces.push_back({{x, box.shapes[0].mesh.bounds()[1].y, z}, {0, 1, 0}, 0});
        faces.push_back({{x, box.shapes[0].mesh.bounds()[0].y, z}, {0, -1, 0}, 0});
    }
    const std::vector<std::array<double, 3>> E = boundary_irradiance(box, faces, LightingOptions{});
    const double t = 1 - dielectric::fresnel_dielectric(w.y, 1.4);
    for (std::size_t k = 0; k < faces.size(); ++k)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(E[k][c], k % 2 ? 0.0 : t * (c + 1) * w.y, 1e-9) << k << " " << c;
    // Bad points: not on a medium, not finite.
    EXPECT_THROW(boundary_irradiance(box, {{{0, 0, 0}, {0, 1, 0}, -1}}, LightingOptions{}),
                 std::invalid_argument);
    EXPECT_THROW(boundary_irradiance(box, {{{0, NAN, 0}, {0, 1, 0}, 0}}, LightingOptions{}),
                 std::invalid_argument);
}

TEST(Lighting, ExitWeightIntegratesToOne) {
    for (double eta : {1.0, 1.3, 1.5}) {
        for (double alpha : {0.0, 0.1, 0.5}) {
            const BoundaryTransmittance T(eta, alpha);
            // Simpson over mu of 2 pi exit_weight(mu) mu.
            const int n = 20000;
            double s = 0;
            for (int k = 0; k <= n; ++k) {
                const double mu = static_cast<double>(k) / n;
                const double f = 2 * kPi * T.exit_weight(mu) * mu;
                s += f * (k == 0 || k == n ? 1 : (k % 2 ? 4 : 2));
            }
            s /= 3.0 * n;
            EXPECT_NEAR(s, 1.0, 1e-6) << eta << " " << alpha;
            if (alpha == 0) {
                EXPECT_NEAR(T(1.0), 1 - std::pow((eta - 1) / (eta + 1), 2), 1e-15);
            }
        }
    }
}

TEST(Lighting, GgxTransmittanceAgainstVolpathSampling) {
    // The table's quadrature against an independent estimate: volpath's sampling of the rough
    // dielectric (visible normals, importance transport), the transmitted weight per sample.
    RngStream rng(5, rng_domain::kTest + 90, 0);
    const std::int64_t n = static_cast<std::int64_t>(100000 * testing::test_scale());
    const double eta = 1.4;
    double worst_z = 0;
    for (double alpha : {0.05, 0.3, 0.8}) {
        const BoundaryTransmittance T(eta, alpha);
        for (double mu : {0.95, 0.6, 0.3, 0.1}) {
            const Vec3 wo{std::sqrt(1 - mu * mu), 0, mu};
            double sum = 0, sum2 = 0;
            for (std::int64_t k = 0; k < n; ++k) {
                const double uc = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                const auto smp = volpath::sample_rough_dielectric(
                    wo, eta, alpha, uc, u1, u2, volpath::TransportMode::kImportance);
                if (!smp || smp->reflection) continue;
                const double wgt = smp->f * std::abs(smp->wi.z) / smp->pdf;
                sum += wgt;
                sum2 += wgt * wgt;
            }
            const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
            const double q = BoundaryTransmittance::ggx(mu, eta, alpha, 64);
            const double z = (q - mean) / se;
            worst_z = std::max(worst_z, std::abs(z));
            std::printf("alpha %g mu %g: quadrature %.5f MC %.5f +- %.5f\n", alpha, mu, q, mean,
                        se);
            EXPECT_LT(std::abs(z), 4.0) << alpha << " " << mu << ": " << q << " vs " << mean;
            // The table interpolates the quadrature closely.
            EXPECT_NEAR(T(mu), q, 2e-3) << alpha << " " << mu;
        }
    }
    std::printf("  [measured] GGX transmittance table vs volpath sampling: worst |z| %.2f\n",
                worst_z);
    // The smooth limit.
    EXPECT_NEAR(BoundaryTransmittance::ggx(0.7, eta, 1e-4, 64),
                1 - dielectric::fresnel_dielectric(0.7, eta), 1e-3);
}

TEST(Lighting, SpecularAgainstVolpath) {
    // First-surface reflection of a medium sphere, direct light only. volpath's radiance at
    // max_depth = 1 is exactly that on a medium seen from outside (transmitted paths end at
    // the boundary from inside). Rough: GGX off a sphere light and the sun's disc; smooth: F
    // times the environment or sphere light in the mirror direction.
    const std::string rough = R"(
[scene]
name = "spec"
[camera]
position = [0, 0, 6]
target = [0, 0, 0]
fov_y_deg = 30
width = 24
height = 24
[[lights]]
type = "sphere"
position = [2, 3, 4]
radius = 1.0
radiance = [4, 3, 2]
[[lights]]
type = "directional"
direction = [-1, 0.5, 1]
angular_radius_deg = 8
irradiance = [1, 1, 1]
[[materials]]
name = "m"
sigma_a_per_mm = 0.2
sigma_s_per_mm = 2.0
eta = 1.4
roughness = 0.3
[[shapes]]
type = "sphere"
radius = 1.2
subdivisions = 5
material = "m"
)";
    const std::string smooth = R"(
[scene]
name = "spec"
[camera]
position = [0, 0, 6]
target = [0, 0, 0]
fov_y_deg = 30
width = 24
height = 24
[[lights]]
type = "sphere"
position = [2, 3, 4]
radius = 1.0
radiance = [4, 3, 2]
[[lights]]
type = "environment"
radiance = [0.3, 0.4, 0.5]
[[materials]]
name = "m"
sigma_a_per_mm = 0.2
sigma_s_per_mm = 2.0
eta = 1.4
[[shapes]]
type = "sphere"
radius = 1.2
subdivisions = 5
material = "m"
)";
    for (const std::string* text : {&rough, &smooth}) {
        const Scene s = parse_scene(*text, "spec.toml", ".");
        const volpath::RenderResult vp = render_vp(s, 24, 24, 600, 11);
        LightingOptions o;
        o.light_samples = 256;
        o.shadow_map_size = 256;
        const Rendered r = render_rt(s, 24, 24, 8, o);
        const Agreement a = agree(r, r.g.specular, vp.image, 1, 1e300);
        // volpath's own "specular" layer is all of it there (volpath-render-3: before, it left
        // out the next-event estimate at the first rough boundary, 0 % of the radiance).
        double sl = 0, rl = 0;
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 24; ++x) {
                if (!interior(r, x, y, 1e300)) continue;
                sl += vp.image.layer("specular").at(x, y, 0);
                rl += vp.image.layer("radiance").at(x, y, 0);
            }
        std::printf(
            "  [measured] %s specular: %d pixel-channels, chi2/n %.2f, mean z %.3f, max |z| %.2f; "
            "volpath's specular / radiance layer sums %.3f\n",
            text == &rough ? "rough" : "smooth", a.n, a.chi2 / a.n, a.mean_z, a.max_z, sl / rl);
        EXPECT_NEAR(sl / rl, 1.0, 1e-9);
        ASSERT_GT(a.n, 300);
        EXPECT_LT(a.chi2, testing::chi2_critical(a.n, 0.01));
        // No offset beyond 1 % RMS. (Against volpath-render-3's noisier reference the mean z
        // was also within 4 / sqrt(n); with volpath-render-4's Sobol points, which stratify the
        // pixel and the Fresnel choice, the smooth sphere's is 0.20, 4.3 / sqrt(n), while the
        // RMS difference stays within the noise, offset 0.0000: a shift far below a percent that
        // the test does not resolve further.)
        std::printf("  [measured] %s specular: offset beyond the noise %.4f\n",
                    text == &rough ? "rough" : "smooth", a.bias);
        EXPECT_LT(a.bias, 0.01);
        // A boundary 10 % too reflective is detected.
        const Agreement off = agree(r, r.g.specular, vp.image, 1.1, 1e300);
        EXPECT_GT(off.mean_z, 4 / std::sqrt(off.n));
    }
}

TEST(Lighting, TranslucencyOfASlabLitFromBehind) {
    // A 0.5 mm slab, the camera in front, a directional light behind (normal and oblique):
    // thickness = 0.5 / cos, translucency = E cos T_slab(0.5 / cos) on the front face.
    const SlabTransmittance table{
        {0.1, 0.3, 1.0, 3.0},
        {{{0.8, 0.85, 0.9}}, {{0.5, 0.6, 0.7}}, {{0.2, 0.3, 0.4}}, {{0.01, 0.02, 0.05}}}};
    for (double tilt : {0.0, 40.0}) {
        const double th = tilt * kPi / 180;
        char light[256];
        std::snprintf(light, sizeof light,
                      "[[lights]]\ntype = \"directional\"\ndirection = [%.17g, 0, %.17g]\n"
                      "irradiance = [1, 2, 3]\n",
                      std::sin(th), -std::cos(th));
        const std::string text = std::string(R"(
[scene]
name = "slab"
[camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 15
width = 16
height = 16
)") + light + R"(
[[materials]]
name = "m"
sigma_a_per_mm = 0.1
sigma_s_per_mm = 1.0
eta = 1.3
[[shapes]]
type = "box"
size = [8, 8, 0.5]
material = "m"
)";
        const Scene s = parse_scene(text, "slab.toml", ".");
        LightingOptions o;
        o.shadow_map_size = 256;
        o.thickness_layer = true;
        const Rendered r = render_rt(s, 16, 16, 1, o, {table});
        const double d = 0.5 / std::cos(th);
        const auto Ts = table.at(d);
        double worst_t = 0, worst_tr = 0;
        for (std::size_t i = 0; i < r.g.samples(); ++i) {
            ASSERT_EQ(r.g.material[i], 0);
            worst_t = std::max(worst_t, std::abs(r.g.thickness[i] - d));
            for (int c = 0; c < 3; ++c) {
                const double e = (c + 1) * std::cos(th) * Ts[static_cast<std::size_t>(c)];
                worst_tr = std::max(worst_tr, std::abs(r.g.translucency[3 * i + c] - e) / e);
            }
            EXPECT_EQ(r.g.irradiance[3 * i], 0.f);  // the front faces away from the light
        }
        std::printf(
            "  [measured] slab tilt %.0f: thickness off by at most %.2e, translucency by "
            "%.2e relative\n",
            tilt, worst_t, worst_tr);
        EXPECT_LT(worst_t, 1e-5);
        EXPECT_LT(worst_tr, 1e-5);
        // Without the thickness layer (the default) translucency is the same bits (it looks
        // the thickness up itself) and the layer holds 0.
        o.thickness_layer = false;
        const Rendered off = render_rt(s, 16, 16, 1, o, {table});
        EXPECT_EQ(off.g.translucency, r.g.translucency);
        EXPECT_EQ(off.g.irradiance, r.g.irradiance);
        EXPECT_TRUE(std::all_of(off.g.thickness.begin(), off.g.thickness.end(),
                                [](float t) { return t == 0.f; }));
    }
    // The table: log-linear between entries, clamped outside.
    EXPECT_NEAR(table.at(0.2)[0], std::sqrt(0.8 * 0.5), 1e-12);
    EXPECT_EQ(table.at(0.01)[1], 0.85);
    EXPECT_EQ(table.at(10)[2], 0.05);
    EXPECT_EQ(SlabTransmittance{}.at(1)[0], 0.0);
}

TEST(Lighting, VolpathMaxDepthIsKeyedOnlyWhenSet) {
    // volpath's direct-lighting reference: the checkpoint key of a default render is what it
    // was (no max_depth item), and max_depth = 1 changes it.
    const Scene s = parse_scene(kDiffuseScene, "diffuse.toml", ".");
    volpath::RenderOptions o;
    const std::string a = volpath::render_fingerprint(s, o);
    EXPECT_EQ(a.find("max_depth"), std::string::npos);
    o.max_depth = 1;
    const std::string b = volpath::render_fingerprint(s, o);
    EXPECT_NE(b.find("max_depth"), std::string::npos);
    EXPECT_NE(a, b);
}

TEST(Lighting, RowShadowTestsEqualTheGeneralPass) {
    // Directional light samples (a sun's disc, the environment) with one orthographic map each
    // take the row-wise shadow test (four samples at a time, then the rest one by one); with a
    // slab table the same samples take the general per-sample pass. Both must give the same
    // bits in every layer but translucency, at widths with and without a remainder of four.
    Scene s = parse_scene(kDiffuseScene, "diffuse.toml", ".");
    s.lights.erase(s.lights.begin());  // no sphere light: it would take the general pass
    s.materials[1].kind = SceneMaterial::Kind::kMedium;  // the sphere: a rough medium
    s.materials[1].medium.eta = 1.3;
    s.materials[1].roughness = 0.2;
    s.materials[1].medium.sigma_a_per_cm = {1, 1, 1};
    s.materials[1].medium.sigma_s_per_cm = {10, 10, 10};
    const SlabTransmittance table{{0.1, 1.0}, {{{0.5, 0.5, 0.5}}, {{0.1, 0.1, 0.1}}}};
    LightingOptions o;
    o.light_samples = 4;
    o.environment_samples = 8;
    o.shadow_map_size = 128;
    for (const auto& [w, ss] : {std::pair{23, 1}, std::pair{24, 2}, std::pair{25, 1}}) {
        const Rendered rows = render_rt(s, w, w, ss, o);
        const Rendered general = render_rt(s, w, w, ss, o, {{}, table});
        auto same = [](const std::vector<float>& a, const std::vector<float>& b) {
            return a.size() == b.size() &&
                   std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
        };
        EXPECT_TRUE(same(rows.g.irradiance, general.g.irradiance)) << w;
        EXPECT_TRUE(same(rows.g.surface, general.g.surface)) << w;
        EXPECT_TRUE(same(rows.g.specular, general.g.specular)) << w;
        EXPECT_TRUE(same(rows.g.exit_weight, general.g.exit_weight)) << w;
        // The row path for 1 and 2 threads.
        GBuffer one;
        tbb::task_arena arena(1);
        const int size = w, spp = ss;  // (a lambda may not capture a structured binding in C++20)
        arena.execute([&] { one = render_rt(s, size, size, spp, o).g; });
        EXPECT_TRUE(same(rows.g.irradiance, one.irradiance)) << w;
        EXPECT_TRUE(same(rows.g.surface, one.surface)) << w;
        EXPECT_TRUE(same(rows.g.specular, one.specular)) << w;
        // Something was lit and something shadowed: the test compares real work.
        const auto lit = std::count_if(rows.g.irradiance.begin(), rows.g.irradiance.end(),
                                       [](float v) { return v > 0; });
        EXPECT_GT(lit, 0) << w;
        EXPECT_GT(std::count_if(general.g.translucency.begin(), general.g.translucency.end(),
                                [](float v) { return v > 0; }),
                  0)
            << w;
    }
}

TEST(Lighting, BitIdenticalForOneAndTwoThreads) {
    Scene s = parse_scene(kDiffuseScene, "diffuse.toml", ".");
    // And a medium with translucency, so that every layer is exercised.
    s.materials[1].kind = SceneMaterial::Kind::kMedium;
    s.materials[1].medium.eta = 1.3;
    s.materials[1].roughness = 0.2;
    s.materials[1].medium.sigma_a_per_cm = {1, 1, 1};
    s.materials[1].medium.sigma_s_per_cm = {10, 10, 10};
    const SlabTransmittance table{{0.1, 1.0}, {{{0.5, 0.5, 0.5}}, {{0.1, 0.1, 0.1}}}};
    const std::vector<SlabTransmittance> slabs{{}, table};
    LightingOptions o;
    o.light_samples = 4;
    o.environment_samples = 8;
    o.shadow_map_size = 128;
    o.thickness_layer = true;
    GBuffer g[2];
    for (int t = 0; t < 2; ++t) {
        tbb::task_arena arena(t + 1);
        arena.execute([&] { g[t] = render_rt(s, 24, 24, 2, o, slabs).g; });
    }
    auto same = [](const auto& a, const auto& b) {
        return a.size() == b.size() &&
               std::equal(a.begin(), a.end(), b.begin(),
                          [](auto x, auto y) { return std::memcmp(&x, &y, sizeof x) == 0; });
    };
    EXPECT_TRUE(same(g[0].view_z, g[1].view_z));
    EXPECT_TRUE(same(g[0].normal, g[1].normal));
    EXPECT_TRUE(same(g[0].irradiance, g[1].irradiance));
    EXPECT_TRUE(same(g[0].exit_weight, g[1].exit_weight));
    EXPECT_TRUE(same(g[0].specular, g[1].specular));
    EXPECT_TRUE(same(g[0].surface, g[1].surface));
    EXPECT_TRUE(same(g[0].thickness, g[1].thickness));
    EXPECT_TRUE(same(g[0].translucency, g[1].translucency));
    double e = 0, tr = 0;
    for (std::size_t i = 0; i < g[0].samples(); ++i) {
        e += g[0].irradiance[3 * i];
        tr += g[0].translucency[3 * i];
    }
    EXPECT_GT(e, 0);
    EXPECT_GT(tr, 0);
}

}  // namespace
}  // namespace ssslab::realtime
