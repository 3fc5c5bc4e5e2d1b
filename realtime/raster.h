// The software rasterizer of the real-time renderer (issue 13, first piece): scene meshes seen
// through volpath's pinhole camera, so that sample (x, y) of a raster frame is the ray volpath
// traces through the same image point.
//
// Pipeline: world -> clip space (RasterCamera) -> near-plane and guard-band clipping
// (Sutherland-Hodgman, barycentrics carried along) -> perspective divide -> viewport -> vertices
// snapped to fixed point with 8 sub-pixel bits -> per triangle a bounding box and three integer
// edge functions [Pineda 1988] with the top-left fill rule of Direct3D 10/11 -> tiles rasterized
// in parallel (oneTBB), each tile drawing its triangles in submission order, so the frame is
// bit-identical for any thread count and any tile size.
//
// Coverage is decided on the snapped vertices, exactly (64-bit integers): triangles that share an
// edge leave no crack and cover no sample twice. Attributes (1/w, barycentrics/w) are
// interpolated from the unsnapped double-precision vertices, so depth and barycentrics at a
// sample are those of the ray-plane intersection to rounding; within 2^-8 pixel of an edge a
// sample may be covered by a triangle whose exact projection just misses it (its barycentrics
// are then slightly outside [0, 1]).
#pragma once

