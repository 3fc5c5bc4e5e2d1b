// Shadow maps of the real-time renderer's lighting pass (realtime/lighting.h): the scene's
// meshes rasterized from a light by realtime::rasterize, keeping per texel the depth of the
// first surface and its shape [Williams 1978, "Casting curved shadows on curved surfaces"].
// Directional lights (and each direction of the sun's disc and of the environment) get an
// orthographic map, point lights (and each point of a sphere light) a perspective one, or six
// cube faces when the receivers do not fit into one frustum. Every map is fitted to the
// receivers (the surfaces the camera sees): the frustum's sides to their bounding box, the near
// plane in front of every caster between the light and them (the effect of "pancaking" casters
// onto the near plane, without its loss of depth, since depth is not quantised here).
#pragma once

#include "core/scene.h"
#include "core/vec3.h"
#include "realtime/raster.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ssslab::realtime {

/// An axis-aligned box, {+inf, -inf} when empty.
struct Box {
    Vec3 lo{kBoxInf, kBoxInf, kBoxInf}, hi{-kBoxInf, -kBoxInf, -kBoxInf};
    static constexpr double kBoxInf = 1e300;
    bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
    void add(const Vec3& p);
    std::array<Vec3, 8> corners() const;
};

/// Where a shadow map looks from and what it covers.
struct ShadowView {
    bool orthographic = true;
    /// Orthographic: a point on the view axis (depth 0 there); perspective: the light.
    Vec3 origin{}, forward{0, 0, -1}, right{1, 0, 0}, up{0, 1, 0};
    /// Orthographic: half the extent across the map [world units]; perspective: tangents of
    /// the half angles.
    double half_x = 1, half_y = 1;
    /// The near plane [world units]; orthographic: fit_directional puts it in front of every
    /// caster.
    double near = 1e-3;
    int size = 1024;  ///< texels per side

    /// Map coordinates of a world point: x, y in [-1, 1] across the map (y up) after the
    /// perspective divide (perspective) or as they are (orthographic), w the depth along
    /// forward.
    ClipVertex to_clip(const Vec3& p) const;
    /// World size of a texel (the larger side) at depth w.
    double texel_size(double w) const;

    /// to_clip's x, y and w (before any perspective divide) for many points of one view: the
    /// axes divided by the half extents once, so a point costs three dot products, and linear
    /// in the offset from the origin, so that a point and a neighbour p + v share one
    /// projection (`at(p) + along(v)`). Equal to to_clip to rounding.
    struct Projection {
        Vec3 origin, x, y, w;
        ClipVertex at(const Vec3& p) const {
            const Vec3 d = p - origin;
            return {dot(d, x), dot(d, y), dot(d, w)};
        }
        ClipVertex along(const Vec3& v) const { return {dot(v, x), dot(v, y), dot(v, w)}; }
    };
    Projection projection() const {
        return {origin, right * (1 / half_x), up * (1 / half_y), forward};
    }
};

/// An orthographic view along -to_light (a unit vector towards the light) covering the box
/// `receivers` (padded by `pad_texels` texels), with the depth origin in front of `casters`.
ShadowView fit_directional(const Vec3& to_light, const Box& receivers, const Box& casters, int size,
                           double pad_texels = 2);
/// Perspective views from `position` covering `receivers`: one frustum when every corner of the
/// box lies within 75 degrees of the axis towards its centre, else the cube faces (tan 1,
/// widened by the padding) that see any part of the box. Empty when `position` is inside the box
/// in no direction (an empty box).
std::vector<ShadowView> fit_point(const Vec3& position, const Box& receivers, double near, int size,
                                  double pad_texels = 2);

/// A rasterized shadow map: depth of the first surface along the view's forward axis (+inf
/// where none) and its shape, per texel (row-major, y down), as float and int32 (8 bytes a
/// texel; rasterized depth-only in bands of at most 2^22 texels, so the rasterizer's 12-byte
/// frame adds at most 51 MB while one is drawn, kept per thread for the next map).
struct ShadowMap {
    ShadowView view;
    std::vector<float> depth;
    std::vector<std::int32_t> shape;

    struct Lookup {
        bool inside = false;     ///< the point projects into the map, beyond its near plane
        double point_depth = 0;  ///< the point's depth along forward
        double map_depth = 0;    ///< the texel's first surface (+inf: none)
        /// The first surface's depth interpolated bilinearly between the four nearest texel
        /// centres when they all hold the nearest texel's shape (exact on a plane: thickness
        /// from it does not step with the texels), else map_depth.
        double map_depth_smooth = 0;
        std::int32_t shape = -1;        ///< the texel's shape
        double distance_per_depth = 1;  ///< distance along the light's ray per unit depth
    };
    /// The texel a world point falls into (nearest texel; the shadow test does not filter).
    /// `smooth` false: a shadow test's lookup (inside, point_depth, map_depth, shape only;
    /// map_depth_smooth = map_depth and distance_per_depth = 1 are not computed).
    Lookup lookup(const Vec3& p, bool smooth = true) const;
    /// The same from p's map coordinates c (view.to_clip(p), or view.projection().at(p)),
    /// computed once by a caller that looks up several points of one projection.
    Lookup lookup(const ClipVertex& c, const Vec3& p, bool smooth) const;
    /// Map coordinates c in texels (fx right, fy down, both in [0, size) on the map), false
    /// where c has none: behind a perspective map's near plane, or outside the map.
    bool texel_coords(const ClipVertex& c, double& fx, double& fy) const {
        double u = c.x, w = c.y;
        if (!view.orthographic) {
            if (!(c.w > view.near)) return false;
            u /= c.w;
            w /= c.w;
        }
        fx = (u + 1) * 0.5 * view.size;
        fy = (1 - w) * 0.5 * view.size;
        return fx >= 0 && fy >= 0 && fx < view.size && fy < view.size;
    }
    /// The nearest texel of map coordinates c (an index into depth and shape), false where
    /// none. What lookup does first; inline, for the lighting pass's shadow test per sample.
    bool texel_of(const ClipVertex& c, std::size_t& index) const {
        double fx = 0, fy = 0;
        if (!texel_coords(c, fx, fy)) return false;
        index = texel_index(fx, fy);
        return true;
    }
    /// The texel containing texel coordinates (fx, fy) on the map.
    std::size_t texel_index(double fx, double fy) const {
        return static_cast<std::size_t>(static_cast<int>(fy)) *
                   static_cast<std::size_t>(view.size) +
               static_cast<std::size_t>(static_cast<int>(fx));
    }
};

/// The scene's shapes rasterized into the view (both sides of every triangle), band by band.
/// `band_texels`: the most texels rasterized at once (the map is the same for any value).
ShadowMap render_shadow_map(const Scene& scene, const ShadowView& view,
                            std::size_t band_texels = std::size_t{1} << 22);
/// The same into `out` (its arrays keep their storage when the size is unchanged).
void render_shadow_map(const Scene& scene, const ShadowView& view, ShadowMap& out,
                       std::size_t band_texels = std::size_t{1} << 22);

}  // namespace ssslab::realtime
