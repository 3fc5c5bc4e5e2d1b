// `ssslab render`: a ground-truth image of a scene file by the volumetric path tracer
// (volpath/render.h), written as a layered OpenEXR (radiance, subsurface, specular, their
// standard errors, depth, normal) with an sRGB PNG preview of the radiance. Progressive: a
// budget in samples per pixel, seconds or relative error of the image mean; checkpoints beside
// the output; an interrupted run (SIGINT) resumes when the same command runs again.
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/progress.h"
#include "core/scene.h"
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
    CommonOptions common;
};

int run_render(const RenderArgs& a) {
    if (a.common.photons || a.common.batch)
        throw InputError({"<command line>", 0, 0}, a.common.photons ? "--photons" : "--batch",
                         "ssslab render counts samples per pixel: use --spp (one per batch)");
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
    o.width = a.width;
    o.height = a.height;
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
    const double total = o.budget.samples ? static_cast<double>(*o.budget.samples) : 0.0;
    std::unique_ptr<Progress> progress;
    if (!a.common.quiet) progress = std::make_unique<Progress>(scene.name, total, "spp");
    o.on_batch = [&](const BatchProgress& p) {
        if (progress)
            progress->update(static_cast<double>(p.samples),
                             p.value > 0 ? "rel.err " + std::to_string(p.se / p.value) : "");
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
    write_exr(r.image, out.string());
    write_png_preview(r.image, "radiance", png.string(), a.exposure);
    if (reference) {
        fs::path conv = out;
        conv.replace_extension("");
        write_file_atomic(conv.string() + "_convergence.csv", csv);
        if (!a.common.quiet) std::printf("%s", csv.c_str());
    }
    std::error_code ec;
    fs::remove(o.checkpoint_path, ec);
    if (!a.common.quiet)
        std::printf("%s: %d x %d, %llu spp in %.1f s, %.3g rays/s -> %s (+ .png)\n",
                    scene.name.c_str(), r.width, r.height, static_cast<unsigned long long>(r.spp),
                    r.seconds, static_cast<double>(r.rays) / std::max(1e-9, r.seconds),
                    out.string().c_str());
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
                         "Budget: stop when the relative standard error of the image mean (the "
                         "radiance over all pixels and channels) falls below this");
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
    sub->callback([a, &action] { action = [a] { return run_render(*a); }; });
}

}  // namespace ssslab::cli
