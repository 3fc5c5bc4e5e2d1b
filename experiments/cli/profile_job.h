// A profile computation read from a config and the command line (shared by `profile` and `run`).
#pragma once

#include "core/config.h"
#include "core/material.h"
#include "core/profile.h"
#include "experiments/cli/common.h"
#include "mcml/profile.h"

#include <filesystem>
#include <memory>
#include <string>

namespace ssslab::cli {

struct ProfileJob {
    std::shared_ptr<ConfigDocument> doc;  ///< holds the resolved configuration
    Medium medium;
    std::uint64_t seed = 1;
    mcml::ProfileGrid grid;
    SampleBudget budget;
    std::int64_t batch = 0;
    LengthUnit unit = LengthUnit::kMm;
    /// "mcml" (default) or "volpath"; with volpath, `mode` is "analog", "weighted" or "hero"
    /// (volpath/pencil.h: per-channel analog or implicit absorption, or one hero path).
    std::string engine = "mcml", mode = "analog";
};

/// Read a job from an optional TOML config, an optional --material, and the common options
/// (which override the config). Validates everything before any work starts.
/// `engine_flag` / `mode_flag` (may be empty) override the config's `engine` and `[volpath] mode`.
ProfileJob read_profile_job(const std::string& config_path, const std::string& material,
                            const CommonOptions& c, const std::string& unit_flag,
                            const std::string& engine_flag = {}, const std::string& mode_flag = {});

/// Simulate and write <out> (CSV) and <out>.toml atomically. Returns the exit status.
int run_profile_job(ProfileJob& job, const std::filesystem::path& out, const CommonOptions& c);

}  // namespace ssslab::cli
