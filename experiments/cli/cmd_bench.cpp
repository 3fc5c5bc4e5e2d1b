// `ssslab bench`: throughput of the MCML engine, single thread and all threads.
//
// Prints photons/ms and ns per scattering event for the van de Hulst slab (the MCML paper's
// validation case) and for the red channel of Skin1 (semi-infinite, albedo 0.959, n = 1.3, the
// Freude14 Table 6.1 grid). The reference figures of the original MCML 1.2.2 on one core of this
// machine class (2270 and 104 photons/ms) are from the issue that specified the port; `--write-mci`
// writes the exact inputs so the original can be timed on the same cases.
#include "core/atomic_file.h"
#include "core/material.h"
#include "experiments/cli/commands.h"
#include "mcml/engine.h"
#include "mcml/mci.h"
#include "mcml/profile.h"

#include <tbb/info.h>

#include <cstdio>
#include <filesystem>
#include <memory>

namespace ssslab::cli {

namespace {

struct BenchCase {
    std::string name;
    mcml::RunSpec run;
    mcml::TallyMode mode;
    std::int64_t photons;
    double original_photons_per_ms;  // 0: none quoted
};

mcml::RunSpec slab_run() {
    mcml::RunSpec r;
    r.out_name = "slab.mco";
    r.photons = 1'000'000;
    r.grid = {0.001, 0.01, 20, 50, 30};
    r.layers.resize(3);
    r.layers[0].n = 1.0;
    r.layers[1] = {0.0, 0.02, 1.0, 10.0, 90.0, 0.75, 0, 0, 0};
    r.layers[2].n = 1.0;
    r.layers[2].z0 = r.layers[2].z1 = 0.02;
    mcml::compute_critical_angles(r);
    return r;
}

mcml::RunSpec skin1_red_run() {
    const Medium skin = *find_material("Skin1");
    const auto g = mcml::freude14_grid(skin);
    mcml::Grid grid{g.dr_cm, g.dr_cm, 50, g.nr, 30};
    mcml::RunSpec r = mcml::run_for_channel(skin, 0, 200'000, grid);
    r.out_name = "skin1_red.mco";
    return r;
}

struct BenchArgs {
    int threads = 0;
    bool quick = false;
    int repeat = 3;
    std::string only;
    std::string write_mci;
};

int run_bench(const BenchArgs& a) {
    const int all = a.threads > 0 ? a.threads : tbb::info::default_concurrency();
    if (!a.write_mci.empty()) {
        namespace fs = std::filesystem;
        write_file_atomic(fs::path(a.write_mci) / "slab.mci", mcml::format_mci({slab_run()}));
        write_file_atomic(fs::path(a.write_mci) / "skin1_red.mci",
                          mcml::format_mci({skin1_red_run()}));
        std::printf("wrote %s/slab.mci and %s/skin1_red.mci\n", a.write_mci.c_str(),
                    a.write_mci.c_str());
        return 0;
    }
    const double q = a.quick ? 0.1 : 1.0;
    std::vector<BenchCase> cases = {
        {"slab (van de Hulst), full tallies", slab_run(), mcml::TallyMode::kFull,
         static_cast<std::int64_t>(2'000'000 * q), 2270},
        {"Skin1 red, full tallies", skin1_red_run(), mcml::TallyMode::kFull,
         static_cast<std::int64_t>(300'000 * q), 104},
        {"Skin1 red, profile tallies", skin1_red_run(), mcml::TallyMode::kProfile,
         static_cast<std::int64_t>(300'000 * q), 0},
    };
    std::printf("MCML default engine, %d hardware threads used for 'all'\n", all);
    std::printf("%-34s %7s %10s %12s %12s %9s %11s\n", "case", "threads", "photons", "photons/ms",
                "ns/event", "events/ph", "x original");
    for (const auto& c : cases) {
        if (!a.only.empty() && c.name.find(a.only) == std::string::npos) continue;
        double single = 0.0;
        std::vector<int> counts = {1};
        if (all > 1) counts.push_back(all);
        for (int t : counts) {
            mcml::EngineOptions o;
            o.seed = 1;
            o.threads = t;
            o.mode = c.mode;
            o.budget.photons = c.photons;
            // Best of `repeat` runs: interference from other processes only ever slows a run.
            mcml::RunResult r = mcml::run_default(c.run, o);
            for (int k = 1; k < a.repeat; ++k) {
                mcml::RunResult again = mcml::run_default(c.run, o);
                if (again.seconds < r.seconds) r = std::move(again);
            }
            const double ppms = static_cast<double>(r.photons) / (r.seconds * 1e3);
            const double ns_event = r.seconds * 1e9 / static_cast<double>(r.events);
            char ratio[32] = "-";
            if (c.original_photons_per_ms > 0)
                std::snprintf(ratio, sizeof ratio, "%.2f", ppms / c.original_photons_per_ms / t);
            std::printf("%-34s %7d %10llu %12.1f %12.2f %9.1f %11s", c.name.c_str(), t,
                        static_cast<unsigned long long>(r.photons), ppms, ns_event * t,
                        static_cast<double>(r.events) / static_cast<double>(r.photons), ratio);
            if (t == 1)
                single = ppms;
            else
                std::printf("   scaling %.2f of %d", ppms / single, t);
            std::printf("\n");
        }
    }
    std::printf(
        "Each row is the fastest of %d runs. ns/event is CPU time per scattering event (wall "
        "time x threads). 'x original' is per thread, against the original MCML 1.2.2 figure for "
        "this machine class (slab 2270, Skin1 red 104 photons/ms on one core).\n",
        a.repeat);
    return 0;
}

}  // namespace

void register_bench(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<BenchArgs>();
    CLI::App* sub = app.add_subcommand(
        "bench",
        "Benchmark the MCML engine: photons/ms and ns per scattering event, one thread "
        "and all threads");
    sub->add_option("--threads", a->threads, "Threads for the multi-threaded rows (default: all)");
    sub->add_flag("--quick", a->quick, "A tenth of the photons");
    sub->add_option("--repeat", a->repeat, "Runs per row; the fastest is reported (default 3)")
        ->check(CLI::PositiveNumber);
    sub->add_option("--case", a->only, "Only the cases whose name contains this text");
    sub->add_option("--write-mci", a->write_mci,
                    "Write the benchmark inputs as .mci files into this directory (to time the "
                    "original program on the same cases) and exit");
    sub->callback([a, &action] { action = [a] { return run_bench(*a); }; });
}

}  // namespace ssslab::cli
