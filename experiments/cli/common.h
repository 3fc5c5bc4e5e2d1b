// Shared pieces of the `ssslab` command line.
#pragma once

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/progress.h"
#include "mcml/engine.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::cli {

/// Options several subcommands share. Each command registers only those it takes, with help
/// text of its own (add_seed_option, ... below); the others stay unset.
struct CommonOptions {
    std::optional<std::uint64_t> seed;
    int threads = 0;
    std::string out;
    std::optional<std::int64_t> photons;
    std::optional<double> seconds;
    std::optional<double> rel_error;
    std::int64_t batch = 0;
    bool quiet = false;
    bool fresh = false;  ///< resumable commands: ignore a checkpoint and start afresh
    /// Resumable commands: --checkpoint-seconds (unset: checkpoint_seconds() below).
    std::optional<double> checkpoint_seconds;
};

/// --seed (a non-negative integer).
void add_seed_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --threads (0: all cores).
void add_threads_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --out.
void add_out_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --photons (a positive integer).
void add_photons_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --time (positive seconds).
void add_time_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --rel-error (in (0, 1)).
void add_rel_error_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// --batch (a positive integer).
void add_batch_option(CLI::App& app, CommonOptions& o, const std::string& help);
/// -q, --quiet.
void add_quiet_flag(CLI::App& app, CommonOptions& o);

/// Checks of command-line values whose messages read as sentences ("must be a positive
/// integer, got 0"); CLI11 prefixes the option's name. Integers are checked as whole numbers
/// (no fractions, no exponents), so the value's conversion cannot fail after them.
CLI::Validator integer_in(std::int64_t lo, std::int64_t hi);
CLI::Validator positive_integer();
CLI::Validator nonnegative_integer();
/// A finite number in (lo, hi) or [lo, hi] (`open`: both ends excluded).
CLI::Validator number_in(double lo, double hi, bool open);
CLI::Validator positive_number();
CLI::Validator one_of(std::vector<std::string> choices);
/// one_of the spellings of enum E (core/enum_names.h), and `extra` ones (e.g. "auto").
template <class E>
CLI::Validator one_of_enum(std::vector<std::string> extra = {}) {
    std::vector<std::string> names = names_of<E>();
    names.insert(names.end(), extra.begin(), extra.end());
    return one_of(std::move(names));
}
/// An existing regular file; `what` names it in the message ("scene file 'x.toml' does not
/// exist"). On a positional argument the message stands alone (main drops the argument's name).
CLI::Validator existing_file(const std::string& what);

/// Write `content` to `path` and beside it `<path>.toml`: "# <comment>", then `doc` (what the
/// command recorded of its inputs, settings and results; none: an empty document) with the
/// provenance section. Both files or neither.
void write_with_provenance(const std::string& path, const std::string& content,
                           const std::string& comment, std::shared_ptr<ConfigDocument> doc = {});

/// Seconds between checkpoints: --checkpoint-seconds, else the environment's
/// SSSLAB_CHECKPOINT_SECONDS (the kill tests checkpoint every few milliseconds), else 30.
/// Throws InputError for a bad SSSLAB_CHECKPOINT_SECONDS.
double checkpoint_seconds(const CommonOptions& o);

/// The options of resumable commands: --fresh (ignore a checkpoint of an earlier run and start
/// afresh) and --checkpoint-seconds.
void add_resume_options(CLI::App& app, CommonOptions& o);
/// --checkpoint-seconds alone (`run`, whose artifacts are keyed and never refused).
void add_checkpoint_seconds_option(CLI::App& app, CommonOptions& o);

/// Install SIGINT/SIGTERM handlers that set the returned flag (a second signal exits at once).
const std::atomic<bool>* install_interrupt_handler();

/// The command line as one string, for provenance.
std::string command_line();
void set_command_line(int argc, char** argv);

/// "0.0973 +- 0.0003" with enough digits to show the standard error.
std::string pm(double value, double se);

/// Budget from the options (unset fields stay unset).
SampleBudget budget_from(const CommonOptions& o);

/// Says on stderr (a terminal or a log alike) that a run continues from a checkpoint:
/// "ssslab <command>: <what>: resuming from 174 of 300 spp (checkpoint <path>)"; total <= 0:
/// no total. Nothing when quiet.
void say_resuming(const std::string& command, const std::string& what, double done, double total,
                  const std::string& unit, const std::string& checkpoint, bool quiet);

/// The error figure of a progress line: "<label> 1.23%" for a relative standard error se/value,
/// or "" while none exists yet (fewer than two batches: se is 0).
std::string error_figure(const std::string& label, double value, double se);

/// The progress of a run made of several runs one after another (the channels R, G, B, or one
/// hero run): a progress line per run, labelled label(run), and the resume notice.
class RunsProgress {
  public:
    RunsProgress(std::string command, std::function<std::string(int run)> label, double total,
                 std::string unit, bool quiet);
    /// After a batch of `run`: done units, the budget quantity and its standard error.
    void batch(int run, double done, double value, double se);
    /// `run` continues from its checkpoint at `checkpoint`, which holds `done` units.
    void resume(int run, double done, const std::string& checkpoint);
    void finish() { progress_.reset(); }

  private:
    void start(int run);
    std::string command_;
    std::function<std::string(int)> label_;
    double total_;
    std::string unit_;
    bool quiet_;
    int current_ = -1;
    std::unique_ptr<Progress> progress_;
};

/// Exit status for an interrupted run.
inline constexpr int kExitInterrupted = 130;

}  // namespace ssslab::cli
