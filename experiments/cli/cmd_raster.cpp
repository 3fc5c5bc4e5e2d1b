// `ssslab raster`: a scene file rendered the way a real-time engine would render it
// (realtime/frame.h: rasterizer, shadow-mapped G-buffer, the separable screen-space SSS pass with
// any kernel model of approx/, composite), written as a layered OpenEXR with the layer names
// `ssslab render` writes and a PNG preview, with the time of every pass.
//
// The kernels come from the materials' MCML profiles on the thesis grid [Freude14 Table 6.1],
// computed once and cached under results/cache/ (experiments/runner/realtime_inputs.h), only for
// the media in view; so do the slab transmittances that translucency reads.
#include "approx/model_spec.h"
#include "core/atomic_file.h"
#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "experiments/runner/realtime_inputs.h"
#include "realtime/frame.h"
#if SSSLAB_HAVE_GL
#include "realtime/gl/frame_gl.h"
#endif

#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace ssslab::cli {

namespace fs = std::filesystem;

namespace {

struct RasterArgs {
    std::string scene;
    std::string model = "svd:rank=1";
    std::string sss = "separable";
    std::string edge = "follow";
    int taps = 17;
    int width = 0, height = 0, supersample = 1;
    int light_samples = 16, environment_samples = 64, shadow_map = 2048, environment_map = 512;
    double jitter = 0, follow_strength = -1, reject_depth = -1;
    int reference_samples = 256;
    bool no_translucency = false, rotate = false;
    double exposure = 0;
    std::string cache = "results";
    std::string backend = "software", platform = "auto";
    CommonOptions common;
};

const SourceLocation kCommandLine{"<command line>", 0, 0};

CLI::Validator model_spec() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            try {
                approx::parse_model(s);
            } catch (const std::invalid_argument& e) {
                return e.what();
            }
            return {};
        },
        "SPEC", "model spec");
}

// What the GL twin reports of a frame (empty for the software backend): its context, and per
// pass the GL_TIME_ELAPSED query and the wall time of the draws (glFinish to glFinish).
struct GlFrameReport {
    std::string context;
    std::vector<std::pair<std::string, double>> times_ms;
};

std::string raster_toml(const RasterArgs& a, const Scene& scene, const realtime::FrameOptions& o,
                        const realtime::FrameResult& r, const runner::RealtimeInputs& in,
                        const GlFrameReport& gl) {
    auto doc = ConfigDocument::empty("raster.toml");
    ConfigTable root = doc->root();
    ConfigTable input = root.table_or_empty("input");
    input.record("scene_file", fs::absolute(a.scene).lexically_normal().string());
    input.record("scene_name", scene.name);
    ConfigTable st = root.table_or_empty("raster");
    st.record("backend", a.backend);
    if (!gl.context.empty()) st.record("gl_context", gl.context);
    st.record("model", a.model);
    st.record("kernel", realtime::sss_kernel_name(o.method, a.model));  // what the pass applied
    st.record("taps", static_cast<std::int64_t>(a.taps));
    st.record("sss", std::string(realtime::to_string(o.method)));
    st.record("edge", a.edge);
    st.record("follow_strength", o.sss.follow_strength);
    st.record("reject_depth", o.sss.reject_depth);
    st.record("jitter", o.sss.jitter);
    st.record("rotate", std::string(o.sss.rotate ? "true" : "false"));
    st.record("width", static_cast<std::int64_t>(r.image.width()));
    st.record("height", static_cast<std::int64_t>(r.image.height()));
    st.record("supersample", static_cast<std::int64_t>(o.raster.supersample));
    st.record("light_samples", static_cast<std::int64_t>(o.lighting.light_samples));
    st.record("environment_samples", static_cast<std::int64_t>(o.lighting.environment_samples));
    st.record("shadow_map_size", static_cast<std::int64_t>(o.lighting.shadow_map_size));
    st.record("environment_map_size", static_cast<std::int64_t>(o.lighting.environment_map_size));
    st.record("translucency", std::string(a.no_translucency ? "off" : "on"));
    ConfigTable t = root.table_or_empty("times_ms");
    for (const auto& p : r.times) t.record(p.pass, p.ms);
    t.record("frame", r.total_ms());
    if (!gl.times_ms.empty()) {
        ConfigTable gt = root.table_or_empty("gl_times_ms");
        for (const auto& [pass, ms] : gl.times_ms) gt.record(pass, ms);
    }
    ConfigTable g = root.table_or_empty("ground_truth");
    g.record("mcml_nodes_computed", static_cast<std::int64_t>(in.computed));
    g.record("mcml_nodes_reused", static_cast<std::int64_t>(in.reused));
    for (const auto& [m, p] : in.profiles)
        for (int c = 0; c < 3; ++c)
            g.record(
                "rd_total_" + scene.materials[static_cast<size_t>(m)].name + "_" + kChannelNames[c],
                p.rd_total[static_cast<size_t>(c)]);
    doc->add_resolved_section("provenance", provenance(command_line()));
    return "# ssslab raster: the scene as resolved, the settings, the pass times, provenance\n" +
           scene.resolved_toml + "\n" + doc->resolved_toml();
}

