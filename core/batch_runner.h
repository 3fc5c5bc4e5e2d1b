// A Monte Carlo run as a sequence of fixed batches: the engine-independent driver that gives every
// ssslab engine built on it the same guarantees (docs/architecture.md, "Determinism",
// "Uncertainty", "Cost"):
//
// - batch b draws its random numbers from its own counter-based stream (the engine creates it from
//   the batch index), and batches are folded into the statistics in batch order, so a result is
//   bit-identical for any thread count;
// - every tally element carries its batch-means standard error (core/stats.h);
// - budgets in samples, wall time or relative error; a cancel flag (SIGINT); checkpoints written
//   atomically every few seconds and on interruption, from which a run resumes bit for bit;
// - a per-batch history (samples, seconds, budget quantity and its standard error) and snapshots
//   of the whole tally after 4, 8, 16, ... batches, for error-vs-time plots.
//
// Both witnesses run on it: MCML's default engine (mcml/engine.cpp) and every engine of the
// volumetric path tracer. Their independence is about transport code, not batching.
#pragma once

#include "core/error.h"
#include "core/stats.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ssslab {

class BinaryWriter;
class BinaryReader;

/// When to stop; the run stops at the first limit reached.
struct SampleBudget {
    std::optional<std::int64_t> samples;
    std::optional<double> seconds;    ///< wall time
    std::optional<double> rel_error;  ///< relative standard error of the budget quantity
    bool any() const { return samples || seconds || rel_error; }
};

/// The default batch size of every engine on this driver (MCML's default engine, the pencil
/// and the sphere): a count of n samples, from the budget or else `run_samples` when the budget
/// holds neither time nor error, runs in batches of ceil(n / 1000) (at least 1000) from 32,000
/// samples on and of ceil(n / 32) below, so that even a small run's standard error comes from
/// 32 batches (with 2 batches it would be a guess); budgets of time or error alone: 1000.
std::int64_t default_batch_samples(const SampleBudget& budget, std::int64_t run_samples = 0);

enum class BatchStop { kSamples, kTime, kRelError, kInterrupted };
/// The stop reason as a word; `samples_word` names what the engine counts (MCML: "photons").
const char* to_string(BatchStop s, const char* samples_word = "samples");

/// One point of a run's progress, recorded after every batch.
struct BatchProgress {
    std::uint64_t samples = 0;
    double seconds = 0;
    double value = 0;  ///< the budget quantity (per sample)
    double se = 0;     ///< its standard error
};

/// The per-sample means of the whole tally after some batches.
struct BatchSnapshot {
    std::uint64_t samples = 0, batches = 0;
    double seconds = 0;
    std::vector<double> mean;
};

/// Simulates `samples` samples of batch `index` into `tally` (size elements, zeroed by the
/// caller) and returns the work done (e.g. scattering events). Called concurrently for different
/// batches; must depend only on (index, samples).
using BatchFunction =
    std::function<std::uint64_t(std::uint64_t index, std::int64_t samples, double* tally)>;

/// The budget quantity's value and standard error from the accumulated statistics.
using BudgetQuantity = std::function<void(const BatchAccumulator&, double& value, double& se)>;

struct BatchRunOptions {
    std::size_t tally_size = 0;
    std::int64_t batch_samples = 1000;
    SampleBudget budget;  ///< must have at least one limit
    int threads = 0;      ///< 0: the caller's task arena; > 0: an arena of that many threads
    /// Identifies everything that determines the result (engine version, the content of the
    /// input, seed, batch size), best a ContentKey's text: a checkpoint is resumed only if its
    /// fingerprint matches, and a refusal names the items that differ (key_difference).
    std::string fingerprint;
    /// Empty: no checkpoints. A finished run leaves its checkpoint (the whole state, written at
    /// the end): the caller removes it with remove_checkpoints once it has stored the result, so
    /// that a kill between the two loses nothing; a rerun from a checkpoint that already holds
    /// the budget runs no batch and returns the same result.
    std::string checkpoint_path;
    /// Ignore (and in time overwrite) a checkpoint found at checkpoint_path: start afresh.
    bool fresh = false;
    /// Called once, before any batch runs, when the run continues from a checkpoint: the samples
    /// and seconds it holds (so that a command can say "resuming from 174 of 300 spp").
    std::function<void(const BatchProgress&)> on_resume;
    double checkpoint_seconds = 30.0;
    const std::atomic<bool>* cancel = nullptr;
    int min_batches_for_error = 16;
    BudgetQuantity quantity;  ///< required for a rel_error budget; recorded in the history
    /// What the budget quantity is, for the error when it stays 0 (e.g. "Rd and Tt").
    std::string quantity_name = "the budget quantity";
    std::function<void(const BatchProgress&)> on_batch;
    bool snapshots = false;
};

