// Heterogeneous media from OpenVDB grids (volpath/density_grid.h) tracked by delta tracking:
// a constant-density grid (active voxels and background alike) equals the homogeneous medium
// of the scaled coefficients, and a two-level grid equals the layered slab of the pencil
// engine, bin by bin; bad grids are refused. Skipped when the build has no OpenVDB.
#include "core/batch_runner.h"
#include "core/error.h"
#include "core/material.h"
#include "core/mesh.h"
#include "core/rng.h"
#include "core/scene.h"
#include "testing.h"
#include "volpath/density_grid.h"
#include "volpath/embree_scene.h"
#include "volpath/mesh_medium.h"
#include "volpath/pencil.h"
#include "volpath/render.h"
#include "volpath/sampling.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>

#ifdef SSSLAB_HAVE_OPENVDB
#include <openvdb/openvdb.h>
#endif

namespace ssslab::volpath {
namespace {

#ifdef SSSLAB_HAVE_OPENVDB

// A float grid named "density" with voxel size (vx, vy, vz) [world units]: `background`
// everywhere, `value` on the active voxels whose centres lie in [lo, hi].
void write_grid(const std::string& path, double vx, double vy, double vz, double background,
                double value, const Vec3& lo, const Vec3& hi) {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(static_cast<float>(background));
    grid->setName("density");
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.preScale(openvdb::Vec3d(vx, vy, vz));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(m));
    auto acc = grid->getAccessor();
    const openvdb::Coord a(static_cast<int>(std::ceil(lo.x / vx)),
                           static_cast<int>(std::ceil(lo.y / vy)),
                           static_cast<int>(std::ceil(lo.z / vz)));
    const openvdb::Coord b(static_cast<int>(std::floor(hi.x / vx)),
                           static_cast<int>(std::floor(hi.y / vy)),
                           static_cast<int>(std::floor(hi.z / vz)));
    grid->tree().fill(openvdb::CoordBBox(a, b), static_cast<float>(value), true);
    openvdb::io::File(path).write({grid});
}

std::int64_t scaled(double n) {
    return static_cast<std::int64_t>(n * testing::test_scale());
}

// A pencil beam into the middle of the top face (y = 50) of a 100 cm box of medium `m` with
// the density grid; R_d(r) per cm^2 with standard errors (MCML's bins), entry factor included.
struct Profile {
    std::vector<double> v, se;
};
Profile box_profile(const Medium& med, const DensityGrid* grid, PencilGrid pg,
                    std::uint32_t stream) {
    const TriangleMesh box = make_box({100, 100, 100});
    const EmbreeScene es({&box});
    MeshMedium m;
    m.scene = &es;
    m.sigma_t = {med.sigma_a_per_cm[0] + med.sigma_s_per_cm[0], 0, 0};
    m.sigma_s = {med.sigma_s_per_cm[0], 0, 0};
    m.g = {med.g[0], 0, 0};
    m.eta_inside = med.eta;
    m.density = grid;
    const double rsp = entry_specular(med);
    BatchRunOptions o;
    o.tally_size = static_cast<std::size_t>(pg.nr);
    o.budget.samples = scaled(1e5);
    o.batch_samples = o.budget.samples.value() / 64;
    const BatchRunResult r = run_batches(o, [&](std::uint64_t index, std::int64_t n, double* t) {
        RngStream rng(9, rng_domain::kTest + stream, index);
        std::uint64_t work = 0;
        for (std::int64_t i = 0; i < n; ++i) {
            const WalkResult w = walk_mesh_medium<1>(m, {0, 50, 0}, {0, -1, 0}, rng);
            work += static_cast<std::uint64_t>(w.events);
            if (w.fate != WalkResult::Fate::kExited || std::fabs(w.p.y - 50) > 1e-4) continue;
            const double bin = std::hypot(w.p.x, w.p.z) / pg.dr_cm;
            if (bin < pg.nr) t[static_cast<std::size_t>(bin)] += (1 - rsp) * w.weight[0];
        }
        return work;
    });
    Profile p;
    for (int i = 0; i < pg.nr; ++i) {
        const double area = 2 * kPi * (i + 0.5) * pg.dr_cm * pg.dr_cm;
        p.v.push_back(r.mean[static_cast<size_t>(i)] / area);
        p.se.push_back(r.se[static_cast<size_t>(i)] / area);
    }
    return p;
}

void expect_agree(const Profile& a, const std::vector<double>& rv, const std::vector<double>& rs,
                  const char* what) {
    testing::ZTally t;
    for (size_t i = 0; i < a.v.size(); ++i) t.add_pair(a.v[i], a.se[i], rv[i], rs[i]);
    std::printf("  [measured] %s: chi2 %.1f over %d bins, max |z| %.2f\n", what, t.chi2, t.n,
                t.max_abs);
    EXPECT_GT(t.n, 40) << what;
    EXPECT_LT(t.chi2, testing::chi2_critical(t.n, testing::sidak(0.001, 2))) << what;
}

TEST(Vdb, ConstantDensityGridEqualsTheHomogeneousMedium) {
    // Skin1 red with doubled coefficients in a grid of density 0.5: active voxels (0.02 cm)
    // around the beam, background 0.5 beyond them. Against the pencil engine on Skin1.
    testing::TempDir dir;
    const std::string path = (dir / "c.vdb").string();
    write_grid(path, 0.02, 0.02, 0.02, 0.5, 0.5, {-1, 48, -1}, {1, 50.5, 1});
    const auto grid = DensityGrid::load(path, "density");
    EXPECT_DOUBLE_EQ(grid->max_density(), 0.5);
    EXPECT_NEAR(grid->density({0.011, 49.5, -0.3}), 0.5, 1e-7);
    EXPECT_NEAR(grid->density({30, 0, 0}), 0.5, 1e-7);  // background
    const Medium skin = *find_material("Skin1");
    Medium doubled = skin;
    for (int c = 0; c < 3; ++c) {
        doubled.sigma_a_per_cm[c] *= 2;
        doubled.sigma_s_per_cm[c] *= 2;
    }
    const PencilGrid pg{0.02, 80};
    const Profile p = box_profile(doubled, grid.get(), pg, 70);
    PencilOptions po;
    po.budget.samples = scaled(1e5);
    po.only_channel = 0;
    po.seed = 71;
    const PencilRun ref = simulate_pencil(skin, pg, po);
    expect_agree(p, ref.profile.rd_per_cm2[0], ref.profile.se_per_cm2[0],
                 "constant grid vs homogeneous");
}

TEST(Vdb, TwoLevelGridEqualsTheLayeredSlab) {
    // Density 1 in the top 0.1 cm, 0.25 below (background): the pencil engine's two-layer slab
    // with an index-matched interface (Skin1 red, then a quarter of it). Voxels 0.0005 cm thick
    // in y, so trilinear smearing of the step is 0.5 % of the layer.
    testing::TempDir dir;
    const std::string path = (dir / "s.vdb").string();
    write_grid(path, 0.05, 0.0005, 0.05, 0.25, 1.0, {-3, 49.9, -3}, {3, 50.5, 3});
    const auto grid = DensityGrid::load(path, "density");
    EXPECT_DOUBLE_EQ(grid->max_density(), 1.0);
    const Medium skin = *find_material("Skin1");
    const PencilGrid pg{0.02, 80};
    const Profile p = box_profile(skin, grid.get(), pg, 72);
    Medium layered = skin;
    layered.thickness_cm = 0.1;
    MediumLayer below{skin.sigma_a_per_cm, skin.sigma_s_per_cm, skin.g, skin.eta, 1e8};
    for (int c = 0; c < 3; ++c) {
        below.sigma_a_per_cm[c] *= 0.25;
        below.sigma_s_per_cm[c] *= 0.25;
    }
    layered.lower_layers = {below};
    PencilOptions po;
    po.budget.samples = scaled(1e5);
    po.only_channel = 0;
    po.seed = 73;
    const PencilRun ref = simulate_pencil(layered, pg, po);
    expect_agree(p, ref.profile.rd_per_cm2[0], ref.profile.se_per_cm2[0],
                 "two-level grid vs layered slab");
    // ... and it is not the homogeneous slab of either level.
    const PencilRun top = simulate_pencil(skin, pg, po);
    double chi2 = 0;
    for (size_t i = 0; i < p.v.size(); ++i)
        if (p.se[i] > 0 && top.profile.se_per_cm2[0][i] > 0)
            chi2 += std::pow((p.v[i] - top.profile.rd_per_cm2[0][i]) /
                                 std::hypot(p.se[i], top.profile.se_per_cm2[0][i]),
                             2);
    EXPECT_GT(chi2, 3 * pg.nr);
}

TEST(Vdb, RenderedWhiteFurnaceWithAHeterogeneousChromaticMedium) {
    // Albedo 1, density 1 in a cube inside the sphere and 0.1 around it, chromatic scattering:
    // null collisions carry the hero MIS weights; every pixel must return the environment.
    testing::TempDir dir;
    write_grid((dir / "d.vdb").string(), 0.05, 0.05, 0.05, 0.1, 1.0, {-0.6, -0.6, -0.6},
               {0.6, 0.6, 0.6});
    dir.write("s.toml", R"([camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 20
width = 16
height = 16
[[lights]]
type = "environment"
radiance = 1
[[materials]]
name = "m"
sigma_a_per_mm = 0
sigma_s_per_mm = [0.4, 1.0, 3.0]
g = [0.0, 0.3, 0.8]
eta = 1.33
density_vdb = "d.vdb"
[[shapes]]
type = "sphere"
radius = 1.2
subdivisions = 4
material = "m"
)");
    const Scene s = read_scene((dir / "s.toml").string());
    RenderOptions o;
    o.budget.samples = static_cast<std::int64_t>(64 * testing::test_scale());
    const RenderResult r = render(s, o);
    const ImageLayer& L = r.image.layer("radiance");
    const ImageLayer& E = r.image.layer("radiance.stderr");
    const double zc = testing::normal_quantile(1 - 0.0005 / (16 * 16 * 3));
    double worst = 0;
    int tested = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                if (!(E.at(x, y, c) > 0)) continue;
                const double z = (L.at(x, y, c) - 1.0) / E.at(x, y, c);
                worst = std::max(worst, std::fabs(z));
                ++tested;
                EXPECT_LT(std::fabs(z), zc) << x << "," << y << " c" << c;
            }
    std::printf("  [measured] heterogeneous furnace: %d pixel-channels, worst |z| %.2f\n", tested,
                worst);
    EXPECT_GT(tested, 100);
}

