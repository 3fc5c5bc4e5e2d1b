// The software rasterizer (realtime/raster.h): the top-left fill rule, watertightness, depth
// and perspective-correct barycentrics against ray-triangle closed forms through volpath's
// camera, near-plane clipping, supersampling, and determinism over thread counts.
#include "realtime/raster.h"

#include "core/mesh.h"
#include "core/scene.h"
#include "volpath/render.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

namespace ssslab::realtime {
namespace {

using Tri = std::array<std::uint32_t, 3>;

// Triangles given in raster coordinates (pixels, y down) of a width x height image, at w = 1:
// for power-of-two sizes and dyadic coordinates the clip coordinates are exact.
struct ScreenMesh {
    std::vector<Tri> triangles;
    RasterMesh mesh;
};
ScreenMesh screen_mesh(int width, int height, const std::vector<std::array<double, 2>>& points,
                       std::vector<Tri> triangles) {
    ScreenMesh s;
    s.triangles = std::move(triangles);
    for (const auto& p : points)
        s.mesh.vertices.push_back({2 * p[0] / width - 1, 1 - 2 * p[1] / height, 1.0});
    s.mesh.triangles = s.triangles;
    return s;
}
RasterCamera screen_camera(int width, int height) {
    RasterCamera c;
    c.width = width;
    c.height = height;
    c.aspect = static_cast<double>(width) / height;
    return c;
}

// Moller-Trumbore in double: the ray's distance to triangle (a, b, c), if it hits.
std::optional<double> ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b,
                                   const Vec3& c) {
    const Vec3 e1 = b - a, e2 = c - a, p = cross(d, e2);
    const double det = dot(e1, p);
    if (det == 0) return std::nullopt;
    const double inv = 1 / det;
    const Vec3 s = o - a;
    const double u = dot(s, p) * inv;
    if (u < 0 || u > 1) return std::nullopt;
    const Vec3 q = cross(s, e1);
    const double v = dot(d, q) * inv;
    if (v < 0 || u + v > 1) return std::nullopt;
    const double t = dot(e2, q) * inv;
    if (!(t > 0)) return std::nullopt;
    return t;
}

struct Hit {
    double t = 0;
    std::int64_t triangle = -1;
};
Hit nearest_hit(const TriangleMesh& m, const Vec3& o, const Vec3& d) {
    Hit h;
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
        const auto& tr = m.triangles[i];
        const auto t =
            ray_triangle(o, d, m.positions[tr[0]], m.positions[tr[1]], m.positions[tr[2]]);
        if (t && (h.triangle < 0 || *t < h.t)) h = {*t, static_cast<std::int64_t>(i)};
    }
    return h;
}

// Pixel position of a world point (in front of the camera).
std::array<double, 2> to_pixel(const RasterCamera& c, const Vec3& p) {
    const ClipVertex v = c.to_clip(p);
    return {(v.x / v.w + 1) * 0.5 * c.width, (1 - v.y / v.w) * 0.5 * c.height};
}
double segment_distance(const std::array<double, 2>& p, const std::array<double, 2>& a,
                        const std::array<double, 2>& b) {
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}
// Distance in pixels from a pixel point to the nearest projected edge of the mesh.
double edge_distance(const RasterCamera& c, const TriangleMesh& m, const std::array<double, 2>& p) {
    double best = 1e300;
    for (const auto& tr : m.triangles)
        for (int k = 0; k < 3; ++k)
            best = std::min(best, segment_distance(p, to_pixel(c, m.positions[tr[k]]),
                                                   to_pixel(c, m.positions[tr[(k + 1) % 3]])));
    return best;
}

std::size_t count_if_equal(const std::vector<std::uint32_t>& v, std::uint32_t x) {
    return static_cast<std::size_t>(std::count(v.begin(), v.end(), x));
}

// ---- the top-left rule ----------------------------------------------------------------------

