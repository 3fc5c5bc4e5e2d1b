// Ray queries against a scene's triangle meshes through Embree 3 [Wald et al. 2014] (Debian's
// libembree-dev). One Embree geometry per scene shape, so a hit names the shape (and with it the
// material) and the triangle. Built only for scenes that have meshes (docs/architecture.md: compute
// only what a scene needs); the pencil and sphere engines never open it.
//
// Embree works in single precision: hits are exact to about 1e-7 of the scene's extent, and a
// ray leaving a surface must start a little off it or skip that surface's triangle
// (`TriangleRef`).
#pragma once

#include "core/mesh.h"
#include "core/vec3.h"

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace ssslab::volpath {

struct RayHit {
    double t = std::numeric_limits<double>::infinity();  ///< distance along the unit direction
    std::uint32_t shape = kNone;                         ///< index of the mesh as added
    std::uint32_t triangle = 0;
    Vec3 normal;  ///< unit geometric normal, outward for the mesh's orientation
    bool hit() const { return shape != kNone; }
    static constexpr std::uint32_t kNone = 0xffffffffu;
};

/// One triangle of the scene: the surface a ray leaves, which its query skips (none: shape
/// kNone).
struct TriangleRef {
    std::uint32_t shape = RayHit::kNone;
    std::uint32_t triangle = 0;
    bool any() const { return shape != RayHit::kNone; }
};

class EmbreeScene {
  public:
    /// Builds the BVH over the meshes (in the given order: hit.shape indexes it). Throws
    /// std::runtime_error with Embree's message if the device or the build fails.
    explicit EmbreeScene(const std::vector<const TriangleMesh*>& meshes);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    /// Nearest hit with t in (t_min, t_max); d must be a unit vector. `leaving`: a triangle the
    /// ray leaves at t_min, whose hits are skipped, and with them hits within rounding() past
    /// t_min (every other surface counts: a distance skipped instead, as eps, misses whatever
    /// lies closer than it). Thread-safe.
    RayHit intersect(const Vec3& o, const Vec3& d, double t_min = 0,
                     double t_max = std::numeric_limits<double>::infinity(),
                     TriangleRef leaving = {}) const;
    /// Whether anything lies on the segment t in (t_min, t_max), `leaving` as above.
    /// Thread-safe.
    bool occluded(const Vec3& o, const Vec3& d, double t_min, double t_max,
                  TriangleRef leaving = {}) const;
    /// A boundary a segment crosses (see crossings()): its distance along the ray and triangle.
    struct Crossing {
        double t;
        std::uint32_t shape, triangle;
    };
    enum class Through { kClear, kBlocked, kTooMany };
    /// The segment t in (t_min, t_max), `leaving` as above, in one occlusion query that passes
    /// through the shapes `passable` marks (indexed by shape): kBlocked if any other shape lies
    /// on it; else up to `cap` passable hits in `out` (in the order Embree met them, a hit
    /// possibly twice; n: how many) and kClear, or kTooMany if there were more. Thread-safe.
    Through crossings(const Vec3& o, const Vec3& d, double t_min, double t_max, TriangleRef leaving,
                      const std::vector<char>& passable, Crossing* out, std::size_t cap,
                      std::size_t& n) const;
    /// The unit geometric normal of a triangle (outward for its mesh's orientation), as a hit
    /// on it reports it.
    const Vec3& normal(std::uint32_t shape, std::uint32_t triangle) const;
    /// Distance from p to the nearest triangle of any mesh (closest points in double precision
    /// on the meshes' own vertices), or `max_distance` if none is nearer: a ball around p that
    /// no surface enters. Embree's point query over the same BVH. Thread-safe.
    double distance_to_surface(const Vec3& p, double max_distance) const;

    std::size_t triangles() const { return triangles_; }
    /// A distance that moves a point off a surface safely for this scene's extent.
    double epsilon() const { return epsilon_; }
    /// The distance within which a hit near the origin of a ray that leaves a triangle (skipped
    /// by TriangleRef) is single-precision rounding, such as a coplanar neighbour of that
    /// triangle met at t ~ 0: 1e-6 of the scene's extent (about 16 ulps), epsilon() / 40.
    /// intersect and occluded skip it for a ray that names the triangle it leaves.
    double rounding() const { return epsilon_ / 40; }

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::size_t triangles_ = 0;
    double epsilon_ = 1e-6;
};

}  // namespace ssslab::volpath