int run_raster(const RasterArgs& a) {
    const Scene scene = read_scene(a.scene);
    realtime::check_drawable(scene);
    const fs::path out = a.common.out.empty()
                             ? fs::path("results") / "raster" / (scene.name + ".exr")
                             : fs::path(a.common.out);
    if (out.extension() != ".exr")
        throw InputError(kCommandLine, "--out", "the output must be an .exr file");
    const approx::ModelSpec model = approx::parse_model(a.model);
    if (model.name == "manual" && model.flag("fit"))
        throw InputError(kCommandLine, "--model",
                         "\"" + a.model +
                             "\" is fitted to a kernel study's test images; a frame takes models "
                             "built from the kernel alone (svd, preintegration, guided, "
                             "manual:table_a1, deon, ssss_skin)");

    realtime::FrameOptions o;
    o.width = a.width;
    o.height = a.height;
    o.raster.supersample = a.supersample;
    o.lighting.light_samples = a.light_samples;
    o.lighting.environment_samples = a.environment_samples;
    o.lighting.shadow_map_size = a.shadow_map;
    o.lighting.environment_map_size = a.environment_map;
    o.method = *parse_name<realtime::SssMethod>(a.sss);  // validated by one_of_enum
    o.sss.mode = *parse_name<realtime::SssEdgeMode>(a.edge);
    o.sss.follow_strength =
        a.follow_strength >= 0 ? a.follow_strength : realtime::default_follow_strength(scene);
    o.sss.reject_depth =
        a.reject_depth >= 0 ? a.reject_depth : realtime::default_reject_depth(scene);
    o.sss.jitter = a.jitter;
    o.sss.rotate = a.rotate;
    o.reference.samples = a.reference_samples;
    o.reference.seed = a.common.seed.value_or(1);

    // The GL twin: its raster, lighting and separable SSS pass plugged into the frame.
    GlFrameReport gl_report;
#if SSSLAB_HAVE_GL
    std::unique_ptr<realtime::gl::GlContext> gl_context;
    std::unique_ptr<realtime::gl::GlFrameBackend> gl;
#endif
    if (a.backend != "gl" && a.platform != "auto")
        throw InputError(kCommandLine, "--platform", "needs --backend gl");
    if (a.backend == "gl") {
#if SSSLAB_HAVE_GL
        std::string why;
        gl_context = realtime::gl::try_gl_context(realtime::gl::parse_gl_platform(a.platform), why);
        if (!gl_context)
            throw InputError(kCommandLine, "--platform",
                             "no OpenGL context on " + a.platform + ": " + why);
        gl_report.context = gl_context->platform() + ", " + gl_context->renderer();
        gl = std::make_unique<realtime::gl::GlFrameBackend>(*gl_context);
        gl->install(o);
#else
        throw InputError(kCommandLine, "--backend",
                         "this build has no GL twin (SSSLAB_WITH_GL; apt-get install "
                         "libosmesa6-dev libegl-dev python3-glad)");
#endif
    }

    // The passes run with --threads workers (the image does not depend on how many).
    tbb::task_arena arena(a.common.threads > 0 ? a.common.threads : tbb::task_arena::automatic);
    realtime::RasterizedFrame frame;
    arena.execute([&] { frame = realtime::rasterize_frame(scene, o); });
    runner::RealtimeInputOptions io;
    io.seed = a.common.seed.value_or(1);
    if (a.common.photons) io.profile_budget.samples = *a.common.photons;
    if (!a.no_translucency) io.slab_thickness_mm = runner::slab_thicknesses(0.05, 25.6, 10);
    io.run.threads = a.common.threads;
    io.run.results_root = a.cache;
    io.run.quiet = a.common.quiet;
    io.run.cancel = install_interrupt_handler();
    const auto t0 = std::chrono::steady_clock::now();
    const runner::RealtimeInputs in = realtime_inputs(scene, frame.media_in_view, io);
    if (in.interrupted) {
        std::fprintf(stderr,
                     "ssslab raster: interrupted while computing ground-truth profiles; their "
                     "checkpoints are kept under %s/cache; run the same command again to "
                     "resume\n",
                     a.cache.c_str());
        return kExitInterrupted;
    }
    const double inputs_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::map<int, realtime::FrameMaterial> materials;
    std::vector<realtime::SlabTransmittance> slabs(scene.materials.size());
    for (const auto& [m, p] : in.profiles) {
        try {
            materials[m] = realtime::make_frame_material(
                p, model, a.taps, o.method == realtime::SssMethod::kReference);
        } catch (const std::invalid_argument& e) {  // e.g. no Table A.1 row for the material
            throw InputError(kCommandLine, "--model", e.what());
        }
    }
    for (const auto& [m, t] : in.slabs) {
        slabs[static_cast<size_t>(m)].thickness_mm = t.thickness_mm;
        slabs[static_cast<size_t>(m)].transmittance = t.transmittance;
    }
    realtime::FrameResult r;
    arena.execute([&] { r = realtime::render_frame(scene, frame, materials, o, slabs); });

#if SSSLAB_HAVE_GL
    if (gl) {
        const bool sss = o.method == realtime::SssMethod::kSeparable && !materials.empty();
        gl_report.times_ms = {{"raster_gpu", gl->raster_times.gpu_ms},
                              {"raster_draw", gl->raster_times.draw_ms},
                              {"shadow_maps_gpu", gl->lighting_times.shadow_gpu_ms},
                              {"shadow_maps_draw", gl->lighting_times.shadow_wall_ms},
                              {"lighting_gpu", gl->lighting_times.shading_gpu_ms},
                              {"lighting_draw", gl->lighting_times.shading_wall_ms},
                              {"sss_gpu", sss ? gl->sss_times.gpu_ms : 0.0},
                              {"sss_draw", sss ? gl->sss_times.draw_ms : 0.0}};
    }
#endif
    fs::path png = out;
    png.replace_extension(".png");
    const std::string toml = raster_toml(a, scene, o, r, in, gl_report);
    auto& md = r.image.metadata();
    md["ssslab.git_revision"] = git_revision();
    md["ssslab.command_line"] = command_line();
    md["ssslab.scene_file"] = a.scene;
    md["ssslab.model"] = realtime::sss_kernel_name(o.method, a.model);
    md["ssslab.provenance"] = toml;
    OutputTransaction tx;
    tx.stage(out, encode_exr(r.image, out.string()));
    tx.stage(png, encode_png_preview(r.image, "radiance", a.exposure));
    tx.stage(out.string() + ".toml", toml);
    tx.commit();
    if (!a.common.quiet) {
        std::printf(
            "%s: %d x %d (%d x %d samples), %zu medium material%s in view (%d MCML runs "
            "computed, %d reused, %.1f s), sss %s, model %s, %d taps\n",
            scene.name.c_str(), r.image.width(), r.image.height(), frame.raster.sample_width(),
            frame.raster.sample_height(), frame.media_in_view.size(),
            frame.media_in_view.size() == 1 ? "" : "s", in.computed, in.reused, inputs_s,
            realtime::to_string(o.method), a.model.c_str(), a.taps);
        if (!gl_report.context.empty()) {
            std::printf("  backend gl (%s); GL_TIME_ELAPSED and draw wall times:\n",
                        gl_report.context.c_str());
            for (const auto& [pass, ms] : gl_report.times_ms)
                std::printf("    %-18s %10.3f ms\n", pass.c_str(), ms);
        }
        for (const auto& p : r.times) std::printf("  %-12s %10.3f ms\n", p.pass.c_str(), p.ms);
        std::printf("  %-12s %10.3f ms  (%d shadow maps) -> %s (+ .png, .exr.toml)\n", "frame",
                    r.total_ms(), r.lighting.shadow_maps, out.string().c_str());
    }
    return 0;
}

}  // namespace

