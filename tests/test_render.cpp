// The scene renderer (volpath/render.h) against closed forms, per pixel with z-tests against
// the reference and the pixel's standard error (as Mitsuba's render tests do): a convex diffuse
// object under a constant environment reflects albedo x L exactly; the white furnace (albedo 1
// medium behind a smooth or index-matched boundary, constant environment) returns L in every
// pixel; determinism for any thread count; resume from a checkpoint; refusals.
#include "core/config.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/image_compare.h"
#include "core/scene.h"
#include "testing.h"
#include "volpath/render.h"
#include "volpath/sphere.h"

#include <gtest/gtest.h>
#include <optional>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ssslab::volpath {
namespace {

std::string scene_text(const std::string& material, const std::string& lights) {
    return R"(
[scene]
name = "t"
[camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 30
width = 24
height = 24
)" + lights +
           material +
           R"(
[[shapes]]
type = "sphere"
radius = 1.5
subdivisions = 4
material = "m"
)";
}

const char* kEnv = "[[lights]]\ntype = \"environment\"\nradiance = [1.0, 0.5, 0.25]\n";

RenderOptions options(double spp, int threads = 0) {
    RenderOptions o;
    o.budget.samples = static_cast<std::int64_t>(spp * testing::test_scale());
    o.threads = threads;
    return o;
}

// Whether the whole pixel sees the sphere (all four corner rays hit a sphere of radius r_in)
// or none of it (the centre ray passes farther than r_out + a pixel from the centre).
int coverage(int x, int y, int n, double r_in, double r_out) {
    const double th = std::tan(15.0 * 3.14159265358979 / 180);
    auto miss_distance = [&](double px, double py) {
        const double ux = (2 * px / n - 1) * th, uy = (1 - 2 * py / n) * th;
        // Ray from (0, 0, 10) along (ux, uy, -1): distance of the origin to the ray.
        const double l2 = ux * ux + uy * uy + 1;
        return 10 * std::sqrt((ux * ux + uy * uy) / l2);
    };
    bool all_in = true;
    for (int a = 0; a <= 1; ++a)
        for (int b = 0; b <= 1; ++b) all_in = all_in && miss_distance(x + a, y + b) < r_in;
    if (all_in) return 1;
    if (miss_distance(x + 0.5, y + 0.5) > r_out + 20 * th / n) return 0;
    return -1;
}

TEST(Render, ConvexDiffuseObjectReflectsAlbedoTimesTheEnvironment) {
    // A convex diffuse object under a constant environment reflects albedo x L. With the
    // environment sampled over the sphere (before volpath-render-6) each pixel is an estimate
    // within its standard error; sampled about the normal by cos(theta), as the BSDF samples,
    // NEE and BSDF sampling each carry half of albedo x L in every sample (power heuristic of
    // equal densities), so the image is exact up to float rounding, without noise.
    const Scene s = parse_scene(
        scene_text("[[materials]]\nname = \"m\"\ntype = \"diffuse\"\nalbedo = [0.8, 0.6, 0.3]\n",
                   kEnv),
        "t.toml", ".");
    const double env[3] = {1.0, 0.5, 0.25}, albedo[3] = {0.8, 0.6, 0.3};
    const double zc = testing::normal_quantile(1 - 0.0005 / (24 * 24 * 3));
    RenderResult r;
    for (const bool cosine : {false, true}) {
        SCOPED_TRACE(cosine ? "cosine" : "sphere");
        RenderOptions o = options(64);
        o.environment_cosine = cosine;
        r = render(s, o);
        const ImageLayer& L = r.image.layer("radiance");
        const ImageLayer& E = r.image.layer("radiance.stderr");
        int inside = 0, outside = 0;
        double worst = 0;
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 24; ++x) {
                const int cov = coverage(x, y, 24, 1.5 * 0.995, 1.5);  // the icosphere's inradius
                for (int c = 0; c < 3; ++c) {
                    if (cov == 0) {
                        EXPECT_EQ(L.at(x, y, c), static_cast<float>(env[c]));
                        ++outside;
                    } else if (cov == 1) {
                        const double expect = albedo[c] * env[c];
                        ++inside;
                        if (cosine) {
                            worst = std::max(worst, std::fabs(L.at(x, y, c) / expect - 1));
                            EXPECT_NEAR(L.at(x, y, c), expect, 1e-6 * expect) << x << "," << y;
                            EXPECT_LT(E.at(x, y, c), 1e-6 * expect) << x << "," << y;
                            continue;
                        }
                        const double z = (L.at(x, y, c) - expect) / E.at(x, y, c);
                        worst = std::max(worst, std::fabs(z));
                        EXPECT_LT(std::fabs(z), zc) << x << "," << y << " c" << c;
                    }
                }
            }
        std::printf(
            "  [measured] diffuse sphere, environment sampled %s: %d pixel-channels on "
            "it, worst %s %.3g\n",
            cosine ? "by cos(theta)" : "over the sphere", inside, cosine ? "relative error" : "|z|",
            worst);
        EXPECT_GT(inside, 100);
        EXPECT_GT(outside, 100);
    }
    // Nothing entered a medium, nothing was a dielectric reflection.
    EXPECT_EQ(r.image.layer("subsurface").at(12, 12, 0), 0.0f);
    EXPECT_GT(r.image.layer("depth").at(12, 12), 8.0f);
}

TEST(Render, WhiteFurnaceWithAMediumBehindADielectricBoundary) {
    // Albedo 1 inside, constant radiance outside: the radiance field is L everywhere outside,
    // whatever the boundary's index (radiance is compressed by eta^2 going in and restored
    // going out). Smooth boundaries with eta 1.5 and 1 (index-matched), chromatic scattering
    // with a different g per channel (hero MIS), 4 mfp across; absorption analog and weighted
    // (their spectral weights differ even where nothing is absorbed).
    for (const Absorption absorption : {Absorption::kAnalog, Absorption::kWeighted})
        for (const char* eta : {"1.5", "1.0"}) {
            SCOPED_TRACE(std::string(eta) + " " + to_string(absorption));
            const std::string m = std::string(
                                      "[[materials]]\nname = \"m\"\nsigma_a_per_mm = 0\n"
                                      "sigma_s_per_mm = [1.0, 3.0, 8.0]\ng = [0.0, 0.5, 0.9]\n"
                                      "eta = ") +
                                  eta + "\n";
            const Scene s = parse_scene(
                scene_text(m, "[[lights]]\ntype = \"environment\"\nradiance = 1\n"), "t.toml", ".");
            RenderOptions o = options(144);  // 48 batches: SEs that are nearly exact
            o.absorption = absorption;
            const RenderResult r = render(s, o);
            const ImageLayer& L = r.image.layer("radiance");
            const ImageLayer& E = r.image.layer("radiance.stderr");
            // A z with the standard error of B batch means is Student-t with B - 1 degrees of
            // freedom (heavier tails than the normal's at B = 48).
            const double zc = testing::student_t_quantile(1 - 0.0005 / (24 * 24 * 3),
                                                          static_cast<double>(r.run.batches - 1));
            double worst = 0;
            int tested = 0;
            for (int y = 0; y < 24; ++y)
                for (int x = 0; x < 24; ++x)
                    for (int c = 0; c < 3; ++c) {
                        if (!(E.at(x, y, c) > 0)) {
                            EXPECT_EQ(L.at(x, y, c), 1.0f) << x << "," << y;  // background
                            continue;
                        }
                        const double z = (L.at(x, y, c) - 1.0) / E.at(x, y, c);
                        worst = std::max(worst, std::fabs(z));
                        ++tested;
                        EXPECT_LT(std::fabs(z), zc)
                            << x << "," << y << " c" << c << " " << L.at(x, y, c);
                    }
            std::printf(
                "  [measured] furnace eta %s, %s absorption: %d pixel-channels, worst |z| %.2f\n",
                eta, to_string(absorption), tested, worst);
            EXPECT_GT(tested, 200);
            EXPECT_GT(r.image.layer("subsurface").at(12, 12, 1), 0.5f);
        }
}