// The Direct3D 11 rasterization rules' example (top-left rule): a 5 x 5 pixel square
// split along a diagonal. The five pixel centres on the diagonal belong to the triangle for
// which the diagonal is a left edge, so it covers 10 + 5 = 15 pixels and the other 10.
TEST(Raster, TopLeftRuleSquareSplitInTwo) {
    const int W = 8, H = 8;
    const std::vector<std::array<double, 2>> pts{{1, 1}, {6, 1}, {6, 6}, {1, 6}};
    for (bool reverse : {false, true})
        for (int diag : {0, 1}) {
            // Triangle 0 owns the diagonal in both layouts.
            std::vector<Tri> tris = diag == 0 ? std::vector<Tri>{{0, 2, 1}, {0, 3, 2}}
                                              : std::vector<Tri>{{1, 3, 2}, {0, 3, 1}};
            if (reverse)
                for (Tri& t : tris) std::swap(t[1], t[2]);
            const ScreenMesh s = screen_mesh(W, H, pts, tris);
            const RasterFrame f = rasterize(screen_camera(W, H), std::span(&s.mesh, 1));
            SCOPED_TRACE(testing::Message() << "diagonal " << diag << " reversed " << reverse);
            EXPECT_EQ(count_if_equal(f.triangle, 0), 15u);
            EXPECT_EQ(count_if_equal(f.triangle, 1), 10u);
            EXPECT_EQ(count_if_equal(f.fragments, 1), 25u);
            EXPECT_EQ(count_if_equal(f.fragments, 0), static_cast<std::size_t>(W * H - 25));
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const bool inside = x >= 1 && x <= 5 && y >= 1 && y <= 5;
                    EXPECT_EQ(f.fragments[f.sample_index(x, y)], inside ? 1u : 0u) << x << "," << y;
                    // On the diagonal: owned by triangle 0.
                    if (inside && (diag == 0 ? x == y : x + y == 6)) {
                        EXPECT_EQ(f.triangle[f.sample_index(x, y)], 0u) << x << "," << y;
                    }
                }
        }
}

// Culling: front faces are counter-clockwise on screen; a clockwise one vanishes when culled.
TEST(Raster, BackFaceCullingByScreenWinding) {
    const int W = 8, H = 8;
    const std::vector<std::array<double, 2>> pts{{1, 1}, {6, 1}, {6, 6}, {1, 6}};
    ScreenMesh s = screen_mesh(W, H, pts, {{0, 2, 1}, {0, 2, 3}});  // front, back
    s.mesh.cull_back_faces = true;
    const RasterFrame f = rasterize(screen_camera(W, H), std::span(&s.mesh, 1));
    EXPECT_EQ(count_if_equal(f.triangle, 0), 15u);
    EXPECT_EQ(count_if_equal(f.triangle, 1), 0u);
    // Front-face culling keeps the other one: its 10 samples (the 25 of the square less the
    // diagonal's, which the fill rule gives the first).
    s.mesh.cull_back_faces = false;
    s.mesh.cull_front_faces = true;
    const RasterFrame b = rasterize(screen_camera(W, H), std::span(&s.mesh, 1));
    EXPECT_EQ(count_if_equal(b.triangle, 0), 0u);
    EXPECT_EQ(count_if_equal(b.triangle, 1), 10u);
}

// A closed sphere (radius 2, 10 from the camera) with its front faces culled: every sample sees
// the far side of the same ray, the two hits symmetric about the ray's closest point to the
// centre, at 10 cos(theta) = 10 view_z / ray_t along the ray.
TEST(Raster, FrontFaceCullingSeesTheFarSideOfAClosedMesh) {
    Scene scene;  // the default camera: at (0, 0, 10) looking at the origin
    SceneShape sh;
    sh.mesh = make_sphere(2, 5);
    scene.shapes.push_back(sh);
    RasterOptions o;
    RasterFrame front, back;
    rasterize(scene, o, 64, 64, front);
    o.cull_front_closed = true;
    rasterize(scene, o, 64, 64, back);
    size_t seen = 0;
    for (size_t i = 0; i < front.view_z.size(); ++i) {
        if (!std::isfinite(front.view_z[i])) continue;
        ++seen;
        ASSERT_TRUE(std::isfinite(back.view_z[i])) << i;
        // Within the tessellation's error (the sag of a level-5 icosphere's faces, ~1e-3 r).
        const double mid = 0.5 * (front.ray_t[i] + back.ray_t[i]);
        EXPECT_NEAR(mid, 10 * front.view_z[i] / front.ray_t[i], 0.01) << i;
        EXPECT_GT(back.view_z[i], front.view_z[i] + 0.1) << i;
    }
    EXPECT_GT(seen, 500u);
}

// ---- watertightness ----------------------------------------------------------------------------

