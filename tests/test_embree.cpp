// Ray queries through Embree (volpath/embree_scene.h) against closed forms: distances to a
// tessellated sphere and box, outward normals from inside and outside, the nearest of several
// shapes, occlusion, and watertightness (no ray from inside a closed mesh escapes).
#include "core/mesh.h"
#include "core/rng.h"
#include "testing.h"
#include "volpath/embree_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace ssslab::volpath {
namespace {

Vec3 random_direction(RngStream& rng) {
    const double z = 2 * rng.uniform() - 1, phi = 2 * std::numbers::pi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

TEST(Embree, DistancesAndNormalsMatchTheShapes) {
    const double R = 2.0;
    const TriangleMesh sphere = transformed(make_sphere(R, 5), {{1, 1, 1}, {0, 0, 0}, {1, 2, 3}});
    const TriangleMesh box = transformed(make_box({2, 4, 6}), {{1, 1, 1}, {0, 0, 0}, {30, 2, 3}});
    const EmbreeScene es({&sphere, &box});
    EXPECT_EQ(es.triangles(), sphere.triangles.size() + 12);
    // The icosphere (5 subdivisions) lies within R (1 - 2e-3) .. R of the sphere.
    const double tol = 2e-3 * R;
    RngStream rng(1, rng_domain::kTest + 40, 0);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 d = random_direction(rng);
        // From outside, aimed at the centre.
        const Vec3 o = Vec3{1, 2, 3} - d * 10.0;
        const RayHit h = es.intersect(o, d);
        ASSERT_TRUE(h.hit());
        EXPECT_EQ(h.shape, 0u);
        EXPECT_NEAR(h.t, 10.0 - R, tol);
        EXPECT_LT(dot(h.normal, d), -0.99);  // outward, facing the ray
        // From the centre outwards: the far side, normal along the ray.
        const RayHit e = es.intersect({1, 2, 3}, d);
        ASSERT_TRUE(e.hit());
        EXPECT_NEAR(e.t, R, tol);
        EXPECT_GT(dot(e.normal, d), 0.99);
    }
    // The box, exactly: along +x from x = 24 its face at x = 29.
    const RayHit b = es.intersect({24, 2, 3}, {1, 0, 0});
    EXPECT_EQ(b.shape, 1u);
    EXPECT_NEAR(b.t, 5.0, 1e-6);
    EXPECT_NEAR(b.normal.x, -1.0, 1e-12);
    // Nearest of two along one ray; t_min skips the sphere; occlusion of segments.
    const RayHit both = es.intersect({-5, 2, 3}, {1, 0, 0});
    EXPECT_EQ(both.shape, 0u);
    EXPECT_NEAR(both.t, 6 - R, tol);
    const RayHit past = es.intersect({-5, 2, 3}, {1, 0, 0}, 6 + R + 0.1);
    EXPECT_EQ(past.shape, 1u);
    EXPECT_NEAR(past.t, 34.0, 1e-5);
    EXPECT_TRUE(es.occluded({-5, 2, 3}, {1, 0, 0}, 0, 10));
    EXPECT_FALSE(es.occluded({-5, 2, 3}, {1, 0, 0}, 0, 6 - R - 0.01));
    EXPECT_FALSE(es.occluded({-5, 2, 3}, {1, 0, 0}, 6 + R + 0.1, 33.9));
    EXPECT_FALSE(es.intersect({0, 50, 0}, {0, 1, 0}).hit());
}

TEST(Embree, ClosedMeshesAreWatertight) {
    // Rays from random points inside a closed mesh (through vertices and edges as often as
    // chance has it) always find the boundary: a leak would let a photon escape a medium.
    const TriangleMesh bumpy = make_bumpy_sphere(1.0, 0.1, 6.0, 3, 4);
    const TriangleMesh torus =
        transformed(make_torus(3, 1, 64, 32), {{1, 1, 1}, {0, 0, 0}, {10, 0, 0}});
    const EmbreeScene es({&bumpy, &torus});
    RngStream rng(2, rng_domain::kTest + 41, 0);
    int misses = 0;
    for (int i = 0; i < 200000; ++i) {
        const Vec3 o = random_direction(rng) * (0.8 * rng.uniform());
        const Vec3 d = random_direction(rng);
        const RayHit h = es.intersect(o, d);
        if (!h.hit() || h.shape != 0 || !(dot(h.normal, d) > 0)) ++misses;
        // ... and from inside the torus tube.
        const double u = 2 * std::numbers::pi * rng.uniform();
        const Vec3 c = Vec3{10 + 3 * std::cos(u), 3 * std::sin(u), 0} + random_direction(rng) * 0.5;
        const RayHit t = es.intersect(c, d);
        if (!t.hit() || t.shape != 1) ++misses;
    }
    EXPECT_EQ(misses, 0);
}

TEST(Embree, CrossingsRecordThePassableBoundariesOfASegment) {
    // Three unit boxes along x (faces exact in floats) at x in [1, 2], [3, 4], [5, 6]: the
    // first two passable, the third opaque. One query records the passable faces a segment
    // crosses (each once after sorting and merging repeats), stops at an opaque one, skips the
    // triangle a ray leaves, and says when the buffer is too small.
    std::vector<TriangleMesh> boxes;
    for (int k = 0; k < 3; ++k) {
        TriangleMesh b = make_box({1, 1, 1});
        for (Vec3& v : b.positions) v += Vec3{1.5 + 2 * k, 0, 0};
        boxes.push_back(std::move(b));
    }
    const EmbreeScene es({&boxes[0], &boxes[1], &boxes[2]});
    const std::vector<char> passable = {1, 1, 0};
    EmbreeScene::Crossing buf[8];
    std::size_t n = 0;
    // Distances of the distinct crossings, sorted (a hit may come twice).
    auto distinct = [&] {
        std::vector<double> t;
        for (std::size_t i = 0; i < n; ++i) t.push_back(buf[i].t);
        std::sort(t.begin(), t.end());
        t.erase(std::unique(t.begin(), t.end()), t.end());
        return t;
    };
    const Vec3 o{0, 0.1, 0.2}, d{1, 0, 0};
    EXPECT_EQ(es.crossings(o, d, 0, 4.5, {}, passable, buf, 8, n), EmbreeScene::Through::kClear);
    EXPECT_EQ(distinct(), (std::vector<double>{1, 2, 3, 4}));
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(buf[i].shape, buf[i].t < 2.5 ? 0u : 1u);
        const Vec3& nrm = es.normal(buf[i].shape, buf[i].triangle);
        EXPECT_EQ(nrm.x, buf[i].t == 1 || buf[i].t == 3 ? -1.0 : 1.0);  // entering, leaving
    }
    // The opaque box blocks a longer segment; a shorter one crosses the first box only.
    EXPECT_EQ(es.crossings(o, d, 0, 5.5, {}, passable, buf, 8, n), EmbreeScene::Through::kBlocked);
    EXPECT_EQ(es.crossings(o, d, 0, 2.5, {}, passable, buf, 8, n), EmbreeScene::Through::kClear);
    EXPECT_EQ(distinct(), (std::vector<double>{1, 2}));
    // Too small a buffer.
    EXPECT_EQ(es.crossings(o, d, 0, 4.5, {}, passable, buf, 3, n), EmbreeScene::Through::kTooMany);
    // Leaving the first box's entry face from its point: that face is skipped.
    const RayHit entry = es.intersect(o, d);
    ASSERT_EQ(entry.shape, 0u);
    EXPECT_EQ(es.crossings(o + d * entry.t, d, 0, 3.5, {entry.shape, entry.triangle}, passable, buf,
                           8, n),
              EmbreeScene::Through::kClear);
    EXPECT_EQ(distinct(), (std::vector<double>{1, 2, 3}));  // from x = 1: x = 2, 3, 4
    // Nothing passable: the first box blocks.
    EXPECT_EQ(es.crossings(o, d, 0, 4.5, {}, {0, 0, 0}, buf, 8, n), EmbreeScene::Through::kBlocked);
}

}  // namespace
}  // namespace ssslab::volpath