TEST(Vdb, BadGridsAndScenesAreRefused) {
    testing::TempDir dir;
    write_grid((dir / "g.vdb").string(), 0.1, 0.1, 0.1, 0.0, 1.0, {0, 0, 0}, {1, 1, 1});
    EXPECT_THROW((void)DensityGrid::load((dir / "g.vdb").string(), "smoke"), InputError);
    EXPECT_THROW((void)DensityGrid::load((dir / "none.vdb").string(), "density"), InputError);
    write_grid((dir / "n.vdb").string(), 0.1, 0.1, 0.1, 0.0, -1.0, {0, 0, 0}, {1, 1, 1});
    EXPECT_THROW((void)DensityGrid::load((dir / "n.vdb").string(), "density"), InputError);
    // In a scene: a wrong grid name is reported at the material's line when rendering.
    dir.write("s.toml", R"([camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 30
[[lights]]
type = "environment"
radiance = 1
[[materials]]
name = "m"
preset = "Skin1"
density_vdb = "g.vdb"
density_grid = "smoke"
[[shapes]]
type = "sphere"
radius = 1
material = "m"
)");
    const Scene s = read_scene((dir / "s.toml").string());
    RenderOptions o;
    o.budget.samples = 1;
    o.width = o.height = 4;
    try {
        (void)render(s, o);
        FAIL() << "accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("s.toml:9"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("smoke"), std::string::npos) << e.what();
    }
}

