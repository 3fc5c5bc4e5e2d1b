// The software rasterizer (see raster.h). Sources:
//   [Pineda 1988] J. Pineda, "A parallel algorithm for polygon rasterization", SIGGRAPH 1988:
//     edge functions, linear in the sample position, stepped incrementally.
//   [D3D11] Direct3D 11 rasterization rules (Microsoft documentation, "Rasterization Rules"):
//     the top-left rule; vertices snapped to fixed point with 8 sub-pixel bits.
//   [Giesen 2013] F. Giesen, "Optimizing the basic rasterizer" and "The barycentric conspiracy"
//     (fgiesen.wordpress.com, Feb 2013): integer edge functions, the top-left rule as a bias of
//     -1 on edges that are neither top nor left, fixed-point ranges.
//   [Sutherland and Hodgman 1974] polygon clipping against one plane at a time.
#include "realtime/raster.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace ssslab::realtime {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::int64_t kOne = std::int64_t{1} << kSubpixelBits;  // one sample in fixed point
constexpr std::int64_t kHalf = kOne / 2;
// Snapped coordinates stay within +-2^21 samples (the guard band below), so that coordinate
// differences fit 31 bits and the edge functions' products 62 bits of an int64 [Giesen 2013].
constexpr double kGuardSamples = 2097152.0;  // 2^21
constexpr int kMaxSide = 65536;              // samples per side

// A clipped vertex: clip coordinates and the original triangle's barycentrics (b1, b2), which
// are linear in clip space and therefore interpolate along a clipped edge exactly as x, y, w do.
struct ClipV {
    double x, y, w, b1, b2;
};

// Sutherland-Hodgman against the plane dist(v) >= 0. The crossing point of an edge is computed
// from its inside end towards its outside end, whichever way the polygon walks it: the two
// triangles sharing a clipped edge then get the bit-identical vertex, and stay watertight.
template <class Dist>
int clip_polygon(const ClipV* in, int n, ClipV* out, Dist dist) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const ClipV& a = in[i];
        const ClipV& b = in[(i + 1) % n];
        const double da = dist(a), db = dist(b);
        const bool ia = da >= 0, ib = db >= 0;
        if (ia) out[m++] = a;
        if (ia != ib) {
            const ClipV& p = ia ? a : b;  // inside end
            const ClipV& q = ia ? b : a;
            const double dp = ia ? da : db, dq = ia ? db : da;
            const double t = dp / (dp - dq);
            out[m++] = {p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t, p.w + (q.w - p.w) * t,
                        p.b1 + (q.b1 - p.b1) * t, p.b2 + (q.b2 - p.b2) * t};
        }
    }
    return m;
}

// A triangle ready to rasterize: snapped vertices, sample bounding box, and the planes of the
// perspective-correct attributes (1/w, b1/w, b2/w) over the sample grid.
struct SetupTriangle {
    std::array<std::int64_t, 3> fx, fy;  // fixed point, clockwise on screen (y down)
    int x0, y0, x1, y1;                  // samples covered lie in [x0, x1] x [y0, y1]
    double ox, oy;                       // attribute planes: a + ddx (x - ox) + ddy (y - oy)
    std::array<double, 3> a, ddx, ddy;   // for 1/w, b1/w, b2/w
    std::int32_t shape;
    std::uint32_t triangle;
};

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

struct Viewport {
    int ws, hs;    // sample grid
    double guard;  // |x / w|, |y / w| <= guard keeps snapped coordinates in range
    bool cull;
    bool cull_front;
    bool ortho;  // RasterOptions::orthographic: no perspective divide, linear attributes
};

