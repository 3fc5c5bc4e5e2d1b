// `ssslab bench --realtime`: the real-time renderer's passes on the built-in scenes (issue 13),
// each the fastest of --repeat runs, with 1 thread and all threads: the rasterizer ("raster"),
// pass 1 ("shadow maps", "lighting": realtime/lighting.h with one stratified sample per light,
// so one shadow map per light; the thickness layer is off, as in a frame), the separable SSS pass
// ("sss": the scene's own media, svd:rank=1 with 17 taps from short MCML runs, follow-surface,
// no jitter), the composite, and the whole frame (realtime/frame.h, all of them in sequence).
// The SSS pass is set beside a streaming floor measured in the same run: the bytes the pass
// reads and writes (per 1D pass irradiance, view z and material in, 3 floats out; rank 1, so 2
// passes) moved by a plain parallel loop with the same thread count. With --backend gl, the GL
// twin's passes (realtime/gl: raster, shadow maps, lighting, sss) run in the same process on the
// frame's own inputs: their draws timed glFinish to glFinish and by GL_TIME_ELAPSED, the whole
// call (uploads, read-back) by the wall clock, and their result compared with the CPU pass's;
// then the whole frame through the GL backend hooks.
#include "approx/hierarchical.h"
#include "approx/model_spec.h"
#include "approx/munoz.h"
#include "core/atomic_file.h"
#include "core/build_info.h"
#include "core/config.h"
#include "core/format.h"
#include "core/image_compare.h"
#include "core/material.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "experiments/cli/bench_volpath.h"
#include "experiments/cli/common.h"
#include "experiments/runner/realtime_inputs.h"
#include "experiments/runner/surface_frames.h"
#include "realtime/frame.h"
#include "realtime/sss_pass.h"
#if SSSLAB_HAVE_GL
#include "realtime/gl/frame_gl.h"
#endif

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::cli {

namespace {

constexpr int kTaps = 17;

/// One 1D pass's traffic: read irradiance, view z and material, write 3 floats, per pixel.
void stream_pass(const realtime::SssGBuffer& g, const std::vector<float>& in,
                 std::vector<float>& out) {
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, g.pixels(), 16384), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                const float w =
                    (g.material[i] >= 0 ? 1.0f : 0.5f) * (g.view_z[i] > 0 ? 1.0f : 0.0f);
                for (size_t c = 0; c < 3; ++c) out[3 * i + c] = in[3 * i + c] * w;
            }
        });
}

struct Row {
    std::string scene;
    int threads;
    std::string pass;
    double ms;
    double floor_ms;  ///< < 0: none
    std::string backend = "software";
};

/// The frame of the speed goal ("one shadow-mapped light"): the scene with only its first light
/// that is not the environment, made a delta light with one shadow map -- a sun its axis, a
/// sphere light a point light of the same intensity (pi r^2 times its radiance) at its centre.
Scene one_light(const Scene& scene) {
    Scene s = scene;
    s.lights.clear();
    for (const SceneLight& l : scene.lights) {
        SceneLight d;
        if (!delta_equivalent(l, d)) continue;
        s.lights.push_back(d);
        break;
    }
    return s;
}

#if SSSLAB_HAVE_GL
/// The fastest of several values.
struct Fastest {
    double v = 1e300;
    void add(double x) { v = std::min(v, x); }
};

