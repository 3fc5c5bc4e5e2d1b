// `ssslab sphere`: the sphere study of experiments/runner/sphere_study.h (a homogeneous sphere
// under a directional light by the light-tracing ground truth and by analytic diffusion
// profiles, side by side) from the command line. Outputs (all or none, through
// OutputTransaction), for the prefix <out>: <out>.exr (the study's image), <out>.png (its
// preview), <out>_beta.csv, <out>.toml (resolved configuration, results, timing, provenance).
// Checkpoints of the path tracer are <out>.<R|G|B|hero>.ckpt; an interrupted run (SIGINT) saves
// them and the same command resumes it.
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/material.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "experiments/runner/sphere_study.h"
#include "volpath/sphere.h"

#include <cstdio>
#include <filesystem>
#include <memory>

namespace ssslab::cli {

namespace fs = std::filesystem;

namespace {

struct SphereArgs {
    std::string config, material, models, mode, entry;
    std::optional<double> radius_mm, light_deg, camera_deg;
    std::optional<int> size;
    CommonOptions common;
};

int run_sphere(const SphereArgs& a) {
    const CommonOptions& c = a.common;
    runner::SphereStudyInput in;
    in.config = a.config;
    in.material = a.material;
    in.models = a.models;
    in.mode = a.mode;
    in.entry = a.entry;
    in.radius_mm = a.radius_mm;
    in.light_deg = a.light_deg;
    in.camera_deg = a.camera_deg;
    in.size = a.size;
    in.seed = c.seed;
    in.photons = c.photons;
    in.seconds = c.seconds;
    in.rel_error = c.rel_error;
    in.batch = c.batch;
    in.threads = c.threads;
    runner::SphereJob job = runner::read_sphere_job(in);
    const volpath::SphereScene& sc = job.scene;
    const fs::path out =
        c.out.empty() ? fs::path("results") / "sphere" / sc.medium.name : fs::path(c.out);
    const std::string prefix = out.string();

    volpath::SphereOptions so;
    so.cancel = install_interrupt_handler();
    so.checkpoint_prefix = prefix;
    so.fresh = c.fresh;
    so.checkpoint_seconds = checkpoint_seconds(c);
    const double total = job.budget.samples ? static_cast<double>(*job.budget.samples) : 0.0;
    RunsProgress progress(
        "sphere",
        [&](int run) {
            return sc.medium.name + " sphere " + (run < 3 ? kChannelNames[run] : "RGB (hero)");
        },
        total, "paths", c.quiet);
    so.on_batch = [&](int run, const BatchProgress& p) {
        progress.batch(run, static_cast<double>(p.samples), p.value, p.se);
    };
    so.on_resume = [&](int run, const BatchProgress& p, const std::string& checkpoint) {
        progress.resume(run, static_cast<double>(p.samples), checkpoint);
    };
    const runner::SphereStudy st = runner::run_sphere_study(job, so, command_line());
    progress.finish();
    if (st.run.interrupted) {
        std::fprintf(stderr,
                     "ssslab sphere: interrupted; checkpoints saved beside %s; run the same "
                     "command again to resume\n",
                     prefix.c_str());
        return kExitInterrupted;
    }

    OutputTransaction tx;
    const fs::path exr_path = prefix + ".exr", png_path = prefix + ".png";
    tx.stage(exr_path, encode_exr(st.image, exr_path.string()));
    tx.stage(png_path, encode_png_preview(st.preview, "preview", st.exposure));
    tx.stage(prefix + "_beta.csv", st.beta_csv);
    tx.stage(prefix + ".toml", st.resolved_toml);
    tx.commit();
    remove_checkpoints(prefix);  // only now: a kill before keeps the runs

    if (!c.quiet) {
        std::printf(
            "%s.{exr,png,toml}, %s_beta.csv: %s sphere of radius %.4g mm, light %g deg, camera "
            "%g deg\n",
            prefix.c_str(), prefix.c_str(), sc.medium.name.c_str(), sc.radius_cm * 10,
            job.light_deg, job.camera_deg);
        std::printf("  volpath (%s): %llu paths in %.3g s; models (%s entry): %.3g s\n",
                    job.mode.c_str(), static_cast<unsigned long long>(st.run.paths), st.run.seconds,
                    approx::to_string(job.integration.entry), st.model_seconds);
        for (int ch = 0; ch < 3; ++ch) {
            const size_t c3 = static_cast<size_t>(ch);
            std::printf("  %s: exitance / incident power: volpath %s", kChannelNames[ch],
                        pm(st.run.diffuse[c3], st.run.diffuse_se[c3]).c_str());
            for (size_t k = 0; k < job.models.size(); ++k)
                std::printf(", %s %.4f", job.models[k].c_str(), st.tables[k][c3].total_fraction());
            std::printf("\n");
        }
        if (!job.models.empty())
            std::printf("  %-16s %s  %12s  %12s  %14s\n", "model", "ch", "relL2 lit", "relL2 unlit",
                        "chi2/dof (dof)");
        for (size_t k = 0; k < job.models.size(); ++k)
            for (int ch = 0; ch < 3; ++ch) {
                const runner::SphereComparison& m = st.cmp[k][static_cast<size_t>(ch)];
                std::printf("  %-16s %s   %12.4g  %12.4g  %10.4g (%d)\n", job.models[k].c_str(),
                            kChannelNames[ch], m.rel_l2_lit, m.rel_l2_unlit,
                            m.dof > 0 ? m.chi2 / m.dof : 0.0, m.dof);
            }
    }
    return 0;
}

}  // namespace

void register_sphere(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<SphereArgs>();
    CLI::App* sub = app.add_subcommand(
        "sphere",
        "A sphere under a directional light by the path tracer (light tracing, volpath) and by "
        "analytic diffusion profiles integrated over the sphere [Bitterli13 3.5], side by side: "
        "<out>.exr (volpath layers + model.<name>), <out>.png (preview: volpath, then each "
        "model), <out>_beta.csv (M(beta) per channel with z-scores), <out>.toml");
    sub->add_option("-m,--material", a->material,
                    "Measured material of Freude14 Table 6.2: " + material_names());
    sub->add_option("-c,--config", a->config,
                    "TOML config: [material] (preset or coefficients, eta), models (array or "
                    "comma-separated string), "
                    "[sphere] (radius_mm/radius_cm, light_deg, camera_deg, size, frame_scale, "
                    "acceptance_deg, beta_bins), [budget] (photons, seconds, rel_error, "
                    "batch_photons), [volpath] (mode), [integration] (entry, nodes_per_bin, "
                    "rel_tol, supersampling), seed")
        ->check(existing_file("config file"));
    sub->add_option("--radius-mm", a->radius_mm, "Sphere radius in mm (default 5)");
    sub->add_option("--models", a->models,
                    "Analytic models, comma-separated (default dipole,better-dipole,pbd; "
                    "\"none\" for the path tracer only)");
    sub->add_option("--mode", a->mode,
                    "Path tracer: analog (one run per channel; default) or hero (one path for "
                    "RGB, spectral MIS)");
    sub->add_option("--entry", a->entry,
                    "Entry weight of the models: fresnel (1 - F(cos theta_i), like the path "
                    "tracer; default) or cosine (no Fresnel factor)");
    sub->add_option("--size", a->size, "Image width and height in pixels (default 256)");
    sub->add_option("--light-deg", a->light_deg,
                    "Direction to the light, degrees from +z in the x-z plane (default 0)");
    sub->add_option("--camera-deg", a->camera_deg,
                    "Direction to the camera, degrees from +z in the x-z plane (default 60)");
    add_out_option(*sub, a->common,
                   "Output prefix (default results/sphere/<material>): <out>.exr, <out>.png, "
                   "<out>_beta.csv, <out>.toml");
    add_photons_option(*sub, a->common,
                       "Light paths per path-tracer run (one run per channel in analog mode, one "
                       "in hero mode; default 1e6 when no other budget is given)");
    add_time_option(*sub, a->common, "Wall-time budget per path-tracer run in seconds");
    add_rel_error_option(*sub, a->common,
                         "Stop a path-tracer run when the relative standard error of the total "
                         "diffuse exitance (of its least precise channel) falls below this");
    add_batch_option(*sub, a->common,
                     "Light paths per batch (default: from the budget and the image size; part "
                     "of what determines the result)");
    add_seed_option(*sub, a->common,
                    "Seed of the counter-based random streams (default 1, or the config's seed)");
    add_threads_option(*sub, a->common,
                       "Worker threads (default: all); the results do not depend on it");
    add_quiet_flag(*sub, a->common);
    add_resume_options(*sub, a->common);
    sub->callback([a, &action] { action = [a] { return run_sphere(*a); }; });
}

}  // namespace ssslab::cli
