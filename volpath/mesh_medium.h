// A homogeneous medium inside a closed triangle mesh (through EmbreeScene): the random walk of
// the pencil and sphere engines with the boundary found by ray queries instead of a plane or a
// sphere. Smooth dielectric boundary (exact Fresnel, total internal reflection), the sampled
// free path continued after an internal reflection [Bitterli13 Alg. 1], analog absorption per
// channel, or one path for RGB with the analog hero estimator of volpath/pencil.h, and the
// long-path roulette of Bitterli13 §3.2.
//
// This is the transport the image renderer of scene files uses for its media; the tests hold it
// to the analytic-geometry engines (a huge box against the half-space profile, a tessellated
// sphere against the lit sphere) and to the white furnace.
#pragma once

#include "core/rng.h"
#include "core/vec3.h"
#include "volpath/density_grid.h"
#include "volpath/embree_scene.h"

#include <array>
#include <cstdint>

namespace ssslab::volpath {

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

/// Walk from `p` (on or inside the boundary) in direction `w` (into the medium) with unit
/// weight. NC = 1: channel 0 of the medium, analog absorption; NC = 3: hero channel `hero`
/// samples, every channel weighted by the one-sample balance heuristic (analog hero).
template <int NC>
WalkResult walk_mesh_medium(const MeshMedium& m, Vec3 p, Vec3 w, RngStream& rng, int hero = 0);

extern template WalkResult walk_mesh_medium<1>(const MeshMedium&, Vec3, Vec3, RngStream&, int);
extern template WalkResult walk_mesh_medium<3>(const MeshMedium&, Vec3, Vec3, RngStream&, int);

}  // namespace ssslab::volpath
