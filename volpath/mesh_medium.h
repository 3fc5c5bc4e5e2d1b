// A medium inside a closed triangle mesh (through EmbreeScene): the geometry the one walk of
// volpath/walk.h uses for the renderer's media, and `walk_mesh_medium`, the walk with a smooth
// dielectric boundary (exact Fresnel, total internal reflection, the sampled free path
// continued after an internal reflection [Bitterli13 Alg. 1]) from a given point, per channel
// or analog hero, with the long-path roulette of Bitterli13 §3.2.
//
// The renderer (volpath/render.cpp) runs the same walk over the same geometry with its own
// boundary vertex (smooth or rough, NEE); the tests hold this walk to the analytic-geometry
// engines (a huge box against the half-space profile, a tessellated sphere against the lit
// sphere) and to the white furnace.
#pragma once

#include "core/mesh.h"
#include "core/rng.h"
#include "core/vec3.h"
#include "volpath/density_grid.h"
#include "volpath/embree_scene.h"
#include "volpath/walk.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

namespace ssslab::volpath {

/// Lower bounds of the distance to the nearest surface of a scene, on a grid over one shape's
/// bounding box: the balls in which a walk needs no boundary queries. A cell holds the
/// distance from its centre to the nearest triangle of any shape (EmbreeScene's point query,
/// the radius doubled from two cells until a triangle is found, capped at the box's diagonal),
/// computed the first time a walk asks for it (concurrent walks may both compute it: the same
/// value) and rounded down to a float. 64 cells along the longest side.
class SurfaceDistanceGrid {
  public:
    SurfaceDistanceGrid(const EmbreeScene& scene, const TriangleMesh& shape);
    /// A ball (centre c, radius r) around the cell of p that no surface enters, less the
    /// scene's epsilon; false where p is outside the grid or its cell touches a surface.
    bool ball(const Vec3& p, Vec3& c, double& r) const;
    /// Whether a grid pays for its point queries in a medium `r` inside `shape`: where some
    /// channel's walks are long (albedo >= 0.99: about 100 events and more) in a shape of at
    /// least 16 of that channel's mean free paths. Short walks stay near the surface, where
    /// balls are small and the cells cost more than the queries they save (measured with
    /// `ssslab bench --render`: skin and ketchup 1.6-2 x slower with balls, apple 1.6 x faster).
    static bool pays(const WalkRegion& r, const TriangleMesh& shape);

  private:
    const EmbreeScene* scene_;
    Vec3 lo_;
    double h_ = 0, cap_ = 0;
    int n_[3] = {1, 1, 1};
    std::unique_ptr<std::atomic<float>[]> d_;  // < 0: not computed yet
};

/// The walk's geometry for the inside of one closed mesh of an EmbreeScene: one region (its
/// medium), boundaries by ray queries. A path on the surface skips hits closer than the scene's
/// epsilon (restarting from the surface itself, not eps inside it: an origin moved off the
/// surface starts every walk eps deep, a bias of sigma_t eps). A hit met from outside within
/// 4 eps is a slip across a concave crease (single-precision hits): the path crosses back and
/// goes on; farther, or another shape, or no hit: the walk is lost.
///
/// With a SurfaceDistanceGrid, flights that stay in a ball no surface enters skip their ray
/// query: their collision comes before any boundary, as the query would have said (the ball
/// is smaller than the true clearance by the scene's epsilon, far above single-precision
/// rounding), so the walk is the same to the bit with a fraction of the queries in dense
/// media. (A mesh that is not closed is then noticed later, by a query outside a ball.)
struct MeshGeometry {
    const EmbreeScene* scene = nullptr;
    std::uint32_t shape = 0;
    WalkRegion inside;
    static constexpr bool multi_region = false;
    const SurfaceDistanceGrid* balls = nullptr;  ///< null: every flight queries
    mutable Vec3 ball_c;
    mutable double ball_r2 = -1;  // squared radius (< 0: no ball)