// Clip, project, snap and set up one triangle; appends 0 to 6 setup triangles (a fan over the
// clipped polygon).
void setup_triangle(const RasterMesh& m, std::uint32_t t, std::int32_t shape, double near,
                    const Viewport& vp, std::vector<SetupTriangle>& out) {
    const auto& tri = m.triangles[t];
    ClipV buf_a[16], buf_b[16];
    for (int k = 0; k < 3; ++k) {
        const ClipVertex& v = m.vertices[tri[static_cast<std::size_t>(k)]];
        buf_a[k] = {v.x, v.y, v.w, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    }
    int n = 3;
    // Trivially inside every plane: no clipping (the common case). Scenes validate their
    // vertices; a non-finite one here drops its triangle.
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
        const ClipV& v = buf_a[k];
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.w)) return;
        const double gw = vp.ortho ? vp.guard : vp.guard * v.w;
        inside = inside && v.w >= near && std::abs(v.x) <= gw && std::abs(v.y) <= gw;
    }
    ClipV* cur = buf_a;
    if (!inside) {
        ClipV* nxt = buf_b;
        const double g = vp.guard;
        auto step = [&](auto dist) {
            n = clip_polygon(cur, n, nxt, dist);
            std::swap(cur, nxt);
        };
        const bool ortho = vp.ortho;
        auto gw = [g, ortho](const ClipV& v) { return ortho ? g : g * v.w; };
        step([near](const ClipV& v) { return v.w - near; });
        if (n >= 3) step([gw](const ClipV& v) { return gw(v) - v.x; });
        if (n >= 3) step([gw](const ClipV& v) { return gw(v) + v.x; });
        if (n >= 3) step([gw](const ClipV& v) { return gw(v) - v.y; });
        if (n >= 3) step([gw](const ClipV& v) { return gw(v) + v.y; });
        if (n < 3) return;
    }
    // Perspective divide and viewport (sample units, y down), then snap.
    double sx[16], sy[16], q[16], qb1[16], qb2[16];
    std::int64_t fx[16], fy[16];
    for (int k = 0; k < n; ++k) {
        const ClipV& v = cur[k];
        // Orthographic: the attributes (w, b1, b2) themselves are linear on screen.
        const double iw = vp.ortho ? 1.0 : 1.0 / v.w;
        sx[k] = (v.x * iw + 1.0) * (0.5 * vp.ws);
        sy[k] = (1.0 - v.y * iw) * (0.5 * vp.hs);
        fx[k] = std::llround(sx[k] * static_cast<double>(kOne));
        fy[k] = std::llround(sy[k] * static_cast<double>(kOne));
        q[k] = vp.ortho ? v.w : iw;
        qb1[k] = v.b1 * iw;
        qb2[k] = v.b2 * iw;
    }
    for (int k = 1; k + 1 < n; ++k) {
        std::array<int, 3> id{0, k, k + 1};
        const std::int64_t area2 = (fx[id[1]] - fx[id[0]]) * (fy[id[2]] - fy[id[0]]) -
                                   (fy[id[1]] - fy[id[0]]) * (fx[id[2]] - fx[id[0]]);
        // Counter-clockwise seen from the front is clockwise in y-down raster coordinates, i.e.
        // a negative area2. Zero area covers nothing.
        if (area2 == 0 || (vp.cull && area2 > 0) || (vp.cull_front && area2 < 0)) continue;
        if (area2 < 0) std::swap(id[1], id[2]);
        SetupTriangle s;
        std::int64_t minx = fx[id[0]], maxx = minx, miny = fy[id[0]], maxy = miny;
        for (int j = 0; j < 3; ++j) {
            s.fx[static_cast<std::size_t>(j)] = fx[id[static_cast<std::size_t>(j)]];
            s.fy[static_cast<std::size_t>(j)] = fy[id[static_cast<std::size_t>(j)]];
            minx = std::min(minx, s.fx[static_cast<std::size_t>(j)]);
            maxx = std::max(maxx, s.fx[static_cast<std::size_t>(j)]);
            miny = std::min(miny, s.fy[static_cast<std::size_t>(j)]);
            maxy = std::max(maxy, s.fy[static_cast<std::size_t>(j)]);
        }
        // Samples sit at (X + 1/2, Y + 1/2): the first X with X one + half >= minx, the last
        // with X one + half <= maxx.
        s.x0 = static_cast<int>(std::max<std::int64_t>(0, -floor_div(kHalf - minx, kOne)));
        s.y0 = static_cast<int>(std::max<std::int64_t>(0, -floor_div(kHalf - miny, kOne)));
        s.x1 = static_cast<int>(std::min<std::int64_t>(vp.ws - 1, floor_div(maxx - kHalf, kOne)));
        s.y1 = static_cast<int>(std::min<std::int64_t>(vp.hs - 1, floor_div(maxy - kHalf, kOne)));
        if (s.x0 > s.x1 || s.y0 > s.y1) continue;
        // Attribute planes from the unsnapped vertices (double precision); from the snapped
        // ones in the (theoretical) case that snapping gave area to a degenerate triangle, so
        // that no covered sample is dropped.
        const int i0 = id[0], i1 = id[1], i2 = id[2];
        s.ox = sx[i0];
        s.oy = sy[i0];
        double d1x = sx[i1] - sx[i0], d1y = sy[i1] - sy[i0];
        double d2x = sx[i2] - sx[i0], d2y = sy[i2] - sy[i0];
        double det = d1x * d2y - d1y * d2x;
        if (!(det != 0) || !std::isfinite(det)) {
            const double u = 1.0 / static_cast<double>(kOne);
            s.ox = static_cast<double>(fx[i0]) * u;
            s.oy = static_cast<double>(fy[i0]) * u;
            d1x = static_cast<double>(fx[i1] - fx[i0]) * u;
            d1y = static_cast<double>(fy[i1] - fy[i0]) * u;
            d2x = static_cast<double>(fx[i2] - fx[i0]) * u;
            d2y = static_cast<double>(fy[i2] - fy[i0]) * u;
            det = static_cast<double>(area2 < 0 ? -area2 : area2) * u * u;
        }
        const double inv = 1.0 / det;
        const double* f[3] = {q, qb1, qb2};
        for (std::size_t c = 0; c < 3; ++c) {
            const double f0 = f[c][i0], e1 = f[c][i1] - f0, e2 = f[c][i2] - f0;
            s.a[c] = f0;
            s.ddx[c] = (e1 * d2y - e2 * d1y) * inv;
            s.ddy[c] = (e2 * d1x - e1 * d2x) * inv;
        }
        s.shape = shape;
        s.triangle = t;
        out.push_back(s);
    }
}