TEST(Vdb, ARenderCheckpointIsRefusedWhenItsGridChanged) {
    // Issue 12: a render interrupted, its grid file rewritten with another density, resumed:
    // refused naming the grid, not 10 samples of one medium and the rest of another.
    testing::TempDir dir;
    write_grid((dir / "d.vdb").string(), 0.05, 0.05, 0.05, 0.1, 1.0, {-0.6, -0.6, -0.6},
               {0.6, 0.6, 0.6});
    dir.write("s.toml", R"([camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 20
width = 8
height = 8
[[lights]]
type = "environment"
radiance = 1
[[materials]]
name = "m"
preset = "Skin1"
roughness = 0.2
density_vdb = "d.vdb"
[[shapes]]
type = "sphere"
radius = 1.2
subdivisions = 3
material = "m"
)");
    RenderOptions o;
    o.budget.samples = 30;
    o.checkpoint_path = (dir / "r.ckpt").string();
    o.checkpoint_seconds = 0;
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    o.on_batch = [&](const BatchProgress& p) {
        if (p.samples >= 6) cancel = true;
    };
    ASSERT_TRUE(render(read_scene((dir / "s.toml").string()), o).interrupted);
    write_grid((dir / "d.vdb").string(), 0.05, 0.05, 0.05, 0.1, 2.0, {-0.6, -0.6, -0.6},
               {0.6, 0.6, 0.6});
    o.cancel = nullptr;
    o.on_batch = nullptr;
    try {
        (void)render(read_scene((dir / "s.toml").string()), o);
        FAIL() << "resumed across a changed grid";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("materials[0].density_vdb: content changed"),
                  std::string::npos)
            << e.what();
    }
}

#else

TEST(Vdb, UnavailableInThisBuild) {
    EXPECT_FALSE(DensityGrid::available());
    EXPECT_THROW((void)DensityGrid::load("x.vdb", "density"), InputError);
}

#endif

}  // namespace
}  // namespace ssslab::volpath