/// The GL twin's rows beside the software ones (all threads), each pass on the frame's own
/// inputs (the software raster frame, its G-buffer, the SSS pass's captured inputs), so that
/// each result is compared with the CPU pass's on identical inputs, after one untimed call (the
/// driver compiles shader variants at their first draws: llvmpipe's first light passes of a
/// scene took 10x their later time): a pass's draws glFinish to
/// glFinish ("pass") and by GL_TIME_ELAPSED ("pass (timer)"), its whole call with uploads and
/// read-back ("pass+transfer"), and the whole frame through the backend hooks (composite: the
/// CPU's, as in realtime/gl/frame_gl.h).
void bench_gl(realtime::gl::GlFrameBackend& gl, const Scene& s, const realtime::RasterizedFrame& f,
              const realtime::LitFrame& lit,
              const std::map<int, realtime::FrameMaterial>& materials,
              const realtime::FrameOptions& fo, int repeat, double floor_ms,
              const std::string& label, std::vector<Row>& rows) {
    realtime::FrameOptions go = fo;
    gl.install(go);
    auto row = [&](const char* pass, const Fastest& v, double floor = -1) {
        rows.push_back({label, 0, pass, v.v, floor, "gl"});
    };

    // The raster: the G-buffer's geometry, its samples against the software frame's.
    Fastest raster, raster_timer, raster_call;
    realtime::RasterizedFrame gf;
    for (int k = -1; k < repeat; ++k) {  // k = -1: the warm-up
        realtime::rasterize_frame(s, go, gf);
        if (k < 0) continue;
        raster.add(gl.raster_times.draw_ms);
        raster_timer.add(gl.raster_times.gpu_ms);
        raster_call.add(gl.raster_times.wall_ms);
    }
    size_t same = 0;
    for (size_t i = 0; i < gf.raster.shape.size(); ++i)
        same += gf.raster.shape[i] == f.raster.shape[i] &&
                gf.raster.triangle[i] == f.raster.triangle[i];
    std::printf(
        "%-18s GL raster against the software raster: the same triangle at %.5f of the "
        "samples\n",
        label.c_str(), static_cast<double>(same) / static_cast<double>(gf.raster.shape.size()));

    // Pass 1 on the software raster frame; "lighting+transfer" is defined as the software
    // row "lighting": the whole pass less its shadow maps.
    Fastest maps, maps_timer, shading, shading_timer, pass1;
    realtime::LitFrame gl_lit;
    for (int k = -1; k < repeat; ++k) {
        realtime::light_frame(s, f, go, gl_lit);
        if (k < 0) continue;
        const realtime::gl::GlLightingTimes& lt = gl.lighting_times;
        maps.add(lt.shadow_wall_ms);
        maps_timer.add(lt.shadow_gpu_ms);
        shading.add(lt.shading_wall_ms);
        shading_timer.add(lt.shading_gpu_ms);
        pass1.add(gl_lit.ms - gl_lit.stats.shadow_ms);
    }
    std::printf(
        "%-18s GL pass 1 against the CPU's on the same raster frame: PSNR irradiance "
        "%.1f dB, specular %.1f dB, surface %.1f dB\n",
        label.c_str(), psnr(gl_lit.gbuffer.irradiance, lit.gbuffer.irradiance),
        psnr(gl_lit.gbuffer.specular, lit.gbuffer.specular),
        psnr(gl_lit.gbuffer.surface, lit.gbuffer.surface));

    // The SSS pass's inputs as the frame builds them, then the GL twin on them: its draws
    // (inputs resident), its whole call and its result against the CPU pass's.
    realtime::SssGBuffer sg;
    std::vector<realtime::SssMaterialKernel> taps;
    realtime::SssParams sp;
    std::vector<float> cpu;
    realtime::FrameOptions cap = fo;
    cap.separable_pass = [&](const realtime::SssGBuffer& g_,
                             const std::vector<realtime::SssMaterialKernel>& t_,
                             const realtime::SssParams& p_, std::vector<float>& out) {
        sg = g_;
        taps = t_;
        sp = p_;
        realtime::sss_pass(g_, t_, p_, out);
        cpu = out;
    };
    realtime::render_frame(s, f, lit, materials, cap);
    Fastest sss, sss_timer, sss_call;
    std::vector<float> out;
    if (!taps.empty()) {
        for (const auto& tm : gl.sss.time_runs(sg, taps, sp, repeat)) {
            sss.add(tm.draw_ms);
            sss_timer.add(tm.gpu_ms);
        }
        for (int k = 0; k < repeat; ++k) {
            realtime::gl::GlSssTimes tm;
            gl.sss.run(sg, taps, sp, out, &tm);
            sss_call.add(tm.wall_ms);
        }
        std::printf(
            "%-18s GL sss pass against the CPU pass on the frame's inputs: worst "
            "relative difference %.2g\n",
            label.c_str(), max_relative_difference(out, cpu));
    }

    // A frame as an engine draws it, every pass on the GL twin (the composite the CPU's).
    realtime::RasterizedFrame ff;
    realtime::LitFrame lf;
    Fastest frame;
    frame.add(1e3 * best_seconds(repeat, [&] {
                  realtime::rasterize_frame(s, go, ff);
                  realtime::light_frame(s, ff, go, lf);
                  realtime::render_frame(s, ff, lf, materials, go);
              }));

    row("raster", raster);
    row("raster (timer)", raster_timer);
    row("raster+transfer", raster_call);
    row("shadow maps", maps);
    row("shadow maps (timer)", maps_timer);
    row("lighting", shading);
    row("lighting (timer)", shading_timer);
    row("lighting+transfer", pass1);
    if (!taps.empty()) {
        row("sss", sss, floor_ms);
        row("sss (timer)", sss_timer);
        row("sss+transfer", sss_call);
    }
    row("frame", frame);
}
#endif

}  // namespace

