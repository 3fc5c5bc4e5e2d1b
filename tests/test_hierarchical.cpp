// Hierarchical integration over point clouds [JB02; Bitterli13 §2.6.4] (approx/hierarchical.h):
// the octree with a threshold of 0 is the brute-force sum to the bit; a constant irradiance on a
// large flat medium gives the profile's total diffuse reflectance (a z-test: with independent
// uniform points the sum is a Monte Carlo estimate of the plane integral, its standard error from
// the points' contributions); clustering error and cost against the threshold; the point cloud's
// count, areas, uniformity (chi-square) and blue noise; bad input.
#include "approx/diffusion.h"
#include "approx/hierarchical.h"
#include "core/mesh.h"
#include "core/rng.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

namespace ssslab::approx {
namespace {

std::shared_ptr<const DiffusionProfile> dipole(double sigma_a, double sigma_s, double eta) {
    DiffusionMedium m;
    m.sigma_a = sigma_a;
    m.sigma_s = sigma_s;
    m.eta = eta;
    return make_diffusion_profile("dipole", m);
}

/// Three media per mm (a diffuse mean free path of 1.8, 0.9 and 3.2 mm).
RadialFunction three_dipoles() {
    return RadialFunction::from_diffusion(
        {dipole(0.05, 2.0, 1.3), dipole(0.2, 2.0, 1.3), dipole(0.02, 1.5, 1.5)});
}

/// Points on a sphere of radius 10 mm with a random irradiance per point and channel.
std::vector<SurfacePoint> lit_sphere(double density) {
    PointCloudOptions o;
    o.points_per_mm2 = density;
    std::vector<SurfacePoint> p = sample_surface(make_sphere(10, 3), 1.0, 0, o);
    RngStream rng(7, rng_domain::kTest + 300, 0);
    for (SurfacePoint& s : p)
        for (double& e : s.irradiance) e = rng.uniform();
    return p;
}

std::vector<Vec3> queries_on(const std::vector<SurfacePoint>& p, size_t n) {
    std::vector<Vec3> q;
    for (size_t i = 0; i < n; ++i) q.push_back(p[(i * 7919) % p.size()].position_mm);
    q.push_back({0, 0, 0});   // inside
    q.push_back({0, 25, 3});  // outside
    return q;
}

TEST(PointOctree, AThresholdOfZeroIsTheBruteForceSumBitForBit) {
    const PointOctree tree(lit_sphere(2), 8);
    const RadialFunction rd = three_dipoles();
    const std::vector<Vec3> q = queries_on(tree.points(), 40);
    for (bool conservative : {false, true}) {
        HierarchicalOptions o;
        o.max_solid_angle = 0;
        o.conservative = conservative;
        HierarchicalStats s;
        const auto many = tree.exitance(rd, q, o, &s);
        EXPECT_EQ(s.points, q.size() * tree.points().size());
        EXPECT_EQ(s.clusters, 0u);
        for (size_t i = 0; i < q.size(); ++i) {
            const auto b = tree.brute_force(rd, q[i]);
            EXPECT_EQ(tree.exitance(rd, q[i], o), b) << i;
            EXPECT_EQ(many[i], b) << i;
        }
    }
}

TEST(PointOctree, ClusteringErrorAndCostFallWithTheThreshold) {
    const PointOctree tree(lit_sphere(2), 8);
    const RadialFunction rd = three_dipoles();
    const std::vector<Vec3> q = queries_on(tree.points(), 60);
    std::vector<std::array<double, 3>> exact;
    for (const Vec3& x : q) exact.push_back(tree.brute_force(rd, x));
    auto rms_error = [&](const std::vector<std::array<double, 3>>& m) {
        double se = 0, ss = 0;
        for (size_t i = 0; i < q.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                se += (m[i][c] - exact[i][c]) * (m[i][c] - exact[i][c]);
                ss += exact[i][c] * exact[i][c];
            }
        return std::sqrt(se / ss);
    };
    double last_error = std::numeric_limits<double>::infinity();
    std::uint64_t last_cost = 0;
    for (double eps : {0.3, 0.03, 0.003}) {
        HierarchicalOptions o;
        o.max_solid_angle = eps;
        HierarchicalStats plain, cons;
        const double e = rms_error(tree.exitance(rd, q, o, &plain));
        o.conservative = true;
        const double ec = rms_error(tree.exitance(rd, q, o, &cons));
        std::printf("eps %.3g: relative RMS error %.3g (%llu nodes), conservative %.3g (%llu)\n",
                    eps, e, static_cast<unsigned long long>(plain.nodes_visited), ec,
                    static_cast<unsigned long long>(cons.nodes_visited));
        EXPECT_LT(e, last_error) << eps;
        EXPECT_GT(plain.nodes_visited, last_cost) << eps;
        // The box is never farther than the centre of power: the conservative rule opens every
        // node the plain one opens, and more.
        EXPECT_GE(cons.nodes_visited, plain.nodes_visited) << eps;
        EXPECT_GT(plain.clusters, 0u) << eps;
        last_error = e;
        last_cost = plain.nodes_visited;
    }
    // At the finest threshold the clusters' error is well below a percent.
    EXPECT_LT(last_error, 1e-2);
}

// A quad of 100 mm lit uniformly with E = (1, 0.5, 2) per channel; K queries uniform in its
// central 20 x 20 mm, 40 mm or more from every edge (the dipoles' R_dr beyond 40 mm is below 1e-4
// of their total): the mean exitance over the queries is E R_dr per channel. With independent
// uniform points the mean is a sum over points of i.i.d. terms g_p = (1/K) sum_k R_d(|x_k - p|)
// E A, so its standard error is sqrt(N var g): a z-test. Poisson-disk points, with and without
// clustering, must do at least as well.
TEST(PointOctree, AConstantIrradianceOnALargeFlatMediumGivesTheTotalDiffuseReflectance) {
    const std::array<std::shared_ptr<const DiffusionProfile>, 3> media = {
        dipole(0.05, 2.0, 1.3), dipole(0.2, 2.0, 1.3), dipole(0.02, 1.5, 1.5)};
    const RadialFunction rd = RadialFunction::from_diffusion(media);
    const std::array<double, 3> e = {1, 0.5, 2};
    std::vector<Vec3> x;
    RngStream rng(3, rng_domain::kTest + 301, 0);
    for (int k = 0; k < 128; ++k)
        x.push_back({20 * rng.uniform() - 10, 0, 20 * rng.uniform() - 10});
    const double kq = static_cast<double>(x.size());
    auto mean = [&](const std::vector<std::array<double, 3>>& m) {
        std::array<double, 3> s{};
        for (const auto& v : m)
            for (int c = 0; c < 3; ++c) s[c] += v[c] / kq;
        return s;
    };
    std::array<double, 3> se_iid{};
    for (int candidates : {1, 5}) {
        PointCloudOptions po;
        po.points_per_mm2 = 4 * testing::test_scale();
        po.candidates_per_point = candidates;
        std::vector<SurfacePoint> p = sample_surface(make_quad(100, 100), 1.0, 0, po);
        for (SurfacePoint& s : p) s.irradiance = e;
        const PointOctree tree(std::move(p));
        HierarchicalOptions o;
        o.max_solid_angle = 0;
        const auto m = mean(tree.exitance(rd, x, o));
        o.max_solid_angle = 0.01;
        HierarchicalStats st;
        const auto mc = mean(tree.exitance(rd, x, o, &st));
        if (candidates == 1) {
            std::array<double, 3> sum{}, sum2{};
            for (const SurfacePoint& s : tree.points()) {
                std::array<double, 3> g{};
                for (const Vec3& q : x) {
                    const auto f = rd(length(q - s.position_mm));
                    for (int c = 0; c < 3; ++c) g[c] += f[c] * e[c] * s.area_mm2 / kq;
                }
                for (int c = 0; c < 3; ++c) {
                    sum[c] += g[c];
                    sum2[c] += g[c] * g[c];
                }
            }
            const double n = static_cast<double>(tree.points().size());
            for (int c = 0; c < 3; ++c)
                se_iid[c] = std::sqrt(n * (sum2[c] / n - (sum[c] / n) * (sum[c] / n)));
        }
        for (int c = 0; c < 3; ++c) {
            const double expected = e[c] * media[c]->total_rd();
            const double z = (m[c] - expected) / se_iid[c], zc = (mc[c] - expected) / se_iid[c];
            std::printf(
                "channel %d, %s points: mean M %.6g (clustered at 0.01 sr: %.6g, %.3g "
                "nodes a query), E R_dr %.6g, SE (independent points) %.2g: z %.2f, "
                "clustered %.2f\n",
                c, candidates == 1 ? "uniform" : "Poisson-disk", m[c], mc[c],
                static_cast<double>(st.nodes_visited) / kq, expected, se_iid[c], z, zc);
            EXPECT_LT(std::fabs(z), 4.0) << c;
            EXPECT_LT(std::fabs(zc), 4.0) << c;
        }
    }
}

TEST(PointCloud, HasTheAskedDensityEqualAreasAndLiesOnTheMesh) {
    PointCloudOptions o;
    o.points_per_mm2 = 3;
    const TriangleMesh mesh = make_quad(20, 10);
    const auto p = sample_surface(mesh, 2.0, 4, o);  // 40 x 20 mm
    ASSERT_EQ(p.size(), 2400u);
    double area = 0;
    for (const SurfacePoint& s : p) {
        area += s.area_mm2;
        EXPECT_EQ(s.shape, 4u);
        EXPECT_EQ(s.position_mm.y, 0.0);
        EXPECT_LE(std::fabs(s.position_mm.x), 20.0);
        EXPECT_LE(std::fabs(s.position_mm.z), 10.0);
        EXPECT_EQ(s.normal, (Vec3{0, 1, 0}));
        EXPECT_EQ(s.area_mm2, 800.0 / 2400);
    }
    EXPECT_NEAR(area, 800, 1e-9);
}

TEST(PointCloud, IsUniformByChiSquareAndBitIdenticalForAnyThreadCount) {
    const TriangleMesh mesh = make_sphere(5, 3);
    for (int candidates : {1, 5}) {
        PointCloudOptions o;
        o.points_per_mm2 = 10;
        o.candidates_per_point = candidates;
        const auto p = sample_surface(mesh, 1.0, 0, o);
        std::vector<SurfacePoint> one;
        tbb::task_arena(1).execute([&] { one = sample_surface(mesh, 1.0, 0, o); });
        ASSERT_EQ(one.size(), p.size());
        for (size_t i = 0; i < p.size(); ++i) ASSERT_EQ(one[i].position_mm, p[i].position_mm);
        // Counts per triangle against its share of the area; chi-square over the triangles
        // (the points per triangle are multinomial for independent points; Poisson-disk points
        // are more even still).
        std::vector<double> count(mesh.triangles.size(), 0.0);
        for (const SurfacePoint& s : p) count[s.triangle] += 1;
        double chi2 = 0;
        const double total = mesh.area();
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const auto& tri = mesh.triangles[t];
            const double a = 0.5 * length(cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                                                mesh.positions[tri[2]] - mesh.positions[tri[0]]));
            const double expected = static_cast<double>(p.size()) * a / total;
            chi2 += (count[t] - expected) * (count[t] - expected) / expected;
        }
        const double dof = static_cast<double>(mesh.triangles.size() - 1);
        std::printf("candidates %d: %zu points, chi2 %.1f over %g dof\n", candidates, p.size(),
                    chi2, dof);
        EXPECT_LT(chi2, testing::chi2_critical(dof, 1e-4)) << candidates;
    }
}

