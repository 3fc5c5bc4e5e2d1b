// `ssslab run` and `ssslab check`: experiments through the runner.
#include "core/atomic_file.h"
#include "core/distributed.h"
#include "core/error.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "experiments/runner/check.h"
#include "experiments/runner/experiment.h"
#include "experiments/runner/runner.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include <unistd.h>

namespace ssslab::cli {

namespace {

struct RunArgs {
    std::vector<std::string> configs;
    bool quick = false, dry_run = false, verbose = false, quiet = false;
    int threads = 0;
    std::string results = "results";
    CommonOptions resume;  ///< --checkpoint-seconds
    // check only
    bool update = false;
    double alpha = 0.01;
    std::string baselines = "results/baselines";
};

std::vector<runner::Experiment> load(const RunArgs& a) {
    std::vector<runner::Experiment> out;
    if (a.configs.empty())
        out.push_back(runner::parse_experiment(runner::default_experiment_toml(),
                                               "experiments/freude14/profiles.toml (built in)"));
    for (const auto& c : a.configs) out.push_back(runner::read_experiment(c));
    return out;
}

runner::RunOptions options(const RunArgs& a) {
    runner::RunOptions o;
    o.quick = a.quick;
    o.threads = a.threads;
    o.quiet = a.quiet;
    o.results_root = a.results;
    o.command_line = command_line();
    o.checkpoint_seconds = checkpoint_seconds(a.resume);
    return o;
}

// Under MPI (core/distributed.h) the ranks other than 0 run the experiment in a results root of
// their own, removed when done: they read back what they write on the way (cache entries,
// tables), while rank 0's cache decides what is computed (ArtifactCache::find) and rank 0 alone
// writes the real results.
class RankResults {
  public:
    explicit RankResults(runner::RunOptions& o) {
        if (dist::is_root()) return;
        root_ = std::filesystem::temp_directory_path() /
                ("ssslab-rank" + std::to_string(dist::rank()) + "-" + std::to_string(::getpid()));
        std::error_code ec;
        std::filesystem::remove_all(root_, ec);
        o.results_root = root_;
        discard_outputs(false);
    }
    ~RankResults() {
        if (root_.empty()) return;
        discard_outputs(true);
        std::error_code ec;
        std::filesystem::remove_all(root_, ec);
    }
    RankResults(const RankResults&) = delete;
    RankResults& operator=(const RankResults&) = delete;

  private:
    std::filesystem::path root_;
};

int interrupted() {
    std::fprintf(stderr,
                 "ssslab: interrupted. Finished artifacts are cached and unfinished ones "
                 "checkpointed; run the same command again to resume. No results were written.\n");
    return kExitInterrupted;
}

int run_experiments(const RunArgs& a) {
    // Every config is read and checked before anything runs.
    const std::vector<runner::Experiment> exps = load(a);
    runner::RunOptions o = options(a);
    o.cancel = install_interrupt_handler();
    const RankResults own(o);
    for (const auto& e : exps) {
        runner::ExperimentRun r = runner::plan(e, o);
        if (a.dry_run || !a.quiet) runner::print_plan(r, std::cout, a.verbose);
        std::cout.flush();
        if (a.dry_run) continue;
        if (!runner::execute(r, o)) return interrupted();
        if (!a.quiet)
            std::printf("%s: %d computed, %d reused in %.3g s -> %s\n", e.name.c_str(), r.computed,
                        r.reused, r.seconds, (r.out_dir / "report.html").string().c_str());
    }
    return 0;
}

int check_experiments(const RunArgs& a) {
    const std::vector<runner::Experiment> exps = load(a);
    runner::RunOptions o = options(a);
    o.cancel = install_interrupt_handler();
    const RankResults own(o);
    runner::CheckOptions co;
    co.alpha = a.alpha;
    co.verbose = a.verbose;
    co.baselines = a.baselines;
    int regressions = 0;
    for (const auto& e : exps) {
        runner::ExperimentRun r = runner::plan(e, o);
        if (!a.quiet) runner::print_plan(r, std::cout, false);
        std::cout.flush();
        if (!runner::execute(r, o)) return interrupted();
        if (a.update) {
            const auto path = runner::baseline_path(r, co);
            if (dist::is_root()) write_file_atomic(path, runner::baseline_toml(r));
            std::printf("%s: baseline of %zu metrics written to %s\n", e.name.c_str(),
                        r.metrics.size(), path.string().c_str());
            continue;
        }
        const runner::CheckResult c = runner::check_against_baseline(r, co);
        runner::print_check(c, e.name, std::cout, a.verbose);
        regressions += c.regressions;
    }
    if (regressions > 0) {
        std::printf("ssslab check: %d regression%s\n", regressions, regressions == 1 ? "" : "s");
        return 1;
    }
    return 0;
}

void common(CLI::App& sub, RunArgs& a) {
    sub.add_option("configs", a.configs,
                   "Experiment configs (TOML); none: the built-in default experiment "
                   "(experiments/freude14/profiles.toml)")
        ->check(existing_file("experiment config"));
    sub.add_flag("--quick", a.quick,
                 "Scale every Monte Carlo budget by the experiment's quick_factor (CI and smoke "
                 "runs; recorded in the provenance, cached separately)");
    sub.add_option("--threads", a.threads,
                   "Worker threads (default: all); results do not depend on it")
        ->check(integer_in(0, 65536));
    sub.add_option("--results", a.results,
                   "Results root: <root>/<experiment>/ and the cache <root>/cache/ (default "
                   "results)");
    add_checkpoint_seconds_option(sub, a.resume);
    sub.add_flag("-v,--verbose", a.verbose, "More detail");
    sub.add_flag("-q,--quiet", a.quiet, "Print nothing but errors");
}

}  // namespace

void register_run(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<RunArgs>();
    CLI::App* sub = app.add_subcommand(
        "run",
        "Run experiments (also what `ssslab` with no command does): compute what the outputs "
        "need, reuse the cache, write results/<experiment>/ with CSV tables, plots and "
        "report.html");
    common(*sub, *a);
    sub->add_flag("-n,--dry-run", a->dry_run,
                  "Show what would be computed and what reused, and stop (with -v: the content "
                  "behind every cache key)");
    sub->callback([a, &action] { action = [a] { return run_experiments(*a); }; });
}

void register_check(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<RunArgs>();
    CLI::App* sub = app.add_subcommand(
        "check",
        "Run experiments and compare their metrics with the baselines in results/baselines/: "
        "z-scores for stochastic metrics, tolerances for deterministic ones; exit 1 on a "
        "regression");
    common(*sub, *a);
    sub->add_flag("--update", a->update, "Write the baselines from this run instead of comparing");
    sub->add_option("--alpha", a->alpha,
                    "Family-wise false-alarm rate of the z-tests (default 0.01)")
        ->check(number_in(1e-12, 0.5, false));
    sub->add_option("--baselines", a->baselines, "Baselines directory (default results/baselines)");
    sub->callback([a, &action] { action = [a] { return check_experiments(*a); }; });
}

}  // namespace ssslab::cli
