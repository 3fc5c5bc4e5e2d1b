// `ssslab render`: a ground-truth image of a scene file by the volumetric path tracer
// (volpath/render.h), written as a layered OpenEXR (radiance, subsurface, specular, their
// standard errors, depth, normal) with an sRGB PNG preview of the radiance. Progressive: a
// budget in samples per pixel, seconds or relative error of the image mean; checkpoints beside
// the output; an interrupted run (SIGINT) resumes when the same command runs again.
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/progress.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "core/stats.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "volpath/render.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

namespace ssslab::cli {

namespace fs = std::filesystem;

namespace {

struct RenderArgs {
    std::string scene;
    std::int64_t spp = 0;
    int width = 0, height = 0;
    double exposure = 0;
    std::string reference;
    std::string error_of = "median-pixel";
    int batch_spp = 0;
    std::string sampler = "sobol";
    std::string absorption = "auto";
    std::string hero = "throughput-albedo";
    std::string exit_guide = "on";
    CommonOptions common;
};

// <out>.exr.toml: what produced the image (the settings, the run and what it measured,
// provenance, and the scene as resolved); the same essentials go into the EXR header.
std::string render_toml(const RenderArgs& a, const Scene& scene, const volpath::RenderOptions& o,
                        const volpath::RenderResult& r, std::uint64_t resumed_from,
                        const RelativeError& err) {
    auto doc = ConfigDocument::empty("render.toml");
    ConfigTable root = doc->root();
    ConfigTable in = root.table_or_empty("input");
    in.record("scene_file", fs::absolute(a.scene).lexically_normal().string());
    in.record("scene_name", scene.name);
    in.record("content_key", r.content_key);
    ConfigTable st = root.table_or_empty("render");
    st.record("engine", std::string(volpath::render_engine_version()));
    st.record("seed", static_cast<std::int64_t>(o.seed));
    st.record("sampler", std::string(name_of(o.sampler)));
    st.record("absorption", a.absorption);
    st.record("hero", a.hero);
    st.record("exit_guide", a.exit_guide);
    // What "auto" (or the requested policy) came to in each medium.
    ConfigTable media = st.table_or_empty("media_absorption");
    for (const auto& [name, policy] : r.media_absorption)
        media.record(name, std::string(volpath::to_string(policy)));
    st.record("batch_spp", static_cast<std::int64_t>(r.batch_spp));
    st.record("width", static_cast<std::int64_t>(r.width));
    st.record("height", static_cast<std::int64_t>(r.height));
    if (o.budget.samples) st.record("budget_spp", *o.budget.samples);
    if (o.budget.seconds) st.record("budget_seconds", *o.budget.seconds);
    if (o.budget.rel_error) {
        st.record("budget_rel_error", *o.budget.rel_error);
        st.record("rel_error_of", std::string(volpath::to_string(o.error_measure)));
    }
    st.record("roulette_depth", static_cast<std::int64_t>(o.roulette_depth));
    st.record("long_path_events", o.long_path_events);
    st.record("threads", static_cast<std::int64_t>(r.run.threads));
    ConfigTable res = root.table_or_empty("result");
    res.record("stop_reason", std::string(to_string(r.run.reason)));
    res.record("spp", static_cast<std::int64_t>(r.spp));
    res.record("resumed_from_spp", static_cast<std::int64_t>(resumed_from));
    res.record("wall_seconds", r.seconds);
    res.record("rays", static_cast<std::int64_t>(r.rays));
    res.record("median_pixel_rel_se", err.median);
    res.record("image_mean_rel_se", err.mean);
    const std::size_t pixels =
        static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height);
    for (int c = 0; c < 3; ++c) {
        double m = 0, s2 = 0;
        for (std::size_t i = 0; i < pixels; ++i) {
            const std::size_t j = i * volpath::RenderLayout::kPerPixel + static_cast<size_t>(c);
            m += r.run.mean[j];
            s2 += r.run.se[j] * r.run.se[j];
        }
        res.record(std::string("image_mean_") + kChannelNames[c], m / static_cast<double>(pixels));
        res.record(std::string("image_mean_se_") + kChannelNames[c],
                   std::sqrt(s2) / static_cast<double>(pixels));
    }
    doc->add_resolved_section("provenance", provenance(command_line()));
    // The scene's own tables ([scene], [camera], [[lights]], [[materials]], [[shapes]]) as
    // resolved, then this run's ([input], [render], [result], [provenance]): one TOML document.
    return "# ssslab render: the scene as resolved, the settings, the run and its result, "
           "provenance\n" +
           scene.resolved_toml + "\n" + doc->resolved_toml();
}

int run_render(const RenderArgs& a) {
    const Scene scene = read_scene(a.scene);
    volpath::check_renderable(scene);
    const fs::path out = a.common.out.empty()
                             ? fs::path("results") / "render" / (scene.name + ".exr")
                             : fs::path(a.common.out);
    if (out.extension() != ".exr")
        throw InputError({"<command line>", 0, 0}, "--out", "the output must be an .exr file");
    volpath::RenderOptions o;
    o.seed = a.common.seed.value_or(1);
    o.threads = a.common.threads;
    if (a.spp > 0) o.budget.samples = a.spp;
    if (a.common.seconds) o.budget.seconds = *a.common.seconds;
    if (a.common.rel_error) o.budget.rel_error = *a.common.rel_error;
    if (!o.budget.any()) o.budget.samples = 64;
    o.batch_spp = a.batch_spp;
    // (each validated by its one_of_enum below)
    o.sampler = *parse_name<volpath::RenderSampler>(a.sampler);
    o.hero = *parse_name<volpath::RenderHero>(a.hero);
    if (a.absorption != "auto") o.absorption = *parse_name<volpath::Absorption>(a.absorption);
    o.exit_guide = a.exit_guide != "off";
    o.boundary_guides = a.exit_guide == "on" || a.exit_guide == "boundary";
    o.diffuse_guides = a.exit_guide == "on";
    o.wide_lobes = a.exit_guide == "on";
    o.error_measure = *parse_name<volpath::RenderErrorMeasure>(a.error_of);
    o.width = a.width;
    o.height = a.height;
    o.fresh = a.common.fresh;
    o.checkpoint_seconds = checkpoint_seconds(a.common);
    std::optional<LayeredImage> reference;
    if (!a.reference.empty()) {
        reference = read_exr(a.reference);
        const int w = a.width > 0 ? a.width : scene.camera.width;
        const int h = a.height > 0 ? a.height : scene.camera.height;
        if (reference->width() != w || reference->height() != h ||
            !reference->has_layer("radiance"))
            throw InputError(
                {a.reference, 0, 0}, "--reference",
                "the reference must be an EXR with a \"radiance\" layer of the render's size (" +
                    std::to_string(w) + " x " + std::to_string(h) + ")");
        o.snapshots = true;
    }
    fs::create_directories(out.parent_path().empty() ? fs::path(".") : out.parent_path());
    o.checkpoint_path = out.string() + ".ckpt";
    o.cancel = install_interrupt_handler();
    const double total =
        o.budget.samples ? static_cast<double>((*o.budget.samples + 2) / 3 * 3) : 0.0;
    std::unique_ptr<Progress> progress;
    if (!a.common.quiet) progress = std::make_unique<Progress>(scene.name, total, "spp");
    std::uint64_t resumed_from = 0;
    o.on_resume = [&](const BatchProgress& p) {
        resumed_from = p.samples;
        if (progress) progress->resume_from(static_cast<double>(p.samples));
        say_resuming("render", "", static_cast<double>(p.samples), total, "spp", o.checkpoint_path,
                     a.common.quiet);
    };
    const std::string measure = volpath::to_string(o.error_measure);
    o.on_batch = [&](const BatchProgress& p) {
        if (!progress) return;
        // An error figure only once one exists (two batches, six spp, for batch means).
        const std::string extra =
            p.samples >= 6 ? error_figure(measure + " rel.err", p.value, p.se) : "";
        progress->update(static_cast<double>(p.samples), extra);
    };
    volpath::RenderResult r = volpath::render(scene, o);
    progress.reset();
    if (r.interrupted) {
        std::fprintf(stderr,
                     "ssslab render: interrupted after %llu spp; checkpoint %s; run the same "
                     "command again to resume\n",
                     static_cast<unsigned long long>(r.spp), o.checkpoint_path.c_str());
        return kExitInterrupted;
    }
    fs::path png = out;
    png.replace_extension(".png");
    std::string csv;
    if (reference) {
        csv = "spp,seconds,rel_rmse,run_rel_se\n";
        char line[128];
        for (const volpath::ConvergencePoint& p : volpath::convergence(r, *reference)) {
            std::snprintf(line, sizeof line, "%llu,%.6g,%.6g,%.6g\n",
                          static_cast<unsigned long long>(p.spp), p.seconds, p.rel_rmse,
                          p.mean_rel_se);
            csv += line;
        }
    }
    const RelativeError err = volpath::radiance_rel_error(r.run.mean, r.run.se);
    const std::string toml = render_toml(a, scene, o, r, resumed_from, err);
    auto& md = r.image.metadata();
    md["ssslab.git_revision"] = git_revision();
    md["ssslab.command_line"] = command_line();
    md["ssslab.scene_file"] = a.scene;
    md["ssslab.content_key"] = r.content_key;
    md["ssslab.resumed_from_spp"] = std::to_string(resumed_from);
    md["ssslab.provenance"] = toml;
    // The image, its preview, its provenance (and the convergence table): all or none.
    OutputTransaction tx;
    tx.stage(out, encode_exr(r.image, out.string()));
    tx.stage(png, encode_png_preview(r.image, "radiance", a.exposure));
    tx.stage(out.string() + ".toml", toml);
    fs::path conv = out;
    conv.replace_extension("");
    if (reference) tx.stage(conv.string() + "_convergence.csv", csv);
    tx.commit();
    if (reference && !a.common.quiet) std::printf("%s", csv.c_str());
    remove_checkpoints(out.string());  // only now: a kill before keeps the run
    if (!a.common.quiet) {
        const std::string how =
            resumed_from ? "resumed from " + std::to_string(resumed_from) + " spp" : "fresh";
        std::printf(
            "%s: %d x %d, %llu spp in %.1f s (%s), %.3g rays/s; median pixel rel. SE %.3g %%, "
            "image mean rel. SE %.3g %% -> %s (+ .png, .exr.toml)\n",
            scene.name.c_str(), r.width, r.height, static_cast<unsigned long long>(r.spp),
            r.seconds, how.c_str(), static_cast<double>(r.rays) / std::max(1e-9, r.seconds),
            100.0 * err.median, 100.0 * err.mean, out.string().c_str());
    }
    return 0;
}

}  // namespace

