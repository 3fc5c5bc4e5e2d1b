// The searchlight problem by volumetric path tracing [Bitterli13 §2.3, §3.2, Alg. 1]: a pencil
// beam at normal incidence on a homogeneous slab (half-infinite or finite) with a smooth
// dielectric boundary. Exit positions are tallied into the radial bins MCML uses for Rd_r, so the
// two engines' profiles compare bin by bin; also the total diffuse reflectance, its
// single-scattering part, and for finite slabs the transmittance.
#pragma once

#include "core/batch_runner.h"
#include "core/material.h"
#include "core/profile.h"
#include "volpath/walk.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ssslab::volpath {

/// Version of the numbers this engine produces for a given seed (part of every checkpoint and
/// cache key): bump it when a change alters them.
const char* engine_version();

/// How RGB media are traced.
enum class ChromaticMode {
    /// One run per channel, analog: free paths from that channel's sigma_t, absorption by
    /// roulette with the single-scattering albedo (as MCML does) [Bitterli13 Alg. 1].
    kPerChannel,
    /// One path for all channels: a hero channel (cycled over the paths) samples free paths and
    /// phase directions, and every channel's contribution carries the one-sample balance-heuristic
    /// weight over the three channels' sampling densities (spectral MIS, as pbrt-v4 and
    /// Mitsuba 3 do). Absorption: analog (the hero's albedo decides survival, and each
    /// channel's strategy includes its own, so the weights stay below 1 / P(hero = c)) or
    /// weighted (absorption in the weights, Russian roulette keeps them bounded).
    kHero,
};
const char* to_string(ChromaticMode m);

/// How hero mode picks the hero channel of a path.
enum class HeroSelection {
    kUniform,       ///< R, G, B in turn (probability 1/3 each, stratified)
    kMeanFreePath,  ///< at random, with probability proportional to the reduced mean free path
};

// Absorption and FlightRule: volpath/walk.h.

struct PencilGrid {
    double dr_cm = 0;
    int nr = 0;
};

/// The run control of the engines that make one batch run per channel (kPerChannel: runs 0..2)
/// or one hero run (run 3): the pencil and the sphere. RunControl (core/batch_runner.h), the
/// checkpoints <prefix>.<R|G|B|hero>.ckpt and callbacks that name the run.
struct ChannelRunControl : RunControl {
    /// Checkpoints are <prefix>.<R|G|B|hero>.ckpt (empty: none).
    std::string checkpoint_prefix;
    /// run: 0..2 (channel) in kPerChannel mode, 3 in kHero mode.
    std::function<void(int run, const BatchProgress&)> on_batch;
    /// Called before a run continues from its checkpoint, with what the checkpoint holds and
    /// the checkpoint's path.
    std::function<void(int run, const BatchProgress&, const std::string& checkpoint)> on_resume;

    /// The driver's run control of run `run` (0..2, 3: hero): RunControl::apply, the
    /// checkpoint's path and the callbacks (which must outlive the run).
    void apply_run(BatchRunOptions& o, int run) const;
};

/// The budget quantity of a run of `nc` channels whose blocks are `stride` tally elements
/// apart: the least precise channel's element block + pick(accumulator, block) (its value and
/// standard error).
BudgetQuantity least_precise_channel(
    std::size_t stride, int nc,
    std::function<std::size_t(const BatchAccumulator&, std::size_t block)> pick);

/// Run control: ChannelRunControl. The budget is per channel in kPerChannel mode, for the single
/// run in kHero mode; samples = paths. With no limit, 1e6 paths.
struct PencilOptions : ChannelRunControl {
    std::int64_t batch_paths = 0;  ///< 0: budget paths / 1000 (at least 1000), 1000 otherwise
    ChromaticMode mode = ChromaticMode::kPerChannel;
    Absorption absorption = Absorption::kAnalog;
    HeroSelection hero_selection = HeroSelection::kUniform;  ///< kHero only
    /// kPerChannel only: simulate just this channel (0..2); -1: all three. The other channels'
    /// runs are left empty and their profiles unfilled.
    int only_channel = -1;
    FlightRule flight = FlightRule::kContinue;
    /// Long-path roulette [Bitterli13 §3.2]: after this many scattering events a path survives
    /// each further event with probability `long_path_survival` and its weight is divided by it.
    /// Unbiased in expectation; it bounds the expected path length (albedo -> 1 in a half-space
    /// has paths of unbounded mean length), but a survivor deep in a half-space practically never
    /// returns, so it acts like a truncation (PencilLayout::lost() measures the mass at risk).
    /// 0 (default): 20 / (1 - albedo) of the run's channel (hero mode: the largest), clamped to
    /// [1e4, 1e6], so that absorption, not the roulette, ends all but a fraction e^-20 of the
    /// paths unless the medium is nearly white.
    std::int64_t long_path_events = 0;
    double long_path_survival = 0.1;
};