TEST(PointCloud, IsBlueNoise) {
    // Mean nearest-neighbour distance: 1 / (2 sqrt(rho)) for independent uniform points
    // (a Poisson process of density rho); a Poisson-disk set keeps its points apart, towards
    // the hexagonal packing's 2 r_max = sqrt(2 / (sqrt(3) rho)) = 1.07 / sqrt(rho).
    const double rho = 4;
    for (int candidates : {1, 5}) {
        PointCloudOptions o;
        o.points_per_mm2 = rho;
        o.candidates_per_point = candidates;
        const auto p = sample_surface(make_quad(30, 30), 1.0, 0, o);
        double sum = 0;
        size_t n = 0;
        for (size_t i = 0; i < p.size(); ++i) {
            const Vec3& a = p[i].position_mm;
            if (std::fabs(a.x) > 13 || std::fabs(a.z) > 13) continue;  // away from the edges
            double best = std::numeric_limits<double>::infinity();
            for (size_t j = 0; j < p.size(); ++j)
                if (j != i) best = std::min(best, length(p[j].position_mm - a));
            sum += best;
            ++n;
        }
        const double mean = sum / static_cast<double>(n) * std::sqrt(rho);
        std::printf("candidates %d: mean nearest-neighbour distance %.3f / sqrt(rho)\n", candidates,
                    mean);
        if (candidates == 1)
            EXPECT_NEAR(mean, 0.5, 0.05);  // SE of the mean: 0.26 / sqrt(n) = 0.01
        else
            EXPECT_GT(mean, 0.75);  // 1.5 times the Poisson process's
    }
}

