#include "experiments/runner/realtime_study.h"

#include "approx/model_spec.h"
#include "approx/munoz.h"
#include "core/atomic_file.h"
#include "core/build_info.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/format.h"
#include "core/image_compare.h"
#include "core/image_io.h"
#include "core/scene.h"
#include "experiments/runner/engines.h"
#include "experiments/runner/plots.h"
#include "experiments/runner/realtime_inputs.h"
#include "experiments/runner/report.h"
#include "experiments/runner/runner.h"
#include "experiments/runner/surface_frames.h"
#include "realtime/frame.h"
#if SSSLAB_HAVE_GL
#include "realtime/gl/sss_pass_gl.h"
#endif
#include "volpath/render.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <sstream>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

/// A model's label as a metric name part (no dots).
std::string metric_label(const std::string& label) {
    std::string s = label;
    std::replace(s.begin(), s.end(), '.', 'p');
    return s;
}

// Freude14 Table 6.4: per thesis scene and model, R, G, B, and their sum (normalised: the
// table's largest per-channel error is 1), and the scene of ours that stands for it.
struct ThesisRow {
    const char* scene;
    const char* ours;
    const char* model;
    double r, g, b, sum;
};
const std::vector<ThesisRow>& thesis_table_6_4() {
    static const std::vector<ThesisRow> rows = {
        {"Dragon", "marble", "svd:rank=1", 0.676, 0.684, 0.677, 2.037},
        {"Fruit", "apple", "svd:rank=1", 0.257, 0.339, 0.247, 0.843},
        {"Head", "skin", "svd:rank=1", 1.000, 0.455, 0.198, 1.653},
        {"Ketchup", "ketchup", "svd:rank=1", 0.425, 0.138, 0.140, 0.702},
        {"Milk", "wholemilk", "svd:rank=1", 0.461, 0.448, 0.384, 1.292},
        {"Plant", "", "svd:rank=1", 0.245, 0.227, 0.147, 0.618},
        {"Dragon", "marble", "preintegration", 0.318, 0.314, 0.304, 0.937},
        {"Fruit", "apple", "preintegration", 0.148, 0.198, 0.140, 0.486},
        {"Head", "skin", "preintegration", 0.320, 0.177, 0.115, 0.611},
        {"Ketchup", "ketchup", "preintegration", 0.246, 0.193, 0.206, 0.644},
        {"Milk", "wholemilk", "preintegration", 0.208, 0.211, 0.186, 0.605},
        {"Plant", "", "preintegration", 0.193, 0.184, 0.115, 0.492},
        {"Dragon", "marble", "guided:k=1", 0.332, 0.315, 0.308, 0.955},
        {"Fruit", "apple", "guided:k=1", 0.141, 0.187, 0.128, 0.456},
        {"Head", "skin", "guided:k=1", 0.298, 0.358, 0.252, 0.908},
        {"Ketchup", "ketchup", "guided:k=1", 0.155, 0.267, 0.494, 0.915},
        {"Milk", "wholemilk", "guided:k=1", 0.210, 0.211, 0.192, 0.613},
        {"Plant", "", "guided:k=1", 0.203, 0.193, 0.111, 0.506},
        {"Dragon", "marble", "manual:table_a1,unit=mm", 0.325, 0.307, 0.323, 0.955},
        {"Fruit", "apple", "manual:table_a1,unit=mm", 0.133, 0.184, 0.133, 0.450},
        {"Head", "skin", "manual:table_a1,unit=mm", 0.524, 0.473, 0.354, 1.351},
        {"Ketchup", "ketchup", "manual:table_a1,unit=mm", 0.124, 0.257, 0.510, 0.891},
        {"Milk", "wholemilk", "manual:table_a1,unit=mm", 0.139, 0.179, 0.159, 0.478},
        {"Plant", "", "manual:table_a1,unit=mm", 0.147, 0.134, 0.094, 0.376},
    };
    return rows;
}

/// One frame's scores against the references, per channel.
/// The relative bias of a's layer against b's over the mask, RGB together: sum (a - b) / sum b
/// (how much light a has too much or too little), with its standard error from b's noise by the
/// delta method (a is taken as exact: a frame of the real-time renderer).
struct RelativeBias {
    double value = 0, se = 0;
};
struct Score {
    std::string model, label;
    int taps = 0;
    double jitter = 0;
    bool rotate = false;
    std::array<NoiseCorrectedRms, 3> vs_reference{}, vs_volpath{};
    RelativeBias bias_vs_reference, bias_vs_volpath;  ///< computed for approximations.csv
    double sss_ms = 0, frame_ms = 0, build_s = 0;
};

/// The values of channel c of `layer` at the mask's pixels, and their variances from
/// `<layer>.stderr` when the image has it (empty otherwise).
void masked(const LayeredImage& im, const std::string& layer, const std::vector<size_t>& mask,
            int c, std::vector<double>& v, std::vector<double>& var) {
    const ImageLayer& l = im.layer(layer);
    v.resize(mask.size());
    for (size_t k = 0; k < mask.size(); ++k)
        v[k] = l.pixels()[mask[k] * 3 + static_cast<size_t>(c)];
    var.clear();
    if (!im.has_layer(layer + ".stderr")) return;
    const ImageLayer& e = im.layer(layer + ".stderr");
    var.resize(mask.size());
    for (size_t k = 0; k < mask.size(); ++k) {
        const double s = e.pixels()[mask[k] * 3 + static_cast<size_t>(c)];
        var[k] = s * s;
    }
}

NoiseCorrectedRms score(const LayeredImage& a, const std::string& la, const LayeredImage& b,
                        const std::string& lb, const std::vector<size_t>& mask, int c,
                        double dof_b) {
    std::vector<double> x, vx, y, vy;
    masked(a, la, mask, c, x, vx);
    masked(b, lb, mask, c, y, vy);
    return noise_corrected_rms(x, vx, y, vy, dof_b);
}

/// RelativeBias of a's layer against b's over the mask.
RelativeBias relative_bias(const LayeredImage& a, const std::string& la, const LayeredImage& b,
                           const std::string& lb, const std::vector<size_t>& mask) {
    double sa = 0, sb = 0, vb = 0;
    std::vector<double> x, vx, y, vy;
    for (int c = 0; c < 3; ++c) {
        masked(a, la, mask, c, x, vx);
        masked(b, lb, mask, c, y, vy);
        for (size_t k = 0; k < x.size(); ++k) {
            sa += x[k];
            sb += y[k];
            if (!vy.empty()) vb += vy[k];
        }
    }
    if (!(sb > 0)) return {};
    return {sa / sb - 1, sa / (sb * sb) * std::sqrt(vb)};
}

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
    return v[k];
}

/// sRGB PNG (core/film_image.h srgb8, as the previews) of an RGB layer times `gain`, optionally
/// cropped to [x0, x0 + cw) x [y0, y0 + ch) and magnified `zoom` times (nearest neighbour).
std::string png_of(const ImageLayer& l, double gain, int x0 = 0, int y0 = 0, int cw = 0, int ch = 0,
                   int zoom = 1) {
    if (cw <= 0) cw = l.width();
    if (ch <= 0) ch = l.height();
    const int W = cw * zoom, H = ch * zoom;
    std::vector<unsigned char> rgb(static_cast<size_t>(W) * static_cast<size_t>(H) * 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[(static_cast<size_t>(y) * static_cast<size_t>(W) + static_cast<size_t>(x)) * 3 +
                    static_cast<size_t>(c)] = srgb8(gain * l.at(x0 + x / zoom, y0 + y / zoom, c));
    return encode_png_rgb8(W, H, rgb);
}

/// |a - b| per channel as an RGB layer.
ImageLayer& abs_difference(LayeredImage& out, const ImageLayer& a, const ImageLayer& b) {
    ImageLayer& d = out.add_layer("diff", 3);
    for (size_t i = 0; i < d.pixels().size(); ++i)
        d.pixels()[i] = std::abs(a.pixels()[i] - b.pixels()[i]);
    return d;
}

}  // namespace

