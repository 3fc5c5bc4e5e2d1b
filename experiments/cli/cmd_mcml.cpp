// `ssslab mcml input.mci`: a drop-in replacement for MCML 1.2.2.
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/provenance.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "mcml/engine.h"
#include "mcml/mci.h"
#include "mcml/mco.h"
#include "mcml/ran3.h"

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>

#include <unistd.h>

namespace ssslab::cli {

namespace {

namespace fs = std::filesystem;

struct McmlArgs {
    std::string file;
    std::string compat;
    std::optional<int> idum;
    bool no_checkpoint = false;
    CommonOptions common;
};

std::string se_name(const std::string& out_name) {
    const std::string ext = ".mco";
    if (out_name.size() > ext.size() &&
        out_name.compare(out_name.size() - ext.size(), ext.size(), ext) == 0)
        return out_name.substr(0, out_name.size() - ext.size()) + "_stderr.mco";
    return out_name + "_stderr.mco";
}

// The resolved description of a run, its engine settings and its results, beside the .mco.
std::string run_record(const McmlArgs& a, const mcml::RunSpec& run, size_t index, bool compat,
                       int idum, const mcml::RunResult& res, const mcml::McoResult& v,
                       const mcml::McoResult& se) {
    auto doc = ConfigDocument::empty(run.out_name + ".toml");
    ConfigTable root = doc->root();
    ConfigTable input = root.table_or_empty("input");
    input.record("mci_file", fs::absolute(a.file).string());
    input.record("run_index", static_cast<std::int64_t>(index + 1));
    input.record("mci_line", static_cast<std::int64_t>(run.source_line));
    ConfigTable r = root.table_or_empty("run");
    r.record("out_name", run.out_name);
    r.record("photons_in_mci", static_cast<std::int64_t>(run.photons));
    r.record("dz_cm", run.grid.dz);
    r.record("dr_cm", run.grid.dr);
    r.record("nz", static_cast<std::int64_t>(run.grid.nz));
    r.record("nr", static_cast<std::int64_t>(run.grid.nr));
    r.record("na", static_cast<std::int64_t>(run.grid.na));
    r.record("n_above", run.layers.front().n);
    r.record("n_below", run.layers.back().n);
    for (int i = 1; i <= run.num_layers(); ++i) {
        const auto& l = run.layers[static_cast<size_t>(i)];
        ConfigTable t = r.table_or_empty("layer_" + std::to_string(i));
        t.record("n", l.n);
        t.record("mua_per_cm", l.mua);
        t.record("mus_per_cm", l.mus);
        t.record("g", l.g);
        t.record("thickness_cm", l.thickness_cm());
    }
    ConfigTable e = root.table_or_empty("engine");
    e.record("mode", std::string(compat ? "compat-mcml-1.2.2" : "default"));
    if (compat) {
        e.record("idum", static_cast<std::int64_t>(idum));
    } else {
        e.record("seed", static_cast<std::int64_t>(a.common.seed.value_or(1)));
        e.record("stream", static_cast<std::int64_t>(index));
        e.record("rng", std::string("Philox4x32-10"));
    }
    e.record("threads", static_cast<std::int64_t>(res.threads));
    e.record("batch_photons", res.batch_photons);
    if (a.common.photons) e.record("budget_photons", *a.common.photons);
    if (a.common.seconds) e.record("budget_seconds", *a.common.seconds);
    if (a.common.rel_error) e.record("budget_rel_error", *a.common.rel_error);
    ConfigTable o = root.table_or_empty("result");
    o.record("stop_reason", std::string(to_string(res.reason, "photons")));
    o.record("photons", static_cast<std::int64_t>(res.photons));
    o.record("batches", static_cast<std::int64_t>(res.batches));
    o.record("wall_seconds", res.seconds);
    o.record("resumed_from_checkpoint", std::string(res.resumed ? "yes" : "no"));
    o.record("scattering_events", static_cast<std::int64_t>(res.events));
    o.record("Rsp", v.rsp);
    o.record("Rd", v.rd);
    o.record("Rd_se", se.rd);
    o.record("A", v.a);
    o.record("A_se", se.a);
    o.record("Tt", v.tt);
    o.record("Tt_se", se.tt);
    o.record("energy_balance", v.rsp + v.rd + v.a + v.tt - 1.0);
    o.record("energy_balance_se", res.se[res.layout.energy]);
    o.record("stderr_file", se_name(run.out_name));
    doc->add_resolved_section("provenance", provenance(command_line()));
    return "# ssslab mcml: resolved run, engine settings, results and provenance\n" +
           doc->resolved_toml();
}

int run_mcml(McmlArgs& a) {
    const bool compat = !a.compat.empty();
    if (compat && a.compat != "mcml-1.2.2")
        throw InputError(
            {"<command line>", 0, 0}, "--compat",
            "unknown compatibility target \"" + a.compat + "\"; the only one is \"mcml-1.2.2\"");
    if (compat && a.common.seed)
        throw InputError({"<command line>", 0, 0}, "--seed",
                         "--compat mcml-1.2.2 uses the original generator: seed it with --idum");
    if (!compat && a.idum)
        throw InputError({"<command line>", 0, 0}, "--idum",
                         "--idum seeds the original generator and needs --compat mcml-1.2.2");
    if (compat && a.common.threads > 1 && !a.common.quiet)
        std::fprintf(stderr, "ssslab mcml: --compat mcml-1.2.2 runs on one thread\n");

    if (a.file.empty()) {
        // As the original: ask for the file name when none is given.
        if (!::isatty(STDIN_FILENO))
            throw InputError({"<command line>", 0, 0}, "file", "no .mci input file given");
        std::printf("Input filename(or . to exit):");
        std::fflush(stdout);
        if (!(std::cin >> a.file) || a.file == ".") return 1;
    }

    // Read and check every run before any is simulated (MCML's CheckParm()): a bad run 3 must
    // not leave the outputs of runs 1 and 2 behind.
    mcml::MciOptions mopt;
    mopt.allow_negative_g = !compat;
    const mcml::MciFile mci = mcml::read_mci(a.file, mopt);
    for (const auto& run : mci.runs) mcml::check_run(run, compat);

    const fs::path out_dir = a.common.out.empty() ? fs::path(".") : fs::path(a.common.out);
    const int idum = a.idum ? *a.idum : -static_cast<int>(std::time(nullptr)) % (1 << 15);
    std::unique_ptr<mcml::Ran3> ran3;
    if (compat) ran3 = std::make_unique<mcml::Ran3>(idum);
    const std::atomic<bool>* cancel = install_interrupt_handler();
    if (compat && !a.common.quiet)
        std::printf("ssslab mcml --compat mcml-1.2.2: idum = %d\n", idum);

    for (size_t i = 0; i < mci.runs.size(); ++i) {
        const mcml::RunSpec& run = mci.runs[i];
        const fs::path out_path = out_dir / run.out_name;
        const SampleBudget budget = budget_from(a.common);
        const double total = budget.samples ? static_cast<double>(*budget.samples)
                             : (budget.seconds || budget.rel_error)
                                 ? 0.0
                                 : static_cast<double>(run.photons);
        Progress progress(run.out_name, total, "photons");
        auto on_batch = [&](const BatchProgress& p) {
            progress.update(static_cast<double>(p.samples), error_figure("rel.err", p.value, p.se));
        };
        mcml::RunResult res;
        if (compat) {
            res = mcml::run_compat(run, *ran3, budget, cancel, on_batch);
        } else {
            mcml::EngineOptions o;
            o.seed = a.common.seed.value_or(1);
            o.stream = i;
            o.threads = a.common.threads;
            o.batch_photons = a.common.batch;
            o.budget = budget;
            o.cancel = cancel;
            o.on_batch = on_batch;
            if (!a.no_checkpoint) o.checkpoint_path = out_path.string() + ".ckpt";
            o.fresh = a.common.fresh;
            o.checkpoint_seconds = checkpoint_seconds(a.common);
            o.on_resume = [&](const BatchProgress& p) {
                progress.resume_from(static_cast<double>(p.samples));
                say_resuming("mcml", run.out_name, static_cast<double>(p.samples), total, "photons",
                             o.checkpoint_path, a.common.quiet);
            };
            res = mcml::run_default(run, o);
        }
        progress.finish();
        if (res.reason == BatchStop::kInterrupted) {
            std::fprintf(stderr, "ssslab mcml: interrupted in %s after %llu photons; %s\n",
                         run.out_name.c_str(), static_cast<unsigned long long>(res.photons),
                         compat || a.no_checkpoint
                             ? "no output written"
                             : "checkpoint saved; run the same command again to resume");
            return kExitInterrupted;
        }
        const mcml::McoResult v = mcml::mco_values(run, res, compat);
        const mcml::McoResult se = mcml::mco_standard_errors(run, res, compat);
        const auto photons = static_cast<std::int64_t>(res.photons);
        OutputTransaction tx;
        tx.stage(out_path, mcml::format_mco(run, v, photons, res.seconds));
        tx.stage(out_dir / se_name(run.out_name), mcml::format_mco(run, se, photons, res.seconds));
        tx.stage(out_path.string() + ".toml", run_record(a, run, i, compat, idum, res, v, se));
        tx.commit();
        if (!compat && !a.no_checkpoint) remove_checkpoints(out_path.string());
        if (!a.common.quiet) {
            std::printf("%s: %lld photons in %.3g s (%d thread%s, %s), stopped by %s\n",
                        out_path.string().c_str(), static_cast<long long>(photons), res.seconds,
                        res.threads, res.threads == 1 ? "" : "s",
                        compat ? "compat mcml-1.2.2" : "default mode",
                        to_string(res.reason, "photons"));
            std::printf("  Rsp %.6g  Rd %s  A %s  Tt %s\n", v.rsp, pm(v.rd, se.rd).c_str(),
                        pm(v.a, se.a).c_str(), pm(v.tt, se.tt).c_str());
        }
    }
    return 0;
}

}  // namespace

void register_mcml(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<McmlArgs>();
    CLI::App* sub = app.add_subcommand(
        "mcml",
        "Run an MCML .mci file (drop-in replacement for MCML 1.2.2): writes each run's .mco, its "
        "standard errors (<name>_stderr.mco) and the resolved run with provenance "
        "(<name>.mco.toml)");
    sub->add_option("file", a->file, ".mci input file (asked for when omitted, as the original)");
    sub->add_option("--compat", a->compat,
                    "Reproduce the original program: 'mcml-1.2.2' (its ran3 generator and call "
                    "order, one thread; output byte-identical after line 10)");
    sub->add_option("--idum", a->idum,
                    "Seed of the original generator in --compat mode, as the original computes it "
                    "(-(time % 32768)); default: from the clock, as the original");
    sub->add_flag("--no-checkpoint", a->no_checkpoint,
                  "Do not save <name>.mco.ckpt checkpoints (default mode saves one every 30 s and "
                  "on interruption, and resumes from it)");
    add_out_option(*sub, a->common,
                   "Directory for the outputs (default: current directory, as the original)");
    add_photons_option(*sub, a->common, "Photons per run, instead of the count in the .mci file");
    add_time_option(*sub, a->common, "Wall-time budget per run in seconds");
    add_rel_error_option(*sub, a->common,
                         "Stop a run when the relative standard error of its total diffuse "
                         "reflectance (or of its transmittance, if larger) falls below this");
    add_batch_option(*sub, a->common,
                     "Photons per batch in the default mode (default: from the photon budget; "
                     "part of what determines the result)");
    add_seed_option(*sub, a->common,
                    "Seed of the counter-based random streams in the default mode (default 1; "
                    "--compat seeds with --idum)");
    add_threads_option(*sub, a->common,
                       "Worker threads in the default mode (default: all); the results do not "
                       "depend on it (--compat runs on one)");
    add_quiet_flag(*sub, a->common);
    add_resume_options(*sub, a->common);
    sub->callback([a, &action] { action = [a] { return run_mcml(*a); }; });
}

}  // namespace ssslab::cli