TEST(RadialFunction, AnMcProfileIsItsBinMeansAndZeroBeyond) {
    RadialProfile prof;
    prof.dr_cm = 0.01;
    prof.nr = 3;
    for (int c = 0; c < 3; ++c) prof.rd_per_cm2[c] = {100.0 * (c + 1), 50, 10};
    const RadialFunction f = RadialFunction::from_profile(prof);
    EXPECT_EQ(f(0.0)[0], 1.0);  // 100 / cm^2 = 1 / mm^2
    EXPECT_EQ(f(0.05)[2], 3.0);
    EXPECT_EQ(f(0.15)[1], 0.5);
    EXPECT_EQ(f(0.29)[0], 0.1);
    EXPECT_EQ(f(0.31)[0], 0.0);
}

TEST(HierarchicalBadInput, IsRefusedNamingWhatIsWrong) {
    const TriangleMesh quad = make_quad(1, 1);
    PointCloudOptions o;
    o.points_per_mm2 = 0;
    EXPECT_THROW(sample_surface(quad, 1, 0, o), std::invalid_argument);
    o.points_per_mm2 = 1;
    EXPECT_THROW(sample_surface(quad, 0, 0, o), std::invalid_argument);
    EXPECT_THROW(sample_surface(TriangleMesh{}, 1, 0, o), std::invalid_argument);
    o.candidates_per_point = 0;
    EXPECT_THROW(sample_surface(quad, 1, 0, o), std::invalid_argument);
    o.candidates_per_point = 5;
    o.points_per_mm2 = 1e9;
    EXPECT_THROW(sample_surface(quad, 1, 0, o), std::invalid_argument);

    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{}), std::invalid_argument);
    SurfacePoint bad;
    bad.irradiance = {1, -1, 1};
    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{bad}), std::invalid_argument);
    bad.irradiance = {1, 1, 1};
    bad.position_mm.x = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{bad}), std::invalid_argument);
    SurfacePoint good;
    good.area_mm2 = 1;
    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{good}, 0), std::invalid_argument);
    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{good}, 8, 0), std::invalid_argument);
    EXPECT_THROW(PointOctree(std::vector<SurfacePoint>{good}, 8, 65), std::invalid_argument);
    const PointOctree tree(std::vector<SurfacePoint>{good});
    HierarchicalOptions h;
    h.max_solid_angle = -1;
    EXPECT_THROW(tree.exitance(three_dipoles(), Vec3{}, h), std::invalid_argument);
}

