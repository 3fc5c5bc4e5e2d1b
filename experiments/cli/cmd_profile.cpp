// `ssslab profile`: R_d(r) per RGB channel with standard errors, to CSV.
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/material.h"
#include "core/progress.h"
#include "core/provenance.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "experiments/cli/profile_job.h"
#include "mcml/profile.h"
#include "volpath/pencil.h"

#include <cstdio>
#include <filesystem>
#include <memory>

namespace ssslab::cli {

namespace fs = std::filesystem;

ProfileJob read_profile_job(const std::string& config_path, const std::string& material,
                            const CommonOptions& c, const std::string& unit_flag,
                            const std::string& engine_flag, const std::string& mode_flag) {
    ProfileJob job;
    job.doc = config_path.empty() ? ConfigDocument::empty("<command line>")
                                  : ConfigDocument::parse_file(config_path);
    ConfigTable root = job.doc->root();
    if (!material.empty()) {
        if (root.has("material"))
            throw InputError({config_path, 0, 0}, "--material",
                             "give the material either with --material or in [material], not both");
        job.medium = find_material(material).value_or(Medium{});
        if (job.medium.name.empty())
            throw InputError({"<command line>", 0, 0}, "--material",
                             unknown_material_message(material));
        ConfigTable mt = root.table_or_empty("material");
        mt.record("preset", job.medium.name);
        mt.record("thickness_cm", job.medium.thickness_cm);
    } else {
        ConfigTable mt = root.table_or_empty("material");
        if (!root.has("material"))
            throw InputError({config_path.empty() ? "<command line>" : config_path, 0, 0},
                             "material",
                             "no material: give --material <name> (one of " + material_names() +
                                 ") or a [material] table in --config");
        job.medium = medium_from_config(mt);
    }
    // The medium as simulated, whichever way it was given (issue 51: provenance complete).
    ConfigTable simulated = root.table_or_empty("simulated_medium");
    record_simulated(simulated, job.medium);
    job.seed = static_cast<std::uint64_t>(root.integer("seed", 1, Range::nonnegative()));
    if (c.seed) {
        job.seed = *c.seed;
        root.record("seed", static_cast<std::int64_t>(job.seed));
    }

    ConfigTable grid = root.table_or_empty("grid");
    job.grid = mcml::freude14_grid(job.medium);
    const mcml::GridOverride go = mcml::read_grid_override(grid);
    job.grid = go.apply(job.grid);
    const std::string rule =
        go.any() ? "config" : "Freude14 Table 6.1 (dr = min MFP / 20, nr = ceil(32 max MFP / dr))";
    grid.record("dr_cm", job.grid.dr_cm);
    grid.record("nr", static_cast<std::int64_t>(job.grid.nr));
    grid.record("rule", rule);

    ConfigTable budget = root.table_or_empty("budget");
    job.budget = mcml::read_budget(budget);
    job.batch = budget.integer("batch_photons", 0, Range::nonnegative());
    if (c.photons) job.budget.samples = c.photons, budget.record("photons", *c.photons);
    if (c.seconds) job.budget.seconds = c.seconds, budget.record("seconds", *c.seconds);
    if (c.rel_error) job.budget.rel_error = c.rel_error, budget.record("rel_error", *c.rel_error);
    if (c.batch) job.batch = c.batch, budget.record("batch_photons", c.batch);
    if (!job.budget.any()) {
        job.budget.samples = mcml::kFreude14Photons;
        budget.record("photons", mcml::kFreude14Photons);
    }

    job.engine = root.choice("engine", "mcml", {"mcml", "volpath"});
    if (!engine_flag.empty()) job.engine = engine_flag, root.record("engine", engine_flag);
    ConfigTable vp = root.table_or_empty("volpath");
    job.mode = vp.choice("mode", "analog", {"analog", "weighted", "hero", "hero-weighted"});
    if (!mode_flag.empty()) job.mode = mode_flag, vp.record("mode", mode_flag);
    if (job.engine != "volpath" && (root.has("volpath") || !mode_flag.empty()))
        throw InputError({config_path.empty() ? "<command line>" : config_path, 0, 0}, "volpath",
                         "[volpath] and --mode apply to engine = \"volpath\" only");

    ConfigTable output = root.table_or_empty("output");
    job.unit = output.enumerated("unit", LengthUnit::kMm);
    if (!unit_flag.empty()) job.unit = *parse_name<LengthUnit>(unit_flag);  // one_of_enum
    if (!unit_flag.empty()) output.record("unit", unit_flag);
    root.finish();
    return job;
}

namespace {

// The path tracer's branch of run_profile_job: <out> holds all diffuse reflectance,
// <out>.single.csv its single-scattering part.
int run_volpath_job(ProfileJob& job, const fs::path& out, const CommonOptions& c,
                    const std::atomic<bool>* cancel) {
    volpath::PencilOptions po;
    po.seed = job.seed;
    po.threads = c.threads;
    po.budget = job.budget;
    po.batch_paths = job.batch;
    const bool hero = job.mode == "hero" || job.mode == "hero-weighted";
    po.mode = hero ? volpath::ChromaticMode::kHero : volpath::ChromaticMode::kPerChannel;
    po.absorption = job.mode == "analog" || job.mode == "hero" ? volpath::Absorption::kAnalog
                                                               : volpath::Absorption::kWeighted;
    po.cancel = cancel;
    po.checkpoint_prefix = out.string();
    po.fresh = c.fresh;
    po.checkpoint_seconds = checkpoint_seconds(c);
    const double total = job.budget.samples ? static_cast<double>(*job.budget.samples) : 0.0;
    RunsProgress progress(
        "profile",
        [&](int run) {
            return job.medium.name + " " + (run < 3 ? kChannelNames[run] : "RGB (hero)");
        },
        total, "paths", c.quiet);
    po.on_batch = [&](int run, const BatchProgress& p) {
        progress.batch(run, static_cast<double>(p.samples), p.value, p.se);
    };
    po.on_resume = [&](int run, const BatchProgress& p, const std::string& checkpoint) {
        progress.resume(run, static_cast<double>(p.samples), checkpoint);
    };
    const volpath::PencilRun run =
        volpath::simulate_pencil(job.medium, {job.grid.dr_cm, job.grid.nr}, po);
    progress.finish();
    if (run.interrupted) {
        std::fprintf(stderr,
                     "ssslab profile: interrupted; checkpoints saved beside %s; run the same "
                     "command again to resume\n",
                     out.string().c_str());
        return kExitInterrupted;
    }
    ConfigTable root = job.doc->root();
    const volpath::PencilLayout& L = run.layout;
    for (int ch = 0; ch < 3; ++ch) {
        const BatchRunResult& r = run.runs[run.mode == volpath::ChromaticMode::kHero ? 0 : ch];
        ConfigTable t = root.table_or_empty(std::string("result_") + kChannelNames[ch]);
        t.record("engine", std::string(volpath::engine_version()));
        t.record("stop_reason", std::string(to_string(r.reason)));
        t.record("paths", static_cast<std::int64_t>(r.samples));
        t.record("batches", static_cast<std::int64_t>(r.batches));
        t.record("threads", static_cast<std::int64_t>(r.threads));
        t.record("wall_seconds", r.seconds);
        t.record("scattering_events_per_path",
                 static_cast<double>(r.work) / static_cast<double>(r.samples));
        t.record("Rsp", run.profile.rsp[ch]);
        t.record("Rd", run.mean(ch, L.rd()));
        t.record("Rd_se", run.se(ch, L.rd()));
        t.record("Rd_single", run.mean(ch, L.rd_ss()));
        t.record("Rd_single_se", run.se(ch, L.rd_ss()));
        t.record("Rd_beyond_grid", run.profile.beyond[ch]);
        t.record("Rd_beyond_grid_se", run.profile.beyond_se[ch]);
        t.record("Tt", run.tt[ch]);
        t.record("Tt_se", run.tt_se[ch]);
        t.record("long_path_roulette_mass", run.lost[ch]);
    }
    job.doc->add_resolved_section("provenance", provenance(command_line()));
    OutputTransaction tx;
    tx.stage(out, run.profile.to_csv(job.unit));
    tx.stage(out.string() + ".single.csv", run.single.to_csv(job.unit));
    tx.stage(out.string() + ".toml",
             "# ssslab profile: resolved configuration, results per channel, provenance\n" +
                 job.doc->resolved_toml());
    tx.commit();
    remove_checkpoints(out.string());  // only now: a kill before keeps the runs
    if (!c.quiet) {
        std::printf("%s: %d bins of %.4g %s (%s), volpath %s, %.3g s\n", out.string().c_str(),
                    job.grid.nr, job.grid.dr_cm * (job.unit == LengthUnit::kMm ? 10 : 1),
                    unit_name(job.unit), job.medium.name.c_str(), job.mode.c_str(), run.seconds);
        for (int ch = 0; ch < 3; ++ch)
            std::printf("  %s: Rd %s (single scattering %s, beyond grid %.2g)\n", kChannelNames[ch],
                        pm(run.mean(ch, L.rd()), run.se(ch, L.rd())).c_str(),
                        pm(run.mean(ch, L.rd_ss()), run.se(ch, L.rd_ss())).c_str(),
                        run.profile.beyond[ch]);
    }
    return 0;
}

}  // namespace

int run_profile_job(ProfileJob& job, const fs::path& out, const CommonOptions& c) {
    const std::atomic<bool>* cancel = install_interrupt_handler();
    if (job.engine == "volpath") return run_volpath_job(job, out, c, cancel);
    mcml::ProfileOptions po;
    po.seed = job.seed;
    po.threads = c.threads;
    po.budget = job.budget;
    po.batch_photons = job.batch;
    po.cancel = cancel;
    po.checkpoint_prefix = out.string();
    po.fresh = c.fresh;
    po.checkpoint_seconds = checkpoint_seconds(c);
    const double total = job.budget.samples ? static_cast<double>(*job.budget.samples) : 0.0;
    RunsProgress progress(
        "profile", [&](int ch) { return job.medium.name + " " + kChannelNames[ch]; }, total,
        "photons", c.quiet);
    po.on_batch = [&](int ch, const BatchProgress& p) {
        progress.batch(ch, static_cast<double>(p.samples), p.value, p.se);
    };
    po.on_resume = [&](int ch, const BatchProgress& p, const std::string& checkpoint) {
        progress.resume(ch, static_cast<double>(p.samples), checkpoint);
    };
    mcml::ProfileRun run = mcml::simulate_profile(job.medium, job.grid, po);
    progress.finish();
    if (run.interrupted) {
        std::fprintf(stderr,
                     "ssslab profile: interrupted; checkpoints saved beside %s; run the same "
                     "command again to resume\n",
                     out.string().c_str());
        return kExitInterrupted;
    }
    ConfigTable root = job.doc->root();
    for (int ch = 0; ch < 3; ++ch) {
        const mcml::RunResult& r = run.channels[ch];
        const auto& L = r.layout;
        ConfigTable t = root.table_or_empty(std::string("result_") + kChannelNames[ch]);
        t.record("stop_reason", std::string(to_string(r.reason, "photons")));
        t.record("photons", static_cast<std::int64_t>(r.photons));
        t.record("batches", static_cast<std::int64_t>(r.batches));
        t.record("batch_photons", r.batch_photons);
        t.record("threads", static_cast<std::int64_t>(r.threads));
        t.record("wall_seconds", r.seconds);
        t.record("scattering_events_per_photon",
                 static_cast<double>(r.events) / static_cast<double>(r.photons));
        t.record("Rsp", r.rsp);
        t.record("Rd", r.mean(L.rd));
        t.record("Rd_se", r.se[L.rd]);
        t.record("Rd_beyond_grid", run.profile.beyond[ch]);
        t.record("Rd_beyond_grid_se", run.profile.beyond_se[ch]);
        t.record("A", r.mean(L.a));
        t.record("A_se", r.se[L.a]);
        t.record("Tt", r.mean(L.tt));
        t.record("Tt_se", r.se[L.tt]);
    }
    job.doc->add_resolved_section("provenance", provenance(command_line()));
    OutputTransaction tx;
    tx.stage(out, run.profile.to_csv(job.unit));
    tx.stage(out.string() + ".toml",
             "# ssslab profile: resolved configuration, results per channel, provenance\n" +
                 job.doc->resolved_toml());
    tx.commit();
    remove_checkpoints(out.string());  // only now: a kill before keeps the runs
    if (!c.quiet) {
        std::printf("%s: %d bins of %.4g %s (%s)\n", out.string().c_str(), job.grid.nr,
                    job.grid.dr_cm * (job.unit == LengthUnit::kMm ? 10 : 1), unit_name(job.unit),
                    job.medium.name.c_str());
        for (int ch = 0; ch < 3; ++ch) {
            const auto& r = run.channels[ch];
            std::printf("  %s: Rd %s (beyond grid %.2g), %llu photons in %.3g s, stopped by %s\n",
                        kChannelNames[ch], pm(r.mean(r.layout.rd), r.se[r.layout.rd]).c_str(),
                        run.profile.beyond[ch], static_cast<unsigned long long>(r.photons),
                        r.seconds, to_string(r.reason, "photons"));
        }
    }
    return 0;
}

namespace {

struct ProfileArgs {
    std::string config, material, unit, engine, mode;
    CommonOptions common;
};

int run_profile(ProfileArgs& a) {
    ProfileJob job = read_profile_job(a.config, a.material, a.common, a.unit, a.engine, a.mode);
    const fs::path out = a.common.out.empty()
                             ? fs::path("results") / "profiles" / (job.medium.name + ".csv")
                             : fs::path(a.common.out);
    return run_profile_job(job, out, a.common);
}

}  // namespace

void register_profile(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<ProfileArgs>();
    CLI::App* sub = app.add_subcommand(
        "profile",
        "Diffuse reflectance profile R_d(r) per RGB channel with standard errors (MCML engine, "
        "Freude14 Table 6.1 set-up by default), written to CSV with the resolved configuration "
        "and provenance beside it (<out>.toml)");
    sub->add_option("-m,--material", a->material,
                    "Measured material of Freude14 Table 6.2: " + material_names());
    sub->add_option("-c,--config", a->config,
                    "TOML config: [material] (preset or sigma_a_per_mm/_per_cm, sigma_s_..., g, "
                    "eta, thickness_mm/_cm), [grid] (dr_mm/dr_cm, nr), [budget] (photons, "
                    "seconds, rel_error, batch_photons), [output] (unit), seed")
        ->check(existing_file("config file"));
    sub->add_option("--unit", a->unit,
                    "Length unit of the CSV: mm (default, as the experiments and reports) or cm")
        ->check(one_of_enum<LengthUnit>());
    sub->add_option("--engine", a->engine,
                    "Ground-truth engine: mcml (default) or volpath (the volumetric path tracer; "
                    "also writes <out>.single.csv, the single-scattering part)")
        ->check(one_of({"mcml", "volpath"}));
    sub->add_option("--mode", a->mode,
                    "volpath estimator: analog (per channel, absorption by roulette; default), "
                    "weighted (per channel, implicit absorption), hero (one path for RGB, "
                    "spectral MIS, absorption by the hero's roulette) or hero-weighted (hero "
                    "with implicit absorption)")
        ->check(one_of({"analog", "weighted", "hero", "hero-weighted"}));
    add_out_option(*sub, a->common, "Output CSV (default results/profiles/<material>.csv)");
    add_photons_option(*sub, a->common,
                       "Photon (path) budget per RGB channel (default 1e7, as Freude14, when no "
                       "other budget is given); overrides [budget] photons");
    add_time_option(*sub, a->common, "Wall-time budget per RGB channel in seconds");
    add_rel_error_option(*sub, a->common,
                         "Stop a channel when the relative standard error of its total diffuse "
                         "reflectance (or of its transmittance, if larger) falls below this");
    add_batch_option(*sub, a->common,
                     "Photons per batch (default: from the photon budget; part of what determines "
                     "the result)");
    add_seed_option(*sub, a->common,
                    "Seed of the counter-based random streams (default 1, or the config's seed)");
    add_threads_option(*sub, a->common,
                       "Worker threads (default: all); the profile does not depend on it");
    add_quiet_flag(*sub, a->common);
    add_resume_options(*sub, a->common);
    sub->callback([a, &action] { action = [a] { return run_profile(*a); }; });
}

}  // namespace ssslab::cli