void register_raster(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<RasterArgs>();
    CLI::App* sub = app.add_subcommand(
        "raster",
        "Render a scene file as a real-time engine would (rasterizer, shadow maps, separable "
        "screen-space SSS with any kernel model): layered EXR named as `render` writes, PNG "
        "preview, the time of every pass");
    sub->add_option("scene", a->scene, "Scene file (TOML)")
        ->required()
        ->check(existing_file("scene file"));
    sub->add_option("--model", a->model,
                    "Kernel model, as in kernel studies: svd:rank=N[,l1], preintegration, "
                    "guided:k=K[,b=B], manual:table_a1[,unit=mm|cm], manual:near=..,far=..,w=.., "
                    "deon:n=N, ssss_skin (default svd:rank=1)")
        ->check(model_spec());
    sub->add_option("--taps", a->taps, "Importance-sampled taps per 1D pass (default 17)")
        ->check(integer_in(1, 1025));
    sub->add_option("--sss", a->sss,
                    "separable (default: the model's passes), reference (the exact 2D kernel: "
                    "screen-space ground truth) or none")
        ->check(one_of_enum<realtime::SssMethod>());
    sub->add_option("--edge", a->edge,
                    "Depth and material edges: follow (follow-surface, Freude14 Eq. 4.12; "
                    "default), reject (drop samples across edges, renormalise) or none")
        ->check(one_of_enum<realtime::SssEdgeMode>());
    sub->add_option("--follow-strength", a->follow_strength,
                    "Follow-surface strength per world unit of depth difference (default 3.6 "
                    "per mm)")
        ->check(number_in(0, 1e12, false));
    sub->add_option("--reject-depth", a->reject_depth,
                    "Rejection: largest depth difference kept, world units (default 1 mm)")
        ->check(number_in(0, 1e12, false));
    sub->add_option("--jitter", a->jitter,
                    "Per-pixel jitter of the taps within their cells, as a fraction (0.33: "
                    "JimenezSupp Fig. S.6; default 0)")
        ->check(number_in(0, 1, false));
    sub->add_flag("--rotate", a->rotate,
                  "Rotate the SSS pass axes per pixel against the cross pattern of separable "
                  "kernels (JimenezSupp Fig. S.7)");
    sub->add_option("--width", a->width, "Override the camera's width")
        ->check(integer_in(1, 16384));
    sub->add_option("--height", a->height, "Override the camera's height")
        ->check(integer_in(1, 16384));
    sub->add_option("--supersample", a->supersample,
                    "s x s samples per pixel, box-filtered as the path tracer's pixels (default 1)")
        ->check(integer_in(1, 16));
    sub->add_option("--light-samples", a->light_samples,
                    "Stratified shadow-mapped samples per sphere light and sun disc (default 16)")
        ->check(integer_in(1, 4096));
    sub->add_option("--env-samples", a->environment_samples,
                    "Stratified shadow-mapped directions of the environment light (default 64)")
        ->check(integer_in(1, 4096));
    sub->add_option("--shadow-map", a->shadow_map,
                    "Shadow map size in texels per side, per light sample (default 2048)")
        ->check(integer_in(16, 16384));
    sub->add_option("--env-map", a->environment_map,
                    "Shadow map size of each environment direction (default 512)")
        ->check(integer_in(16, 16384));
    sub->add_option("--reference-samples", a->reference_samples,
                    "--sss reference: kernel samples per pixel where the exact 2D sum is too "
                    "wide (default 256)")
        ->check(integer_in(1, 1 << 20));
    sub->add_flag("--no-translucency", a->no_translucency,
                  "No light through thin parts (and no MCML slab runs for it)");
    sub->add_option("--backend", a->backend,
                    "software (default: the CPU passes) or gl (the GL twin's raster, lighting "
                    "and separable SSS pass, headless)")
        ->check(one_of({"software", "gl"}));
    sub->add_option("--platform", a->platform,
                    "With --backend gl: the headless GL platform, auto (default), osmesa or egl")
        ->check(one_of({"auto", "osmesa", "egl"}));
    add_photons_option(*sub, a->common,
                       "MCML photons per channel of each material's ground-truth profile "
                       "(default 1e6, as experiments/freude14/kernels.toml; cached)");
    sub->add_option("--cache", a->cache,
                    "Results root whose cache/ holds the ground-truth profiles (default results)");
    sub->add_option("--exposure", a->exposure, "Exposure of the PNG preview in stops (default 0)")
        ->check(number_in(-100, 100, false));
    add_out_option(*sub, a->common, "Output EXR (default results/raster/<scene>.exr)");
    add_seed_option(
        *sub, a->common,
        "Seed of the ground-truth profiles and of the reference's sampling (default 1)");
    add_threads_option(*sub, a->common,
                       "Worker threads (default: all); the image does not depend on it");
    add_quiet_flag(*sub, a->common);
    sub->callback([a, &action] { action = [a] { return run_raster(*a); }; });
}

}  // namespace ssslab::cli