    template <int NC>
    bool clear(const WalkState<NC>& s, double t) const {
        if (!balls) return false;
        const Vec3 e = s.p + s.w * t;
        auto in_ball = [&](const Vec3& x) {
            const Vec3 d = x - ball_c;
            return dot(d, d) < ball_r2;
        };
        if (ball_r2 > 0 && in_ball(s.p) && in_ball(e)) return true;
        if (s.on_surface) return false;
        double r = 0;
        if (!balls->ball(s.p, ball_c, r)) {
            ball_r2 = -1;
            return false;
        }
        ball_r2 = r * r;
        return in_ball(s.p) && in_ball(e);
    }

    const WalkRegion& region(int) const { return inside; }
    template <int NC>
    WalkBoundary next(WalkState<NC>& s) const {
        ++s.queries;
        const double eps = scene->epsilon();
        const RayHit hit = scene->intersect(s.p, s.w, s.on_surface ? eps : 0.0);
        WalkBoundary b;
        if (!hit.hit() || hit.shape != shape) {
            b.kind = WalkBoundary::Kind::kLeak;
            return b;
        }
        b.t = hit.t;
        b.n = hit.normal;
        b.shape = hit.shape;
        b.triangle = hit.triangle;
        const double cos_i = dot(s.w, hit.normal);  // leaving: along the outward normal
        if (!(cos_i > 0))
            b.kind = hit.t < 4 * eps && cos_i == cos_i ? WalkBoundary::Kind::kSlip
                                                       : WalkBoundary::Kind::kWrongSide;
        return b;
    }
    template <int NC>
    void arrive(WalkState<NC>& s, WalkBoundary& b) const {
        s.p += s.w * b.t;
        s.on_surface = true;
    }
};

/// The medium of one shape, in the scene's world unit.
struct MeshMedium {
    const EmbreeScene* scene = nullptr;
    std::uint32_t shape = 0;  ///< the closed mesh that bounds the medium
    /// Per tally channel (index 0 only for a per-channel walk) [1 / world unit].
    std::array<double, 3> sigma_t{}, sigma_s{}, g{};
    double eta_inside = 1, eta_outside = 1;
    /// Heterogeneous medium: sigma_t and sigma_s above are scaled by this density (null: 1);
    /// tracked by delta tracking against sigma_t max(d).
    const DensityGrid* density = nullptr;
    /// Long-path roulette: after this many events survive each further one with this
    /// probability (weight divided by it).
    std::int64_t long_events = 1'000'000;
    double long_survival = 0.1;
    /// Hero mode: probability of each channel to be the hero.
    std::array<double, 3> hero_prob{1.0 / 3, 1.0 / 3, 1.0 / 3};
    /// Skip the queries of flights inside balls no surface enters (null: query every flight).
    const SurfaceDistanceGrid* balls = nullptr;
};

struct WalkResult {
    enum class Fate {
        kExited,    ///< left through the boundary: p, w, n, weight are set
        kAbsorbed,  ///< absorbed (or ended by a roulette)
        kLost,      ///< a ray query found no boundary (a leak), hit another shape, or 10^6
                    ///< boundary hits in one flight: weight holds the weight lost
    };
    Fate fate = Fate::kAbsorbed;
    Vec3 p, w, n;  ///< exit point, direction outside, outward normal there
    std::array<double, 3> weight{};
    std::int64_t events = 0;  ///< scattering events
};

/// Walk from `p` (on the boundary, or inside it: `on_surface` says which) in direction `w`
/// (into the medium) with unit weight. NC = 1: channel 0 of the medium, analog absorption;
/// NC = 3: hero channel `hero` samples, every channel weighted by the one-sample balance
/// heuristic (analog hero).
template <int NC>
WalkResult walk_mesh_medium(const MeshMedium& m, Vec3 p, Vec3 w, RngStream& rng, int hero = 0,
                            bool on_surface = true);

extern template WalkResult walk_mesh_medium<1>(const MeshMedium&, Vec3, Vec3, RngStream&, int,
                                               bool);
extern template WalkResult walk_mesh_medium<3>(const MeshMedium&, Vec3, Vec3, RngStream&, int,
                                               bool);

}  // namespace ssslab::volpath