// A fan of N triangles around one vertex (a regular polygon, randomly wound triangles) covers
// every pixel centre inside the polygon exactly once, also with the centre vertex on a sample.
TEST(Raster, FanAroundOneVertexCoversEachPixelOnce) {
    const int W = 64, H = 64;
    std::mt19937_64 rng(20130213);
    std::uniform_real_distribution<double> u(0, 1);
    int cases = 0;
    for (int n : {3, 4, 5, 8, 17, 40, 97})
        for (int rep = 0; rep < 4; ++rep) {
            // rep 0: the shared vertex on a pixel centre; otherwise anywhere.
            const double cx = rep == 0 ? 31.5 : 24 + 16 * u(rng);
            const double cy = rep == 0 ? 32.5 : 24 + 16 * u(rng);
            const double r = 14 + 8 * u(rng), phase = 2 * std::numbers::pi * u(rng);
            std::vector<std::array<double, 2>> pts{{cx, cy}};
            for (int i = 0; i < n; ++i)
                pts.push_back({cx + r * std::cos(phase + 2 * std::numbers::pi * i / n),
                               cy + r * std::sin(phase + 2 * std::numbers::pi * i / n)});
            std::vector<Tri> tris;
            for (int i = 0; i < n; ++i) {
                Tri t{0, static_cast<std::uint32_t>(1 + i),
                      static_cast<std::uint32_t>(1 + (i + 1) % n)};
                if (u(rng) < 0.5) std::swap(t[1], t[2]);
                tris.push_back(t);
            }
            const ScreenMesh s = screen_mesh(W, H, pts, tris);
            const RasterFrame f = rasterize(screen_camera(W, H), std::span(&s.mesh, 1));
            std::size_t inside = 0;
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    // Signed distance to the polygon's rim (positive inside).
                    double d = 1e300;
                    for (int i = 0; i < n; ++i) {
                        const auto& a = pts[static_cast<std::size_t>(1 + i)];
                        const auto& b = pts[static_cast<std::size_t>(1 + (i + 1) % n)];
                        const double ex = b[0] - a[0], ey = b[1] - a[1];
                        auto side = [&](double px, double py) {
                            return ((px - a[0]) * ey - (py - a[1]) * ex) / std::hypot(ex, ey);
                        };
                        const double sign = side(cx, cy) > 0 ? 1 : -1;  // the centre is inside
                        d = std::min(d, sign * side(x + 0.5, y + 0.5));
                    }
                    const std::uint32_t c = f.fragments[f.sample_index(x, y)];
                    ASSERT_LE(c, 1u) << "n " << n << " rep " << rep << " at " << x << "," << y;
                    if (std::abs(d) > 0.01) {
                        EXPECT_EQ(c, d > 0 ? 1u : 0u) << "n " << n << " at " << x << "," << y;
                        inside += d > 0;
                    }
                }
            EXPECT_GT(inside, 200u);
            ++cases;
        }
    EXPECT_EQ(cases, 28);
}

// A jittered grid of triangles with random diagonals and windings, vertices at random sub-pixel
// positions (some exactly on pixel centres): every pixel centre inside the outline once.
TEST(Raster, RandomSharedEdgesLeaveNoCrackAndNoOverlap) {
    const int W = 64, H = 64;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    const double x0 = 4.3, x1 = 59.7, y0 = 5.1, y1 = 58.2;
    int on_centre = 0;
    for (int rep = 0; rep < 6; ++rep) {
        const int n = 4 + 5 * rep;  // cells per side
        std::vector<std::array<double, 2>> pts;
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                double x = x0 + (x1 - x0) * i / n, y = y0 + (y1 - y0) * j / n;
                if (i > 0 && i < n && j > 0 && j < n) {
                    // Within 0.2 cell of the grid point in each axis: no triangle folds over.
                    const double hx = 0.2 * (x1 - x0) / n, hy = 0.2 * (y1 - y0) / n;
                    const double gx = x, gy = y;
                    x += hx * (2 * u(rng) - 1);
                    y += hy * (2 * u(rng) - 1);
                    const double sx = std::floor(x) + 0.5, sy = std::floor(y) + 0.5;
                    if (u(rng) < 0.3 && std::abs(sx - gx) <= hx && std::abs(sy - gy) <= hy) {
                        x = sx;  // onto a pixel centre
                        y = sy;
                        ++on_centre;
                    }
                }
                pts.push_back({x, y});
            }
        std::vector<Tri> tris;
        auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1),
                                    d = at(i, j + 1);
                std::array<Tri, 2> t = u(rng) < 0.5
                                           ? std::array<Tri, 2>{Tri{a, b, c}, Tri{a, c, d}}
                                           : std::array<Tri, 2>{Tri{a, b, d}, Tri{b, c, d}};
                for (Tri& x : t) {
                    if (u(rng) < 0.5) std::swap(x[1], x[2]);
                    tris.push_back(x);
                }
            }
        const ScreenMesh s = screen_mesh(W, H, pts, tris);
        const RasterFrame f = rasterize(screen_camera(W, H), std::span(&s.mesh, 1));
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const bool inside = x + 0.5 > x0 && x + 0.5 < x1 && y + 0.5 > y0 && y + 0.5 < y1;
                ASSERT_EQ(f.fragments[f.sample_index(x, y)], inside ? 1u : 0u)
                    << "grid " << n << " at " << x << "," << y;
            }
    }
    EXPECT_GT(on_centre, 50);
}

