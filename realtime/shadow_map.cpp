// Shadow maps (see shadow_map.h).
#include "realtime/shadow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ssslab::realtime {

void Box::add(const Vec3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

std::array<Vec3, 8> Box::corners() const {
    std::array<Vec3, 8> c;
    for (int i = 0; i < 8; ++i)
        c[static_cast<std::size_t>(i)] = {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y,
                                          (i & 4) ? hi.z : lo.z};
    return c;
}

ClipVertex ShadowView::to_clip(const Vec3& p) const {
    const Vec3 d = p - origin;
    if (orthographic) return {dot(d, right) / half_x, dot(d, up) / half_y, dot(d, forward)};
    // As RasterCamera::to_clip, with tan_half = half_y and tan_half aspect = half_x.
    return {dot(d, right) / half_x, dot(d, up) / half_y, dot(d, forward)};
}

double ShadowView::texel_size(double w) const {
    const double h = 2 * std::max(half_x, half_y) / size;
    return orthographic ? h : h * std::max(w, 0.0);
}

namespace {

// A frame (right, up, forward) with forward = f.
void frame_along(const Vec3& f, Vec3& right, Vec3& up) {
    Vec3 s, t;
    basis(f, s, t);
    right = s;
    up = t;  // (s, t, f) is right-handed; the map's handedness does not matter for depth
}

}  // namespace

ShadowView fit_directional(const Vec3& to_light, const Box& receivers, const Box& casters, int size,
                           double pad_texels) {
    ShadowView v;
    v.orthographic = true;
    v.size = size;
    v.forward = -normalize(to_light);
    frame_along(v.forward, v.right, v.up);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    double x0 = kInf, x1 = -kInf, y0 = kInf, y1 = -kInf, z0 = kInf, z1 = -kInf;
    for (const Vec3& c : receivers.corners()) {
        x0 = std::min(x0, dot(c, v.right));
        x1 = std::max(x1, dot(c, v.right));
        y0 = std::min(y0, dot(c, v.up));
        y1 = std::max(y1, dot(c, v.up));
        z0 = std::min(z0, dot(c, v.forward));
        z1 = std::max(z1, dot(c, v.forward));
    }
    // Casters anywhere in front of the receivers: the depth origin before all of them.
    if (!casters.empty())
        for (const Vec3& c : casters.corners()) z0 = std::min(z0, dot(c, v.forward));
    const double span = std::max({x1 - x0, y1 - y0, 1e-9 * (1 + std::abs(z0))});
    // Square texels: the larger side sets the texel size; padding of pad_texels on each side.
    const double half = 0.5 * span * size / std::max(1.0, size - 2 * pad_texels);
    v.half_x = v.half_y = half;
    // Every caster then lies at depth >= gap > 0; the near plane at half of it clips none.
    const double gap = 1e-6 * (span + (z1 - z0)) + 1e-9;
    const double depth0 = z0 - gap;
    v.near = 0.5 * gap;
    v.origin = v.right * (0.5 * (x0 + x1)) + v.up * (0.5 * (y0 + y1)) + v.forward * depth0;
    return v;
}

std::vector<ShadowView> fit_point(const Vec3& position, const Box& receivers, double near, int size,
                                  double pad_texels) {
    std::vector<ShadowView> out;
    if (receivers.empty()) return out;
    const auto corners = receivers.corners();
    const Vec3 centre = (receivers.lo + receivers.hi) * 0.5;
    const Vec3 to_c = centre - position;
    const double widen = size / std::max(1.0, size - 2 * pad_texels);
    if (length(to_c) > 0) {
        ShadowView v;
        v.orthographic = false;
        v.size = size;
        v.near = near;
        v.origin = position;
        v.forward = normalize(to_c);
        frame_along(v.forward, v.right, v.up);
        const double cos_max = std::cos(75.0 * 3.14159265358979323846 / 180);
        bool fits = true;
        double tx = 0, ty = 0;
        for (const Vec3& c : corners) {
            const Vec3 d = c - position;
            const double z = dot(d, v.forward), l = length(d);
            if (!(z > cos_max * l) || !(l > 0)) {
                fits = false;
                break;
            }
            tx = std::max(tx, std::abs(dot(d, v.right)) / z);
            ty = std::max(ty, std::abs(dot(d, v.up)) / z);
        }
        if (fits) {
            const double t = std::max({tx, ty, 1e-6}) * widen;
            v.half_x = v.half_y = t;
            out.push_back(v);
            return out;
        }
    }
    // Cube faces (tan 1, widened by the padding), each kept unless the whole box lies behind
    // its plane: a coarse fit, for lights among their receivers.
    const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const Vec3& f : axes) {
        ShadowView v;
        v.orthographic = false;
        v.size = size;
        v.near = near;
        v.origin = position;
        v.forward = f;
        frame_along(f, v.right, v.up);
        v.half_x = v.half_y = widen;
        bool sees = false;
        for (const Vec3& c : corners) sees = sees || dot(c - position, f) > 0;
        if (sees) out.push_back(v);
    }
    return out;
}

ShadowMap::Lookup ShadowMap::lookup(const Vec3& p, bool smooth) const {
    return lookup(view.to_clip(p), p, smooth);
}