// Munoz11 and Jensen-Buhler in place of the SSS pass (experiments/runner/surface_frames.h), on
// the frame's inputs, in the calling arena: the pass's own seconds (Munoz11's layered
// convolution; Jensen-Buhler's cloud with its lighting and octree, and its queries apart).
size_t bench_integrations(const Scene& s, const realtime::RasterizedFrame& f,
                          const realtime::LitFrame& lit,
                          const std::map<int, realtime::FrameMaterial>& materials,
                          const std::map<int, RadialProfile>& profiles,
                          const realtime::FrameOptions& fo, int repeat, int threads,
                          const std::string& label, std::vector<Row>& rows) {
    const realtime::LitFrame back = runner::light_back_frame(s, fo);
    const std::pair<const char*, const char*> variants[] = {
        {"layers=4", "munoz l4"}, {"layers=4,t=0.001,downsample=2", "munoz l4 t.001 d2"}};
    for (const auto& [text, name] : variants) {
        const approx::MunozOptions mo = approx::parse_munoz(text);
        double best = 1e300;
        for (int k = 0; k < repeat; ++k)
            best = std::min(best,
                            runner::render_munoz_frame(s, f, lit, back, materials, profiles, mo, fo)
                                .stats.seconds);
        rows.push_back({label, threads, name, best * 1e3, -1});
    }
    const approx::JensenBuhlerOptions jo = approx::parse_jensen_buhler("density=4,threshold=0.03");
    double cloud = 1e300, queries = 1e300;
    size_t points = 0;
    for (int k = 0; k < repeat; ++k) {
        const runner::JensenBuhlerCloud c =
            runner::build_jensen_buhler_cloud(s, f.media_in_view, jo, fo, 1);
        cloud = std::min(cloud, c.seconds());
        points = c.points;
        queries = std::min(
            queries, runner::render_jensen_buhler_frame(s, f, lit, materials, profiles, c, jo, fo)
                         .query_seconds);
    }
    rows.push_back({label, threads, "jb d4 cloud", cloud * 1e3, -1});
    rows.push_back({label, threads, "jb d4 t.03 queries", queries * 1e3, -1});
    return points;
}

#if SSSLAB_HAVE_GL
using GlBackend = realtime::gl::GlFrameBackend;
#else
struct GlBackend {};
#endif

/// What a scene's timing needs: the scene, its label, the frame options, kernels and profiles.
struct BenchScene {
    const Scene& s;
    const std::string& label;
    const realtime::FrameOptions& fo;
    const std::map<int, realtime::FrameMaterial>& materials;
    const std::map<int, RadialProfile>& profiles;
};

/// Every pass of one scene on `t` threads (in the caller's arena), the fastest of `repeat`
/// runs, into `rows`; the integrations and the GL twin where asked. Returns the shadow maps.
int time_passes(const BenchScene& bs, int repeat, int t, bool integrations, GlBackend* gl,
                std::vector<Row>& rows, size_t& jb_points) {
    const Scene& s = bs.s;
    const std::string& label = bs.label;
    const realtime::FrameOptions& fo = bs.fo;
    const std::map<int, realtime::FrameMaterial>& materials = bs.materials;
    int maps = 0;

    realtime::RasterizedFrame f;
    const double raster = best_seconds(repeat, [&] { realtime::rasterize_frame(s, fo, f); });
    realtime::LitFrame lit;
    double shadow = 1e300, lighting = 1e300;
    for (int k = 0; k < repeat; ++k) {
        realtime::light_frame(s, f, fo, lit);
        shadow = std::min(shadow, lit.stats.shadow_ms);
        lighting = std::min(lighting, lit.ms - lit.stats.shadow_ms);
    }
    maps = lit.stats.shadow_maps;
    double sss = 1e300, composite = 1e300;
    for (int k = 0; k < repeat; ++k) {
        const realtime::FrameResult r = realtime::render_frame(s, f, lit, materials, fo);
        for (const auto& p : r.times) {
            if (p.pass == "sss") sss = std::min(sss, p.ms);
            if (p.pass == "composite") composite = std::min(composite, p.ms);
        }
    }
    // The floor: the SSS pass's bytes streamed, on a G-buffer of the frame's size.
    realtime::SssGBuffer g(f.raster.sample_width(), f.raster.sample_height());
    for (size_t i = 0; i < g.pixels(); ++i) g.material[i] = lit.gbuffer.material[i] >= 0 ? 0 : -1;
    std::vector<float> a(g.irradiance.size()), b(g.irradiance.size());
    const double floor = best_seconds(repeat, [&] {
        stream_pass(g, g.irradiance, a);
        stream_pass(g, a, b);
    });
    // A frame as an engine draws it, frame after frame into the same render
    // targets (raster frame, G-buffer, shadow map scratch).
    realtime::RasterizedFrame ff;
    realtime::LitFrame lf;
    const double frame = best_seconds(repeat, [&] {
        realtime::rasterize_frame(s, fo, ff);
        realtime::light_frame(s, ff, fo, lf);
        realtime::render_frame(s, ff, lf, materials, fo);
    });
    rows.push_back({label, t, "raster", raster * 1e3, -1});
    rows.push_back({label, t, "shadow maps", shadow, -1});
    rows.push_back({label, t, "lighting", lighting, -1});
    rows.push_back({label, t, "sss", sss, floor * 1e3});
    rows.push_back({label, t, "composite", composite, -1});
    rows.push_back({label, t, "frame", frame * 1e3, -1});
    if (integrations)
        jb_points =
            bench_integrations(s, f, lit, materials, bs.profiles, fo, repeat, t, label, rows);
#if SSSLAB_HAVE_GL
    if (gl) bench_gl(*gl, s, f, lit, materials, fo, repeat, floor * 1e3, label, rows);
#endif
#if !SSSLAB_HAVE_GL
    (void)gl;
#endif
    return maps;
}