void register_render(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<RenderArgs>();
    CLI::App* sub = app.add_subcommand(
        "render",
        "Path-trace a scene file (ground truth): layered EXR (radiance, subsurface, specular, "
        "standard errors, depth, normal) and a PNG preview; resumable");
    sub->add_option("scene", a->scene, "Scene file (TOML)")
        ->required()
        ->check(existing_file("scene file"));
    sub->add_option("--spp", a->spp,
                    "Budget in samples per pixel, rounded up to a multiple of 3 (default 64 when "
                    "no other budget is given)")
        ->check(positive_integer());
    add_time_option(*sub, a->common, "Budget in seconds of wall time");
    add_rel_error_option(*sub, a->common,
                         "Budget: stop when the median pixel's relative standard error of the "
                         "radiance falls below this (see --rel-error-of)");
    sub->add_option("--width", a->width, "Override the camera's width")
        ->check(integer_in(1, 16384));
    sub->add_option("--height", a->height, "Override the camera's height")
        ->check(integer_in(1, 16384));
    sub->add_option("--exposure", a->exposure, "Exposure of the PNG preview in stops (default 0)")
        ->check(number_in(-100, 100, false));
    sub->add_option("--reference", a->reference,
                    "A reference EXR (its \"radiance\" layer, same size): write "
                    "<out>_convergence.csv, the relative RMS error after 4, 8, 16, ... spp and at "
                    "the end, with the seconds it took")
        ->check(existing_file("reference image"));
    add_out_option(*sub, a->common, "Output EXR (default results/render/<scene>.exr)");
    add_seed_option(*sub, a->common,
                    "Seed of the counter-based random streams (default 1); with it the image is "
                    "the same for any thread count");
    add_threads_option(*sub, a->common,
                       "Worker threads (default: all); the image does not depend on it");
    add_quiet_flag(*sub, a->common);
    add_resume_options(*sub, a->common);
    sub->add_option("--rel-error-of", a->error_of,
                    "What --rel-error measures: median-pixel (default; the median over the lit "
                    "pixel channels of the radiance's relative standard error) or image-mean (the "
                    "relative standard error of the image mean, far smaller than any pixel's)")
        ->check(one_of_enum<volpath::RenderErrorMeasure>());
    sub->add_option("--batch-spp", a->batch_spp,
                    "Samples per pixel in a batch, a multiple of 3 (default: 3 x 2^m, the largest "
                    "with at least 32 batches in an --spp budget, else 3; a resumed render keeps "
                    "the batch size it started with)")
        ->check(CLI::Validator(
            [](std::string& v) {
                int n = 0;
                try {
                    n = std::stoi(v);
                } catch (...) {
                }
                return n > 0 && n % 3 == 0 && n <= 3 * 65536
                           ? std::string()
                           : "must be a positive multiple of 3, got " + v;
            },
            "MULTIPLE OF 3"));
    sub->add_option("--sampler", a->sampler,
                    "The first random numbers of a path: sobol (default; Owen-scrambled Sobol "
                    "points, scrambled anew in every batch) or independent (the stream alone)")
        ->check(one_of_enum<volpath::RenderSampler>());
    sub->add_option("--absorption", a->absorption,
                    "Absorption inside media: auto (default; weighted where every channel's "
                    "albedo is at least 0.9, else analog), analog (the hero's roulette with its "
                    "albedo) or weighted (the albedos in the path's weights, Russian roulette on "
                    "small weights) or per-channel (each channel's strategy weighted where its "
                    "albedo is at least 0.5, analog below)")
        ->check(one_of_enum<volpath::Absorption>({"auto"}));
    sub->add_option("--hero", a->hero,
                    "The hero channel of walks in media: throughput-albedo (default; chosen "
                    "anew at every entry into a medium, with probability proportional to the "
                    "path's throughput times the medium's albedo) or uniform (R, G, B in turn "
                    "per camera path, as before volpath-render-6)")
        ->check(one_of_enum<volpath::RenderHero>());
    sub->add_option("--exit-guide", a->exit_guide,
                    "Inside media behind rough boundaries, the exit guide's estimator of the "
                    "light of sphere lights and sun discs that leaves straight from a vertex "
                    "near the boundary: on (default since volpath-render-11: scattering "
                    "vertices, the boundary's own vertices from which the walk goes on inside, "
                    "and diffuse vertices straight after the way out, through the medium; a narrow "
                    "and a wide lobe per light), boundary (the first two, volpath-render-9), "
                    "scattering (scattering vertices only, volpath-render-8) or off")
        ->check(one_of({"on", "boundary", "scattering", "off"}));
    sub->callback([a, &action] { action = [a] { return run_render(*a); }; });
}

}  // namespace ssslab::cli