// Coincident points (a degenerate cloud) end in one leaf instead of recursing forever.
TEST(PointOctree, CoincidentPointsMakeOneLeaf) {
    std::vector<SurfacePoint> p(100);
    for (SurfacePoint& s : p) {
        s.area_mm2 = 0.01;
        s.irradiance = {1, 1, 1};
    }
    const PointOctree tree(p, 8);
    EXPECT_EQ(tree.nodes(), 1u);
    HierarchicalOptions o;
    o.max_solid_angle = 0;
    EXPECT_EQ(tree.exitance(three_dipoles(), Vec3{1, 0, 0}, o),
              tree.brute_force(three_dipoles(), Vec3{1, 0, 0}));
}

// An analytic profile tabulated for millions of queries (RadialFunction::tabulated, what the
// frames use for dipole and pbd, 4096 radii from 1e-3 of a mean free path to a scene's
// diagonal): log-log interpolation within 1e-4 of the exact profile wherever it is above 1e-12
// of its peak (further out an exponential tail bends between the radii: 3e-3 at 1 m), f(r_min)
// below the range, 0 beyond it.
TEST(RadialFunction, TabulatedProfilesFollowTheExactOnes) {
    DiffusionMedium m;
    m.sigma_a = 0.05;
    m.sigma_s = 2.0;
    m.eta = 1.3;
    const std::shared_ptr<const DiffusionProfile> pbd = make_diffusion_profile("pbd", m);
    const RadialFunction exact =
        RadialFunction::from_diffusion({dipole(0.05, 2.0, 1.3), pbd, dipole(0.02, 1.5, 1.5)});
    const RadialFunction t = RadialFunction::tabulated(exact, 1e-3, 1e3, 4096);
    const auto peak = exact(1e-3);
    double worst = 0;
    RngStream rng(3, rng_domain::kTest + 301, 0);
    for (int i = 0; i < 4000; ++i) {
        const double r = 1e-3 * std::pow(1e6, rng.uniform());
        const auto a = exact(r), b = t(r);
        for (int c = 0; c < 3; ++c)
            if (a[c] > 1e-12 * peak[c]) worst = std::max(worst, std::abs(b[c] - a[c]) / a[c]);
    }
    std::printf("  [measured] worst relative error of the table: %.2e\n", worst);
    EXPECT_LT(worst, 1e-4);
    EXPECT_EQ(t(1e-6), exact(1e-3));
    EXPECT_EQ(t(2e3)[0], 0.0);
    EXPECT_THROW(RadialFunction::tabulated(exact, 0, 1, 10), std::invalid_argument);
    EXPECT_THROW(RadialFunction::tabulated(exact, 1, 1, 10), std::invalid_argument);
    EXPECT_THROW(RadialFunction::tabulated(exact, 1, 2, 1), std::invalid_argument);
    const RadialFunction negative([](double) { return std::array<double, 3>{1, -1, 1}; });
    EXPECT_THROW(RadialFunction::tabulated(negative, 1, 2, 10), std::invalid_argument);
}