TEST(Render, AnAbsorbingSphereUnderAWhiteSkyShowsWhatTheLitSphereEngineDoesNotAbsorb) {
    // Reciprocity: under a constant environment of radiance 1, a camera ray that meets the sphere
    // sees 1 - (1 - F) P(absorbed) of a photon entering along it, so the image mean is
    // 1 - cover x a, with `cover` the part of the image inside the silhouette and `a` the
    // absorbed part of a beam spread uniformly over the disc the sphere presents (for a far
    // camera: every ray meeting a sphere is such a beam's ray at the same distance from the
    // centre, and their distances are spread as over the disc up to (R / D)^2 = 1e-4). The lit-
    // sphere engine (volpath/sphere.h) gives 1 - a as its first-surface reflection (quadrature)
    // plus the part that left after entering, traced from the light on the exact sphere, one run
    // per channel; the renderer traces from the camera through an icosphere of 20,480 triangles
    // with one hero-wavelength walk for the three channels. Chromatic, every albedo near 1 (the
    // walks of hundreds of events where Cycles 3.4's means drift: README "Ground truth against
    // Cycles"), weighted and analog absorption, and a dense (eta 2.5) boundary that traps
    // most of the light by total internal reflection.
    struct Case {
        const char* eta;
        double eta_v;
        std::array<double, 3> sa, ss;  // per mm
        double g;
    };
    const Case cases[] = {{"1.3", 1.3, {0.01, 0.02, 0.04}, {1.0, 0.8, 0.6}, 0.3},
                          {"2.5", 2.5, {0.002, 0.01, 0.05}, {0.5, 1.0, 2.0}, -0.3}};
    const double R = 2.5, D = 100 * R;                       // mm
    const double half = 1.1 * R / std::sqrt(D * D - R * R);  // tan of half the field of view
    const double fov = 2 * std::atan(half) * 180 / std::numbers::pi;
    const double s = R / std::sqrt(D * D - R * R);  // the silhouette's radius on that plane
    const double cover = std::numbers::pi * s * s / (4 * half * half);
    for (const Case& k : cases) {
        SphereScene sc;
        sc.medium.eta = k.eta_v;
        for (std::size_t c = 0; c < 3; ++c) {
            sc.medium.sigma_a_per_cm[c] = 10 * k.sa[c];
            sc.medium.sigma_s_per_cm[c] = 10 * k.ss[c];
            sc.medium.g[c] = k.g;
        }
        sc.radius_cm = R / 10;
        SphereOptions so;
        so.budget.samples = static_cast<std::int64_t>(1.6e6 * testing::test_scale());
        so.image = false;
        so.seed = 71;
        const SphereRun ref = simulate_sphere(sc, so);
        for (const Absorption absorption : {Absorption::kWeighted, Absorption::kAnalog}) {
            const std::string what = std::string("eta ") + k.eta + ", " + to_string(absorption);
            SCOPED_TRACE(what);
            char text[1024];
            std::snprintf(text, sizeof text, R"(
[scene]
name = "t"
[camera]
position = [0, 0, %.17g]
target = [0, 0, 0]
fov_y_deg = %.17g
width = 32
height = 32
[[lights]]
type = "environment"
radiance = 1
[[materials]]
name = "m"
sigma_a_per_mm = [%g, %g, %g]
sigma_s_per_mm = [%g, %g, %g]
g = %g
eta = %s
[[shapes]]
type = "sphere"
radius = %g
subdivisions = 5
material = "m"
)",
                          D, fov, k.sa[0], k.sa[1], k.sa[2], k.ss[0], k.ss[1], k.ss[2], k.g, k.eta,
                          R);
            const Scene scene = parse_scene(text, "t.toml", ".");
            RenderOptions o = options(1536);
            o.absorption = absorption;
            const RenderResult r = render(scene, o);
            const ImageEstimate image = estimate_with_stderr(r.image, "radiance", what);
            for (int c = 0; c < 3; ++c) {
                const auto [mean, se] = image_mean(image, c);
                const std::size_t i = static_cast<std::size_t>(c);
                const double expected = 1 - cover * (1 - ref.specular_expected - ref.diffuse[i]);
                const double se_expected = cover * ref.diffuse_se[i];
                const double z = (mean - expected) / std::hypot(se, se_expected);
                std::printf(
                    "  [measured] %s, channel %d: image mean %.6f +- %.6f, lit sphere %.6f +- "
                    "%.6f (absorbed %.4f), z %.2f\n",
                    what.c_str(), c, mean, se, expected, se_expected,
                    1 - ref.specular_expected - ref.diffuse[i], z);
                EXPECT_LT(std::fabs(z), testing::normal_quantile(1 - 0.001 / 24)) << c;
            }
        }
    }
}

TEST(Render, IndexMatchedMediaAreLitThroughTheirBoundaryByNextEventEstimation) {
    // An index-matched chromatic medium (g differs per channel) lit by a sphere light and a dim
    // environment: NEE at every scattering vertex with shadow rays through the boundary, MIS
    // with phase sampling, against the path crossing the boundary alone (which finds the light
    // only by chance). The same image within the noise, per 4 x 4 block, for a light large
    // enough that the plain estimator's noise is Gaussian; for a small light, far less noise.
    const std::string m =
        "[[materials]]\nname = \"m\"\nsigma_a_per_mm = [0.05, 0.1, 0.2]\n"
        "sigma_s_per_mm = [1.0, 3.0, 8.0]\ng = [0.0, 0.5, 0.9]\neta = 1.0\n";
    auto lights = [](const char* radius, const char* radiance) {
        return std::string("[[lights]]\ntype = \"sphere\"\nposition = [4, 4, 3]\nradius = ") +
               radius + "\nradiance = " + radiance +
               "\n[[lights]]\ntype = \"environment\"\nradiance = 0.05\n";
    };
    auto both = [&](const Scene& s, double spp_nee, double spp_plain,
                    RenderHero hero = RenderHero::kUniform,
                    std::optional<Absorption> absorption = std::nullopt) {
        RenderOptions with = options(spp_nee), without = options(spp_plain);
        with.hero = hero;
        with.absorption = absorption;
        without.index_matched_nee = false;
        without.hero = RenderHero::kUniform;
        without.seed = 2;
        const RenderResult a = render(s, with), b = render(s, without);
        return compare_images(estimate_with_stderr(a.image, "radiance", "NEE"),
                              estimate_with_stderr(b.image, "radiance", "no NEE"), 4);
    };
    const Scene large = parse_scene(scene_text(m, lights("1.5", "3")), "t.toml", ".");
    const ImageComparison c = both(large, 256, 1024, RenderHero::kUniform);
    for (size_t k = 0; k < 3; ++k) EXPECT_LT(std::fabs(c.z_mean[k]), 4.0) << k;
    EXPECT_GT(c.p_min_corrected(), 1e-3);
    // The hero chosen at the medium's entry by throughput x albedo, in a medium whose albedos
    // differ (0.95, 0.5, 0.17: hero probabilities 0.59, 0.31, 0.10) and with g per channel, so
    // that the MIS of NEE against phase sampling needs the hero probabilities.
    const std::string chromatic =
        "[[materials]]\nname = \"m\"\nsigma_a_per_mm = [0.05, 3.0, 40.0]\n"
        "sigma_s_per_mm = [1.0, 3.0, 8.0]\ng = [0.0, 0.5, 0.9]\neta = 1.0\n";
    const Scene strong = parse_scene(scene_text(chromatic, lights("1.5", "3")), "c.toml", ".");
    // With it, each channel's own absorption policy: R and G (albedo 0.95, 0.5) weighted, B
    // (0.17) analog, so that heroes of different policies share one MIS.
    for (const auto absorption :
         {std::optional<Absorption>{}, std::optional{Absorption::kPerChannel}}) {
        const ImageComparison ta =
            both(strong, 256, 1024, RenderHero::kThroughputAlbedo, absorption);
        for (size_t k = 0; k < 3; ++k) EXPECT_LT(std::fabs(ta.z_mean[k]), 4.0) << k;
        EXPECT_GT(ta.p_min_corrected(), 1e-3);
        std::printf(
            "  [measured] index-matched NEE, hero by throughput x albedo, %s absorption, vs "
            "none: block chi2 %.1f/%d %.1f/%d %.1f/%d, image-mean z %.2f %.2f %.2f\n",
            absorption ? to_string(*absorption) : "auto", ta.chi2[0], ta.dof[0], ta.chi2[1],
            ta.dof[1], ta.chi2[2], ta.dof[2], ta.z_mean[0], ta.z_mean[1], ta.z_mean[2]);
    }
    const ImageComparison small =
        both(parse_scene(scene_text(m, lights("0.3", "75")), "s.toml", "."), 64, 1024);
    double ratio[3];
    for (size_t k = 0; k < 3; ++k) ratio[k] = small.se_a[k] / small.se_b[k];
    // 16x fewer samples, a fraction of the noise in R and G (B, g = 0.9 at 8/mm, is dominated
    // by its many forward scatterings either way).
    EXPECT_LT(ratio[0], 0.5);
    EXPECT_LT(ratio[1], 0.5);
    std::printf(
        "  [measured] index-matched NEE vs none: block chi2 %.1f/%d %.1f/%d %.1f/%d; small "
        "light: image-mean SE ratio (64 vs 1024 spp) %.2f %.2f %.2f\n",
        c.chi2[0], c.dof[0], c.chi2[1], c.dof[1], c.chi2[2], c.dof[2], ratio[0], ratio[1],
        ratio[2]);

    // A point light, which only NEE can reach, now lights the medium (refused only behind
    // refractive or heterogeneous smooth boundaries).
    const std::string point =
        "[[lights]]\ntype = \"point\"\nposition = [4, 4, 3]\nintensity = 20\n";
    const Scene p = parse_scene(scene_text(m, point), "p.toml", ".");
    EXPECT_NO_THROW(check_renderable(p));
    const RenderResult r = render(p, options(16));
    EXPECT_GT(r.image.layer("subsurface").at(12, 12, 0), 0.01f);
}