// Draw one setup triangle into the part of a tile [tx0, tx1] x [ty0, ty1] it overlaps.
template <bool kDepthOnly>
void draw(const SetupTriangle& s, int tx0, int ty0, int tx1, int ty1, const RasterOptions& o,
          RasterFrame& f) {
    const bool depth_test = o.depth_test, ortho = o.orthographic;
    const bool bary = o.barycentrics, frags = o.count_fragments;
    const int x0 = std::max(s.x0, tx0), x1 = std::min(s.x1, tx1);
    const int y0 = std::max(s.y0, ty0), y1 = std::min(s.y1, ty1);
    if (x0 > x1 || y0 > y1) return;
    // Edge k runs from vertex k+1 to k+2; E(p) = (b - a) x (p - a) > 0 inside a clockwise
    // (y down) triangle. Top edge: horizontal, going right; left edge: going up. Samples on
    // other edges are outside: bias -1 on the integer E [D3D11, Giesen 2013].
    std::array<std::int64_t, 3> row{}, step_x{}, step_y{};
    const std::int64_t px0 = std::int64_t{x0} * kOne + kHalf, py0 = std::int64_t{y0} * kOne + kHalf;
    for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t a = (k + 1) % 3, b = (k + 2) % 3;
        const std::int64_t dx = s.fx[b] - s.fx[a], dy = s.fy[b] - s.fy[a];
        const bool top_left = dy < 0 || (dy == 0 && dx > 0);
        row[k] = dx * (py0 - s.fy[a]) - dy * (px0 - s.fx[a]) - (top_left ? 0 : 1);
        step_x[k] = -dy * kOne;
        step_y[k] = dx * kOne;
    }
    const auto sw = static_cast<std::size_t>(f.sample_width());
    for (int y = y0; y <= y1; ++y) {
        std::array<std::int64_t, 3> e = row;
        const double py = y + 0.5;
        for (int x = x0; x <= x1; ++x) {
            if ((e[0] | e[1] | e[2]) >= 0) {
                const std::size_t i =
                    static_cast<std::size_t>(y) * sw + static_cast<std::size_t>(x);
                if constexpr (!kDepthOnly)
                    if (frags) ++f.fragments[i];
                const double ex = (x + 0.5) - s.ox, ey = py - s.oy;
                const double q = s.a[0] + s.ddx[0] * ex + s.ddy[0] * ey;
                const double z = ortho ? q : 1.0 / q;
                if (!depth_test || z < f.view_z[i]) {
                    f.view_z[i] = z;
                    f.shape[i] = s.shape;
                    if constexpr (!kDepthOnly) {
                        f.triangle[i] = s.triangle;
                        if (bary) {
                            const double m = ortho ? 1.0 : z;
                            f.barycentric[i] = {(s.a[1] + s.ddx[1] * ex + s.ddy[1] * ey) * m,
                                                (s.a[2] + s.ddx[2] * ex + s.ddy[2] * ey) * m};
                        }
                    }
                }
            }
            for (std::size_t k = 0; k < 3; ++k) e[k] += step_x[k];
        }
        for (std::size_t k = 0; k < 3; ++k) row[k] += step_y[k];
    }
}

}  // namespace

