// Radial reflectance profiles of homogeneous media with the MCML engine: the ground truth of the
// kernel work [Freude14 §6.1, Table 6.1].
#pragma once

#include "core/material.h"
#include "core/profile.h"
#include "mcml/engine.h"

#include <array>
#include <functional>
#include <optional>
#include <string>

namespace ssslab {
class ConfigTable;
}

namespace ssslab::mcml {

struct ProfileGrid {
    double dr_cm = 0;
    int nr = 0;
};

/// [Freude14 Table 6.1]: dr = min over RGB of MFP / 20, nr = ceil(32 max MFP / dr), with
/// MFP = 1 / (sigma_a + sigma_s').
ProfileGrid freude14_grid(const Medium& m);

/// A grid given in a config (dr_mm or dr_cm, nr; each optional) over a default rule.
struct GridOverride {
    std::optional<double> dr_cm;
    std::optional<int> nr;
    bool any() const { return dr_cm || nr; }
    ProfileGrid apply(ProfileGrid g) const {
        if (dr_cm) g.dr_cm = *dr_cm;
        if (nr) g.nr = *nr;
        return g;
    }
};
GridOverride read_grid_override(ConfigTable& t);

/// A budget from a config table: photons, seconds, rel_error (each optional).
SampleBudget read_budget(ConfigTable& t);

/// The run control (RunControl: seed, threads, the budget per channel in photons, with none 1e7
/// [Freude14 Table 6.1], checkpoint interval, fresh, cancel, snapshots) and the profile's own.
struct ProfileOptions : RunControl {
    std::int64_t batch_photons = 0;
    /// Checkpoint files are <prefix>.<R|G|B>.ckpt (empty: none).
    std::string checkpoint_prefix;
    std::function<void(int channel, const BatchProgress&)> on_batch;
    /// Called before a channel continues from its checkpoint, with what the checkpoint holds and
    /// the checkpoint's path.
    std::function<void(int channel, const BatchProgress&, const std::string& checkpoint)> on_resume;
};

inline constexpr std::int64_t kFreude14Photons = 10'000'000;

struct ProfileRun {
    Medium medium;
    ProfileGrid grid;
    std::array<RunResult, 3> channels;
    bool interrupted = false;
    RadialProfile profile;  ///< filled unless interrupted
};

/// Simulate the three channels one after the other (each on all threads), stream = channel.
ProfileRun simulate_profile(const Medium& m, const ProfileGrid& grid, const ProfileOptions& o);

/// R_d(r) of one channel's profile-mode result, MCML's scaling: weight / (2 pi (i + 1/2) dr^2).
void fill_profile(const RunResult& r, const ProfileGrid& grid, int channel, RadialProfile& p);

}  // namespace ssslab::mcml