const char* kSphereScene = R"(
[scene]
name = "raster"

[camera]
position = [0.4, 0.3, 7]
target = [0.1, 0, 0]
fov_y_deg = 35
width = 96
height = 80

[[lights]]
type = "directional"
direction = [0, 1, 0]
irradiance = [1, 1, 1]

[[materials]]
name = "white"
type = "diffuse"
albedo = [0.8, 0.8, 0.8]

[[shapes]]
type = "sphere"
radius = 1
subdivisions = 3
scale = [1.6, 1.2, 1.4]
rotate_deg = [20, 35, -10]
translate = [0.3, -0.2, 0.5]
material = "white"
)";

// A closed icosphere seen from outside: with back faces culled (and no depth test) every pixel
// centre is covered at most once; without culling, exactly as many back faces as front faces
// cover each one (the projection of a closed surface has degree 0).
TEST(Raster, ClosedIcosphereIsCoveredOnceByFrontFaces) {
    const Scene scene = parse_scene(kSphereScene, "raster.toml", ".");
    ASSERT_TRUE(check_mesh(scene.shapes[0].mesh).closed());
    RasterOptions o;
    o.depth_test = false;
    const RasterFrame culled = rasterize(scene, o);
    o.cull_closed = false;
    const RasterFrame both = rasterize(scene, o);
    std::size_t once = 0;
    for (std::size_t i = 0; i < culled.fragments.size(); ++i) {
        ASSERT_LE(culled.fragments[i], 1u) << i;
        ASSERT_EQ(both.fragments[i], 2 * culled.fragments[i]) << i;
        once += culled.fragments[i];
    }
    std::printf("icosphere: %zu of %zu pixel centres covered once by front faces\n", once,
                culled.fragments.size());
    EXPECT_GT(once, 1000u);
}

// Coverage, triangle ids and depth of the icosphere agree with ray-triangle intersection
// (Moller-Trumbore) along volpath's ray through each pixel centre, except at pixel centres
// within the snapping distance (2^-8 pixel) of a projected edge.
TEST(Raster, SphereMeshAgreesWithRayTriangleIntersection) {
    const Scene scene = parse_scene(kSphereScene, "raster.toml", ".");
    const TriangleMesh& mesh = scene.shapes[0].mesh;
    const RasterCamera cam = RasterCamera::from_scene(scene.camera);
    const RasterFrame f = rasterize(scene);
    std::size_t hits = 0, disagree = 0, disagree_far = 0;
    double max_rel = 0, max_edge = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            const Vec3 d = cam.ray_direction(x + 0.5, y + 0.5);
            const Hit h = nearest_hit(mesh, cam.position, d);
            const std::size_t i = f.sample_index(x, y);
            const bool same = (h.triangle < 0 && f.shape[i] < 0) ||
                              (h.triangle >= 0 && f.shape[i] == 0 &&
                               f.triangle[i] == static_cast<std::uint32_t>(h.triangle));
            if (!same) {
                ++disagree;
                const double e = edge_distance(cam, mesh, {x + 0.5, y + 0.5});
                max_edge = std::max(max_edge, e);
                if (e > 1.0 / 256) {
                    ++disagree_far;
                    ADD_FAILURE() << "pixel " << x << "," << y << " " << e << " px from an edge";
                }
                continue;
            }
            if (h.triangle < 0) continue;
            ++hits;
            max_rel = std::max(max_rel, std::abs(f.depth[f.pixel_index(x, y)] - h.t) / h.t);
        }
    std::printf(
        "sphere: %zu hits agree, %zu disagreements (at most %.3g px from an edge), max relative "
        "depth error %.3g\n",
        hits, disagree, max_edge, max_rel);
    EXPECT_GT(hits, 1000u);
    EXPECT_EQ(disagree_far, 0u);
    EXPECT_LT(max_rel, 1e-12);
}

// ---- depth and perspective-correct attributes ----------------------------------------------