/// The run control every engine built on this driver takes besides its physics: its option
/// structs inherit it (volpath's PencilOptions, SphereOptions, RenderOptions), and `apply`
/// hands it to the driver. Where the checkpoints go and the progress callbacks stay with the
/// engine (one file per channel run, or one per image).
struct RunControl {
    std::uint64_t seed = 1;
    int threads = 0;  ///< 0: the caller's task arena; > 0: an arena of that many threads
    /// Samples, wall time or relative error; engines choose a default when none is set.
    SampleBudget budget;
    double checkpoint_seconds = 30.0;
    /// Ignore existing checkpoints (start afresh) instead of resuming or refusing them.
    bool fresh = false;
    /// Set asynchronously (e.g. by a signal handler) to stop after the batches in flight.
    const std::atomic<bool>* cancel = nullptr;
    /// Keep the whole tally after 4, 8, 16, ... batches (BatchRunResult::snapshots).
    bool snapshots = false;

    /// Copies threads, checkpoint interval, fresh, cancel and snapshots into `o` (not the
    /// budget, which engines adjust first).
    void apply(BatchRunOptions& o) const {
        o.threads = threads;
        o.checkpoint_seconds = checkpoint_seconds;
        o.fresh = fresh;
        o.cancel = cancel;
        o.snapshots = snapshots;
    }
};

struct BatchRunResult {
    std::vector<double> mean, se;  ///< per sample
    std::uint64_t samples = 0, batches = 0, work = 0;
    double seconds = 0;
    int threads = 1;
    BatchStop reason = BatchStop::kSamples;
    bool resumed = false;
    std::vector<BatchProgress> history;
    std::vector<BatchSnapshot> snapshots;
};

/// Run batches 0, 1, 2, ... until the budget is met or `cancel` is set. Throws InputError for a
/// checkpoint of another run (checkpoint_refusal's message), InfeasibleError when a relative-error
/// budget alone cannot be met (the quantity stays 0 for 10000 batches).
BatchRunResult run_batches(const BatchRunOptions& options, const BatchFunction& simulate);

/// The checkpoint of run `run` ("R", "G", "B", "hero") of an engine that runs several under one
/// prefix: "<prefix>.<run>.ckpt".
std::string run_checkpoint_path(const std::string& prefix, const std::string& run);

/// Remove the checkpoints of a stored result: "<prefix>.ckpt" and the runs'
/// "<prefix>.<R|G|B|hero>.ckpt" (run_checkpoint_path). Call after the outputs are in place.
void remove_checkpoints(const std::string& prefix);

/// The fingerprint of the driver's checkpoint at `path`, nullopt if there is none (InputError if
/// the file is not a checkpoint): for an engine that adapts to the run it resumes (e.g. its
/// batch size).
std::optional<std::string> batch_checkpoint_fingerprint(const std::string& path);

/// The error for a checkpoint at `path` whose fingerprint `before` is not `now`: what differs,
/// and how to start afresh (remove the file, or --fresh). Shared by every engine's checkpoints.
InputError checkpoint_refusal(const std::string& path, const std::string& before,
                              const std::string& now);

/// The per-batch history and the snapshots as bytes, and back: shared by the driver's checkpoints
/// and result files and by engines that serialize results of their own (MCML's).
void put_batch_progress(BinaryWriter& w, const std::vector<BatchProgress>& history,
                        const std::vector<BatchSnapshot>& snapshots);
void get_batch_progress(BinaryReader& r, std::vector<BatchProgress>& history,
                        std::vector<BatchSnapshot>& snapshots);

/// A finished result as bytes (exact doubles), and back (InputError naming `name` if corrupt).
std::string serialize_batch_result(const BatchRunResult& r);
BatchRunResult deserialize_batch_result(const std::string& bytes, const std::string& name);

}  // namespace ssslab