RasterCamera RasterCamera::from_scene(const SceneCamera& c, int width, int height) {
    RasterCamera r;
    r.width = width > 0 && height > 0 ? width : c.width;
    r.height = width > 0 && height > 0 ? height : c.height;
    // As volpath/render.cpp (Renderer::Renderer) builds its camera.
    r.position = c.position;
    r.forward = normalize(c.target - c.position);
    r.right = normalize(cross(r.forward, c.up));
    r.up = cross(r.right, r.forward);
    r.tan_half = std::tan(0.5 * c.fov_y_deg * kPi / 180);
    r.aspect = static_cast<double>(r.width) / r.height;
    return r;
}

ClipVertex RasterCamera::to_clip(const Vec3& p) const {
    const Vec3 d = p - position;
    // x / w = dot(d, right) / (dot(d, forward) tan_half aspect) is the ray's ndc_x in
    // volpath's trace(); likewise y.
    return {dot(d, right) / (tan_half * aspect), dot(d, up) / tan_half, dot(d, forward)};
}

Vec3 RasterCamera::ray_direction(double px, double py) const {
    const double ndc_x = (2 * px / width - 1) * tan_half * aspect;
    const double ndc_y = (1 - 2 * py / height) * tan_half;
    return normalize(forward + right * ndc_x + up * ndc_y);
}

RasterCamera::SampleRays RasterCamera::sample_rays(int ss) const {
    SampleRays r{forward, right, up, std::vector<double>(static_cast<std::size_t>(width) * ss),
                 std::vector<double>(static_cast<std::size_t>(height) * ss)};
    // The expressions of ray_direction with px = (sx + 1/2) / s, py = (sy + 1/2) / s.
    for (std::size_t sx = 0; sx < r.ndc_x.size(); ++sx)
        r.ndc_x[sx] = (2 * ((static_cast<double>(sx) + 0.5) / ss) / width - 1) * tan_half * aspect;
    for (std::size_t sy = 0; sy < r.ndc_y.size(); ++sy)
        r.ndc_y[sy] = (1 - 2 * ((static_cast<double>(sy) + 0.5) / ss) / height) * tan_half;
    return r;
}

double RasterCamera::ray_length_per_depth(double px, double py) const {
    const double ndc_x = (2 * px / width - 1) * tan_half * aspect;
    const double ndc_y = (1 - 2 * py / height) * tan_half;
    return length(forward + right * ndc_x + up * ndc_y);
}

RasterMesh project(const RasterCamera& camera, const TriangleMesh& mesh, bool cull_back_faces) {
    RasterMesh m;
    m.vertices.resize(mesh.positions.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              m.vertices[i] = camera.to_clip(mesh.positions[i]);
                      });
    m.triangles = mesh.triangles;
    m.cull_back_faces = cull_back_faces;
    return m;
}

RasterFrame rasterize(const RasterCamera& camera, std::span<const RasterMesh> meshes,
                      const RasterOptions& o) {
    RasterFrame f;
    rasterize(camera, meshes, o, f);
    return f;
}

