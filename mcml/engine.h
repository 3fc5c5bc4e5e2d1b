// Running MCML: the default engine (counter-based streams, oneTBB, batch statistics, budgets,
// checkpoints) and the compatibility engine (the original's ran3 and call order).
#pragma once

#include "core/batch_runner.h"
#include "mcml/run_spec.h"
#include "mcml/tally.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::mcml {

class Ran3;

/// The run control of the default engine: the driver's (core/batch_runner.h: seed, threads, a
/// SampleBudget in photons, checkpoint interval, fresh, cancel, snapshots) and MCML's own. With no
/// budget limit set, the run's own photon count is used; a relative-error budget is on the larger
/// of Rd and Tt.
struct EngineOptions : RunControl {
    /// Stream domain: runs sharing a seed must differ here (e.g. the RGB channel).
    std::uint64_t stream = 0;
    std::int64_t batch_photons = 0;  ///< 0: default_batch_samples (core/batch_runner.h)
    TallyMode mode = TallyMode::kFull;
    /// Resume from and save to this file (empty: no checkpoints). A checkpoint is written every
    /// `checkpoint_seconds`, and when the run is interrupted; it is removed when the run ends.
    std::string checkpoint_path;
    /// Called once, before any batch runs, when the run continues from a checkpoint: the photons
    /// and seconds it holds.
    std::function<void(const BatchProgress&)> on_resume;
    /// Batches needed before a relative-error target may stop the run.
    int min_batches_for_error = 16;
    /// Called in batch order after each batch (progress display).
    std::function<void(const BatchProgress&)> on_batch;
};

/// Version of the default engine's numbers: it changes whenever a change alters what the engine
/// produces for a given seed (it is part of every checkpoint and cache key).
const char* engine_version();

/// Result of a run, in raw (unscaled) tally units.
struct RunResult {
    TallyLayout layout;
    /// `values / divisor` is the per-photon estimate: raw sums and the photon count in
    /// compatibility mode (so scaling matches the original bit for bit), means and 1 otherwise.
    std::vector<double> values;
    double divisor = 1.0;
    std::vector<double> se;  ///< per-photon standard errors from batch statistics
    double rsp = 0.0;
    std::uint64_t photons = 0, batches = 0, events = 0;
    std::int64_t batch_photons = 0;
    double seconds = 0.0;
    int threads = 1;
    BatchStop reason = BatchStop::kSamples;
    bool resumed = false;  ///< continued from a checkpoint
    std::vector<BatchProgress> history;
    std::vector<BatchSnapshot> snapshots;  ///< with EngineOptions::snapshots

    double mean(size_t i) const { return values[i] / divisor; }
};

/// The default engine, on the shared batch driver (run_batches): deterministic for any thread
/// count; batch b uses the stream (seed, kMcml + stream, b).
RunResult run_default(const RunSpec& run, const EngineOptions& options);

/// The compatibility engine: one thread, photons in the original order from `rng`; tallies
/// summed exactly as MCML 1.2.2 sums them. Standard errors come from consecutive photon batches.
RunResult run_compat(const RunSpec& run, Ran3& rng, const SampleBudget& budget,
                     const std::atomic<bool>* cancel = nullptr,
                     const std::function<void(const BatchProgress&)>& on_batch = {});

/// A finished run as bytes (exact doubles; the tally layout, history and snapshots included), for
/// caches of results. The run spec is not included: the cache key stands for it.
std::string serialize_result(const RunResult& r);
/// Inverse of serialize_result(); `name` names the source in errors (InputError if corrupt).
RunResult deserialize_result(const std::string& bytes, const std::string& name);

/// Scale a full-layout result to the .mco quantities, and its standard errors.
McoResult mco_values(const RunSpec& run, const RunResult& r, bool compat);
McoResult mco_standard_errors(const RunSpec& run, const RunResult& r, bool compat);

/// Everything that determines a default-mode result (run, seed, stream, batch size, tally mode,
/// engine version): a checkpoint is resumed only if its fingerprint matches.
std::string checkpoint_fingerprint(const RunSpec& run, const EngineOptions& o,
                                   std::int64_t batch_photons);

}  // namespace ssslab::mcml