#include "core/mesh.h"
#include "core/scene.h"
#include "core/vec3.h"

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace ssslab::realtime {

/// A vertex in clip space: x / w and y / w run over [-1, 1] across the image (y up), w is the
/// view depth (distance along the camera's forward axis, world units).
struct ClipVertex {
    double x = 0, y = 0, w = 1;
};

/// volpath's pinhole camera (volpath/render.cpp): the ray through image point (px, py) of a
/// width x height image (raster coordinates, y down, pixel (x, y) covering [x, x+1) x [y, y+1))
/// has direction normalize(forward + right * ((2 px / width - 1) tan_half aspect) +
/// up * ((1 - 2 py / height) tan_half)).
struct RasterCamera {
    Vec3 position{0, 0, 10}, forward{0, 0, -1}, right{1, 0, 0}, up{0, 1, 0};
    double tan_half = 1, aspect = 1;  ///< tan(fov_y / 2); width / height
    int width = 1, height = 1;        ///< pixels

    /// The scene's camera at its own size, or at width x height when both are > 0 (the aspect
    /// follows the size used, as in volpath's RenderOptions::width/height).
    static RasterCamera from_scene(const SceneCamera& c, int width = 0, int height = 0);
    /// Clip coordinates of a world point.
    ClipVertex to_clip(const Vec3& p) const;
    /// Unit direction of the ray through raster point (px, py) of this camera's image.
    Vec3 ray_direction(double px, double py) const;
    /// Ray distance over view depth at raster point (px, py): |forward + right nx + up ny|.
    double ray_length_per_depth(double px, double py) const;

    /// The rays through the samples of an s x s supersampled frame of this camera, their ndc
    /// coordinates computed once per column and row: direction(sx, sy) is
    /// ray_direction((sx + 1/2) / s, (sy + 1/2) / s) and length_per_depth likewise, to the bit.
    struct SampleRays {
        Vec3 forward, right, up;
        std::vector<double> ndc_x, ndc_y;  ///< per sample column, per sample row
        Vec3 direction(int sx, int sy) const { return normalize(unnormalized(sx, sy)); }
        double length_per_depth(int sx, int sy) const { return length(unnormalized(sx, sy)); }
        Vec3 unnormalized(int sx, int sy) const {
            return forward + right * ndc_x[static_cast<std::size_t>(sx)] +
                   up * ndc_y[static_cast<std::size_t>(sy)];
        }
    };
    SampleRays sample_rays(int supersample) const;
};

/// One mesh to draw: clip-space vertices and triangles (counter-clockwise seen from the front).
struct RasterMesh {
    std::vector<ClipVertex> vertices;
    std::span<const std::array<std::uint32_t, 3>> triangles;  ///< must outlive rasterize()
    /// Skip triangles facing away from the camera: right for closed, outward-oriented meshes,
    /// wrong for open ones (a plane seen from below would vanish).
    bool cull_back_faces = false;
    /// Skip triangles facing the camera instead: a closed mesh's far side (the back samples of
    /// layered methods such as Munoz11's, experiments/runner/surface_frames.h).
    bool cull_front_faces = false;
};
/// A world-space mesh through the camera (the triangles are referenced, not copied).
RasterMesh project(const RasterCamera& camera, const TriangleMesh& mesh, bool cull_back_faces);

struct RasterOptions {
    /// s x s samples per pixel at (x + (i + 0.5) / s, y + (j + 0.5) / s): the frame is
    /// rasterized at s width x s height with the same field of view.
    int supersample = 1;
    int tile_size = 64;       ///< samples per tile side
    double near = 1e-3;       ///< near plane [world units]: geometry closer is clipped away
    bool depth_test = true;   ///< false: the last triangle drawn at a sample wins
    bool cull_closed = true;  ///< rasterize(Scene): cull back faces of closed meshes
    /// rasterize(Scene): cull the front faces of closed meshes instead (with cull_closed), so
    /// that each sample sees the nearest face turned away from the camera: a medium's far side.
    /// The software rasterizer only (GlRaster refuses it).
    bool cull_front_closed = false;
    /// Fill view_z and shape only (shadow maps): ray_t, triangle, barycentric, fragments,
    /// coverage and depth are left empty, 12 bytes a sample instead of 44.
    bool depth_only = false;
    /// Fill `barycentric` (16 bytes a sample); off, it is left empty. Attributes interpolated
    /// over the triangle need it; the lighting pass does not (realtime/frame.h turns it off).
    bool barycentrics = true;
    /// Fill `fragments` (the watertightness tests' count); off, it is left empty.
    bool count_fragments = true;
    /// Fill the per-pixel `coverage` and `depth` (volpath's box filter; 16 bytes a pixel); off,
    /// they are left empty (a frame that presents radiance only does not read them).
    bool pixel_layers = true;
    /// Called from each tile's task once its samples are final, with the tile's samples
    /// [x0, x1] x [y0, y1] (inclusive): a resolve of the tile into another target while it is
    /// in cache (a shadow map's float depth). Tiles run in parallel: it must touch only what
    /// belongs to its tile. Empty: none.
    std::function<void(int x0, int y0, int x1, int y1)> on_tile;
    /// An orthographic projection (the shadow maps of directional lights): vertices' x and y
    /// are [-1, 1] across the image already (not divided by w) and w is the depth along the
    /// view axis; depth and barycentrics interpolate linearly, ray_t = view_z. The near plane
    /// clips w < near as before; the guard band is |x|, |y| <= its bound.
    bool orthographic = false;
};

/// What a rasterization produced, as plain arrays (row-major, y down). Per sample arrays have
/// sample_width() x sample_height() entries, per pixel arrays width x height.
struct RasterFrame {
    int width = 0, height = 0;  ///< pixels
    int supersample = 1;        ///< samples per pixel side

    // Per sample.
    std::vector<double> view_z;           ///< depth along the camera axis (+inf: nothing)
    std::vector<double> ray_t;            ///< distance along the sample's unit ray (0: nothing)
    std::vector<std::int32_t> shape;      ///< mesh index (-1: nothing)
    std::vector<std::uint32_t> triangle;  ///< triangle index in its mesh (UINT32_MAX: nothing)
    /// Perspective-correct barycentrics (b1, b2) of the triangle's vertices 1 and 2 (vertex 0
    /// has 1 - b1 - b2): world position, normals, uv follow by interpolation
    /// (RasterOptions::barycentrics; empty without).
    std::vector<std::array<double, 2>> barycentric;
    /// Triangles that covered the sample, depth test or not (back faces culled are not counted):
    /// overdraw, and the watertightness tests' coverage count (RasterOptions::count_fragments;
    /// empty without).
    std::vector<std::uint32_t> fragments;

    // Per pixel (box filter over its samples, as volpath's pixels are box filtered).
    /// (RasterOptions::pixel_layers; both empty without.)
    std::vector<double> coverage;  ///< fraction of the pixel's samples covered
    std::vector<double> depth;     ///< mean ray_t over the samples, 0 where nothing: volpath's
                                   ///< "depth" layer

    int sample_width() const { return width * supersample; }
    int sample_height() const { return height * supersample; }
    std::size_t sample_index(int sx, int sy) const {
        return static_cast<std::size_t>(sy) * static_cast<std::size_t>(sample_width()) +
               static_cast<std::size_t>(sx);
    }
    std::size_t pixel_index(int x, int y) const {
        return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
               static_cast<std::size_t>(x);
    }
};

/// Rasterize meshes (drawn in the order given) into a camera.width x camera.height frame.
/// Throws std::invalid_argument for a size or supersampling factor out of range (the sample
/// grid at most 2^16 on a side) or a tile size < 1.
RasterFrame rasterize(const RasterCamera& camera, std::span<const RasterMesh> meshes,
                      const RasterOptions& options = {});
/// A scene's shapes through its camera (width x height override when both > 0); back faces of
/// the shapes whose mesh is closed (check_mesh) are culled when options.cull_closed.
RasterFrame rasterize(const Scene& scene, const RasterOptions& options = {}, int width = 0,
                      int height = 0);
/// The same into `out`, whose arrays keep their storage when the size is unchanged: a renderer
/// that draws frame after frame reuses its render targets instead of faulting in fresh pages
/// (at 1080p about 100 MB a frame).
void rasterize(const RasterCamera& camera, std::span<const RasterMesh> meshes,
               const RasterOptions& options, RasterFrame& out);
void rasterize(const Scene& scene, const RasterOptions& options, int width, int height,
               RasterFrame& out);
/// The per-pixel layers from the samples' shape and ray_t: coverage (the fraction of the
/// pixel's samples that see a shape) and depth (their mean ray distance, 0 for those that see
/// nothing), volpath's box filter; both sized to the pixels. The software rasterizer's and the
/// GL twin's (realtime/gl/raster_gl.h) supersampled frames.
void resolve_pixel_layers(RasterFrame& f);

/// Fixed point of the snapped raster coordinates: 8 fractional bits (1/256 pixel).
inline constexpr int kSubpixelBits = 8;

}  // namespace ssslab::realtime