void rasterize(const RasterCamera& camera, std::span<const RasterMesh> meshes,
               const RasterOptions& o, RasterFrame& f) {
    if (camera.width < 1 || camera.height < 1 || o.supersample < 1 || o.tile_size < 1 ||
        static_cast<long long>(camera.width) * o.supersample > kMaxSide ||
        static_cast<long long>(camera.height) * o.supersample > kMaxSide)
        throw std::invalid_argument(
            "rasterize: image size, supersampling or tile size out of range");
    if (!(o.near > 0)) throw std::invalid_argument("rasterize: the near plane must be > 0");
    f.width = camera.width;
    f.height = camera.height;
    f.supersample = o.supersample;
    const int ws = f.sample_width(), hs = f.sample_height();
    const std::size_t samples = static_cast<std::size_t>(ws) * static_cast<std::size_t>(hs);
    // Sized only: each tile clears its own samples before it draws them (in cache, once).
    f.view_z.resize(samples);
    f.shape.resize(samples);
    if (!o.depth_only) {
        f.ray_t.resize(samples);
        f.triangle.resize(samples);
        if (o.barycentrics)
            f.barycentric.resize(samples);
        else
            f.barycentric.clear();
        if (o.count_fragments)
            f.fragments.resize(samples);
        else
            f.fragments.clear();
    } else {
        f.ray_t.clear();
        f.triangle.clear();
        f.barycentric.clear();
        f.fragments.clear();
        f.coverage.clear();
        f.depth.clear();
    }

    // Geometry: fixed blocks of triangles set up in parallel, concatenated in submission order.
    const double guard = kGuardSamples / std::max(ws, hs) - 1;
    struct Block {
        std::size_t mesh, begin, end;
    };
    // The set-up triangles and the tiles' bins: scratch of the calling thread, kept between
    // calls with their capacity (a frame of 100k triangles sets up ~17 MB, which fresh vectors
    // fault in and grow by copying every call). The result does not depend on it. (References:
    // the worker threads below must see this thread's.)
    static thread_local std::vector<std::vector<SetupTriangle>> setup_scratch;
    static thread_local std::vector<std::vector<const SetupTriangle*>> bins_scratch;
    std::vector<std::vector<SetupTriangle>>& setup = setup_scratch;
    std::vector<std::vector<const SetupTriangle*>>& bins = bins_scratch;
    std::vector<Block> blocks;
    constexpr std::size_t kBlock = 1024;
    for (std::size_t mi = 0; mi < meshes.size(); ++mi)
        for (std::size_t b = 0; b < meshes[mi].triangles.size(); b += kBlock)
            blocks.push_back({mi, b, std::min(b + kBlock, meshes[mi].triangles.size())});
    if (setup.size() < blocks.size()) setup.resize(blocks.size());
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t bi) {
        const Block& b = blocks[bi];
        const RasterMesh& m = meshes[b.mesh];
        const Viewport vp{ws, hs, guard, m.cull_back_faces, m.cull_front_faces, o.orthographic};
        setup[bi].clear();
        for (std::size_t t = b.begin; t < b.end; ++t)
            setup_triangle(m, static_cast<std::uint32_t>(t), static_cast<std::int32_t>(b.mesh),
                           o.near, vp, setup[bi]);
    });

    // Binning, in submission order.
    const int ts = o.tile_size;
    const int ntx = (ws + ts - 1) / ts, nty = (hs + ts - 1) / ts;
    bins.resize(static_cast<std::size_t>(ntx) * static_cast<std::size_t>(nty));
    for (auto& b : bins) b.clear();
    for (std::size_t bi = 0; bi < blocks.size(); ++bi)
        for (const SetupTriangle& s : setup[bi])
            for (int ty = s.y0 / ts; ty <= s.y1 / ts; ++ty)
                for (int tx = s.x0 / ts; tx <= s.x1 / ts; ++tx)
                    bins[static_cast<std::size_t>(ty) * static_cast<std::size_t>(ntx) +
                         static_cast<std::size_t>(tx)]
                        .push_back(&s);

    // Tiles in parallel: each owns its samples, clears them, draws its triangles in order and,
    // at one sample a pixel, finishes its pixels (ray distance, coverage, depth) while they are
    // in cache.
    const int ss = o.supersample;
    const RasterCamera::SampleRays rays =
        o.depth_only ? RasterCamera::SampleRays{} : camera.sample_rays(ss);
    const bool pixels = !o.depth_only && o.pixel_layers;
    if (pixels) {
        // Every entry is written below.
        f.coverage.resize(static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height));
        f.depth.resize(f.coverage.size());
    } else {
        f.coverage.clear();
        f.depth.clear();
    }
    // The ray distance of a covered sample.
    auto ray_t = [&](int sx, int sy, std::size_t k) {
        return o.orthographic ? f.view_z[k] : f.view_z[k] * rays.length_per_depth(sx, sy);
    };
    const auto sw = static_cast<std::size_t>(ws);
    tbb::parallel_for(std::size_t{0}, bins.size(), [&](std::size_t bi) {
        const int tx = static_cast<int>(bi % static_cast<std::size_t>(ntx));
        const int ty = static_cast<int>(bi / static_cast<std::size_t>(ntx));
        const int x0 = tx * ts, y0 = ty * ts;
        const int x1 = std::min(x0 + ts, ws) - 1, y1 = std::min(y0 + ts, hs) - 1;
        const auto n = static_cast<std::ptrdiff_t>(x1 - x0 + 1);
        for (int y = y0; y <= y1; ++y) {
            const auto k = static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * sw +
                                                       static_cast<std::size_t>(x0));
            std::fill_n(f.view_z.begin() + k, n, std::numeric_limits<double>::infinity());
            std::fill_n(f.shape.begin() + k, n, std::int32_t{-1});
            if (o.depth_only) continue;
            std::fill_n(f.triangle.begin() + k, n, std::numeric_limits<std::uint32_t>::max());
            if (o.barycentrics)
                std::fill_n(f.barycentric.begin() + k, n, std::array<double, 2>{0.0, 0.0});
            if (o.count_fragments) std::fill_n(f.fragments.begin() + k, n, 0u);
        }
        for (const SetupTriangle* s : bins[bi]) {
            if (o.depth_only)
                draw<true>(*s, x0, y0, x1, y1, o, f);
            else
                draw<false>(*s, x0, y0, x1, y1, o, f);
        }
        if (o.on_tile) o.on_tile(x0, y0, x1, y1);
        if (o.depth_only || ss != 1) return;
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const std::size_t k = f.sample_index(x, y);
                const bool covered = f.shape[k] >= 0;
                f.ray_t[k] = covered ? ray_t(x, y, k) : 0.0;
                if (!pixels) continue;
                f.coverage[k] = covered ? 1.0 : 0.0;
                f.depth[k] = f.ray_t[k];
            }
    });
    if (o.depth_only || ss == 1) return;

    // Supersampled: ray distances per sample, then the pixels box-filtered.
    tbb::parallel_for(0, f.sample_height(), [&](int sy) {
        for (int sx = 0; sx < f.sample_width(); ++sx) {
            const std::size_t k = f.sample_index(sx, sy);
            f.ray_t[k] = f.shape[k] < 0 ? 0.0 : ray_t(sx, sy, k);
        }
    });
    if (pixels) resolve_pixel_layers(f);
}

