// `ssslab check`: an experiment's metrics against the committed baselines under
// results/baselines/. Stochastic metrics are compared by z-score with both standard errors,
// z = (current - baseline) / sqrt(se_c^2 + se_b^2), at a family-wise significance alpha (Sidak
// over the stochastic metrics, two-sided); deterministic ones with their relative tolerance.
#pragma once

#include "experiments/runner/runner.h"

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace ssslab::runner {

struct CheckOptions {
    double alpha = 0.01;
    bool verbose = false;  ///< list every metric, not only what moved
    std::filesystem::path baselines = "results/baselines";
};

/// results/baselines/<name>[.quick].toml
std::filesystem::path baseline_path(const ExperimentRun& r, const CheckOptions& o);
/// The baseline file for an executed run.
std::string baseline_toml(const ExperimentRun& r);

struct CheckRow {
    std::string name, status;  ///< status: ok, moved (|z| > 2, within the threshold), REGRESSION,
                               ///< new, MISSING
    double base = 0, base_se = 0, current = 0, current_se = 0, z = 0;
    bool stochastic = true;
};

struct CheckResult {
    std::vector<CheckRow> rows;
    double z_threshold = 0;
    int regressions = 0;
};

/// Compare an executed run with its baseline. Throws InputError if the baseline is missing or
/// malformed.
CheckResult check_against_baseline(const ExperimentRun& r, const CheckOptions& o);
void print_check(const CheckResult& c, const std::string& experiment, std::ostream& os,
                 bool verbose);

}  // namespace ssslab::runner