TEST(Render, IndexMatchedHalfSpaceUnderASunIsAnalyticSingleScattering) {
    // A nearly absorbing (albedo 1e-4, so multiple scattering is below 1e-4 of the image)
    // index-matched half-space lit by a sun straight above and seen at 45 degrees: each pixel
    // is the closed form of single scattering, (sigma_s / sigma_t) E / (4 pi) / (1 + mu_v) for
    // an isotropic phase function and a view cosine mu_v, averaged over the pixel. Catches
    // geometric offsets at the boundary (a walk started eps deep loses exp(-sigma_t eps)), the
    // NEE through the index-matched boundary and the shadow transmittance.
    const std::string text = R"(
[scene]
name = "ss"
[camera]
position = [0, 50, 50]
target = [0, 0, 0]
fov_y_deg = 10
width = 16
height = 16
[[lights]]
type = "directional"
direction = [0, 1, 0]
irradiance = 10000
angular_radius_deg = 0.27
[[materials]]
name = "m"
sigma_a_per_mm = [1.0, 0.5, 2.0]
sigma_s_per_mm = 0.0001
g = 0
eta = 1.0
[[shapes]]
type = "box"
size = [2000, 400, 2000]
translate = [0, -200, 0]
material = "m"
)";
    const Scene s = parse_scene(text, "ss.toml", ".");
    // The closed form per pixel-channel (8 x 8 view directions over the pixel), the reference
    // of both policies.
    const SceneCamera& cam = s.camera;
    const Vec3 f = normalize(cam.target - cam.position), rt = normalize(cross(f, cam.up)),
               up = cross(rt, f);
    const double th = std::tan(0.5 * cam.fov_y_deg * std::numbers::pi / 180);
    std::vector<double> ref(16 * 16 * 3, 0.0);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                const double sa[3] = {1.0, 0.5, 2.0};
                const double ratio = 1e-4 / (sa[c] + 1e-4);
                double& r = ref[static_cast<size_t>((y * 16 + x) * 3 + c)];
                for (int a = 0; a < 8; ++a)
                    for (int b = 0; b < 8; ++b) {
                        const double ndx = (2 * (x + (a + 0.5) / 8) / 16 - 1) * th;
                        const double ndy = (1 - 2 * (y + (b + 0.5) / 8) / 16) * th;
                        const Vec3 d = normalize(f + rt * ndx + up * ndy);
                        r += ratio * 10000 / (4 * std::numbers::pi) / (1 - d.y) / 64;
                    }
            }
    // The medium's albedo (1e-4) makes its walks analog; weighted absorption carries the albedo
    // in the weights and does NEE at every collision with them. Either with the hero chosen
    // uniformly or by throughput x albedo (probabilities 0.29, 0.57, 0.14 here).
    for (const RenderHero hero : {RenderHero::kUniform, RenderHero::kThroughputAlbedo})
        for (const Absorption absorption : {Absorption::kAnalog, Absorption::kWeighted}) {
            SCOPED_TRACE(std::string(to_string(absorption)) + " " + to_string(hero));
            RenderOptions o = options(192);
            o.absorption = absorption;
            o.hero = hero;
            const RenderResult r = render(s, o);
            const ImageLayer& L = r.image.layer("radiance");
            const ImageLayer& E = r.image.layer("radiance.stderr");
            testing::ZTally t;
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 16; ++x)
                    for (int c = 0; c < 3; ++c)
                        t.add((L.at(x, y, c) - ref[static_cast<size_t>((y * 16 + x) * 3 + c)]) /
                              E.at(x, y, c));
            std::printf(
                "  [measured] analytic single scattering, %s absorption, %s hero: chi-square %.1f "
                "over %d pixel-channels, worst |z| %.2f\n",
                to_string(absorption), to_string(hero), t.chi2, t.n, t.max_abs);
            EXPECT_LT(t.chi2, testing::chi2_critical(t.n, 0.001));
            EXPECT_LT(t.max_abs, testing::normal_quantile(1 - 0.0005 / t.n));
        }
}

// A camera 10 mm above the floor at x = 1 mm looking straight down, size x size pixels over
// x, z in [0, 2] mm.
std::string down_camera(int size) {
    const double fov = 2 * std::atan(0.1) * 180 / std::numbers::pi;  // half-width 1 mm at 10 mm
    char camera[200];
    std::snprintf(camera, sizeof camera,
                  "[camera]\nposition = [1, 10, 0]\ntarget = [1, 0, 0]\nup = [0, 0, -1]\n"
                  "fov_y_deg = %.17g\nwidth = %d\nheight = %d\n",
                  fov, size, size);
    return camera;
}

// A diffuse floor (albedo 0.5) 40,000 mm wide, so that the scene epsilon (4e-5 of the extent)
// is 0.8 mm, seen straight down over x in [0, 2] mm by 8 x 8 pixels (column x covers
// [x / 4, (x + 1) / 4] mm), and a step of material "step" from 0.05 to 0.45 mm above the floor
// (below the epsilon) over x < 0, 10 m long and deep (infinite as seen from the view).
// `lights_and_step`: the lights and the step's material.
Scene step_scene(const std::string& lights_and_step) {
    return parse_scene(
        std::string("[scene]\nname = \"step\"\n") + down_camera(8) + lights_and_step + R"(
[[materials]]
name = "floor"
type = "diffuse"
albedo = 0.5
[[shapes]]
type = "plane"
size_x = 40000
size_z = 40000
material = "floor"
[[shapes]]
type = "box"
size = [10000, 0.4, 10000]
translate = [-5000, 0.25, 0]
material = "step"
)",
        "step.toml", ".");
}

// A step_scene, direct light only, 96 spp; rays leave surfaces from the surface (the default)
// or eps off it (as before volpath-render-7).
RenderResult render_step(const Scene& s, bool from_surface) {
    RenderOptions o = options(96);
    o.max_depth = 1;
    o.rays_from_surface = from_surface;
    return render(s, o);
}

