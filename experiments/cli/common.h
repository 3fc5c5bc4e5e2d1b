// Shared pieces of the `ssslab` command line.
#pragma once

#include "mcml/engine.h"

#include <CLI/CLI.hpp>

#include <atomic>
#include <optional>
#include <string>

namespace ssslab::cli {

/// Options most subcommands share.
struct CommonOptions {
    std::optional<std::uint64_t> seed;
    int threads = 0;
    std::string out;
    std::optional<std::int64_t> photons;
    std::optional<double> seconds;
    std::optional<double> rel_error;
    std::int64_t batch = 0;
    bool quiet = false;
};

/// Add --seed, --threads, --out, --photons, --time, --rel-error, --batch, --quiet.
void add_common_options(CLI::App& app, CommonOptions& o, const std::string& out_help);

/// Install SIGINT/SIGTERM handlers that set the returned flag (a second signal exits at once).
const std::atomic<bool>* install_interrupt_handler();

/// The command line as one string, for provenance.
std::string command_line();
void set_command_line(int argc, char** argv);

/// "0.0973 +- 0.0003" with enough digits to show the standard error.
std::string pm(double value, double se);

/// Budget from the options (unset fields stay unset).
mcml::Budget budget_from(const CommonOptions& o);

/// Exit status for an interrupted run.
inline constexpr int kExitInterrupted = 130;

}  // namespace ssslab::cli