// A steeply slanted triangle: the depth at each covered pixel centre is the closed-form
// ray-plane distance, the world position from the perspective-correct barycentrics is the ray's
// hit point, and screen-space (affine) interpolation would be far off.
TEST(Raster, DepthAndPerspectiveCorrectBarycentricsMatchClosedForms) {
    SceneCamera sc;
    sc.position = {0, 0.5, 5};
    sc.target = {0, 0, 0};
    sc.fov_y_deg = 50;
    sc.width = 80;
    sc.height = 64;
    const RasterCamera cam = RasterCamera::from_scene(sc);
    TriangleMesh m;
    m.positions = {{-2, -1.5, -6}, {2.5, -1, 3}, {-0.5, 2, -1}};
    m.triangles = {{0, 1, 2}};
    const RasterMesh rm = project(cam, m, false);
    const RasterFrame f = rasterize(cam, std::span(&rm, 1));
    const Vec3 n = cross(m.positions[1] - m.positions[0], m.positions[2] - m.positions[0]);
    std::array<std::array<double, 2>, 3> s;
    for (int k = 0; k < 3; ++k)
        s[static_cast<std::size_t>(k)] = to_pixel(cam, m.positions[static_cast<std::size_t>(k)]);
    std::size_t covered = 0;
    double max_rel_depth = 0, max_err_x = 0, max_err_naive = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            const std::size_t i = f.sample_index(x, y);
            if (f.shape[i] < 0) continue;
            ++covered;
            const Vec3 d = cam.ray_direction(x + 0.5, y + 0.5);
            const double t = dot(n, m.positions[0] - cam.position) / dot(n, d);
            max_rel_depth = std::max(max_rel_depth, std::abs(f.ray_t[i] - t) / t);
            const auto [b1, b2] = f.barycentric[i];
            const Vec3 p =
                m.positions[0] * (1 - b1 - b2) + m.positions[1] * b1 + m.positions[2] * b2;
            const Vec3 hit = cam.position + d * t;
            max_err_x = std::max(max_err_x, std::abs(p.x - hit.x));
            // Affine barycentrics of the pixel centre in the projected triangle.
            const double px = x + 0.5, py = y + 0.5;
            const double area = (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) -
                                (s[1][1] - s[0][1]) * (s[2][0] - s[0][0]);
            const double l1 =
                ((px - s[0][0]) * (s[2][1] - s[0][1]) - (py - s[0][1]) * (s[2][0] - s[0][0])) /
                area;
            const double l2 =
                ((s[1][0] - s[0][0]) * (py - s[0][1]) - (s[1][1] - s[0][1]) * (px - s[0][0])) /
                area;
            const double naive_x =
                m.positions[0].x * (1 - l1 - l2) + m.positions[1].x * l1 + m.positions[2].x * l2;
            max_err_naive = std::max(max_err_naive, std::abs(naive_x - hit.x));
        }
    std::printf(
        "slanted triangle: %zu pixels, max relative depth error %.3g, world x error "
        "%.3g (perspective-correct) vs %.3g (screen-space)\n",
        covered, max_rel_depth, max_err_x, max_err_naive);
    EXPECT_GT(covered, 500u);
    EXPECT_LT(max_rel_depth, 1e-12);
    EXPECT_LT(max_err_x, 1e-11);
    EXPECT_GT(max_err_naive, 0.3);
}

// The depth test keeps the nearest of overlapping triangles whatever the drawing order.
TEST(Raster, DepthTestKeepsTheNearestSurface) {
    SceneCamera sc;
    sc.width = 48;
    sc.height = 32;
    const RasterCamera cam = RasterCamera::from_scene(sc);
    // Two crossing planes (x-y quads tilted in opposite directions) over the whole view.
    TriangleMesh a, b;
    a.positions = {{-5, -5, -1}, {5, -5, 1}, {5, 5, 1}, {-5, 5, -1}};
    a.triangles = {{0, 1, 2}, {0, 2, 3}};
    b.positions = {{-5, -5, 1}, {5, -5, -1}, {5, 5, -1}, {-5, 5, 1}};
    b.triangles = a.triangles;
    for (bool swap : {false, true}) {
        std::vector<RasterMesh> ms{project(cam, swap ? b : a, false),
                                   project(cam, swap ? a : b, false)};
        const RasterFrame f = rasterize(cam, ms);
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x) {
                const Vec3 d = cam.ray_direction(x + 0.5, y + 0.5);
                const Hit ha = nearest_hit(a, cam.position, d),
                          hb = nearest_hit(b, cam.position, d);
                ASSERT_GE(ha.triangle, 0);
                ASSERT_GE(hb.triangle, 0);
                if (std::abs(ha.t - hb.t) < 1e-9) continue;  // on the crossing line
                const int nearer = ha.t < hb.t ? (swap ? 1 : 0) : (swap ? 0 : 1);
                EXPECT_EQ(f.shape[f.sample_index(x, y)], nearer) << x << "," << y;
                EXPECT_NEAR(f.depth[f.pixel_index(x, y)], std::min(ha.t, hb.t), 1e-12 * ha.t);
            }
    }
}