TEST(Render, ShadowsOfOccludersCloserThanTheSceneEpsilonAreCast) {
    // step_scene under a sun at 45 degrees, direct light only; the step opaque and diffuse,
    // or an index-matched absorbing medium (which may not touch the floor). Its shadow is
    // closed-form: a floor point at x < 0.45 sees the sun through a chord
    // sqrt(2) (0.45 - max(x, 0.05)) of the step (opaque: not at all), farther points see it
    // unblocked, so each pixel column is L (1/w) integral of that transmittance over its x
    // range, with L = albedo E cos(45) / pi. NEE's shadow rays from the floor start at the
    // floor point, skipping its triangle (volpath-render-7); before, they started eps above it,
    // above the step: no shadow at all (the legacy option below shows the test sees that).
    const std::string sun =
        "[[lights]]\ntype = \"directional\"\ndirection = [-1, 1, 0]\nirradiance = 2\n";
    const double sigma[3] = {1.0, 2.0, 4.0};
    const double L = 0.5 * 2 * std::sqrt(0.5) / std::numbers::pi;
    for (const bool medium : {false, true}) {
        const std::string step =
            medium ? "[[materials]]\nname = \"step\"\nsigma_a_per_mm = [1.0, 2.0, 4.0]\n"
                     "sigma_s_per_mm = 0\ng = 0\neta = 1.0\n"
                   : "[[materials]]\nname = \"step\"\ntype = \"diffuse\"\nalbedo = 0.5\n";
        const Scene s = step_scene(sun + step);
        for (const bool from_surface : {true, false}) {
            SCOPED_TRACE(std::string(medium ? "medium" : "opaque") +
                         (from_surface ? ", from the surface" : ", eps off it"));
            const RenderResult r = render_step(s, from_surface);
            const ImageLayer& img = r.image.layer("radiance");
            const ImageLayer& se = r.image.layer("radiance.stderr");
            // Per channel: the channels' noise is the same samples' (one x per sample).
            testing::ZTally t[3];
            int exact = 0;
            for (int x = 0; x < 8; ++x)
                for (int c = 0; c < 3; ++c) {
                    // Column x covers floor x in [x / 4, (x + 1) / 4] mm.
                    const double a = medium ? sigma[c] * std::sqrt(2.0) : 0;
                    auto lit = [&](double u) {  // integral of the transmittance from 0 to u
                        const double y0 = 0.05, y1 = 0.45;
                        double i = std::max(0.0, u - y1);
                        if (medium) {
                            const double t0 = std::exp(-a * (y1 - y0));
                            i += std::min(u, y0) * t0;
                            if (u > y0) i += (std::exp(-a * (y1 - std::min(u, y1))) - t0) / a;
                        }
                        return i;
                    };
                    const double ref = L * (lit((x + 1) / 4.0) - lit(x / 4.0)) * 4;
                    for (int y = 0; y < 8; ++y) {
                        const double v = img.at(x, y, c), e = se.at(x, y, c);
                        // Wholly lit or wholly shadowed pixels have no noise (their standard
                        // error is rounding): they must be exact (to the EXR's floats).
                        if (e > 1e-6 * L) {
                            t[c].add((v - ref) / e);
                        } else if (std::fabs(v - ref) <= 1e-6 * L) {
                            ++exact;
                        } else {
                            t[c].add(std::numeric_limits<double>::infinity());
                        }
                    }
                }
            std::printf(
                "  [measured] step %s, NEE %s: column 0 %.4f %.4f %.4f (L %.4f), chi-square "
                "%.1f, %.1f, %.1f over %d noisy pixels per channel (worst |z| %.2f), %d exact\n",
                medium ? "(medium)" : "(opaque)", from_surface ? "from the surface" : "eps off it",
                img.at(0, 4, 0), img.at(0, 4, 1), img.at(0, 4, 2), L, t[0].chi2, t[1].chi2,
                t[2].chi2, t[0].n, std::max({t[0].max_abs, t[1].max_abs, t[2].max_abs}), exact);
            bool pass = true;
            for (const testing::ZTally& tc : t)
                pass = pass && tc.chi2 < testing::chi2_critical(std::max(tc.n, 1), 0.001 / 3) &&
                       tc.max_abs < testing::normal_quantile(1 - 0.0005 / 192);
            EXPECT_EQ(pass, from_surface);
            // The legacy origin starts above the step and misses its shadow.
            if (!from_surface) {
                EXPECT_NEAR(img.at(0, 4, 0), L, 1e-6 * L);
            }
        }
    }
}

TEST(Render, AnOccluderCloserThanTheSceneEpsilonShadowsTheSky) {
    // step_scene (epsilon 0.8 mm) under a constant sky of radiance 1 only, direct light only,
    // the step opaque and diffuse. From a floor point at x the step hides
    // the directions whose projection on the x-y plane rises less than beta = atan(0.45 / x)
    // toward -x (below the step the ray meets its underside), and for a shape infinite along
    // z the cosine-weighted share of such directions is (1 - cos beta) / 2, so the radiance is
    // albedo (1 + x / sqrt(x^2 + 0.45^2)) / 2, and a pixel column [x0, x1] averages it to
    // albedo / 2 (1 + (sqrt(x1^2 + h^2) - sqrt(x0^2 + h^2)) / (x1 - x0)). The sky is found by
    // NEE (cos-sampled) and by the path's cosine-sampled ray, each with MIS weight 1/2: both
    // must leave the floor from the floor itself. With shadow rays alone from the surface half
    // of the step's shadow was missing; with neither, all of it (the legacy option below).
    const Scene s = step_scene(
        "[[lights]]\ntype = \"environment\"\nradiance = 1\n[[materials]]\nname = \"step\"\n"
        "type = \"diffuse\"\nalbedo = 0.5\n");
    const double h = 0.45;
    for (const bool from_surface : {true, false}) {
        const RenderResult r = render_step(s, from_surface);
        const ImageLayer& img = r.image.layer("radiance");
        const ImageLayer& se = r.image.layer("radiance.stderr");
        testing::ZTally t;  // channel 0 (the channels are the same samples)
        for (int x = 0; x < 8; ++x) {
            const double x0 = x / 4.0, x1 = (x + 1) / 4.0;
            const double ref = 0.25 * (1 + (std::hypot(x1, h) - std::hypot(x0, h)) / (x1 - x0));
            for (int y = 0; y < 8; ++y) t.add((img.at(x, y, 0) - ref) / se.at(x, y, 0));
        }
        std::printf(
            "  [measured] sky over a step below eps, rays %s: column 0 %.4f (closed form "
            "%.4f, no shadow 0.5), chi-square %.1f over %d pixels, worst |z| %.2f\n",
            from_surface ? "from the surface" : "eps off it", img.at(0, 4, 0),
            0.25 * (1 + (std::hypot(0.25, h) - h) / 0.25), t.chi2, t.n, t.max_abs);
        const bool pass = t.chi2 < testing::chi2_critical(t.n, 0.001) &&
                          t.max_abs < testing::normal_quantile(1 - 0.0005 / t.n);
        EXPECT_EQ(pass, from_surface);
    }
}

TEST(Render, ShadowRaysCrossManyIndexMatchedBoundariesInOneQuery) {
    // A diffuse floor (albedo 0.5, 400 mm: epsilon 8 um) seen straight down over x in [0, 2]
    // mm, under a sun at 45 degrees from -x, direct light only. Between floor and sun a stack of
    // K absorbing index-matched slabs 0.5 mm thick (sigma_a 0.02, 0.05, 0.1 /mm) at
    // y = 3 + k .. 3.5 + k, x < -1 (the camera's rays miss them): every shadow ray crosses 2 K
    // boundaries and the radiance is closed-form, with no noise: L = albedo E cos(45) / pi
    // exp(-sigma sqrt(2) K 0.5). K = 20 takes one occlusion query per shadow ray
    // (EmbreeScene::crossings, 40 crossings recorded and put in order); K = 40 is more than
    // its buffer holds (64) and steps from boundary to boundary; the legacy option steps from
    // eps beyond each. All three must give the closed form.
    const double sigma[3] = {0.02, 0.05, 0.1};
    for (const int K : {20, 40}) {
        std::string text = std::string("[scene]\nname = \"slabs\"\n") + down_camera(4) + R"(
[[lights]]
type = "directional"
direction = [-1, 1, 0]
irradiance = 2
[[materials]]
name = "floor"
type = "diffuse"
albedo = 0.5
[[materials]]
name = "slab"
sigma_a_per_mm = [0.02, 0.05, 0.1]
sigma_s_per_mm = 0
g = 0
eta = 1.0
[[shapes]]
type = "plane"
size_x = 400
size_z = 400
material = "floor"
)";
        for (int k = 0; k < K; ++k) {
            char slab[200];
            std::snprintf(slab, sizeof slab,
                          "[[shapes]]\ntype = \"box\"\nsize = [100, 0.5, 100]\n"
                          "translate = [-51, %.2f, 0]\nmaterial = \"slab\"\n",
                          3.25 + k);
            text += slab;
        }
        const Scene s = parse_scene(text, "slabs.toml", ".");
        for (const bool from_surface : {true, false}) {
            RenderOptions o = options(6);
            o.budget.samples = 6;
            o.max_depth = 1;
            o.rays_from_surface = from_surface;
            const RenderResult r = render(s, o);
            const ImageLayer& img = r.image.layer("radiance");
            double worst = 0;
            for (int c = 0; c < 3; ++c) {
                const double ref = 0.5 * 2 * std::sqrt(0.5) / std::numbers::pi *
                                   std::exp(-sigma[c] * std::sqrt(2.0) * K * 0.5);
                for (int y = 0; y < 4; ++y)
                    for (int x = 0; x < 4; ++x)
                        worst = std::max(worst, std::fabs(img.at(x, y, c) / ref - 1));
            }
            // Queries per path: the camera ray, the path's next ray from the floor (for the
            // MIS of a light it would meet) and the floor's shadow ray: one query, or one per
            // boundary and the last (the fallback after the query that found too many).
            const double per_path =
                static_cast<double>(r.rays) / (16.0 * static_cast<double>(r.spp));
            std::printf(
                "  [measured] %d slabs, rays %s: worst relative error %.2e against the closed "
                "form, %.1f queries per path\n",
                K, from_surface ? "from the surface" : "eps off it", worst, per_path);
            EXPECT_LT(worst, 1e-6);
            if (from_surface && K == 20) {
                EXPECT_EQ(per_path, 3.0);
            } else {
                EXPECT_EQ(per_path, 2.0 + (from_surface ? 1 : 0) + 2 * K + 1);
            }
        }
    }
}

