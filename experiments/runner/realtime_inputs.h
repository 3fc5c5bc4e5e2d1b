// The ground truth a real-time frame needs, through the runner's artifact cache: for every medium
// material of a scene that is in view, its MCML profile on the thesis grid [Freude14 Table 6.1]
// (what every kernel model and the screen-space reference are built from), and for translucency
// the total transmittance of slabs of the material at a few thicknesses [Jimenez et al. 2010,
// generalised from skin's Gaussians to the material's own transport].
//
// Both are the runner's MCML nodes (experiments/runner/runner.h): keyed by the medium, grid,
// budget and seed, so `ssslab raster`, the real-time study and the kernel experiments share one
// cache entry per (material, channel, budget), and a killed run resumes from its checkpoints.
// Seeds are derived as in every experiment (from `seed`, the medium, the channel and the role),
// so the Freude14 kernel experiment's profiles at the same budget and seed are these.
#pragma once

#include "core/profile.h"
#include "core/scene.h"
#include "experiments/runner/runner.h"

#include <array>
#include <cstdint>
#include <map>
#include <vector>

namespace ssslab::runner {

/// Total transmittance T_t (diffuse and unscattered, normal incidence, MCML) of slabs of one
/// material, per thickness, with standard errors.
struct SlabTable {
    std::vector<double> thickness_mm;                      ///< increasing
    std::vector<std::array<double, 3>> transmittance, se;  ///< per thickness, RGB
};

struct RealtimeInputOptions {
    std::uint64_t seed = 1;
    SampleBudget profile_budget;  ///< per channel (default: 1e6 photons, as freude14/kernels)
    /// Slab thicknesses for translucency [mm] (empty: no slab runs) and their budget per
    /// channel (default: 1e5 photons).
    std::vector<double> slab_thickness_mm;
    SampleBudget slab_budget;
    RunOptions run;  ///< threads, cache root, quiet, cancel, checkpoints (quick is ignored)
    RealtimeInputOptions();
};

struct RealtimeInputs {
    std::map<int, RadialProfile> profiles;  ///< by scene material index
    std::map<int, SlabTable> slabs;         ///< by scene material index (with slab_thickness_mm)
    int computed = 0, reused = 0;           ///< MCML nodes
    bool interrupted = false;
};

/// The profiles (and slab tables) of the scene's medium materials listed in `materials` (scene
/// material indices; others are ignored). Computes what the cache lacks.
RealtimeInputs realtime_inputs(const Scene& scene, const std::vector<int>& materials,
                               const RealtimeInputOptions& o);

/// The same slab thicknesses as a geometric series from `min_mm` to `max_mm` (n >= 2 values).
std::vector<double> slab_thicknesses(double min_mm, double max_mm, int n);

}  // namespace ssslab::runner