RealtimeStudySpec read_realtime_study(ConfigTable& t, const std::string& config_dir) {
    RealtimeStudySpec s;
    s.enabled = true;
    // Both renderers draw every scene: the path tracer's reference and the real-time frames.
    s.scenes = read_scene_files(t, config_dir, [](const Scene& sc) {
        volpath::check_renderable(sc);
        realtime::check_drawable(sc);
    });
    auto read_models = [&](const char* key, std::vector<std::string> fallback) {
        const std::vector<std::string> m = t.optional_string_list(key).value_or(fallback);
        std::set<std::string> labels;
        for (size_t i = 0; i < m.size(); ++i) {
            try {
                const approx::ModelSpec spec = approx::parse_model(m[i]);
                if (spec.name == "manual" && spec.flag("fit"))
                    t.fail_item(key, i,
                                "\"" + m[i] +
                                    "\" is fitted to a kernel study's test images; a frame "
                                    "takes models built from the kernel alone");
                if (!labels.insert(spec.label()).second)
                    t.fail_item(key, i, "model \"" + m[i] + "\" is listed twice");
            } catch (const std::invalid_argument& e) {
                t.fail_item(key, i, e.what());
            }
        }
        return m;
    };
    s.models = read_models(
        "models", {"svd:rank=1", "preintegration", "guided:k=1", "manual:table_a1,unit=mm"});
    // Table A.1 has rows for five presets: every scene's media must be one of them.
    for (size_t i = 0; i < s.models.size(); ++i) {
        const approx::ModelSpec spec = approx::parse_model(s.models[i]);
        if (spec.name != "manual" || !spec.flag("table_a1")) continue;
        for (const std::string& path : s.scenes)
            for (const SceneMaterial& m : read_scene(path).materials)
                if (m.kind == SceneMaterial::Kind::kMedium &&
                    !approx::freude14_table_a1().count(m.preset))
                    t.fail_item(
                        "models", i,
                        "\"" + s.models[i] + "\" needs a Table A.1 preset (Apple, " +
                            "Ketchup, Marble, Skin1, Wholemilk), and material \"" + m.name +
                            "\" of " + path + " is " +
                            (m.preset.empty() ? "given by coefficients" : "\"" + m.preset + "\""));
    }
    if (s.models.empty()) t.fail("models", "expected at least one model");
    s.taps = static_cast<int>(t.integer("taps", 17, Range::closed(1, 1025)));
    s.sweep_models = read_models("sweep_models", {});
    if (auto v = t.optional_number_list("taps_sweep", Range::closed(1, 1025)))
        for (double x : *v) {
            if (x != std::floor(x)) t.fail("taps_sweep", "tap counts are whole numbers");
            s.taps_sweep.push_back(static_cast<int>(x));
        }
    s.jitter = t.number("jitter", 0.33, Range::closed(0, 1));
    s.rotate = t.boolean("rotate", false);
    s.width = static_cast<int>(t.integer("width", 512, Range::closed(0, 16384)));
    s.height = static_cast<int>(t.integer("height", 512, Range::closed(0, 16384)));
    if ((s.width == 0) != (s.height == 0))
        t.fail("width", "give both width and height, or neither");
    s.edge = t.enumerated("edge", realtime::SssEdgeMode::kFollowSurface);
    s.backend = t.choice("backend", "software", {"software", "gl"});
    s.platform = t.choice("platform", "auto", {"auto", "osmesa", "egl"});
    if (s.backend == "gl" && !SSSLAB_HAVE_GL)
        t.fail("backend",
               "this build has no GL twin (SSSLAB_WITH_GL; apt-get install "
               "libosmesa6-dev libegl-dev python3-glad)");
    s.spp = t.integer("spp", 252, Range::closed(3, 1e9));
    s.photons = t.integer("photons", 1'000'000, Range::closed(100, 1e12));
    s.light_samples = static_cast<int>(t.integer("light_samples", 16, Range::closed(1, 4096)));
    s.environment_samples =
        static_cast<int>(t.integer("environment_samples", 64, Range::closed(1, 4096)));
    s.shadow_map_size =
        static_cast<int>(t.integer("shadow_map_size", 2048, Range::closed(16, 16384)));
    s.environment_map_size =
        static_cast<int>(t.integer("environment_map_size", 512, Range::closed(16, 16384)));
    s.reference_samples =
        static_cast<int>(t.integer("reference_samples", 256, Range::closed(1, 1 << 20)));
    s.quick_factor = t.number("quick_factor", 0.125, Range::left_open(0, 1));
    s.quick_size = static_cast<int>(t.integer("quick_size", 64, Range::closed(4, 16384)));
    s.images = t.boolean("images", true);
    if (auto v = t.optional_string_list("munoz")) {
        std::set<std::string> labels;
        for (size_t i = 0; i < v->size(); ++i) {
            try {
                if (!labels.insert(approx::munoz_label(approx::parse_munoz((*v)[i]))).second)
                    t.fail_item("munoz", i, "variant \"" + (*v)[i] + "\" is listed twice");
            } catch (const std::invalid_argument& e) {
                t.fail_item("munoz", i, e.what());
            }
        }
        s.munoz = *v;
    }
    if (auto v = t.optional_string_list("jensen_buhler")) {
        std::set<std::string> labels;
        for (size_t i = 0; i < v->size(); ++i) {
            try {
                if (!labels
                         .insert(approx::jensen_buhler_label(approx::parse_jensen_buhler((*v)[i])))
                         .second)
                    t.fail_item("jensen_buhler", i, "variant \"" + (*v)[i] + "\" is listed twice");
            } catch (const std::invalid_argument& e) {
                t.fail_item("jensen_buhler", i, e.what());
            }
        }
        s.jensen_buhler = *v;
    }
    return s;
}

