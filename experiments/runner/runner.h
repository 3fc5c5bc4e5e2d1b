// The experiment runner: from a config to cached artifacts to tables, plots and a report.
//
// An experiment is planned into artifacts (here: one MCML run per material, RGB channel and role),
// each keyed by a content hash of everything that determines it. The runner reuses what the cache
// holds, computes the rest (independent runs in parallel, each checkpointing its batches), and
// writes results/<experiment>/ in one step: nothing is replaced until every output is ready.
#pragma once

#include "core/batch_runner.h"
#include "core/profile.h"
#include "experiments/runner/cache.h"
#include "experiments/runner/experiment.h"
#include "mcml/engine.h"
#include "mcml/profile.h"

#include <atomic>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace ssslab::runner {

struct RunOptions {
    bool quick = false;  ///< multiply Monte Carlo budgets by the experiment's quick_factor
    int threads = 0;     ///< 0: all cores
    bool quiet = false;
    std::filesystem::path results_root = "results";  ///< results/<name>/ and results/cache/
    const std::atomic<bool>* cancel = nullptr;
    double checkpoint_seconds = 30.0;
    std::string command_line;
};

/// Where an artifact came from (the provenance shown beside every number).
struct Provenance {
    std::string key;
    std::string engine = "mcml";
    std::string engine_version;
    std::uint64_t seed = 0;
    std::uint64_t photons = 0, batches = 0;
    std::int64_t batch_photons = 0;
    double seconds = 0;
    std::string stop_reason;
    std::string budget;  ///< e.g. "photons = 1000000"
    std::string revision, date_utc;
    bool computed_now = false;
    bool resumed = false;  ///< continued from a checkpoint of an interrupted run
};

/// One ground-truth run: a channel of a material, by MCML (role "main", or "reference" for an
/// independent run of the convergence study) or by the path tracer (role "volpath").
struct ChannelNode {
    std::string material;  ///< label
    int channel = 0;
    std::string role;             ///< "main", "reference" or "volpath"
    std::string engine = "mcml";  ///< "mcml" or "volpath"
    Medium medium;
    mcml::ProfileGrid grid;
    mcml::Budget budget;
    std::int64_t batch_photons = 0;
    std::uint64_t seed = 0;  ///< derived from the experiment seed, the medium, channel and role
    std::string key, key_text;
    bool cached = false;
    mcml::RunResult result;    ///< engine "mcml"
    BatchRunResult vresult;    ///< engine "volpath": the channel's tally (volpath/pencil.h)
    std::string volpath_mode;  ///< engine "volpath": "analog" | "weighted"
    Provenance provenance;
};

struct Metric {
    std::string name, unit;
    double value = 0, se = 0;
    bool stochastic = true;
    double tolerance = 0;  ///< relative, for deterministic metrics
};

struct ExperimentRun {
    Experiment exp;
    bool quick = false;
    std::vector<ChannelNode> nodes;
    bool interrupted = false;
    int computed = 0, reused = 0;
    double seconds = 0;
    std::filesystem::path out_dir;
    std::vector<Metric> metrics;
};

/// Plan the artifacts an experiment needs and look them up in the cache.
ExperimentRun plan(const Experiment& e, const RunOptions& o);
/// The plan as a table: what is reused, what will be computed (for --dry-run).
void print_plan(const ExperimentRun& r, std::ostream& os, bool verbose);
/// Load the cached nodes and compute the missing ones (in parallel, each checkpointing), writing
/// nothing but cache entries: what execute does first, and all that a caller who only needs
/// ground-truth profiles (ssslab raster, the real-time study) asks for. Returns false if
/// interrupted.
bool compute_nodes(ExperimentRun& r, const RunOptions& o);
/// Compute what is missing and write results/<name>/. Returns false if interrupted (checkpoints
/// are kept; nothing is written).
bool execute(ExperimentRun& r, const RunOptions& o);

/// The experiment's metrics for regression checks (needs executed nodes).
std::vector<Metric> compute_metrics(const ExperimentRun& r);

/// The main-role profile of a material (needs executed nodes).
RadialProfile material_profile(const ExperimentRun& r, const std::string& material);
/// The path tracer's profile of a material (all diffuse reflectance, or with `single` its
/// single-scattering part); needs executed volpath nodes.
RadialProfile volpath_profile(const ExperimentRun& r, const std::string& material, bool single);

/// The node of (material, channel, role), or nullptr.
const ChannelNode* find_node(const ExperimentRun& r, const std::string& material, int channel,
                             const std::string& role);

}  // namespace ssslab::runner