// ---- near-plane clipping -----------------------------------------------------------------------

// A floor reaching behind the camera renders only where its ray hit lies beyond the near plane:
// no wrap-around of vertices behind the eye, no cracks or double coverage along shared edges
// that the near plane cuts, and a huge triangle (clipped to the guard band) as well.
TEST(Raster, NearPlaneClippingKeepsOnlyTheInFrontPart) {
    SceneCamera sc;
    sc.position = {0, 0, 0};
    sc.target = {0, -0.3, -1};
    sc.fov_y_deg = 60;
    sc.width = 64;
    sc.height = 48;
    const RasterCamera cam = RasterCamera::from_scene(sc);
    struct Case {
        TriangleMesh mesh;
        double near;
        const char* what;
        double depth_tolerance = 1e-12;  // relative
    };
    TriangleMesh one;
    one.positions = {{-3, -1, -4}, {3, -1.2, -4}, {0.5, -0.9, 5}};
    one.triangles = {{0, 1, 2}};
    // A floor at y = -1 around the camera, 16 x 16 unit quads of two triangles each (shared
    // edges: bit-identical vertex positions).
    TriangleMesh tess;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i)
            tess.append(transformed(make_quad(1, 1),
                                    Transform{{1, 1, 1}, {0, 0, 0}, {i - 7.5, -1, j - 7.5}}));
    TriangleMesh huge;
    huge.positions = {{-1e6, -1, -1e6}, {1e6, -1, -1e6}, {0, -1, 1e6}};
    huge.triangles = {{0, 2, 1}};
    const std::vector<Case> cases{{one, 1e-3, "one"},         {one, 0.5, "one"},
                                  {one, 2.0, "one"},          {tess, 1.0, "tessellated"},
                                  {tess, 2.5, "tessellated"}, {huge, 1e-3, "huge", 1e-9},
                                  {huge, 3.0, "huge", 1e-9}};
    for (const Case& c : cases) {
        const TriangleMesh& m = c.mesh;
        RasterOptions o;
        o.near = c.near;
        const RasterMesh rm = project(cam, m, false);
        const RasterFrame f = rasterize(cam, std::span(&rm, 1), o);
        // Whether the ray through (px, py) hits the mesh in front of the near plane.
        auto expected = [&](double px, double py, double* t_out) {
            const Vec3 d = cam.ray_direction(px, py);
            const Hit h = nearest_hit(m, cam.position, d);
            if (t_out) *t_out = h.t;
            return h.triangle >= 0 && h.t * dot(d, cam.forward) >= c.near;
        };
        std::size_t covered = 0, skipped = 0;
        double max_rel = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x) {
                double t = 0;
                const bool want = expected(x + 0.5, y + 0.5, &t);
                // Robust: the same answer within 2^-7 pixel around the centre.
                bool robust = true;
                for (int k = 0; k < 8; ++k) {
                    const double a = k * std::numbers::pi / 4, r = 1.0 / 128;
                    robust = robust && expected(x + 0.5 + r * std::cos(a),
                                                y + 0.5 + r * std::sin(a), nullptr) == want;
                }
                const std::size_t i = f.sample_index(x, y);
                ASSERT_LE(f.fragments[i], 1u)
                    << c.what << " near " << c.near << " at " << x << "," << y;
                if (!robust) {
                    ++skipped;
                    continue;
                }
                EXPECT_EQ(f.fragments[i], want ? 1u : 0u)
                    << c.what << " near " << c.near << " at " << x << "," << y;
                if (want && f.shape[i] == 0) {
                    ++covered;
                    max_rel = std::max(max_rel, std::abs(f.ray_t[i] - t) / t);
                }
            }
        std::printf(
            "%s, near %g: %zu pixels covered, %zu within 2^-7 px of an edge skipped, "
            "max relative depth error %.3g\n",
            c.what, c.near, covered, skipped, max_rel);
        EXPECT_GT(covered, 200u);
        // Vertices 1e6 away cost both this and the reference ~6 digits.
        EXPECT_LT(max_rel, c.depth_tolerance);
    }
}

// ---- supersampling ------------------------------------------------------------------------------