ShadowMap::Lookup ShadowMap::lookup(const ClipVertex& c, const Vec3& p, bool smooth) const {
    Lookup r;
    double fx = 0, fy = 0;
    if (!texel_coords(c, fx, fy)) return r;
    const std::size_t i = texel_index(fx, fy);
    r.inside = true;
    r.point_depth = c.w;
    r.map_depth = depth[i];
    r.map_depth_smooth = r.map_depth;
    r.shape = shape[i];
    if (!smooth) return r;
    // Bilinear between the texel centres around (fx, fy).
    const double gx = fx - 0.5, gy = fy - 0.5;
    const int x0 = static_cast<int>(std::floor(gx)), y0 = static_cast<int>(std::floor(gy));
    if (x0 >= 0 && y0 >= 0 && x0 + 1 < view.size && y0 + 1 < view.size) {
        const double tx = gx - x0, ty = gy - y0;
        double v[4];
        bool ok = true;
        for (int k = 0; k < 4 && ok; ++k) {
            const std::size_t j =
                static_cast<std::size_t>(y0 + k / 2) * static_cast<std::size_t>(view.size) +
                static_cast<std::size_t>(x0 + k % 2);
            v[k] = depth[j];
            ok = shape[j] == r.shape && std::isfinite(v[k]);
        }
        if (ok)
            r.map_depth_smooth =
                (v[0] * (1 - tx) + v[1] * tx) * (1 - ty) + (v[2] * (1 - tx) + v[3] * tx) * ty;
    }
    r.distance_per_depth = view.orthographic ? 1.0 : length(p - view.origin) / c.w;
    return r;
}

ShadowMap render_shadow_map(const Scene& scene, const ShadowView& view, std::size_t band_texels) {
    ShadowMap sm;
    render_shadow_map(scene, view, sm, band_texels);
    return sm;
}

void render_shadow_map(const Scene& scene, const ShadowView& view, ShadowMap& sm,
                       std::size_t band_texels) {
    // The meshes in the view's clip space (and per band below): scratch of the calling thread,
    // kept between calls, like the band's frame (references: the worker threads must see this
    // thread's).
    static thread_local std::vector<std::vector<ClipVertex>> clip_scratch;
    static thread_local std::vector<RasterMesh> meshes_scratch;
    std::vector<std::vector<ClipVertex>>& clip = clip_scratch;
    clip.resize(scene.shapes.size());
    for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
        const std::vector<Vec3>& pos = scene.shapes[k].mesh.positions;
        clip[k].resize(pos.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pos.size(), 4096),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t v = r.begin(); v != r.end(); ++v)
                                  clip[k][v] = view.to_clip(pos[v]);
                          });
    }
    sm.view = view;
    const std::size_t S = static_cast<std::size_t>(view.size);
    sm.depth.resize(S * S);  // every texel is written by its band below
    sm.shape.resize(S * S);
    // Horizontal bands of at most 2^22 texels, each rasterized on its own (depth only), so that
    // the rasterizer's frame (12 bytes a texel) stays below 51 MB for any map size. A band of rows
    // [r0, r1) is the map's clip space stretched in y: y' = (y - yc w) / hh (w = 1 when
    // orthographic), which keeps clip coordinates linear.
    const int rows = std::max(1, static_cast<int>(band_texels / S));
    RasterOptions o;
    o.depth_only = true;
    o.orthographic = view.orthographic;
    // Orthographic: the origin lies in front of every caster, so the near plane clips nothing.
    o.near = view.near;
    // The band's frame: scratch of the calling thread, kept between calls (maps of one size
    // then reuse its storage instead of faulting in up to 50 MB of fresh pages per map).
    static thread_local RasterFrame band_scratch;
    RasterFrame& f = band_scratch;
    std::vector<RasterMesh>& meshes = meshes_scratch;
    meshes.resize(scene.shapes.size());
    for (int r0 = 0; r0 < view.size; r0 += rows) {
        const int r1 = std::min(view.size, r0 + rows);
        const double top = 1 - 2.0 * r0 / view.size, bottom = 1 - 2.0 * r1 / view.size;
        const double yc = 0.5 * (top + bottom), hh = 0.5 * (top - bottom);
        RasterCamera cam;  // only its size matters for a frame of clip-space meshes
        cam.width = view.size;
        cam.height = r1 - r0;
        for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
            RasterMesh& m = meshes[k];
            m.vertices.resize(clip[k].size());
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clip[k].size(), 4096),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t v = r.begin(); v != r.end(); ++v) {
                                      const ClipVertex& c = clip[k][v];
                                      m.vertices[v] = {
                                          c.x, (c.y - yc * (view.orthographic ? 1.0 : c.w)) / hh,
                                          c.w};
                                  }
                              });
            m.triangles = scene.shapes[k].mesh.triangles;
            m.cull_back_faces = false;
        }
        // Each tile of the band is copied into the map as soon as it is drawn (in cache).
        o.on_tile = [&](int x0, int y0, int x1, int y1) {
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) {
                    const std::size_t i = f.sample_index(x, y);
                    const std::size_t j =
                        static_cast<std::size_t>(r0 + y) * S + static_cast<std::size_t>(x);
                    sm.depth[j] = static_cast<float>(f.view_z[i]);
                    sm.shape[j] = f.shape[i];
                }
        };
        rasterize(cam, meshes, o, f);
    }
}

}  // namespace ssslab::realtime