/// The rows from `first` on, as the table prints them.
void print_rows(const std::vector<Row>& rows, size_t first, int width, int height) {
    for (size_t k = first; k < rows.size(); ++k) {
        const Row& r = rows[k];
        char size[32], fl[32] = "", ratio[32] = "";
        std::snprintf(size, sizeof size, "%dx%d", width, height);
        if (r.floor_ms >= 0) {
            std::snprintf(fl, sizeof fl, "%.3f", r.floor_ms);
            std::snprintf(ratio, sizeof ratio, "%.2f", r.ms / r.floor_ms);
        }
        const std::string th = r.backend == "gl" ? std::string("gl") : std::to_string(r.threads);
        std::printf("%-18s %11s %7s %-19s %10.3f %10s %7s\n", r.scene.c_str(), size, th.c_str(),
                    r.pass.c_str(), r.ms, fl, ratio);
    }
}

int run_realtime_bench(int threads, bool quick, const std::string& scenes_dir, int width,
                       int height, int repeat, const std::string& only, const std::string& csv,
                       const std::string& backend, const std::string& platform, bool integrations) {
    const std::vector<std::filesystem::path> files = list_scenes(scenes_dir, only);
#if SSSLAB_HAVE_GL
    std::unique_ptr<realtime::gl::GlContext> gl_context;
    std::unique_ptr<realtime::gl::GlFrameBackend> gl;
    if (backend == "gl") {
        gl_context = realtime::gl::GlContext::create(realtime::gl::parse_gl_platform(platform));
        gl = std::make_unique<realtime::gl::GlFrameBackend>(*gl_context);
        std::printf("GL twin: %s, %s, OpenGL %s\n", gl_context->platform().c_str(),
                    gl_context->renderer().c_str(), gl_context->version().c_str());
    }
#else
    (void)platform;  // cmd_bench.cpp refuses --backend gl in a build without the GL twin
#endif
    // MCML and the kernel build are set-up, not timed; the timed work runs in explicit arenas.
    const std::int64_t photons = quick ? 2'000 : 20'000;
    std::printf(
        "real-time passes, %d x %d, 1 and %d threads, fastest of %d run%s; lighting: 1 sample "
        "per light; SSS: each scene's media, svd:rank=1, %d taps (%lld MCML photons per channel, "
        "cached under results/cache)\n",
        width, height, threads, repeat, repeat == 1 ? "" : "s", kTaps,
        static_cast<long long>(photons));
    std::vector<int> counts = {1};
    if (threads > 1) counts.push_back(threads);
    const approx::ModelSpec model = approx::parse_model("svd:rank=1");

    std::vector<Row> rows;
    std::printf("%-18s %11s %7s %-19s %10s %10s %7s\n", "scene", "W x H", "threads", "pass", "ms",
                "floor_ms", "ratio");
    for (const auto& file : files) {
        const Scene full = read_scene(file.string());
        for (int variant = 0; variant < 2; ++variant) {
            const Scene s = variant == 0 ? full : one_light(full);
            if (variant == 1 && s.lights.empty()) continue;
            const std::string label = variant == 0 ? full.name : full.name + "/1-light";
            size_t triangles = 0;
            for (const auto& sh : s.shapes) triangles += sh.mesh.triangles.size();
            realtime::FrameOptions fo;
            fo.width = width;
            fo.height = height;
            fo.lighting.light_samples = 1;
            fo.lighting.environment_samples = 1;
            fo.sss.follow_strength = realtime::default_follow_strength(s);
            fo.sss.reject_depth = realtime::default_reject_depth(s);
            fo.all_layers = false;  // a game's frame: the radiance it presents
            const realtime::RasterizedFrame probe = realtime::rasterize_frame(s, fo);
            runner::RealtimeInputOptions io;
            io.profile_budget.samples = photons;
            io.run.threads = threads;
            const runner::RealtimeInputs in = runner::realtime_inputs(s, probe.media_in_view, io);
            std::map<int, realtime::FrameMaterial> materials;
            for (const auto& [m, p] : in.profiles)
                materials[m] = realtime::make_frame_material(p, model, kTaps, false);
            int maps = 0;
            size_t jb_points = 0;
            for (int t : counts) {
                const size_t first = rows.size();
                tbb::task_arena arena(t);
                arena.execute([&] {
                    const BenchScene bs{s, label, fo, materials, in.profiles};
#if SSSLAB_HAVE_GL
                    GlBackend* g = t == counts.back() ? gl.get() : nullptr;
#else
                    GlBackend* g = nullptr;
#endif
                    maps = time_passes(bs, repeat, t,
                                       integrations && variant == 0 && t == counts.back(), g, rows,
                                       jb_points);
                });
                print_rows(rows, first, width, height);
            }
            std::printf(
                "%-18s %zu triangles, %zu medium material%s in view, %zu light%s, %d shadow "
                "map%s\n",
                "", triangles, materials.size(), materials.size() == 1 ? "" : "s", s.lights.size(),
                s.lights.size() == 1 ? "" : "s", maps, maps == 1 ? "" : "s");
            if (jb_points > 0) std::printf("%-18s jb: %zu points in the cloud\n", "", jb_points);
        }
    }
    std::printf(
        "raster: realtime::rasterize of the scene (1 sample per pixel); shadow maps, lighting: "
        "pass 1 (one sample per light); sss: the separable SSS pass alone; composite: pass 4 "
        "(the radiance layer only); frame: all of them in sequence. floor_ms: a parallel loop "
        "streaming the bytes the SSS "
        "pass reads and writes (2 x (20 B in, 12 B out) per pixel); ratio = ms / floor_ms.\n");
    if (integrations)
        std::printf(
            "munoz l4: Munoz11's layered convolution (approx/munoz.h) of the media's front and "
            "back samples in place of the sss pass, 4 layers; munoz l4 t.001 d2: with Eq. 8's "
            "t = 0.1 %% and layers at 50 %% (the paper: 7 s and about 2 s on average at 800 x 600, "
            "an Intel i7 at 2.66 GHz, 2011); jb d4 cloud: Jensen-Buhler's Poisson-disk points "
            "(4 per mm^2) on the media, lit by pass 1's lights and shadow maps, and their "
            "octree; jb d4 t.03 queries: the hierarchical sum at every medium pixel, threshold "
            "0.03 sr. All threads, each scene with its lights only.\n");
    if (backend == "gl")
        std::printf(
            "threads gl: the GL twin (its platform's own threads; llvmpipe: LP_NUM_THREADS, "
            "default all cores), each pass on the software frame's inputs after one untimed call "
            "(shader variants compiled at first draw). A pass's row: its "
            "draws, glFinish to glFinish (meshes, G-buffer and taps resident); (timer): the same "
            "by GL_TIME_ELAPSED (llvmpipe's query does not see its deferred rasterization: read "
            "the plain row there); +transfer: the whole call (projection, uploads, read-back; "
            "for pass 1 defined as the software row: the whole pass less its shadow maps). "
            "frame: raster, pass 1 and sss on the GL twin, the composite the CPU's.\n");

    if (!csv.empty()) {
        std::ostringstream o;
        o << "scene,width,height,backend,threads,pass,ms,floor_ms\n";
        for (const Row& r : rows)
            o << r.scene << ',' << width << ',' << height << ',' << r.backend << ',' << r.threads
              << ',' << r.pass << ',' << format_g(r.ms, 6) << ','
              << (r.floor_ms >= 0 ? format_g(r.floor_ms, 6) : "") << '\n';
        write_with_provenance(csv, o.str(),
                              "ssslab bench --realtime: provenance of " + csv +
                                  " (timings depend on the machine: see host_threads)");
        std::printf("wrote %s (+ .toml)\n", csv.c_str());
    }
    return 0;
}

}  // namespace ssslab::cli
