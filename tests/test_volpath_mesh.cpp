// Media inside closed meshes (volpath/mesh_medium.h, boundaries through Embree) against the
// engines with analytic geometry and against physics: the white furnace inside a closed, partly
// concave mesh; a very large box against the half-space pencil profile; a tessellated sphere
// under a directional light against the lit-sphere engine's exitance.
#include "core/batch_runner.h"
#include "core/material.h"
#include "core/mesh.h"
#include "core/rng.h"
#include "testing.h"
#include "volpath/embree_scene.h"
#include "volpath/mesh_medium.h"
#include "volpath/pencil.h"
#include "volpath/sampling.h"
#include "volpath/sphere.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace ssslab::volpath {
namespace {

std::int64_t scaled(double n) {
    return static_cast<std::int64_t>(n * testing::test_scale());
}

Vec3 isotropic(RngStream& rng) {
    const double z = 2 * rng.uniform() - 1, phi = 2 * kPi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

MeshMedium grey(const EmbreeScene& es, double sigma_a, double sigma_s, double g, double eta) {
    MeshMedium m;
    m.scene = &es;
    m.shape = 0;
    m.sigma_t = {sigma_a + sigma_s, sigma_a + sigma_s, sigma_a + sigma_s};
    m.sigma_s = {sigma_s, sigma_s, sigma_s};
    m.g = {g, g, g};
    m.eta_inside = eta;
    return m;
}

// Batches of `n` paths in total, in parallel, deterministic; `body` adds one path to the tally.
template <class Body>
BatchRunResult batches(std::size_t size, std::int64_t n, std::uint32_t stream, Body body) {
    BatchRunOptions o;
    o.tally_size = size;
    o.batch_samples = std::max<std::int64_t>(100, n / 64);
    o.budget.samples = n;
    return run_batches(o, [&](std::uint64_t index, std::int64_t count, double* tally) {
        RngStream rng(5, rng_domain::kTest + stream, index);
        std::uint64_t work = 0;
        for (std::int64_t i = 0; i < count; ++i) work += body(rng, tally);
        return work;
    });
}

TEST(VolpathMesh, WhiteFurnaceInsideAClosedConcaveMesh) {
    // Albedo 1: every path from a point source inside a bumpy (partly concave) sphere leaves it,
    // whatever the boundary: index-matched, or 1.5 with total internal reflection. Analog paths
    // keep weight 1, so the count is exact; analog hero weights average to 1 per channel.
    const TriangleMesh bumpy = make_bumpy_sphere(1.0, 0.15, 5.0, 9, 5);
    const EmbreeScene es({&bumpy});
    for (double eta : {1.0, 1.5}) {
        SCOPED_TRACE(eta);
        const MeshMedium m = grey(es, 0.0, 8.0, 0.6, eta);
        std::int64_t exited = 0, other = 0;
        RngStream rng(3, rng_domain::kTest + 50, eta > 1 ? 1 : 0);
        const std::int64_t n = scaled(2e4);
        for (std::int64_t i = 0; i < n; ++i) {
            const WalkResult r = walk_mesh_medium<1>(m, {0, 0, 0}, isotropic(rng), rng);
            if (r.fate == WalkResult::Fate::kExited && r.weight[0] == 1.0)
                ++exited;
            else
                ++other;
            if (r.fate == WalkResult::Fate::kExited) {
                EXPECT_GT(dot(r.w, r.n), 0.0);  // leaves outwards
                EXPECT_NEAR(length(r.w), 1.0, 1e-12);
            }
        }
        EXPECT_EQ(exited, n);
        EXPECT_EQ(other, 0);
    }
    MeshMedium h = grey(es, 0.0, 8.0, 0.0, 1.4);
    h.sigma_s = {2.0, 8.0, 30.0};
    h.sigma_t = h.sigma_s;
    h.g = {0.0, 0.5, 0.9};
    const BatchRunResult r = batches(3, scaled(3e4), 51, [&](RngStream& rng, double* t) {
        const int hero = static_cast<int>(3 * rng.uniform());
        const WalkResult w = walk_mesh_medium<3>(h, {0, 0, 0}, isotropic(rng), rng, hero);
        EXPECT_EQ(w.fate, WalkResult::Fate::kExited);
        for (int c = 0; c < 3; ++c) t[c] += w.weight[static_cast<size_t>(c)];
        return static_cast<std::uint64_t>(w.events);
    });
    for (int c = 0; c < 3; ++c)
        EXPECT_LT(std::fabs(r.mean[static_cast<size_t>(c)] - 1.0), 4 * r.se[static_cast<size_t>(c)])
            << kChannelNames[c] << ": " << r.mean[static_cast<size_t>(c)] << " +- "
            << r.se[static_cast<size_t>(c)];
}

TEST(VolpathMesh, VeryLargeBoxEqualsTheHalfSpacePencilProfile) {
    // Skin1's red channel in a box 100 cm on a side (770 mean free paths): a pencil beam into the
    // middle of its top face sees a half-space. Exits through the top face, binned by distance
    // from the entry as MCML bins them, times the entry factor 1 - Rsp, against the pencil
    // engine (independent seed), bin by bin. The walk skips the queries of flights inside the
    // balls of a SurfaceDistanceGrid, as the renderer's walks do in dense media.
    const Medium skin = *find_material("Skin1");
    const TriangleMesh box = make_box({100, 100, 100});
    const EmbreeScene es({&box});
    const SurfaceDistanceGrid balls(es, box);
    MeshMedium m = grey(es, skin.sigma_a_per_cm[0], skin.sigma_s_per_cm[0], skin.g[0], skin.eta);
    m.balls = &balls;
    const PencilGrid grid{0.02, 100};
    const double rsp = entry_specular(skin);
    const std::size_t size = static_cast<std::size_t>(grid.nr) + 2;  // bins, beyond, other faces
    const BatchRunResult r = batches(size, scaled(1e5), 52, [&](RngStream& rng, double* t) {
        const WalkResult w = walk_mesh_medium<1>(m, {0, 50, 0}, {0, -1, 0}, rng);
        if (w.fate != WalkResult::Fate::kExited) return static_cast<std::uint64_t>(w.events);
        if (std::fabs(w.p.y - 50) > 1e-4) {
            t[size - 1] += 1;
            return static_cast<std::uint64_t>(w.events);
        }
        const double bin = std::hypot(w.p.x, w.p.z) / grid.dr_cm;
        t[bin < grid.nr ? static_cast<std::size_t>(bin) : static_cast<std::size_t>(grid.nr)] +=
            (1 - rsp) * w.weight[0];
        return static_cast<std::uint64_t>(w.events);
    });
    PencilOptions po;
    po.budget.samples = scaled(1e5);
    po.only_channel = 0;
    po.seed = 77;
    const PencilRun ref = simulate_pencil(skin, grid, po);
    testing::ZTally t;
    for (int i = 0; i < grid.nr; ++i) {
        const double area = 2 * kPi * (i + 0.5) * grid.dr_cm * grid.dr_cm;
        t.add_pair(r.mean[static_cast<size_t>(i)] / area, r.se[static_cast<size_t>(i)] / area,
                   ref.profile.rd_per_cm2[0][static_cast<size_t>(i)],
                   ref.profile.se_per_cm2[0][static_cast<size_t>(i)]);
    }
    std::printf(
        "  [measured] box vs pencil, Skin1 R: chi2 %.1f over %d bins, max |z| %.2f; other "
        "faces %.2g\n",
        t.chi2, t.n, t.max_abs, r.mean[size - 1]);
    EXPECT_GT(t.n, 60);
    EXPECT_LT(t.chi2, testing::chi2_critical(t.n, 0.001));
    EXPECT_LT(t.max_abs, testing::normal_quantile(1 - 0.0005 / t.n));
    EXPECT_EQ(r.mean[size - 1], 0.0);
}

TEST(VolpathMesh, TessellatedSphereEqualsTheLitSphereEngine) {
    // A sphere of radius 5 mm (about 4 reduced mean free paths of Skin1 red) as an icosphere of
    // 81,920 triangles, lit by a directional light and traced from the light as the sphere
    // engine does: entry points uniform over the disc the sphere presents, Fresnel at the facet,
    // the walk, then (1) exitance per zone of beta = angle from the subsolar point, M / E0 =
    // weight / (2 (cos b0 - cos b1)) per photon, and (2) the exitance image seen along the light
    // (16 x 16 pixels, the engine's orthographic frame): per pixel sum w (n . v) R^2 / A_pix.
    // Both against volpath/sphere.h on the exact sphere, zone by zone and pixel by pixel.
    const Medium skin = *find_material("Skin1");
    Medium m1 = skin;  // the red channel in all three (the sphere engine's hero is then exact)
    for (int c = 0; c < 3; ++c) {
        m1.sigma_a_per_cm[c] = skin.sigma_a_per_cm[0];
        m1.sigma_s_per_cm[c] = skin.sigma_s_per_cm[0];
    }
    const double R = 0.5;
    const int nb = 18, W = 16;
    SphereScene sc;
    sc.medium = m1;
    sc.radius_cm = R;
    sc.beta_bins = nb;
    sc.width = sc.height = W;
    const SphereCamera cam = sphere_camera(sc);
    const TriangleMesh sphere = make_sphere(R, 6);
    const EmbreeScene es({&sphere});
    const MeshMedium m = grey(es, m1.sigma_a_per_cm[0], m1.sigma_s_per_cm[0], 0.0, m1.eta);
    const std::size_t size = static_cast<std::size_t>(nb + W * W);
    const BatchRunResult r = batches(size, scaled(2e5), 53, [&](RngStream& rng, double* t) {
        const double rr = R * std::sqrt(rng.uniform()), phi = 2 * kPi * rng.uniform();
        const Vec3 d{0, 0, -1};
        const RayHit hit = es.intersect({rr * std::cos(phi), rr * std::sin(phi), 10}, d);
        if (!hit.hit()) return std::uint64_t{0};
        const double cos_i = -dot(d, hit.normal);
        double cos_t = 0;
        const double F = fresnel_dielectric(cos_i, m1.eta, cos_t);
        if (rng.uniform() < F) return std::uint64_t{0};  // first-surface reflection
        const Vec3 p = Vec3{rr * std::cos(phi), rr * std::sin(phi), 10} + d * hit.t;
        const WalkResult w = walk_mesh_medium<1>(m, p, refract(d, hit.normal, m1.eta, cos_t), rng);
        if (w.fate == WalkResult::Fate::kExited) {
            const double beta = std::acos(std::clamp(normalize(w.p).z, -1.0, 1.0));
            t[std::min(nb - 1, static_cast<int>(beta / kPi * nb))] += w.weight[0];
            const double nv = dot(w.n, cam.v);
            const double x = (dot(w.p, cam.right) + cam.half_x) / cam.pixel_cm;
            const double y = (cam.half_y - dot(w.p, cam.up)) / cam.pixel_cm;
            if (nv > 0 && x >= 0 && y >= 0 && x < W && y < W)
                t[static_cast<size_t>(nb) + static_cast<size_t>(y) * W + static_cast<size_t>(x)] +=
                    w.weight[0] * nv;
        }
        return static_cast<std::uint64_t>(w.events);
    });
    SphereOptions so;
    so.budget.samples = scaled(2e5);
    so.mode = ChromaticMode::kHero;
    so.image = true;
    const SphereRun ref = simulate_sphere(sc, so);
    testing::ZTally zones;
    for (int j = 0; j < nb; ++j) {
        const double b0 = kPi * j / nb, b1 = kPi * (j + 1) / nb;
        const double zone = 2 * (std::cos(b0) - std::cos(b1));
        zones.add_pair(r.mean[static_cast<size_t>(j)] / zone, r.se[static_cast<size_t>(j)] / zone,
                       ref.exitance[0][static_cast<size_t>(j)],
                       ref.exitance_se[0][static_cast<size_t>(j)]);
    }
    std::printf("  [measured] tessellated vs exact sphere: chi2 %.1f over %d zones, max |z| %.2f\n",
                zones.chi2, zones.n, zones.max_abs);
    EXPECT_GE(zones.n, 15);
    EXPECT_LT(zones.chi2, testing::chi2_critical(zones.n, testing::sidak(0.001, 2)));
    // The image: the engine's layer is M / pi per pixel [per unit E0]; ours the same estimator.
    const ImageLayer& E = ref.image->layer("exitance");
    const ImageLayer& Es = ref.image->layer("exitance.stderr");
    const double to_exitance = R * R / (cam.pixel_cm * cam.pixel_cm);
    testing::ZTally pixels;
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = static_cast<size_t>(nb + y * W + x);
            pixels.add_pair(r.mean[i] * to_exitance, r.se[i] * to_exitance, E.at(x, y, 0),
                            Es.at(x, y, 0));
        }
    std::printf(
        "  [measured] exitance image, tessellated vs exact sphere: chi2 %.1f over %d pixels, "
        "max |z| %.2f\n",
        pixels.chi2, pixels.n, pixels.max_abs);
    EXPECT_GT(pixels.n, 150);
    EXPECT_LT(pixels.chi2, testing::chi2_critical(pixels.n, testing::sidak(0.001, 2)));
    EXPECT_LT(pixels.max_abs, testing::normal_quantile(1 - 0.0005 / pixels.n));
}

}  // namespace
}  // namespace ssslab::volpath