// s x s stratified samples: a square with corners at quarter pixels gets exact coverage
// fractions, summing to its area, and the pixel depth is the mean of its samples' ray distances.
TEST(Raster, SupersamplingGivesCoverageFractions) {
    const int W = 8, H = 8;
    const std::vector<std::array<double, 2>> pts{
        {1.25, 1.25}, {6.25, 1.25}, {6.25, 6.25}, {1.25, 6.25}};
    const ScreenMesh s = screen_mesh(W, H, pts, {{0, 2, 1}, {0, 3, 2}});
    RasterOptions o;
    o.supersample = 4;
    const RasterFrame f = rasterize(screen_camera(W, H), std::span(&s.mesh, 1), o);
    ASSERT_EQ(f.sample_width(), 32);
    double sum = 0;
    for (double c : f.coverage) sum += c;
    EXPECT_EQ(sum, 25.0);
    EXPECT_EQ(f.coverage[f.pixel_index(1, 1)], 9.0 / 16);
    EXPECT_EQ(f.coverage[f.pixel_index(3, 1)], 3.0 / 4);
    EXPECT_EQ(f.coverage[f.pixel_index(3, 3)], 1.0);
    EXPECT_EQ(f.coverage[f.pixel_index(6, 6)], 1.0 / 16);
    EXPECT_EQ(f.coverage[f.pixel_index(0, 0)], 0.0);
    for (std::uint32_t c : f.fragments) EXPECT_LE(c, 1u);
    // Depth: w = 1 everywhere, so the ray distance is |forward + right nx + up ny| per sample.
    const RasterCamera cam = screen_camera(W, H);
    double mean = 0;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
            mean += cam.ray_length_per_depth(3 + (i + 0.5) / 4, 3 + (j + 0.5) / 4);
    EXPECT_NEAR(f.depth[f.pixel_index(3, 3)], mean / 16, 1e-15);
}

// ---- scenes, determinism
// -------------------------------------------------------------------------

const char* kManyShapes = R"(
[scene]
name = "raster-many"

[camera]
position = [3, 4, 12]
target = [0, 0.5, 0]
fov_y_deg = 40
width = 160
height = 120

[[lights]]
type = "directional"
direction = [0, 1, 0]
irradiance = [1, 1, 1]

[[materials]]
name = "white"
type = "diffuse"
albedo = [0.8, 0.8, 0.8]

[[shapes]]
type = "plane"
size_x = 30
size_z = 30
material = "white"

[[shapes]]
type = "sphere"
radius = 1.5
subdivisions = 4
translate = [-1.5, 1.5, 0]
material = "white"

[[shapes]]
type = "box"
size = [2, 3, 2]
rotate_deg = [0, 30, 0]
translate = [2, 1.5, -1]
material = "white"

[[shapes]]
type = "torus"
major_radius = 1.2
minor_radius = 0.4
segments_major = 48
segments_minor = 24
rotate_deg = [60, 0, 0]
translate = [0.5, 0.6, 2.5]
material = "white"
)";

bool same(const RasterFrame& a, const RasterFrame& b) {
    return a.view_z == b.view_z && a.ray_t == b.ray_t && a.shape == b.shape &&
           a.triangle == b.triangle && a.barycentric == b.barycentric &&
           a.fragments == b.fragments && a.coverage == b.coverage && a.depth == b.depth;
}

// Bit-identical frames for 1 and 2 threads and for any tile size.
TEST(Raster, DeterministicForAnyThreadCountAndTileSize) {
    const Scene scene = parse_scene(kManyShapes, "many.toml", ".");
    RasterOptions o;
    o.supersample = 2;
    RasterFrame one, two, small_tiles;
    tbb::task_arena(1).execute([&] { one = rasterize(scene, o); });
    tbb::task_arena(2).execute([&] { two = rasterize(scene, o); });
    o.tile_size = 7;
    tbb::task_arena(2).execute([&] { small_tiles = rasterize(scene, o); });
    EXPECT_TRUE(same(one, two));
    EXPECT_TRUE(same(one, small_tiles));
    // Every shape is in view; the open plane is drawn without culling, the closed ones with.
    for (int s = 0; s < 4; ++s)
        EXPECT_GT(std::count(one.shape.begin(), one.shape.end(), s), 100) << "shape " << s;
    EXPECT_FALSE(check_mesh(scene.shapes[0].mesh).closed());
}

