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
#include "experiments/runner/nodes.h"
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

}  // namespace ssslab::runner
