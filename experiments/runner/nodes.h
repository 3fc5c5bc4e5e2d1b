// The artifacts of an experiment run and the helpers that the runner's studies (engines, plots,
// report) read them through: one ground-truth run per material, channel and role
// (`ChannelNode`, cached and keyed by content), the run that holds them (`ExperimentRun`), and
// a material's profiles assembled from its nodes. The planning and execution that fill them
// are runner.h's.
#pragma once

#include "core/batch_runner.h"
#include "core/material.h"
#include "core/profile.h"
#include "experiments/runner/experiment.h"
#include "mcml/engine.h"
#include "mcml/profile.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::runner {

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
    SampleBudget budget;
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

/// The main-role profile of a material (needs executed nodes).
RadialProfile material_profile(const ExperimentRun& r, const std::string& material);
/// The path tracer's profile of a material (all diffuse reflectance, or with `single` its
/// single-scattering part); needs executed volpath nodes.
RadialProfile volpath_profile(const ExperimentRun& r, const std::string& material, bool single);

/// The node of (material, channel, role), or nullptr.
const ChannelNode* find_node(const ExperimentRun& r, const std::string& material, int channel,
                             const std::string& role);

}  // namespace ssslab::runner