TEST(JensenBuhlerSpec, NamesVariantsAndRefusesBadOnes) {
    const JensenBuhlerOptions o =
        parse_jensen_buhler("density=16,threshold=0.01,bound=box,profile=pbd,candidates=3");
    EXPECT_EQ(o.points_per_mm2, 16);
    EXPECT_EQ(o.max_solid_angle, 0.01);
    EXPECT_TRUE(o.conservative);
    EXPECT_EQ(o.profile, "pbd");
    EXPECT_EQ(o.candidates_per_point, 3);
    EXPECT_EQ(jensen_buhler_label(parse_jensen_buhler(jensen_buhler_label(o))),
              jensen_buhler_label(o));
    EXPECT_EQ(jensen_buhler_label(parse_jensen_buhler("")),
              "density=4,threshold=0.05,bound=centre,profile=mc,candidates=5");
    EXPECT_EQ(parse_jensen_buhler("threshold=0").max_solid_angle, 0.0);
    for (const char* bad :
         {"threshold=-0.01", "threshold=x", "threshold=inf", "density=0", "density=-1",
          "density=1e5", "bound=sphere", "profile=dipol", "candidates=0", "candidates=1.5",
          "colour=red", "density", "density=1,density=2"}) {
        EXPECT_THROW(parse_jensen_buhler(bad), std::invalid_argument) << bad;
        try {
            parse_jensen_buhler(bad);
        } catch (const std::invalid_argument& e) {
            EXPECT_EQ(std::string(e.what()).rfind("jensen_buhler", 0), 0u) << e.what();
        }
    }
}

}  // namespace
}  // namespace ssslab::approx