namespace ssslab::volpath {
namespace {

TEST(Embree, DistanceToTheNearestSurfaceIsTheClosedForm) {
    // Inside a 4 x 2 x 6 box (vertices exact in floats) the nearest surface is the nearest
    // face: min over the axes of (half size - |p_i|); outside, the distance to the box; a
    // second shape nearer than the faces wins; the cap bounds the answer.
    const TriangleMesh box = make_box({4, 2, 6});
    TriangleMesh small = make_box({0.25, 0.25, 0.25});  // exact in floats
    for (Vec3& v : small.positions) v += Vec3{1.5, 0, 2.5};
    const EmbreeScene one({&box}), two({&box, &small});
    RngStream rng(2, rng_domain::kTest + 63, 0);
    for (int i = 0; i < 2000; ++i) {
        const Vec3 p{4 * rng.uniform() - 2, 2 * rng.uniform() - 1, 6 * rng.uniform() - 3};
        const double faces = std::min({2 - std::fabs(p.x), 1 - std::fabs(p.y), 3 - std::fabs(p.z)});
        EXPECT_NEAR(one.distance_to_surface(p, 100), faces, 1e-12);
        EXPECT_EQ(one.distance_to_surface(p, 0.1), std::min(0.1, faces));
        // The small box: the distance to its surface from outside it.
        const Vec3 q = p - Vec3{1.5, 0, 2.5};
        const double dx = std::max(std::fabs(q.x) - 0.125, 0.0),
                     dy = std::max(std::fabs(q.y) - 0.125, 0.0),
                     dz = std::max(std::fabs(q.z) - 0.125, 0.0);
        const bool inside_small = dx == 0 && dy == 0 && dz == 0;
        if (inside_small) continue;
        const double to_small = std::sqrt(dx * dx + dy * dy + dz * dz);
        EXPECT_NEAR(two.distance_to_surface(p, 100), std::min(faces, to_small), 1e-12);
    }
    // Outside: the distance to the box.
    EXPECT_NEAR(one.distance_to_surface({5, 0, 0}, 100), 3.0, 1e-12);
    EXPECT_NEAR(one.distance_to_surface({3, 2, 0}, 100), std::sqrt(2.0), 1e-12);
}

}  // namespace
}  // namespace ssslab::volpath