TEST(Render, BitIdenticalForAnyThreadCountAndResumable) {
    const Scene s = parse_scene(
        scene_text("[[materials]]\nname = \"m\"\npreset = \"Skin1\"\nroughness = 0.3\n",
                   "[[lights]]\ntype = \"directional\"\ndirection = [1, 1, 1]\nirradiance = 2\n" +
                       std::string(kEnv)),
        "t.toml", ".");
    RenderOptions o = options(6, 1);
    o.budget.samples = 6;
    const RenderResult one = render(s, o);
    o.threads = 2;
    const RenderResult two = render(s, o);
    EXPECT_EQ(one.run.mean, two.run.mean);
    EXPECT_EQ(one.run.se, two.run.se);
    EXPECT_GT(one.image.layer("subsurface").at(12, 12, 0),
              0.0f);  // a delta light through a rough boundary
    testing::TempDir dir;
    RenderOptions f = o;
    f.budget.samples = 40;  // rounded up to 42: three samples (one per hero) per batch
    const RenderResult full = render(s, f);
    std::atomic<bool> cancel{false};
    RenderOptions c = f;
    c.checkpoint_path = (dir / "r.ckpt").string();
    c.cancel = &cancel;
    c.checkpoint_seconds = 0;
    c.on_batch = [&](const BatchProgress& p) {
        if (p.samples >= 10) cancel = true;
    };
    const RenderResult cut = render(s, c);
    EXPECT_TRUE(cut.interrupted);
    EXPECT_LT(cut.spp, 42u);
    c.cancel = nullptr;
    c.on_batch = nullptr;
    const RenderResult resumed = render(s, c);
    EXPECT_TRUE(resumed.run.resumed);
    EXPECT_EQ(resumed.spp, 42u);
    EXPECT_EQ(resumed.run.mean, full.run.mean);
    EXPECT_EQ(resumed.run.se, full.run.se);
}

TEST(Render, FlightsInABallNoSurfaceEntersSkipTheirQueriesAndChangeNoBit) {
    // Media of long walks (Apple, albedo 0.999; Marble) in a sphere of 15 mm, rendered with a
    // ray query for every flight and with the queries skipped inside balls of a
    // SurfaceDistanceGrid (volpath/mesh_medium.h): the same image to the bit, with fewer
    // queries.
    for (const char* preset : {"Apple", "Marble"}) {
        SCOPED_TRACE(preset);
        std::string text =
            scene_text(std::string("[[materials]]\nname = \"m\"\npreset = \"") + preset +
                           "\"\nroughness = 0.3\n",
                       "[[lights]]\ntype = \"sphere\"\nposition = [4, 4, 3]\nradius = 1\n"
                       "radiance = 5\n" +
                           std::string(kEnv));
        text.replace(text.find("name = \"t\""), 10, "name = \"t\"\nunit_mm = 10");
        const Scene s = parse_scene(text, "t.toml", ".");
        RenderOptions o = options(6, 2);
        o.budget.samples = 6;
        const RenderResult with = render(s, o);
        o.skip_queries_in_balls = false;
        const RenderResult without = render(s, o);
        EXPECT_EQ(with.run.mean, without.run.mean);
        EXPECT_EQ(with.run.se, without.run.se);
        EXPECT_LT(with.rays, without.rays);
        std::printf("  [measured] %s: %llu ray queries with balls, %llu without\n", preset,
                    static_cast<unsigned long long>(with.rays),
                    static_cast<unsigned long long>(without.rays));
    }
}

TEST(Render, ARelativeErrorBudgetMeasuresTheMedianPixelUnlessAskedForTheImageMean) {
    // Issue 12: a --rel-error of the image mean stopped a visibly noisy image early; the
    // default measure is the median lit pixel's relative standard error.
    const Scene s = parse_scene(
        scene_text("[[materials]]\nname = \"m\"\npreset = \"Skin1\"\nroughness = 0.3\n", kEnv),
        "t.toml", ".");
    RenderOptions o;
    o.threads = 2;
    o.width = o.height = 12;
    o.budget.rel_error = 0.05;
    o.budget.samples = 30000;  // a cap that is never reached
    const RenderResult pixel = render(s, o);
    EXPECT_EQ(pixel.run.reason, BatchStop::kRelError);
    const RelativeError pe = radiance_rel_error(pixel.run.mean, pixel.run.se);
    EXPECT_LE(pe.median, 0.05);
    EXPECT_GT(pe.counted, 100u);
    o.error_measure = RenderErrorMeasure::kImageMean;
    const RenderResult mean = render(s, o);
    EXPECT_EQ(mean.run.reason, BatchStop::kRelError);
    EXPECT_LE(radiance_rel_error(mean.run.mean, mean.run.se).mean, 0.05);
    // The image mean reaches 5 % long before its pixels do.
    EXPECT_LT(mean.spp * 4, pixel.spp);
    EXPECT_GT(radiance_rel_error(mean.run.mean, mean.run.se).median, 0.1);
}

TEST(Render, DeltaLightOnASmoothMediumIsRefusedAtTheLight) {
    const Scene s = parse_scene(
        scene_text("[[materials]]\nname = \"m\"\npreset = \"Skin1\"\n",
                   "[[lights]]\ntype = \"point\"\nposition = [5, 5, 5]\nintensity = 10\n"),
        "t.toml", ".");
    try {
        (void)render(s, options(1));
        FAIL() << "accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("t.toml:11"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("roughness"), std::string::npos) << e.what();
    }
}

TEST(Render, CommandWritesTheLayeredExrAndPreviewOrNothing) {
    testing::TempDir dir;
    dir.write(
        "s.toml",
        scene_text("[[materials]]\nname = \"m\"\npreset = \"Skin1\"\nroughness = 0.2\n", kEnv));
    const auto r = testing::run_ssslab({"render", "s.toml", "--spp", "2", "--width", "8",
                                        "--height", "6", "--out", "o.exr", "-q"},  // 2 -> 3 spp
                                       dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"o.exr", "o.exr.toml", "o.png", "s.toml"}));
    const LayeredImage img = read_exr((dir / "o.exr").string());
    EXPECT_EQ(img.width(), 8);
    EXPECT_EQ(img.height(), 6);
    for (const char* l : {"radiance", "radiance.stderr", "subsurface", "subsurface.stderr",
                          "specular", "specular.stderr", "depth", "normal"})
        EXPECT_TRUE(img.has_layer(l)) << l;
    EXPECT_EQ(img.metadata().at("ssslab.spp"), "3");  // a multiple of three
    // The settings record the requested policy and what it came to in the medium m (read back
    // with the config reader): Skin1's blue albedo (0.68) is below 0.9, so "auto" makes its
    // walks analog; a requested policy is what the medium gets.
    using Recorded = std::pair<std::string, std::string>;
    auto recorded = [&](const char* file) {
        const auto doc = ConfigDocument::parse_file((dir / file).string());
        ConfigTable settings = doc->root().require_table("render");
        return Recorded{settings.string("absorption"),
                        settings.table_or_empty("media_absorption").string("m", "(none)")};
    };
    EXPECT_EQ(recorded("o.exr.toml"), (Recorded{"auto", "analog"}));
    const auto w =
        testing::run_ssslab({"render", "s.toml", "--spp", "2", "--width", "8", "--height", "6",
                             "--out", "w.exr", "-q", "--absorption", "weighted"},
                            dir.path());
    ASSERT_EQ(w.exit_code, 0) << w.err;
    EXPECT_EQ(recorded("w.exr.toml"), (Recorded{"weighted", "weighted"}));
    // Bad arguments: exit 2, nothing written.
    testing::TempDir bad;
    bad.write("s.toml",
              scene_text("[[materials]]\nname = \"m\"\npreset = \"Skin1\"\n",
                         "[[lights]]\ntype = \"point\"\nposition = [5, 5, 5]\nintensity = 1\n"));
    const auto e =
        testing::run_ssslab({"render", "s.toml", "--spp", "2", "--out", "o.exr"}, bad.path());
    EXPECT_EQ(e.exit_code, 2) << e.out << e.err;
    EXPECT_NE(e.err.find("s.toml:11"), std::string::npos) << e.err;
    // render counts samples per pixel: --photons is not one of its options.
    const auto p = testing::run_ssslab({"render", "s.toml", "--photons", "5"}, bad.path());
    EXPECT_EQ(p.exit_code, 2);
    EXPECT_NE(p.err.find("ssslab render: error:"), std::string::npos) << p.err;
    EXPECT_NE(p.err.find("--photons"), std::string::npos) << p.err;
    EXPECT_EQ(bad.files(), std::vector<std::string>{"s.toml"});
}