void resolve_pixel_layers(RasterFrame& f) {
    const int ss = f.supersample;
    f.coverage.resize(static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height));
    f.depth.resize(f.coverage.size());
    tbb::parallel_for(0, f.height, [&](int y) {
        for (int x = 0; x < f.width; ++x) {
            int covered = 0;
            double sum_t = 0;
            for (int j = 0; j < ss; ++j)
                for (int i = 0; i < ss; ++i) {
                    const std::size_t k = f.sample_index(x * ss + i, y * ss + j);
                    if (f.shape[k] < 0) continue;
                    ++covered;
                    sum_t += f.ray_t[k];
                }
            const std::size_t p = f.pixel_index(x, y);
            f.coverage[p] = static_cast<double>(covered) / (ss * ss);
            f.depth[p] = sum_t / (ss * ss);
        }
    });
}

RasterFrame rasterize(const Scene& scene, const RasterOptions& o, int width, int height) {
    RasterFrame f;
    rasterize(scene, o, width, height, f);
    return f;
}

void rasterize(const Scene& scene, const RasterOptions& o, int width, int height,
               RasterFrame& out) {
    const RasterCamera camera = RasterCamera::from_scene(scene.camera, width, height);
    std::vector<RasterMesh> meshes;
    meshes.reserve(scene.shapes.size());
    for (const SceneShape& s : scene.shapes) {
        const bool cull = o.cull_closed && (s.closed ? *s.closed : check_mesh(s.mesh).closed());
        meshes.push_back(project(camera, s.mesh, cull && !o.cull_front_closed));
        meshes.back().cull_front_faces = cull && o.cull_front_closed;
    }
    rasterize(camera, meshes, o, out);
}

}  // namespace ssslab::realtime