// Across engines: volpath's "depth" layer (the first hit's t averaged over uniformly jittered
// samples in each pixel, with its batch-means standard error) against the rasterizer's
// box-filtered depth at 16 x 16 samples. Pixels whose 3 x 3 neighbourhood sees one convex shape
// or the plane (depth continuous over the pixel) are compared by z = (volpath - raster) / SE.
// With SEs from 16 batch means z follows Student's t with 15 degrees of freedom: E[z^2] = 15/13
// and Var[z^2] = 3 * 15^2 / (13 * 11) - (15/13)^2; the mean of z^2 over N pixels must lie within
// 5 of its standard deviations. A camera off by a fraction of a pixel gives z of tens.
TEST(Raster, DepthAgreesWithVolpathsDepthLayer) {
    const Scene scene = parse_scene(kManyShapes, "many.toml", ".");
    const int W = 40, H = 30;
    volpath::RenderOptions vo;
    vo.budget.samples = 48;  // 16 batches of three
    vo.width = W;
    vo.height = H;
    const volpath::RenderResult r = volpath::render(scene, vo);
    ASSERT_EQ(r.width, W);
    RasterOptions o;
    o.supersample = 16;
    const RasterFrame f = rasterize(scene, o, W, H);
    const int s = f.supersample;
    double sum_z2 = 0;
    int n = 0;
    for (int y = 1; y + 1 < H; ++y)
        for (int x = 1; x + 1 < W; ++x) {
            const std::int32_t shape = f.shape[f.sample_index(x * s, y * s)];
            if (shape < 0 || shape == 3) continue;  // nothing, or the torus (self-occluding)
            bool one_shape = true;
            for (int sy = (y - 1) * s; sy < (y + 2) * s && one_shape; ++sy)
                for (int sx = (x - 1) * s; sx < (x + 2) * s && one_shape; ++sx)
                    one_shape = f.shape[f.sample_index(sx, sy)] == shape;
            if (!one_shape) continue;
            const std::size_t k = (static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x)) *
                                      volpath::RenderLayout::kPerPixel +
                                  volpath::RenderLayout::kDepth;
            const double se = r.run.se[k];
            ASSERT_GT(se, 0) << x << "," << y;
            const double z = (r.run.mean[k] - f.depth[f.pixel_index(x, y)]) / se;
            sum_z2 += z * z;
            ++n;
        }
    const double mean_z2 = sum_z2 / n, expect = 15.0 / 13;
    const double sd = std::sqrt((3.0 * 225 / (13 * 11) - expect * expect) / n);
    std::printf("volpath depth: %d pixels, mean z^2 %.3f (expected %.3f +- %.3f)\n", n, mean_z2,
                expect, sd);
    EXPECT_GT(n, 300);
    EXPECT_LT(std::abs(mean_z2 - expect), 5 * sd);
}

// An open plane seen from below is drawn (no culling of open meshes).
TEST(Raster, OpenMeshSeenFromBehindIsDrawn) {
    std::string text = kManyShapes;
    text.replace(text.find("position = [3, 4, 12]"), 21, "position = [3, -4, 12]");
    const Scene scene = parse_scene(text, "below.toml", ".");
    const RasterFrame f = rasterize(scene, {}, 64, 48);
    EXPECT_EQ(f.width, 64);
    EXPECT_GT(std::count(f.shape.begin(), f.shape.end(), 0), 100);
}

// Depth only (shadow maps) draws the same depths and shapes as the full frame, and nothing else.
TEST(Raster, DepthOnlyDrawsTheSameDepthAndShapes) {
    const Scene scene = parse_scene(kManyShapes, "many.toml", ".");
    for (bool ortho : {false, true}) {
        RasterOptions o;
        o.orthographic = ortho;
        o.cull_closed = false;
        const RasterFrame full = rasterize(scene, o, 96, 64);
        o.depth_only = true;
        const RasterFrame d = rasterize(scene, o, 96, 64);
        EXPECT_EQ(d.view_z, full.view_z);
        EXPECT_EQ(d.shape, full.shape);
        EXPECT_TRUE(d.triangle.empty() && d.barycentric.empty() && d.ray_t.empty() &&
                    d.fragments.empty() && d.coverage.empty());
        EXPECT_GT(std::count_if(d.shape.begin(), d.shape.end(), [](int s) { return s >= 0; }),
                  1000);
    }
}

TEST(Raster, RefusesSizesOutOfRange) {
    const RasterCamera cam = screen_camera(8, 8);
    RasterOptions o;
    o.supersample = 0;
    EXPECT_THROW((void)rasterize(cam, {}, o), std::invalid_argument);
    o.supersample = 1 << 14;
    EXPECT_THROW((void)rasterize(cam, {}, o), std::invalid_argument);
    o.supersample = 1;
    o.near = 0;
    EXPECT_THROW((void)rasterize(cam, {}, o), std::invalid_argument);
}

}  // namespace
}  // namespace ssslab::realtime