TEST(Render, BenchmarkReportsRaysPerSecondAndTimeToOnePercent) {
    testing::TempDir dir;
    const auto r = testing::run_ssslab({"bench", "--render", "--quick", "--case", "ketchup",
                                        "--scenes", testing::source_path("experiments/scenes")},
                                       dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("ketchup"), std::string::npos) << r.out;
    for (const char* column : {"t1%pix_own", "t1%pix_ref", "t1%img_own", "t1%img_ref", "z2_ratio"})
        EXPECT_NE(r.out.find(column), std::string::npos) << column << "\n" << r.out;
    EXPECT_NE(r.out.find("references of 64 spp"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("apple"), std::string::npos) << r.out;
    const auto bad = testing::run_ssslab({"bench", "--render", "--scenes", "nowhere"}, dir.path());
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
    EXPECT_TRUE(dir.files().empty());
}

TEST(Render, ErrorAgainstTimeMatchesTheStandardErrors) {
    // The white furnace has an exact reference (1 in every pixel): the relative RMS error after
    // 4, 8, ... spp falls as 1 / sqrt(spp), and at the end equals the run's own estimate from
    // its standard errors.
    testing::TempDir dir;
    dir.write("s.toml",
              scene_text("[[materials]]\nname = \"m\"\nsigma_a_per_mm = 0\nsigma_s_per_mm = 2\n"
                         "eta = 1.4\n",
                         "[[lights]]\ntype = \"environment\"\nradiance = 1\n"));
    LayeredImage ref(24, 24);
    ref.add_layer("radiance", 3, std::vector<float>(24 * 24 * 3, 1.0f));
    write_exr(ref, (dir / "ref.exr").string());
    const auto r = testing::run_ssslab({"render", "s.toml", "--spp", "192", "--batch-spp", "3",
                                        "--reference", "ref.exr", "--out", "o.exr", "-q"},
                                       dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string csv = testing::read_text(dir / "o_convergence.csv");
    std::vector<std::array<double, 4>> rows;
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
        std::array<double, 4> v{};
        ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3]), 4)
            << line;
        rows.push_back(v);
    }
    ASSERT_EQ(rows.size(), 5u);  // after 4, 8, 16, 32 batches of 3 spp, and at 192 spp
    EXPECT_EQ(rows.front()[0], 12);
    EXPECT_EQ(rows.back()[0], 192);
    // 16x the samples: 4x less error, within the scatter of an error estimate.
    const double ratio = rows.front()[2] / rows.back()[2];
    EXPECT_GT(ratio, 2.5);
    EXPECT_LT(ratio, 6.5);
    EXPECT_NEAR(rows.back()[2] / rows.back()[3], 1.0, 0.25);
    // A reference of another size is refused.
    LayeredImage small(8, 8);
    small.add_layer("radiance", 3);
    write_exr(small, (dir / "small.exr").string());
    const auto bad = testing::run_ssslab(
        {"render", "s.toml", "--spp", "4", "--reference", "small.exr", "--out", "b.exr", "-q"},
        dir.path());
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_FALSE(std::filesystem::exists(dir / "b.exr"));
}

// measured_error against a reference, on synthetic images whose noise is known: truth T per
// pixel-channel, the run T + N(0, se^2), the reference T + N(0, sr^2). With honest standard-error
// layers the median z^2 ratio is 1 and the corrected RMS error is the run's own; with a run whose
// layer says half its real noise the ratio is (4 se^2 + sr^2) / (se^2 + sr^2) and the measured
// median pixel error twice the run's own estimate. Tolerances from the sampling distributions:
// the median of n chi-square(1) values has SE 1 / (2 f(m) sqrt n), f(m) = 0.4711 its density at
// the median; the sum of n squared normals has relative SE sqrt(2 / n).
TEST(Render, MeasuredErrorSeesHonestAndUnderstatedStandardErrors) {
    const int w = 64, h = 64;
    const double n = 3.0 * w * h;
    for (const double understate : {1.0, 2.0}) {
        std::mt19937_64 rng(17);
        std::normal_distribution<double> gauss;
        LayeredImage run(w, h), ref(w, h);
        ImageLayer& rl = run.add_layer("radiance", 3);
        ImageLayer& re = run.add_layer("radiance.stderr", 3);
        ImageLayer& fl = ref.add_layer("radiance", 3);
        ImageLayer& fe = ref.add_layer("radiance.stderr", 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    const double t = 1.0 + 0.5 * std::sin(0.1 * x + 0.07 * y + c);
                    const double se = 0.02 * t, sr = 0.005 * t;
                    rl.at(x, y, c) = static_cast<float>(t + understate * se * gauss(rng));
                    re.at(x, y, c) = static_cast<float>(se);
                    fl.at(x, y, c) = static_cast<float>(t + sr * gauss(rng));
                    fe.at(x, y, c) = static_cast<float>(sr);
                }
        const MeasuredError m = measured_error(run, ref);
        EXPECT_EQ(m.counted, static_cast<std::size_t>(n));
        const double q = 0.005 / 0.02;  // sr / se
        const double expect_ratio = (understate * understate + q * q) / (1 + q * q);
        const double ratio_se = expect_ratio * 1.0 / (2 * 0.4711 * std::sqrt(n));
        EXPECT_NEAR(m.z2_median_ratio, expect_ratio, 4 * ratio_se) << "understate " << understate;
        EXPECT_NEAR(m.median_pixel / m.own.median, std::sqrt(expect_ratio),
                    4 * ratio_se / (2 * std::sqrt(expect_ratio)));
        // The corrected RMS error is the run's real noise: understate x its own estimate.
        const double u2 = understate * understate;
        EXPECT_NEAR(m.rel_rmse_corrected / m.own.rms, understate,
                    4 * understate * 0.5 * std::sqrt(2.0 / n) * (u2 + q * q) / u2);
        EXPECT_GT(m.rel_rmse, m.rel_rmse_corrected);
    }
    LayeredImage small(8, 8);
    small.add_layer("radiance", 3);
    small.add_layer("radiance.stderr", 3);
    LayeredImage other(4, 4);
    EXPECT_THROW(measured_error(small, other), std::invalid_argument);
    EXPECT_THROW(measured_error(small, small), std::invalid_argument);  // a black reference
}

TEST(Render, StudentTQuantileOfTheTestHelpers) {
    // Table values (Abramowitz & Stegun Table 26.10).
    EXPECT_NEAR(testing::student_t_quantile(0.975, 20), 2.085963, 2e-3);
    EXPECT_NEAR(testing::student_t_quantile(0.99, 40), 2.423257, 2e-3);
    EXPECT_NEAR(testing::student_t_quantile(0.995, 60), 2.660283, 2e-3);
    EXPECT_NEAR(testing::student_t_quantile(0.975, 1e9), 1.959964, 1e-6);
}

// A sphere of radius 1.5 (material "m", given with `lights`) above a diffuse floor, seen by a
// size x size camera.
Scene floor_scene(int size, const std::string& lights_and_m) {
    return parse_scene(R"(
[scene]
name = "floor"
[camera]
position = [0, 2, 10]
target = [0, 0, 0]
fov_y_deg = 30
width = )" + std::to_string(size) +
                           "\nheight = " + std::to_string(size) + "\n" + lights_and_m + R"(
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.6, 0.5, 0.4]
[[shapes]]
type = "sphere"
radius = 1.5
subdivisions = 3
material = "m"
[[shapes]]
type = "plane"
size_x = 20
size_z = 20
translate = [0, -1.6, 0]
material = "floor"
)",
                       "floor.toml", ".");
}

