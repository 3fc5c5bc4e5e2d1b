// `ssslab run`: the main job. Until the experiment runner lands, its built-in default computes
// the MCML ground-truth profiles of the five main materials of Freude14 ch. 6.
#include "core/material.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "experiments/cli/profile_job.h"

#include <cstdio>
#include <filesystem>
#include <memory>

namespace ssslab::cli {

namespace {

struct RunArgs {
    CommonOptions common;
};

int run_default_job(RunArgs& a) {
    CommonOptions c = a.common;
    if (!c.photons && !c.seconds && !c.rel_error) c.photons = 1'000'000;
    const std::filesystem::path dir =
        c.out.empty() ? std::filesystem::path("results/default") : std::filesystem::path(c.out);
    if (!c.quiet)
        std::printf(
            "ssslab run: MCML profiles of the five main materials of Freude14 ch. 6 -> "
            "%s/\n",
            dir.string().c_str());
    for (const auto& name : freude14_main_materials()) {
        ProfileJob job = read_profile_job("", name, c, "mm");
        const int rc = run_profile_job(job, dir / (name + ".csv"), c);
        if (rc != 0) return rc;
    }
    return 0;
}

}  // namespace

void register_run(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<RunArgs>();
    CLI::App* sub = app.add_subcommand(
        "run",
        "The main job (also what `ssslab` with no command does): MCML ground-truth profiles of the "
        "five main materials of Freude14 (Apple, Marble, Ketchup, Skin1, Wholemilk), 1e6 photons "
        "per channel by default, to results/default/<material>.csv");
    add_common_options(*sub, a->common, "Output directory (default results/default)");
    sub->callback([a, &action] { action = [a] { return run_default_job(*a); }; });
}

}  // namespace ssslab::cli