/// Tally layout of one channel: radial bins (the last is "beyond the grid") of all diffuse
/// reflectance, of its single-scattering part and of transmittance, then the totals.
struct PencilLayout {
    int nr = 0;
    std::size_t rd_r() const { return 0; }
    std::size_t ss_r() const { return static_cast<std::size_t>(nr + 1); }
    std::size_t tt_r() const { return static_cast<std::size_t>(2 * (nr + 1)); }
    std::size_t rd() const { return static_cast<std::size_t>(3 * (nr + 1)); }
    std::size_t rd_ss() const { return rd() + 1; }
    std::size_t tt() const { return rd() + 2; }
    /// Weight of the paths when they reach the long-path roulette (its first round): the mass
    /// at risk. The roulette is unbiased, but in a half-space with albedo near 1 a survivor at
    /// depth ~sqrt(N) mean free paths needs ~N more events to return, each another roulette,
    /// so in practice the estimate behaves like a truncation that misses about this mass.
    /// Also the weight of paths given up after 1e6 interface hits in one free flight (a guard
    /// against rounding; physics does not trap a path between parallel interfaces).
    std::size_t lost() const { return rd() + 3; }
    std::size_t per_channel() const { return rd() + 4; }
};

struct PencilRun {
    Medium medium;
    PencilGrid grid;
    ChromaticMode mode = ChromaticMode::kPerChannel;
    Absorption absorption = Absorption::kAnalog;
    HeroSelection hero_selection = HeroSelection::kUniform;  ///< kHero only
    /// kPerChannel only: simulate just this channel (0..2); -1: all three. The other channels'
    /// runs are left empty and their profiles unfilled.
    int only_channel = -1;
    PencilLayout layout;
    /// kPerChannel: three runs (R, G, B) of one channel each; kHero: one run of three channels.
    std::vector<BatchRunResult> runs;
    bool interrupted = false;
    /// Filled unless interrupted: all diffuse reflectance, and its single-scattering part
    /// (paths with exactly one scattering event). Both carry the entry factor 1 - Rsp.
    RadialProfile profile, single;
    std::array<double, 3> tt{}, tt_se{};      ///< total transmittance (finite slabs)
    std::array<double, 3> lost{}, lost_se{};  ///< see PencilLayout::lost()
    double seconds = 0;
    std::uint64_t paths = 0, events = 0;

    /// Mean and standard error of tally element i of channel c.
    double mean(int c, std::size_t i) const;
    double se(int c, std::size_t i) const;
};

/// Specular reflectance at entry (normal incidence, from the index above into the medium).
double entry_specular(const Medium& m);

/// Fill channel c of `p` (R_d per cm^2 and SE, beyond the grid, totals, Rsp) from a run's tally
/// whose channel block starts at element `base` (0 for a per-channel run; c x per_channel() in
/// hero mode); `single` selects the single-scattering part. MCML's scaling: bin weight /
/// (2 pi (i + 1/2) dr^2).
void fill_profile(const BatchRunResult& r, std::size_t base, const PencilGrid& grid, int c,
                  double rsp, RadialProfile& p, bool single);

/// The long-path roulette threshold of the run of `channel` (-1: all three, hero mode) for `o`
/// on medium `m` (resolves long_path_events = 0).
std::int64_t long_path_threshold(const Medium& m, const PencilOptions& o, int channel);

/// Checks that the run can terminate in bounded expected time and memory; throws
/// InfeasibleError saying why (e.g. sigma_t = 0 in a half-space: paths never end).
void check_pencil(const Medium& m, const PencilGrid& grid);

/// Simulate. Deterministic for any thread count: batch b of run s uses the stream
/// (seed, kVolpath + s, b), s = channel or 3 for kHero.
PencilRun simulate_pencil(const Medium& m, const PencilGrid& grid, const PencilOptions& o);

}  // namespace ssslab::volpath