// Every light path the renderer has: a sphere light, a sun and an environment, a rough
// chromatic medium, a diffuse floor.
Scene estimator_scene(int size) {
    return floor_scene(size, R"(
[[lights]]
type = "sphere"
position = [4, 4, 3]
radius = 1
radiance = 5
[[lights]]
type = "directional"
direction = [-0.3, 1, 0.2]
irradiance = 1.5
angular_radius_deg = 1
[[lights]]
type = "environment"
radiance = 0.2
[[materials]]
name = "m"
sigma_a_per_mm = [0.05, 0.1, 0.2]
sigma_s_per_mm = [1.0, 3.0, 8.0]
g = [0.0, 0.5, 0.9]
eta = 1.3
roughness = 0.3
)");
}

// Two renders of the same image agree: block chi-square (4 x 4 pixel blocks) and image means
// per channel at level alpha, no pixel deterministic in one and not the other; the figures
// printed under `what`.
void expect_same_image(const ImageEstimate& a, const ImageEstimate& b, double alpha,
                       const std::string& what) {
    const ImageComparison c = compare_images(a, b, 4);
    for (int ch = 0; ch < 3; ++ch) {
        std::printf(
            "  [measured] %s, channel %d: chi2 %.1f over %d blocks, p %.3g, image mean z %.2f\n",
            what.c_str(), ch, c.chi2[ch], c.dof[ch], c.p[ch], c.z_mean[ch]);
        EXPECT_GT(c.p[ch], alpha) << what << " " << ch;
        EXPECT_LT(std::fabs(c.z_mean[ch]), testing::normal_quantile(1 - alpha / 2)) << what;
    }
    EXPECT_EQ(c.deterministic_differences, 0) << what;
}

// A render's radiance estimate (named `name`) and its subsurface layer's summed SE^2.
std::pair<ImageEstimate, double> render_with_se2(const Scene& s, const RenderOptions& o,
                                                 const std::string& name) {
    const RenderResult r = render(s, o);
    double se2 = 0;
    for (float v : r.image.layer("subsurface.stderr").pixels()) se2 += static_cast<double>(v) * v;
    return {estimate_with_stderr(r.image, "radiance", name), se2};
}

TEST(Render, NewerEstimatorsAgreeWithTheLegacyOne) {
    // volpath-render-4 samples every light at each NEE and draws the first numbers of a path
    // from scrambled Sobol points; volpath-render-5 weights absorption in media of albedo
    // >= 0.9; volpath-render-6 chooses the hero at every entry into a medium by throughput x
    // albedo and samples the environment about a surface's normal by cos(theta);
    // volpath-render-7 starts NEE's shadow rays at the surface point, skipping its triangle.
    // volpath-render-3's estimator (one light chosen uniformly, the stream alone, analog, the
    // hero in turn, the environment over the sphere, shadow rays eps off the surface) stays an
    // option, and so does each step.
    // Every combination estimates the same image: their block means agree with the legacy
    // image's by chi-square (batch standard errors on both sides), and the image means by z.
    const Scene s = estimator_scene(32);
    RenderOptions legacy = options(192);
    legacy.nee_all_lights = false;
    legacy.sampler = RenderSampler::kIndependent;
    legacy.batch_spp = 3;
    legacy.absorption = Absorption::kAnalog;
    legacy.hero = RenderHero::kUniform;
    legacy.environment_cosine = false;
    legacy.rays_from_surface = false;
    legacy.seed = 5;
    const RenderResult ref = render(s, legacy);
    const ImageEstimate b = estimate_with_stderr(ref.image, "radiance", "legacy");
    struct Variant {
        bool all_lights;
        RenderSampler sampler;
        Absorption absorption;
        RenderHero hero;
        bool env_cosine;
        bool from_surface = false;
    };
    constexpr auto kSobol = RenderSampler::kSobol;
    constexpr auto kUniform = RenderHero::kUniform, kTA = RenderHero::kThroughputAlbedo;
    // volpath-render-5's default weights the absorption of this medium (albedo 0.95-0.98);
    // volpath-render-4's was analog.
    const Variant variants[] = {
        {false, kSobol, Absorption::kWeighted, kUniform, false},
        {true, RenderSampler::kIndependent, Absorption::kWeighted, kUniform, false},
        {true, kSobol, Absorption::kWeighted, kUniform, false},
        {true, kSobol, Absorption::kAnalog, kUniform, false},
        {true, kSobol, Absorption::kAnalog, kTA, false},
        {true, kSobol, Absorption::kWeighted, kUniform, true},
        {true, kSobol, Absorption::kWeighted, kTA, true},        // volpath-render-6
        {true, kSobol, Absorption::kWeighted, kTA, true, true},  // volpath-render-7
    };
    const double alpha = 0.001 / (3.0 * std::size(variants));
    for (const Variant& v : variants) {
        RenderOptions o = options(192);
        o.nee_all_lights = v.all_lights;
        o.sampler = v.sampler;
        o.seed = 6;
        o.absorption = v.absorption;
        o.hero = v.hero;
        o.environment_cosine = v.env_cosine;
        o.rays_from_surface = v.from_surface;
        const RenderResult r = render(s, o);
        char what[160];
        std::snprintf(what, sizeof what,
                      "all lights %d, sobol %d, weighted %d, hero %s, cosine env %d, from the "
                      "surface %d",
                      v.all_lights, v.sampler == kSobol, v.absorption == Absorption::kWeighted,
                      to_string(v.hero), v.env_cosine, v.from_surface);
        expect_same_image(estimate_with_stderr(r.image, "radiance", "new"), b, alpha, what);
    }
}

// A sphere of a medium behind a rough boundary (g the same in all channels, so that its
// vertices have exit guides), lit from behind by a sphere light and from above by a sun disc,
// with a dim environment.
Scene backlit_scene(int size) {
    return floor_scene(size, R"(
[[lights]]
type = "sphere"
position = [-3, 3, -5]
radius = 1.2
radiance = 5
[[lights]]
type = "directional"
direction = [-0.3, 1, 0.2]
irradiance = 1.5
angular_radius_deg = 3
[[lights]]
type = "environment"
radiance = 0.05
[[materials]]
name = "m"
sigma_a_per_mm = [0.02, 0.05, 0.1]
sigma_s_per_mm = [1.0, 2.0, 4.0]
g = 0.3
eta = 1.4
roughness = 0.35
)");
}

TEST(Render, TheExitGuideAgreesWithTheWalkAloneAndLowersItsVariance) {
    // volpath-render-8's exit guide adds an estimator of the light that leaves a medium through
    // its rough boundary straight from a scattering vertex, combined with the walk's own ways
    // to the same paths by the balance heuristic. With the guide and without it the image is
    // the same (block chi-square and image means, batch standard errors on both sides), for
    // analog and weighted absorption (the guide's estimator runs before the absorption
    // decision in both); and the medium's pixels are less noisy with it at the same samples.
    const Scene s = backlit_scene(24);
    const Absorption policies[] = {Absorption::kWeighted, Absorption::kAnalog};
    const double alpha = 0.001 / (3.0 * std::size(policies));
    for (const Absorption a : policies) {
        std::pair<ImageEstimate, double> e[2];
        for (int guided = 0; guided < 2; ++guided) {
            RenderOptions o = options(3072);
            o.absorption = a;
            o.exit_guide = guided == 1;
            o.seed = 21 + static_cast<std::uint64_t>(guided);
            e[guided] = render_with_se2(s, o, guided ? "guided" : "walk");
        }
        expect_same_image(e[1].first, e[0].first, alpha, std::string(to_string(a)) + " absorption");
        const double ratio = e[1].second / e[0].second;
        std::printf(
            "  [measured] %s absorption: the subsurface layer's summed SE^2 with the "
            "guide over without: %.3f\n",
            to_string(a), ratio);
        // Measured 0.11 for both policies (0.13 with volpath-render-8's guides at scattering
        // vertices only); required: below 0.5.
        EXPECT_LT(ratio, 0.5) << to_string(a);
    }
}