RealtimeStudyResult run_realtime_study(const RealtimeStudySpec& spec, const RenderStudyContext& ctx,
                                       const ArtifactCache& cache, const fs::path& results_root,
                                       const fs::path& stage, std::vector<Metric>& metrics) {
    RealtimeStudyResult res;
    const fs::path dir = stage / "realtime";
    fs::create_directories(dir);
    tbb::task_arena arena(ctx.threads > 0 ? ctx.threads : tbb::task_arena::automatic);
    std::ostringstream table, sweep, decomposition, html, munoz, jb, approximations;
    table << "scene,model,label,taps,channel,pixels,rms_vs_reference,rms_vs_reference_se,"
             "norm_table,norm_scene,rel_rms_vs_reference,rms_vs_volpath,rms_vs_volpath_se,"
             "raw_rms_vs_volpath,volpath_noise_rms,sss_ms,frame_ms,kernel_build_s\n";
    sweep << "scene,model,label,taps,jitter,rotate,rms_vs_reference_rgb,rms_vs_reference_rgb_se,"
             "rms_vs_volpath_rgb,rms_vs_volpath_rgb_se,sss_ms,frame_ms\n";
    munoz << "scene,variant,layers,threshold,downsample,split,rms_vs_reference,"
             "rms_vs_reference_se,rms_vs_volpath,rms_vs_volpath_se,seconds,convolutions,"
             "skipped_threshold,skipped_invisible,kernel,visible\n";
    jb << "scene,threshold,points,rms_vs_volpath,rms_vs_volpath_se,seconds,variant,density,bound,"
          "profile,rms_vs_reference,rms_vs_reference_se,query_seconds,cloud_seconds,"
          "light_seconds,nodes_visited,clusters,point_terms\n";
    approximations << "scene,method,rms_vs_volpath,rms_vs_volpath_se,seconds,family,"
                      "rms_vs_reference,rms_vs_reference_se,bias_vs_volpath,bias_vs_volpath_se,"
                      "bias_vs_reference\n";
    decomposition << "scene,channel,pixels,reference_signal_rms,separability_model,separability,"
                     "screen_space,screen_space_se,specular,specular_se,surfaces,surfaces_se,total,"
                     "total_se\n";
    struct SceneScores {
        std::string scene;
        size_t pixels = 0;
        std::array<double, 3> signal{};
        std::vector<Score> scores;  // the table's models at spec.taps
    };
    std::vector<SceneScores> all;
    std::ostringstream viewers;
    // The GL twin's SSS pass, where the config names it: one context for the study, on this
    // thread (render_frame calls the pass on the thread that runs the arena's work).
#if SSSLAB_HAVE_GL
    std::unique_ptr<realtime::gl::GlContext> gl_context;
    std::unique_ptr<realtime::gl::GlSssPass> gl_pass;
    if (spec.backend == "gl") {
        gl_context =
            realtime::gl::GlContext::create(realtime::gl::parse_gl_platform(spec.platform));
        gl_pass = std::make_unique<realtime::gl::GlSssPass>(*gl_context);
    }
#endif
    const realtime::SssEdgeMode mode = spec.edge;

    for (const std::string& path : spec.scenes) {
        const Scene scene = read_scene(path);
        int w = spec.width > 0 ? spec.width : scene.camera.width;
        int h = spec.height > 0 ? spec.height : scene.camera.height;
        std::int64_t spp = spec.spp, photons = spec.photons;
        if (ctx.quick) {
            const double f = std::min(1.0, static_cast<double>(spec.quick_size) / std::max(w, h));
            w = std::max(1, static_cast<int>(std::lround(w * f)));
            h = std::max(1, static_cast<int>(std::lround(h * f)));
            spp = std::max<std::int64_t>(
                12, std::llround(static_cast<double>(spp) * spec.quick_factor));
            photons = std::max<std::int64_t>(
                1000, std::llround(static_cast<double>(photons) * spec.quick_factor));
        }
        realtime::FrameOptions fo;
        fo.width = w;
        fo.height = h;
        fo.lighting.light_samples = spec.light_samples;
        fo.lighting.environment_samples = spec.environment_samples;
        fo.lighting.shadow_map_size = spec.shadow_map_size;
        fo.lighting.environment_map_size = spec.environment_map_size;
        fo.sss.mode = mode;
        fo.sss.follow_strength = realtime::default_follow_strength(scene);
        fo.sss.reject_depth = realtime::default_reject_depth(scene);
        fo.reference.samples = spec.reference_samples;
        fo.reference.seed = ctx.seed;
        realtime::RasterizedFrame frame;
        arena.execute([&] { frame = realtime::rasterize_frame(scene, fo); });

        // Ground truth: the media's profiles (and slabs for translucency), the path tracer.
        RealtimeInputOptions io;
        io.seed = ctx.seed;
        io.profile_budget.samples = photons;
        io.slab_budget.samples = std::max<std::int64_t>(1000, photons / 10);
        io.slab_thickness_mm = slab_thicknesses(0.05, 25.6, 10);
        io.run.threads = ctx.threads;
        io.run.results_root = results_root;
        io.run.quiet = ctx.quiet;
        io.run.cancel = ctx.cancel;
        io.run.checkpoint_seconds = ctx.checkpoint_seconds;
        const RealtimeInputs in = realtime_inputs(scene, frame.media_in_view, io);
        if (in.interrupted) {
            res.interrupted = true;
            return res;
        }
        res.computed += in.computed;
        res.reused += in.reused;
        SampleBudget vb;
        vb.samples = spp;
        const std::optional<CachedRender> vp =
            cached_render(scene, "realtime", w, h, vb, ctx, cache);
        if (!vp) {
            res.interrupted = true;
            return res;
        }
        (vp->computed_now ? res.computed : res.reused) += 1;
        const double vp_dof = static_cast<double>(vp->spp / 3) - 1;  // batch statistics
        std::vector<realtime::SlabTransmittance> slabs(scene.materials.size());
        for (const auto& [m, t] : in.slabs) {
            slabs[static_cast<size_t>(m)].thickness_mm = t.thickness_mm;
            slabs[static_cast<size_t>(m)].transmittance = t.transmittance;
        }

        // Kernels per (model, taps), built once.
        std::map<std::pair<std::string, int>, std::map<int, realtime::FrameMaterial>> kernels;
        std::map<std::pair<std::string, int>, double> build_s;
        auto kernels_of = [&](const std::string& model, int taps,
                              bool exact) -> const std::map<int, realtime::FrameMaterial>& {
            auto& k = kernels[{model, taps}];
            if (!k.empty() || in.profiles.empty()) return k;
            const auto t0 = std::chrono::steady_clock::now();
            const approx::ModelSpec ms = approx::parse_model(model);
            for (const auto& [m, p] : in.profiles)
                k[m] = realtime::make_frame_material(p, ms, taps, exact);
            build_s[{model, taps}] =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            return k;
        };
        // Pass 1 once: every model's frame shares the G-buffer.
        realtime::LitFrame lit;
        arena.execute([&] { lit = realtime::light_frame(scene, frame, fo, slabs); });
        auto run = [&](const std::map<int, realtime::FrameMaterial>& k, realtime::SssMethod m,
                       double jitter, bool rotate = false) {
            realtime::FrameOptions o = fo;
            o.method = m;
            o.sss.jitter = jitter;
            o.sss.rotate = rotate;
            o.sss.seed = static_cast<std::uint32_t>(ctx.seed);
#if SSSLAB_HAVE_GL
            if (gl_pass)
                o.separable_pass = [&](const realtime::SssGBuffer& g,
                                       const std::vector<realtime::SssMaterialKernel>& taps,
                                       const realtime::SssParams& p,
                                       std::vector<float>& out) { gl_pass->run(g, taps, p, out); };
#endif
            realtime::FrameResult r;
            arena.execute([&] { r = realtime::render_frame(scene, frame, lit, k, o); });
            return r;
        };
        const realtime::FrameResult ref =
            run(kernels_of(spec.models[0], spec.taps, true), realtime::SssMethod::kReference, 0);

        // The scored pixels: every sample a medium.
        std::vector<size_t> mask, surfaces;
        const int s = frame.raster.supersample;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = frame.raster.pixel_index(x, y);
                bool all_medium = true, covered = frame.raster.coverage[i] >= 1.0;
                for (int j = 0; j < s; ++j)
                    for (int q = 0; q < s; ++q) {
                        const std::int32_t sh =
                            frame.raster.shape[frame.raster.sample_index(x * s + q, y * s + j)];
                        all_medium =
                            all_medium && sh >= 0 &&
                            scene.materials[static_cast<size_t>(
                                                scene.shapes[static_cast<size_t>(sh)].material)]
                                    .kind == SceneMaterial::Kind::kMedium;
                    }
                if (all_medium)
                    mask.push_back(i);
                else if (covered)
                    surfaces.push_back(i);
            }
        SceneScores ss;
        ss.scene = scene.name;
        ss.pixels = mask.size();
        for (int c = 0; c < 3; ++c) {
            std::vector<double> v, var;
            masked(ref.image, "subsurface", mask, c, v, var);
            double q = 0;
            for (double x : v) q += x * x;
            ss.signal[static_cast<size_t>(c)] = v.empty() ? 0 : std::sqrt(q / v.size());
        }
        auto score_frame = [&](const realtime::FrameResult& f, Score& sc) {
            for (int c = 0; c < 3; ++c) {
                sc.vs_reference[static_cast<size_t>(c)] =
                    score(f.image, "subsurface", ref.image, "subsurface", mask, c, 0);
                sc.vs_volpath[static_cast<size_t>(c)] =
                    score(f.image, "subsurface", vp->image, "subsurface", mask, c, vp_dof);
            }
            sc.bias_vs_reference =
                relative_bias(f.image, "subsurface", ref.image, "subsurface", mask);
            sc.bias_vs_volpath =
                relative_bias(f.image, "subsurface", vp->image, "subsurface", mask);
            for (const auto& p : f.times)
                if (p.pass == "sss") sc.sss_ms = p.ms;
            sc.frame_ms = f.total_ms();
        };
        std::map<std::string, realtime::FrameResult> frames;  // the table's models, for images
        for (const std::string& model : spec.models) {
            Score sc;
            sc.model = model;
            sc.label = approx::parse_model(model).label();
            sc.taps = spec.taps;
            const auto& k = kernels_of(model, spec.taps, model == spec.models[0]);
            realtime::FrameResult f = run(k, realtime::SssMethod::kSeparable, 0);
            score_frame(f, sc);
            sc.build_s = build_s[{model, spec.taps}];
            ss.scores.push_back(sc);
            frames.emplace(sc.label, std::move(f));
        }
        // The RGB error is the root of the channels' mean squared error; its standard error by the
        // delta method as noise_corrected_rms's, from the mean of the channels' standard errors of
        // D^2 (their errors are correlated, the same paths carry all three: the mean bounds the
        // sum's).
        struct Rgb {
            double rms, rms_se;
        };
        auto rgb = [](const std::array<NoiseCorrectedRms, 3>& e) {
            const double ms = (e[0].ms + e[1].ms + e[2].ms) / 3.0;
            const double ms_se = (e[0].ms_se + e[1].ms_se + e[2].ms_se) / 3.0;
            const double rms = std::sqrt(std::max(0.0, ms));
            return Rgb{
                rms, rms > 0 ? std::min(ms_se / (2.0 * rms), std::sqrt(ms_se)) : std::sqrt(ms_se)};
        };
        // The table of every approximation (approximations.csv): the RGB errors and the
        // seconds of the pass that replaces the SSS pass (kernels built before the frame).
        auto approximation_row = [&](const std::string& method, const std::string& family,
                                     const Score& sc, double seconds) {
            const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
            approximations << scene.name << "," << csv_field(method) << ","
                           << format_g(vp_rgb.rms, 6) << "," << format_g(vp_rgb.rms_se, 6) << ","
                           << format_g(seconds, 6) << "," << family << ","
                           << format_g(ref_rgb.rms, 6) << "," << format_g(ref_rgb.rms_se, 6) << ","
                           << format_g(sc.bias_vs_volpath.value, 6) << ","
                           << format_g(sc.bias_vs_volpath.se, 6) << ","
                           << format_g(sc.bias_vs_reference.value, 6) << "\n";
        };
        {
            Score sc;
            score_frame(ref, sc);
            approximation_row("reference:2d", "screen-space reference", sc, sc.sss_ms / 1000);
        }
        for (const Score& sc : ss.scores)
            approximation_row(sc.model, "separable", sc, sc.sss_ms / 1000);

        // Error against frame time: the sweep models over tap counts, with and without jitter;
        // and every table model at its taps (ranks, d'Eon counts).
        auto sweep_row = [&](const Score& sc) {
            const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
            sweep << scene.name << "," << csv_field(sc.model) << "," << sc.label << "," << sc.taps
                  << "," << format_g(sc.jitter, 6) << "," << (sc.rotate ? 1 : 0) << ","
                  << format_g(ref_rgb.rms, 6) << "," << format_g(ref_rgb.rms_se, 6) << ","
                  << format_g(vp_rgb.rms, 6) << "," << format_g(vp_rgb.rms_se, 6) << ","
                  << format_g(sc.sss_ms, 6) << "," << format_g(sc.frame_ms, 6) << "\n";
        };
        for (const Score& sc : ss.scores) sweep_row(sc);
        // Variants of the sweep: (jitter, rotate).
        std::vector<std::pair<double, bool>> variants = {{0.0, false}};
        if (spec.jitter > 0) variants.push_back({spec.jitter, false});
        if (spec.rotate) variants.push_back({0.0, true});
        for (const std::string& model : spec.sweep_models)
            for (int taps : spec.taps_sweep)
                for (const auto& [jit, rot] : variants) {
                    if (taps == spec.taps && jit == 0.0 && !rot &&
                        std::find(spec.models.begin(), spec.models.end(), model) !=
                            spec.models.end())
                        continue;  // already a table row
                    Score sc;
                    sc.model = model;
                    sc.label = approx::parse_model(model).label();
                    sc.taps = taps;
                    sc.jitter = jit;
                    sc.rotate = rot;
                    score_frame(run(kernels_of(model, taps, false), realtime::SssMethod::kSeparable,
                                    jit, rot),
                                sc);
                    sweep_row(sc);
                }

        // Munoz11's layered convolution in place of the SSS pass: the media's far sides lit
        // once, then every variant scored like a model.
        if (!spec.munoz.empty()) {
            realtime::LitFrame back;
            arena.execute([&] { back = light_back_frame(scene, fo, slabs); });
            const auto& k = kernels_of(spec.models[0], spec.taps, true);
            for (const std::string& text : spec.munoz) {
                const approx::MunozOptions mo = approx::parse_munoz(text);
                MunozFrame mf;
                arena.execute([&] {
                    mf = render_munoz_frame(scene, frame, lit, back, k, in.profiles, mo, fo);
                });
                Score sc;
                score_frame(mf.frame, sc);
                const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
                std::string variant = approx::munoz_label(mo);  // spaces for commas
                std::replace(variant.begin(), variant.end(), ',', ' ');
                munoz << scene.name << "," << variant << "," << mo.layers << ","
                      << format_g(mo.threshold, 6) << "," << mo.downsample << ","
                      << approx::split_name(mo.split) << "," << format_g(ref_rgb.rms, 6) << ","
                      << format_g(ref_rgb.rms_se, 6) << "," << format_g(vp_rgb.rms, 6) << ","
                      << format_g(vp_rgb.rms_se, 6) << "," << format_g(mf.stats.seconds, 6) << ","
                      << mf.stats.convolutions << "," << mf.stats.skipped_threshold << ","
                      << mf.stats.skipped_invisible << ","
                      << (mo.kernel == approx::MunozKernel::point ? "point" : "average") << ","
                      << (mo.skip_invisible ? "skip" : "all") << "\n";
                // Under regression like the models: scene.munoz_l<layers>_t<t>_d<downsample>
                // [_linear][_all][_avg].rms_vs_volpath, the RGB error.
                const std::string id = "munoz_l" + std::to_string(mo.layers) + "_t" +
                                       format_g(mo.threshold, 6) + "_d" +
                                       std::to_string(mo.downsample) +
                                       (mo.split == approx::MunozSplit::equal
                                            ? std::string()
                                            : std::string("_") + approx::split_name(mo.split)) +
                                       (mo.skip_invisible ? "" : "_all") +
                                       (mo.kernel == approx::MunozKernel::point ? "" : "_avg");
                metrics.push_back({scene.name + "." + metric_label(id) + ".rms_vs_volpath", "1",
                                   vp_rgb.rms, vp_rgb.rms_se, true, 0});
                approximation_row("munoz:" + approx::munoz_label(mo), "Munoz11", sc,
                                  mf.stats.seconds);
                if (!ctx.quiet)
                    std::printf(
                        "  realtime %s: munoz %s: RGB error %.4g +- %.2g against the path "
                        "tracer, %.3g s\n",
                        scene.name.c_str(), approx::munoz_label(mo).c_str(), vp_rgb.rms,
                        vp_rgb.rms_se, mf.stats.seconds);
            }
        }

        // Jensen-Buhler's hierarchical integration in place of the SSS pass: one lit point
        // cloud per (density, candidates), shared by the variants that differ only in their
        // threshold, bound or profile; each variant's seconds are its cloud's and its queries'.
        if (!spec.jensen_buhler.empty()) {
            const auto& k = kernels_of(spec.models[0], spec.taps, true);
            std::map<std::pair<double, int>, JensenBuhlerCloud> clouds;
            for (const std::string& text : spec.jensen_buhler) {
                const approx::JensenBuhlerOptions jo = approx::parse_jensen_buhler(text);
                const std::pair<double, int> key{jo.points_per_mm2, jo.candidates_per_point};
                if (!clouds.count(key))
                    arena.execute([&] {
                        clouds.emplace(
                            key, build_jensen_buhler_cloud(scene, frame.media_in_view, jo, fo,
                                                           static_cast<std::uint64_t>(ctx.seed)));
                    });
                const JensenBuhlerCloud& cloud = clouds.at(key);
                JensenBuhlerFrame jf;
                arena.execute([&] {
                    jf = render_jensen_buhler_frame(scene, frame, lit, k, in.profiles, cloud, jo,
                                                    fo);
                });
                Score sc;
                score_frame(jf.frame, sc);
                const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
                const double seconds = cloud.seconds() + jf.query_seconds;
                std::string variant = approx::jensen_buhler_label(jo);
                std::replace(variant.begin(), variant.end(), ',', ' ');
                jb << scene.name << "," << format_g(jo.max_solid_angle, 6) << "," << cloud.points
                   << "," << format_g(vp_rgb.rms, 6) << "," << format_g(vp_rgb.rms_se, 6) << ","
                   << format_g(seconds, 6) << "," << variant << ","
                   << format_g(jo.points_per_mm2, 6) << "," << (jo.conservative ? "box" : "centre")
                   << "," << jo.profile << "," << format_g(ref_rgb.rms, 6) << ","
                   << format_g(ref_rgb.rms_se, 6) << "," << format_g(jf.query_seconds, 6) << ","
                   << format_g(cloud.seconds(), 6) << "," << format_g(cloud.light_seconds, 6) << ","
                   << jf.stats.nodes_visited << "," << jf.stats.clusters << "," << jf.stats.points
                   << "\n";
                // Under regression: scene.jb_d<density>_t<threshold>[_box][_<profile>]
                // [_c<candidates>].rms_vs_volpath, the RGB error.
                const std::string id =
                    "jb_d" + format_g(jo.points_per_mm2, 6) + "_t" +
                    format_g(jo.max_solid_angle, 6) + (jo.conservative ? "_box" : "") +
                    (jo.profile == "mc" ? "" : "_" + jo.profile) +
                    (jo.candidates_per_point == 5 ? ""
                                                  : "_c" + std::to_string(jo.candidates_per_point));
                metrics.push_back({scene.name + "." + metric_label(id) + ".rms_vs_volpath", "1",
                                   vp_rgb.rms, vp_rgb.rms_se, true, 0});
                approximation_row("jensen_buhler:" + approx::jensen_buhler_label(jo),
                                  "Jensen-Buhler", sc, seconds);
                if (!ctx.quiet)
                    std::printf(
                        "  realtime %s: jensen_buhler %s: %zu points, RGB error %.4g +- %.2g "
                        "against the path tracer, %.3g s (queries %.3g s)\n",
                        scene.name.c_str(), approx::jensen_buhler_label(jo).c_str(), cloud.points,
                        vp_rgb.rms, vp_rgb.rms_se, seconds, jf.query_seconds);
            }
        }

        // The error decomposition: separability (the first model against the screen-space
        // reference), the screen-space assumption (reference against the path tracer), the
        // lighting (specular on the media, radiance of the diffuse surfaces) and the total
        // (the first model's radiance against the path tracer's).
        const realtime::FrameResult& first = frames.at(ss.scores[0].label);
        for (int c = 0; c < 3; ++c) {
            const NoiseCorrectedRms scr =
                score(ref.image, "subsurface", vp->image, "subsurface", mask, c, vp_dof);
            const NoiseCorrectedRms spec_err =
                score(first.image, "specular", vp->image, "specular", mask, c, vp_dof);
            const NoiseCorrectedRms surf =
                score(first.image, "radiance", vp->image, "radiance", surfaces, c, vp_dof);
            const NoiseCorrectedRms total =
                score(first.image, "radiance", vp->image, "radiance", mask, c, vp_dof);
            decomposition << scene.name << "," << kChannelNames[c] << "," << mask.size() << ","
                          << format_g(ss.signal[static_cast<size_t>(c)], 6) << ","
                          << csv_field(ss.scores[0].model) << ","
                          << format_g(ss.scores[0].vs_reference[static_cast<size_t>(c)].rms, 6)
                          << "," << format_g(scr.rms, 6) << "," << format_g(scr.rms_se, 6) << ","
                          << format_g(spec_err.rms, 6) << "," << format_g(spec_err.rms_se, 6) << ","
                          << format_g(surf.rms, 6) << "," << format_g(surf.rms_se, 6) << ","
                          << format_g(total.rms, 6) << "," << format_g(total.rms_se, 6) << "\n";
            const std::string base = scene.name + ".reference." + kChannelNames[c];
            metrics.push_back({base + ".rms_vs_volpath", "1", scr.rms, scr.rms_se, true, 0});
        }

        // Images: the same exposure for every image of a scene (the reference's 99th
        // percentile at 0.8), differences to the reference 10 times brighter.
        if (spec.images && !mask.empty()) {
            const fs::path sd = dir / scene.name;
            fs::create_directories(sd);
            std::vector<double> v, var, all_v;
            for (int c = 0; c < 3; ++c) {
                masked(ref.image, "subsurface", mask, c, v, var);
                all_v.insert(all_v.end(), v.begin(), v.end());
            }
            const double p99 = percentile(all_v, 0.99);
            const double gain = p99 > 0 ? 0.8 / p99 : 1.0;
            // The cut-out: a third of the image around the scored pixels' centroid, 3x.
            double cx = 0, cy = 0;
            for (size_t i : mask) {
                cx += static_cast<double>(i % static_cast<size_t>(w));
                cy += static_cast<double>(i / static_cast<size_t>(w));
            }
            cx /= mask.size();
            cy /= mask.size();
            const int cw = std::max(4, w / 3), chh = std::max(4, h / 3);
            const int x0 = std::clamp(static_cast<int>(cx) - cw / 2, 0, w - cw);
            const int y0 = std::clamp(static_cast<int>(cy) - chh / 2, 0, h - chh);
            struct Entry {
                std::string name, caption;
                const ImageLayer* layer;
                std::string diff;  // its difference image, if any
            };
            std::vector<Entry> entries;
            std::vector<LayeredImage> diffs;
            diffs.reserve(frames.size() + 2);
            auto add_entry = [&](const std::string& name, const std::string& caption,
                                 const ImageLayer& l) {
                write_file_atomic(sd / (name + ".png"), png_of(l, gain));
                write_file_atomic(sd / ("cut_" + name + ".png"),
                                  png_of(l, gain, x0, y0, cw, chh, 3));
                diffs.emplace_back(w, h);
                const ImageLayer& d =
                    abs_difference(diffs.back(), l, ref.image.layer("subsurface"));
                write_file_atomic(sd / ("diff_" + name + ".png"), png_of(d, 10 * gain));
                write_file_atomic(sd / ("cutdiff_" + name + ".png"),
                                  png_of(d, 10 * gain, x0, y0, cw, chh, 3));
                entries.push_back({name, caption, &l, "diff_" + name + ".png"});
            };
            add_entry("volpath", "path tracer (" + std::to_string(vp->spp) + " spp)",
                      vp->image.layer("subsurface"));
            add_entry("reference", "screen-space 2D reference", ref.image.layer("subsurface"));
            for (const Score& sc : ss.scores)
                add_entry(sc.label, sc.model, frames.at(sc.label).image.layer("subsurface"));
            write_file_atomic(sd / "radiance_reference.png",
                              png_of(ref.image.layer("radiance"), gain));
            const std::string id = "flip-" + scene.name;
            viewers << "<h3 id=\"realtime-" << esc(scene.name) << "\">" << esc(scene.name)
                    << ": flip between images</h3>\n<div class=\"flip\" id=\"" << esc(id)
                    << "\">\n<p class=\"flipbar\">";
            for (size_t i = 0; i < entries.size(); ++i)
                viewers << "<button type=\"button\" data-src=\"realtime/" << esc(scene.name) << "/"
                        << esc(entries[i].name) << ".png\" data-diff=\"realtime/" << esc(scene.name)
                        << "/" << esc(entries[i].diff) << "\"" << (i == 1 ? " class=\"on\"" : "")
                        << ">" << esc(entries[i].caption) << "</button> ";
            viewers << "<br><label>exposure <input type=\"range\" class=\"exposure\" min=\"-4\" "
                       "max=\"4\" step=\"0.5\" value=\"0\"> <span class=\"ev\">0</span> "
                       "stops</label> <label><input type=\"checkbox\" class=\"diffmode\"> "
                       "difference to the screen-space reference (10x)</label> (keys: left / "
                       "right flip, d difference)</p>\n<img class=\"view\" src=\"realtime/"
                    << esc(scene.name) << "/reference.png\" alt=\"" << esc(scene.name)
                    << " subsurface\" style=\"width:" << std::max(256, std::min(512, w))
                    << "px;image-rendering:pixelated\">\n<p class=\"caption\">Subsurface layer "
                       "(the same exposure for all); showing <span class=\"which\">screen-space "
                       "2D reference</span>.</p>\n<div class=\"cuts\">";
            for (const Entry& e : entries)
                viewers << "<figure><img src=\"realtime/" << esc(scene.name) << "/cut_"
                        << esc(e.name) << ".png\" alt=\"cut-out " << esc(e.caption)
                        << "\"><br><img src=\"realtime/" << esc(scene.name) << "/cutdiff_"
                        << esc(e.name) << ".png\" alt=\"difference " << esc(e.caption) << "\"><br>"
                        << esc(e.caption) << "</figure>";
            viewers << "</div>\n</div>\n";
        }
        if (!ctx.quiet)
            std::printf(
                "  realtime %s: %d x %d, %zu medium pixels, %zu models, path tracer %s "
                "(%llu spp)\n",
                scene.name.c_str(), w, h, mask.size(), ss.scores.size(),
                vp->computed_now ? "rendered" : "reused", static_cast<unsigned long long>(vp->spp));
        all.push_back(std::move(ss));
    }

    // Table 6.4: normalised by the table's largest per-channel error (vs the screen-space
    // reference), and per scene.
    double table_max = 0;
    for (const SceneScores& ss : all)
        for (const Score& sc : ss.scores)
            for (const auto& e : sc.vs_reference) table_max = std::max(table_max, e.rms);
    std::ostringstream ours_vs_thesis;
    for (const SceneScores& ss : all) {
        double scene_max = 0;
        for (const Score& sc : ss.scores)
            for (const auto& e : sc.vs_reference) scene_max = std::max(scene_max, e.rms);
        for (const Score& sc : ss.scores) {
            double sum_norm = 0;
            for (int c = 0; c < 3; ++c) {
                {
                    const NoiseCorrectedRms& r = sc.vs_reference[static_cast<size_t>(c)];
                    const NoiseCorrectedRms& v = sc.vs_volpath[static_cast<size_t>(c)];
                    const double sig = ss.signal[static_cast<size_t>(c)];
                    table << ss.scene << "," << csv_field(sc.model) << "," << sc.label << ","
                          << sc.taps << "," << kChannelNames[c] << "," << ss.pixels << ","
                          << format_g(r.rms, 6) << "," << format_g(r.rms_se, 6) << ","
                          << format_g(table_max > 0 ? r.rms / table_max : 0, 6) << ","
                          << format_g(scene_max > 0 ? r.rms / scene_max : 0, 6) << ","
                          << format_g(sig > 0 ? r.rms / sig : 0, 6) << "," << format_g(v.rms, 6)
                          << "," << format_g(v.rms_se, 6) << "," << format_g(v.raw_rms, 6) << ","
                          << format_g(v.noise_rms, 6) << "," << format_g(sc.sss_ms, 6) << ","
                          << format_g(sc.frame_ms, 6) << "," << format_g(sc.build_s, 6) << "\n";
                    sum_norm += table_max > 0 ? r.rms / table_max : 0;
                    const std::string base =
                        ss.scene + "." + metric_label(sc.label) + "." + kChannelNames[c];
                    metrics.push_back({base + ".rms_vs_reference", "1", r.rms, r.rms_se,
                                       r.rms_se > 0, r.rms_se > 0 ? 0 : 1e-4});
                    metrics.push_back({base + ".rms_vs_volpath", "1", v.rms, v.rms_se, true, 0});
                }
            }
            for (const ThesisRow& t : thesis_table_6_4())
                if (t.ours == ss.scene && t.model == sc.model) {
                    ours_vs_thesis << "<tr><td class=\"l\">" << esc(ss.scene) << " / " << t.scene
                                   << "</td><td class=\"l\"><code>" << esc(sc.model)
                                   << "</code></td>";
                    for (int c = 0; c < 3; ++c)
                        ours_vs_thesis
                            << "<td>"
                            << format_g(sc.vs_reference[static_cast<size_t>(c)].rms / table_max, 3)
                            << "</td>";
                    ours_vs_thesis << "<td><b>" << format_g(sum_norm, 3) << "</b></td><td>"
                                   << format_g(t.r, 3) << "</td><td>" << format_g(t.g, 3)
                                   << "</td><td>" << format_g(t.b, 3) << "</td><td><b>"
                                   << format_g(t.sum, 3) << "</b></td></tr>\n";
                }
        }
    }
    std::ostringstream thesis;
    thesis << "thesis_scene,our_scene,model,R,G,B,sum\n";
    for (const ThesisRow& t : thesis_table_6_4())
        thesis << t.scene << "," << t.ours << ",\"" << t.model << "\"," << t.r << "," << t.g << ","
               << t.b << "," << t.sum << "\n";
    write_file_atomic(dir / "table_6_4.csv", table.str());
    write_file_atomic(dir / "error_vs_time.csv", sweep.str());
    write_file_atomic(dir / "decomposition.csv", decomposition.str());
    write_file_atomic(dir / "thesis_table_6_4.csv", thesis.str());
    if (!spec.munoz.empty()) write_file_atomic(dir / "munoz11.csv", munoz.str());
    if (!spec.jensen_buhler.empty()) write_file_atomic(dir / "jensen_buhler.csv", jb.str());
    write_file_atomic(dir / "approximations.csv", approximations.str());

    // Error against time, a figure per scene (scripts/plot.py "error_vs_time"), drawn here:
    // this section is written before the report's other plots are. Against the SSS pass's time:
    // the frame's other passes are the same for every model (raster and lighting are measured
    // once per scene) and take nearly all of a frame of this software renderer.
    std::vector<PlotRequest> plot_requests;
    for (const SceneScores& ss : all) {
        const std::string stem = "plots/realtime_error_vs_time_" + ss.scene;
        std::ostringstream js, caption;
        js << "{\"kind\": \"error_vs_time\", \"csv\": \"realtime/error_vs_time.csv\", \"scene\": "
           << json_string(ss.scene) << ", \"taps\": " << spec.taps
           << ", \"x\": \"sss_ms\", \"out\": " << json_string(stem) << "}";
        caption << ss.scene << ": RMS error of the subsurface layer over the " << ss.pixels
                << " medium pixels (RGB: the root of the channels' mean squared error) against the "
                   "SSS pass time on this machine, both axes logarithmic. Not against the whole "
                   "frame time: the rest of the frame (raster, shadow maps and lighting, measured "
                   "once for the scene, and the composite) is the same work for every model and "
                   "in this software renderer far longer than the pass (the last sentence gives "
                   "both). Left against the screen-space 2D reference (the "
                   "separability error), right against the path tracer (noise-corrected, error "
                   "bars +-1 standard error). A line per swept model through its tap counts "
                   "(points labelled by taps), solid without jitter, dashed with jitter "
                << format_g(spec.jitter, 3)
                << (spec.rotate ? ", dash-dotted with the pass axes rotated per pixel" : "")
                << "; the table's models of one family at " << spec.taps
                << " taps (SVD ranks, d'Eon's numbers of Gaussians) joined by a dotted line, "
                   "points labelled by that parameter; other models as single markers.";
        plot_requests.push_back(
            {js.str(),
             {"realtime/error_vs_time.csv"},
             {"realtime", ss.scene + ": error against SSS pass time", stem, caption.str()}});
    }
    // The integrations over the surfaces, per scene: Munoz11's error against its parameters
    // (the paper's Figs. 5, 2 and 3 as errors) and time, Jensen-Buhler's against the octree
    // threshold, the number of points and time, and every approximation against time.
    const bool integrations = !spec.munoz.empty() || !spec.jensen_buhler.empty();
    for (const SceneScores& ss : all) {
        if (!integrations) break;
        auto request = [&](const std::string& what, const std::string& csv,
                           const std::string& title, const std::string& panels,
                           const std::string& caption) {
            const std::string stem = "plots/realtime_" + what + "_" + ss.scene;
            std::ostringstream js;
            js << "{\"kind\": \"sweep\", \"csv\": \"realtime/" << csv
               << "\", \"scene\": " << json_string(ss.scene)
               << ", \"y\": \"rms_vs_volpath\", \"ylabel\": \"RMS error against the path "
                  "tracer (RGB)\", \"title\": "
               << json_string(ss.scene + ": " + title) << ", \"out\": " << json_string(stem)
               << ", \"panels\": [" << panels << "]}";
            plot_requests.push_back({js.str(),
                                     {"realtime/" + csv},
                                     {"realtime-integrations", ss.scene + ": " + title, stem,
                                      ss.scene + ": " + caption}});
        };
        const std::string time_panel =
            "{\"x\": \"seconds\", \"xscale\": \"log\", \"markers_only\": true, "
            "\"xlabel\": \"seconds (two cores)\", \"title\": \"against time\"";
        if (!spec.munoz.empty())
            request("munoz11", "munoz11.csv", "Munoz11's layered convolution",
                    "{\"x\": \"layers\", \"xscale\": \"log\", \"min_points\": 2, \"series\": "
                    "[\"threshold\", \"downsample\", \"split\", \"kernel\"], \"title\": "
                    "\"against layers (Fig. 5)\"}, {\"x\": \"threshold\", \"xscale\": "
                    "\"symlog\", \"min_points\": 2, \"series\": [\"layers\", \"downsample\", "
                    "\"split\", \"kernel\"], \"xlabel\": \"t of Eq. 8\", \"title\": \"against "
                    "the threshold (Fig. 2)\"}, {\"x\": \"downsample\", \"xscale\": \"log\", "
                    "\"min_points\": 2, \"series\": [\"layers\", \"threshold\", \"split\", "
                    "\"kernel\"], \"xlabel\": \"down-sampling factor\", \"title\": \"against "
                    "layer resolution (Fig. 3)\"}, " +
                        time_panel + ", \"series\": [\"kernel\"]}",
                    "the RGB RMS error of Munoz11's variants against the path tracer "
                    "(noise-corrected, +-1 SE) against the number of layers, the threshold t of "
                    "Eq. 8 and the down-sampling of the layers (a line per combination of the "
                    "other parameters that varies), and every variant against its time "
                    "(realtime/munoz11.csv). The paper shows these as images and times only.");
        if (!spec.jensen_buhler.empty())
            request("jensen_buhler", "jensen_buhler.csv",
                    "Jensen-Buhler's hierarchical integration",
                    "{\"x\": \"threshold\", \"xscale\": \"log\", \"min_points\": 2, "
                    "\"series\": [\"points\", \"bound\", \"profile\"], \"xlabel\": \"octree "
                    "threshold [sr]\", \"title\": \"against the threshold\"}, {\"x\": "
                    "\"points\", \"xscale\": \"log\", \"min_points\": 2, \"series\": "
                    "[\"threshold\", \"bound\", \"profile\"], \"xlabel\": \"points in the "
                    "cloud\", \"title\": \"against the point density\"}, " +
                        time_panel + ", \"series\": [\"profile\"]}",
                    "the RGB RMS error of Jensen-Buhler's variants against the path tracer "
                    "(noise-corrected, +-1 SE) against the octree's solid-angle threshold, the "
                    "number of points and the time (cloud, lighting and queries; "
                    "realtime/jensen_buhler.csv).");
        request("approximations", "approximations.csv", "every approximation against time",
                time_panel + ", \"series\": [\"family\"]}",
                "the RGB RMS error of every approximation against the path tracer "
                "(noise-corrected, +-1 SE) against the seconds of the pass that replaces the SSS "
                "pass, a colour per family (realtime/approximations.csv).");
    }
    const PlotResult plots = draw_plots(plot_requests, stage, cache, ctx.quiet);

    // The report section.
    html << "<h2 id=\"realtime\">Real-time renderer against the ground truth</h2>\n<p>Each "
            "scene rasterized and shaded with shadow maps (realtime/frame.h), its subsurface "
            "light by the separable screen-space pass with each kernel model ("
         << spec.taps
         << " importance-sampled taps per 1D pass, as the thesis), scored over the pixels that "
            "see only a medium against the same pipeline with the exact 2D kernel "
            "(<i>vs reference</i>: the separability error alone) and against the path tracer's "
            "subsurface layer (<i>vs volpath</i>: everything, its noise taken out: the expected "
            "squared difference minus the path tracer's variance, with the metric's standard "
            "error). Absolute RMS in radiance units; Table 6.4's normalisation divides by the "
            "largest per-channel error of the table.</p>\n";
    html << "<h3 id=\"realtime-table\">Table 6.4, ours beside the thesis's</h3>\n<p>Normalised "
            "RMS against the screen-space reference (ours) and the thesis's normalised image "
            "RMS (against its ground-truth rendering, on its scenes: ours stand in for Dragon "
            "(marble), Fruit (apple), Head (skin), Ketchup and Milk (wholemilk); the thesis "
            "has no scene for each of our materials and its normalisation is over its own "
            "table, so the comparison is of the ranking and the ratios between models, not of "
            "the values).</p>\n<table><tr><th class=\"l\">scene / thesis</th><th "
            "class=\"l\">model</th><th>R</th><th>G</th><th>B</th><th>sum</th><th>thesis "
            "R</th><th>G</th><th>B</th><th>sum</th></tr>\n"
         << ours_vs_thesis.str() << "</table>\n";
    html << "<h3 id=\"realtime-errors\">Every model, per scene</h3>\n<p>RMS over the medium's "
            "pixels in radiance units: against the screen-space reference (the separability "
            "error) and against the path tracer (noise-corrected, &plusmn; its standard error); "
            "the sss pass's and the frame's time on this machine. All columns in <a "
            "href=\"realtime/table_6_4.csv\">realtime/table_6_4.csv</a>.</p>\n";
    for (const SceneScores& ss : all) {
        html << "<table><tr><th class=\"l\">" << esc(ss.scene) << " (" << ss.pixels
             << " px)</th><th>vs ref. R</th><th>G</th><th>B</th><th>vs volpath R</th><th>G</th>"
                "<th>B</th><th>sss ms</th><th>frame ms</th></tr>\n";
        for (const Score& sc : ss.scores) {
            html << "<tr><td class=\"l\"><code>" << esc(sc.model) << "</code></td>";
            for (const auto& e : sc.vs_reference) html << "<td>" << format_g(e.rms, 3) << "</td>";
            for (const auto& e : sc.vs_volpath)
                html << "<td>" << with_error(e.rms, e.rms_se) << "</td>";
            html << "<td>" << format_g(sc.sss_ms, 3) << "</td><td>" << format_g(sc.frame_ms, 4)
                 << "</td></tr>\n";
        }
        html << "</table>\n";
    }
    csv_table(html, decomposition.str(),
              "The error decomposition (realtime/decomposition.csv): separability, the "
              "screen-space assumption, lighting, total");
    html << "<h3 id=\"realtime-time\">Error against time</h3>\n<p>Every model of the "
            "table at "
         << spec.taps << " taps, and the swept models over their tap counts with and without jitter"
         << (spec.rotate ? " and with rotated pass axes" : "")
         << ": the "
            "error against the time the SSS pass took, per scene (the frame times are in the "
            "table). Table: <a "
            "href=\"realtime/error_vs_time.csv\">realtime/error_vs_time.csv</a>.</p>\n";
    if (!plots.problem.empty())
        html << "<p class=\"note\">No plots: " << esc(plots.problem) << "</p>\n";
    figures(html, plots, "realtime");
    csv_table(html, sweep.str(), "Error against frame time (realtime/error_vs_time.csv)");
    if (integrations) {
        html << "<h3 id=\"realtime-integrations\">Integrations over the surfaces: Munoz11, "
                "Jensen-Buhler, and every approximation</h3>\n<p>The SSS pass replaced by "
                "Munoz11's layered convolution (the media's far sides from a second raster) and "
                "by Jensen-Buhler's hierarchical integration (a Poisson-disk point cloud on every "
                "surface of the media, lit by pass 1's lights and shadow maps), scored like the "
                "models. Seconds: Munoz11's layered convolution; Jensen-Buhler's point cloud, its "
                "lighting and octree, and the queries; the separable models' and the reference's "
                "SSS pass. Tables: <a href=\"realtime/approximations.csv\">approximations.csv"
                "</a>, <a href=\"realtime/munoz11.csv\">munoz11.csv</a>, <a "
                "href=\"realtime/jensen_buhler.csv\">jensen_buhler.csv</a>.</p>\n";
        figures(html, plots, "realtime-integrations");
        csv_table(html, approximations.str(),
                  "Every approximation against the path tracer (realtime/approximations.csv)");
    }
    html << viewers.str();
    html << "<script>\n(function () {\n"
            "  document.querySelectorAll('div.flip').forEach(function (v) {\n"
            "    var img = v.querySelector('img.view'), which = v.querySelector('span.which');\n"
            "    var buttons = Array.prototype.slice.call(v.querySelectorAll('button'));\n"
            "    var range = v.querySelector('input.exposure'), ev = v.querySelector('span.ev');\n"
            "    var diff = v.querySelector('input.diffmode'), at = 1;\n"
            "    function show(i) {\n"
            "      at = (i + buttons.length) % buttons.length;\n"
            "      buttons.forEach(function (b, k) { b.className = k === at ? 'on' : ''; });\n"
            "      var b = buttons[at];\n"
            "      img.src = diff.checked ? b.dataset.diff : b.dataset.src;\n"
            "      which.textContent = b.textContent + (diff.checked ? ' (difference)' : '');\n"
            "      v.dataset.showing = img.getAttribute('src');\n"
            "    }\n"
            "    buttons.forEach(function (b, k) { b.addEventListener('click', function () { "
            "show(k); }); });\n"
            "    diff.addEventListener('change', function () { show(at); });\n"
            "    range.addEventListener('input', function () {\n"
            "      ev.textContent = range.value;\n"
            "      img.style.filter = 'brightness(' + Math.pow(2, range.value) + ')';\n"
            "    });\n"
            "    v.tabIndex = 0;\n"
            "    v.addEventListener('keydown', function (e) {\n"
            "      if (e.key === 'ArrowRight') show(at + 1);\n"
            "      else if (e.key === 'ArrowLeft') show(at - 1);\n"
            "      else if (e.key === 'd') { diff.checked = !diff.checked; show(at); }\n"
            "    });\n"
            "    v.dataset.ready = 'yes';\n"
            "  });\n"
            "})();\n</script>\n"
            "<style>div.flip button.on { font-weight: bold; background: #dde; } div.cuts { "
            "display: flex; flex-wrap: wrap; gap: 4px; } div.cuts figure { margin: 0; width: "
            "128px; font-size: 80%; } div.cuts img { width: 128px; display: block; "
            "image-rendering: pixelated; }</style>\n";
    res.html = html.str();
    return res;
}

}  // namespace ssslab::runner