// A thin puddle of ketchup's coefficients (optically thin in R: light crosses it without a
// collision) behind a rough boundary on a white floor under a sun and a dim environment, seen
// from above: by default nearly smooth (alpha 0.05) under a sun of 0.27 degrees.
Scene puddle_scene(int size, double roughness = 0.05, double sun_deg = 0.27) {
    return parse_scene(R"(
[scene]
name = "puddle"
[camera]
position = [0, 6, 8]
target = [0, 0, 0]
fov_y_deg = 30
width = )" + std::to_string(size) +
                           "\nheight = " + std::to_string(size) + R"(
[[lights]]
type = "directional"
direction = [0.5, 0.8, 0.3]
irradiance = 2
angular_radius_deg = )" + std::to_string(sun_deg) +
                           R"(
[[lights]]
type = "environment"
radiance = 0.05
[[materials]]
name = "m"
sigma_a_per_mm = [0.061, 0.97, 1.45]
sigma_s_per_mm = [0.18, 0.07, 0.03]
g = 0
eta = 1.3
roughness = )" + std::to_string(roughness) +
                           R"(
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.75, 0.75, 0.75]
[[shapes]]
type = "sphere"
radius = 2
scale = [1, 0.15, 0.8]
translate = [0, 0.32, 0]
subdivisions = 4
material = "m"
[[shapes]]
type = "plane"
size_x = 20
size_z = 20
material = "floor"
)",
                       "puddle.toml", ".");
}

// The puddle rendered with the walk alone (mode 0), the scattering vertices' exit guides (1),
// those and the boundary's (2), and those, the diffuse vertices' and a wide lobe beside each
// narrow one (3: volpath-render-11).
std::pair<ImageEstimate, double> render_puddle(const Scene& s, double spp, int mode,
                                               std::uint64_t seed) {
    RenderOptions o = options(spp);
    o.exit_guide = mode > 0;
    o.boundary_guides = mode >= 2;
    o.diffuse_guides = mode == 3;
    o.wide_lobes = mode == 3;
    o.seed = seed;
    return render_with_se2(s, o, "mode " + std::to_string(mode));
}

// A guide (render_puddle's `mode`) on the puddle: against the walk alone where its tails are
// light (alpha 0.3, a sun of 3 degrees; seeds[0], seeds[1]), the same image; nearly smooth
// (alpha 0.05, a sun of 0.27 degrees), where the walk alone's heavy tails would break the
// chi-square's normal approximation, the same image as mode `before` (seeds[2], seeds[3]) and
// a subsurface layer's summed SE^2 below 0.85 of it.
void check_puddle_guide(int mode, int before, const std::uint64_t (&seeds)[4],
                        const std::string& what, const std::string& before_what) {
    const double alpha = 0.001 / 6.0;
    {
        const Scene s = puddle_scene(16, 0.3, 3.0);
        expect_same_image(render_puddle(s, 49152, mode, seeds[0]).first,
                          render_puddle(s, 49152, 0, seeds[1]).first, alpha,
                          "rough, " + what + " against the walk alone");
    }
    const Scene s = puddle_scene(24);
    const auto [ref, se2_ref] = render_puddle(s, 6144, before, seeds[2]);
    const auto [est, se2_est] = render_puddle(s, 6144, mode, seeds[3]);
    expect_same_image(est, ref, alpha, "smooth, " + what + " against " + before_what);
    const double ratio = se2_est / se2_ref;
    std::printf("  [measured] the subsurface layer's summed SE^2 with %s over without: %.2f\n",
                what.c_str(), ratio);
    EXPECT_LT(ratio, 0.85);
}

TEST(Render, BoundaryGuidesAgreeWithTheWalkAloneAndLowerTheVarianceOfAThinMedium) {
    // volpath-render-9's exit guides at the boundary's own vertices (the entry, an internal
    // reflection): where light crosses a thin medium without a collision, the walk's direction
    // from the entry (one narrow lobe of the rough boundary) must meet the exit's narrow lobe
    // towards the sun, which the scattering vertices' guides do not cover. Running the
    // boundary's estimator only where the walk's own sample went on inside (a bias: z -5 in R
    // against the walk alone) fails here. Measured SE^2 ratio 0.60.
    check_puddle_guide(2, 1, {51, 52, 42, 43}, "boundary guides", "scattering only");
}

TEST(Render, DiffuseGuidesAgreeWithTheWalkAloneAndLowerTheVarianceOfACausticSeenThroughIt) {
    // volpath-render-10's guides at a diffuse vertex straight after the way out of a guided
    // medium (with volpath-render-11's wide lobes): the floor under the puddle, seen through it,
    // lit by the sun through it (two rough refractions in, two out). The walk alone reaches the sun
    // from there only where the floor's cosine falls into the entry's narrow lobe and the entry's
    // direction into the exit's. Leaving the new density out of the entry guide's MIS (z 71 against
    // the walk alone) or out of its own (z 284) fails here. Measured SE^2 ratio 0.14.
    check_puddle_guide(3, 2, {61, 62, 44, 45}, "diffuse guides", "boundary guides");
}

TEST(Render, MediaOfHighAlbedoWeightTheirAbsorption) {
    // Single-scattering albedos sigma_s / sigma_t of Freude14 Table 6.2's media (sigma_a,
    // sigma_s' per mm): whole milk 0.9996, 0.9993, 0.9963 (weighted), ketchup 0.747, 0.067,
    // 0.020 (analog), skin1 0.959, 0.838, 0.678 (analog: one channel below 0.9). A requested
    // policy wins.
    const double milk_s[3] = {25.5, 32.1, 37.7}, milk_t[3] = {25.511, 32.124, 37.84};
    const double ketchup_s[3] = {1.8, 0.7, 0.3}, ketchup_t[3] = {2.41, 10.4, 14.8};
    const double skin_s[3] = {7.4, 8.8, 10.1}, skin_t[3] = {7.72, 10.5, 14.9};
    EXPECT_EQ(render_absorption(milk_s, milk_t, std::nullopt), Absorption::kWeighted);
    EXPECT_EQ(render_absorption(ketchup_s, ketchup_t, std::nullopt), Absorption::kAnalog);
    EXPECT_EQ(render_absorption(skin_s, skin_t, std::nullopt), Absorption::kAnalog);
    EXPECT_EQ(render_absorption(milk_s, milk_t, Absorption::kAnalog), Absorption::kAnalog);
    EXPECT_EQ(render_absorption(ketchup_s, ketchup_t, Absorption::kWeighted),
              Absorption::kWeighted);
    // The boundary: exactly 0.9 is weighted; a medium that does not scatter is analog.
    const double edge_s[3] = {0.9, 0.9, 0.9}, edge_t[3] = {1, 1, 1}, zero[3] = {0, 0, 0};
    EXPECT_EQ(render_absorption(edge_s, edge_t, std::nullopt), Absorption::kWeighted);
    EXPECT_EQ(render_absorption(zero, edge_t, std::nullopt), Absorption::kAnalog);
}

TEST(Render, SobolPointsAndAllLightsLowerTheVarianceOfDirectLighting) {
    // What the two changes are for: on diffuse surfaces under a sun and an environment the
    // uniform light choice makes each sample carry the sun's whole share or none of it; and
    // the scrambled Sobol points stratify the pixel position and the light and surface
    // directions within a batch. At 384 spp in batches of 48 spp the mean pixel variance of
    // each step is measured (the factors are printed) and must fall by more than 2x.
    const Scene s = floor_scene(16, R"(
[[lights]]
type = "directional"
direction = [-0.3, 1, 0.2]
irradiance = 1.5
angular_radius_deg = 1
[[lights]]
type = "environment"
radiance = 0.2
[[materials]]
name = "m"
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
)");
    auto mean_variance = [&](bool all_lights, RenderSampler sampler) {
        RenderOptions o = options(384);
        o.nee_all_lights = all_lights;
        o.sampler = sampler;
        o.batch_spp = 48;
        const RenderResult r = render(s, o);
        return mean_pixel_variance(estimate_with_stderr(r.image, "radiance", "r"), 1);
    };
    const double one = mean_variance(false, RenderSampler::kIndependent);
    const double all = mean_variance(true, RenderSampler::kIndependent);
    const double sobol = mean_variance(true, RenderSampler::kSobol);
    std::printf(
        "  [measured] mean pixel variance (G): one light %.3g, all lights %.3g (%.1fx), "
        "and Sobol %.3g (%.1fx)\n",
        one, all, one / all, sobol, all / sobol);
    EXPECT_GT(one / all, 2.0);
    EXPECT_GT(all / sobol, 2.0);
}

}  // namespace
}  // namespace ssslab::volpath
