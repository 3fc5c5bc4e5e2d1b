// [outputs.realtime]: the real-time renderer scored image against image [Freude14 Table 6.4,
// Figs. 6.11-6.22]. For every scene, every kernel model's frame (realtime/frame.h) against two
// references: the same pipeline with the exact 2D kernel (the screen-space ground truth:
// the model's separability error alone) and the path tracer's subsurface layer (the physical
// ground truth), with the path tracer's noise taken out (core/image_compare.h
// noise_corrected_rms). A study plugin (experiments/runner/study.h): its files, metrics, plots and
// report section (with a flip viewer per scene) are returned as data.
//
//   [outputs.realtime]
//   scenes = ["../scenes/skin.toml", ...]   # relative to the config file
//   models = ["svd:rank=1", "preintegration", "guided:k=1", "manual:table_a1,unit=mm", ...]
//   taps = 17                     # importance-sampled taps per 1D pass, as the thesis
//   sweep_models = ["svd:rank=1", "preintegration"]   # error against frame time ...
//   taps_sweep = [5, 9, 17, 33, 65]                   # ... over these tap counts ...
//   jitter = 0.33                 # ... with and without this jitter (0: without only)
//   width = 512                   # every scene at this size (0: the scene camera's)
//   height = 512
//   edge = "follow"               # follow | reject | none (realtime/sss_pass.h)
//   backend = "software"          # software | gl: the SSS pass on the GL twin (realtime/gl)
//   platform = "auto"             # with gl: auto | osmesa | egl
//   spp = 252                     # the path tracer's reference (a cached render, role
//                                 # "realtime"; shared with any study of the same budget)
//   photons = 1e6                 # MCML photons per channel of each material's profile
//   light_samples = 16, environment_samples = 64, shadow_map_size = 2048,
//   environment_map_size = 512    # realtime/lighting.h LightingOptions
//   reference_samples = 256       # the exact reference's samples per pixel where it samples
//   quick_factor = 0.125          # --quick: spp and photons times this (spp at least 12) ...
//   quick_size = 64               # ... and at most this many pixels wide and high
//   images = true                 # PNG panels, difference images, cut-outs, the flip viewer
//   munoz = ["layers=4", "layers=8,t=0.001,downsample=2"]   # Munoz11's layered convolution
//                                 # (approx::parse_munoz) in place of the SSS pass, with the
//                                 # media's far sides as back samples (surface_frames.h)
//
// The scored pixels of a scene are those whose samples all see a medium (material layer); per
// model and channel: the RMS against the screen-space reference (exact where the reference
// summed exactly, with the reference's standard error otherwise) and against the path tracer
// (noise-corrected, with its standard error), both absolute (radiance units) and normalised as
// Table 6.4 (the largest per-channel error of the table is 1; per scene too).
//
// results/<name>/realtime/: table_6_4.csv, error_vs_time.csv, decomposition.csv,
// thesis_table_6_4.csv (Freude14's numbers beside ours), munoz11.csv (with munoz: per scene and
// variant the RGB error against the screen-space reference and the path tracer with standard
// errors, the layered convolution's seconds and counts), and with images <scene>/*.png; per scene
// results/<name>/plots/realtime_error_vs_time_<scene>.{png,svg}: the RGB error against the
// screen-space reference and against the path tracer (+-1 SE) over the SSS pass time, log axes
// (scripts/plot.py "error_vs_time", drawn by the runner from
// StudyResult::plots and shown in the section).
#include "approx/model_spec.h"
#include "approx/munoz.h"
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
#include "experiments/runner/study.h"
#include "experiments/runner/surface_frames.h"
#include "realtime/frame.h"
#include "realtime/sss_pass.h"
#if SSSLAB_HAVE_GL
#include "realtime/gl/sss_pass_gl.h"
#endif
#include "volpath/render.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

struct RealtimeStudySpec {
    std::vector<std::string> scenes;  ///< resolved paths
    std::vector<std::string> models;  ///< model spec texts (validated)
    int taps = 17;
    std::vector<std::string> sweep_models;
    std::vector<int> taps_sweep;
    double jitter = 0.33;
    /// The sweep also runs every tap count with the pass axes rotated per pixel
    /// (SssParams::rotate, JimenezSupp Fig. S.7), without jitter.
    bool rotate = false;
    int width = 512, height = 512;
    realtime::SssEdgeMode edge = realtime::SssEdgeMode::kFollowSurface;
    /// The separable pass's backend: "software" (realtime/sss_pass.h) or "gl" (the GL twin,
    /// realtime/gl) on `platform` ("auto", "osmesa", "egl").
    std::string backend = "software", platform = "auto";
    std::int64_t spp = 252;
    std::int64_t photons = 1'000'000;
    int light_samples = 16, environment_samples = 64, shadow_map_size = 2048,
        environment_map_size = 512;
    int reference_samples = 256;
    double quick_factor = 0.125;
    int quick_size = 64;
    bool images = true;
    std::vector<std::string> munoz;  ///< Munoz11 variants (approx::parse_munoz texts)
    /// Jensen-Buhler variants (approx::parse_jensen_buhler texts)
    std::vector<std::string> jensen_buhler;
};

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

RealtimeStudySpec read_realtime_study(ConfigTable& t, const std::string& config_dir) {
    RealtimeStudySpec s;
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

/// A scene's scores of the table's models at spec.taps, and the scale of its signal.
struct SceneScores {
    std::string scene;
    size_t pixels = 0;
    std::array<double, 3> signal{};
    std::vector<Score> scores;  // the table's models at spec.taps
};

// The RGB error is the root of the channels' mean squared error; its standard error by the
// delta method as noise_corrected_rms's, from the mean of the channels' standard errors of
// D^2 (their errors are correlated, the same paths carry all three: the mean bounds the
// sum's).
struct Rgb {
    double rms, rms_se;
};
Rgb rgb(const std::array<NoiseCorrectedRms, 3>& e) {
    const double ms = (e[0].ms + e[1].ms + e[2].ms) / 3.0;
    const double ms_se = (e[0].ms_se + e[1].ms_se + e[2].ms_se) / 3.0;
    const double rms = std::sqrt(std::max(0.0, ms));
    return Rgb{rms, rms > 0 ? std::min(ms_se / (2.0 * rms), std::sqrt(ms_se)) : std::sqrt(ms_se)};
}

using FrameKernels = std::map<int, realtime::FrameMaterial>;

/// One scene of the study: its frame (pass 1 shared by every model), its ground truth (the
/// media's profiles and slabs, the path tracer's image), the kernels built so far, the
/// screen-space reference and the scored pixels.
struct SceneRun {
    Scene scene;
    int w = 0, h = 0;
    realtime::FrameOptions fo;
    realtime::RasterizedFrame frame;
    RealtimeInputs in;
    std::optional<CachedRender> vp;
    double vp_dof = 0;
    std::vector<realtime::SlabTransmittance> slabs;
    // Kernels per (model, taps), built once.
    std::map<std::pair<std::string, int>, FrameKernels> kernels;
    std::map<std::pair<std::string, int>, double> build_s;
    realtime::LitFrame lit;
    realtime::FrameResult ref;
    std::vector<size_t> mask, surfaces;
    std::map<std::string, realtime::FrameResult> frames;  // the table's models, for images
};

/// The study's CSV tables as they grow scene by scene, and the flip viewers' subsections.
struct RealtimeTables {
    std::ostringstream table, sweep, decomposition, munoz, jb, approximations;
    std::vector<StudySection> viewers;
    RealtimeTables() {
        table << "scene,model,label,taps,channel,pixels,rms_vs_reference,rms_vs_reference_se,"
                 "norm_table,norm_scene,rel_rms_vs_reference,rms_vs_volpath,rms_vs_volpath_se,"
                 "raw_rms_vs_volpath,volpath_noise_rms,sss_ms,frame_ms,kernel_build_s\n";
        sweep
            << "scene,model,label,taps,jitter,rotate,rms_vs_reference_rgb,rms_vs_reference_rgb_se,"
               "rms_vs_volpath_rgb,rms_vs_volpath_rgb_se,sss_ms,frame_ms\n";
        munoz << "scene,variant,layers,threshold,downsample,split,rms_vs_reference,"
                 "rms_vs_reference_se,rms_vs_volpath,rms_vs_volpath_se,seconds,convolutions,"
                 "skipped_threshold,skipped_invisible,kernel,visible\n";
        jb << "scene,threshold,points,rms_vs_volpath,rms_vs_volpath_se,seconds,variant,density,"
              "bound,profile,rms_vs_reference,rms_vs_reference_se,query_seconds,cloud_seconds,"
              "light_seconds,nodes_visited,clusters,point_terms\n";
        approximations << "scene,method,rms_vs_volpath,rms_vs_volpath_se,seconds,family,"
                          "rms_vs_reference,rms_vs_reference_se,bias_vs_volpath,bias_vs_volpath_se,"
                          "bias_vs_reference\n";
        decomposition
            << "scene,channel,pixels,reference_signal_rms,separability_model,separability,"
               "screen_space,screen_space_se,specular,specular_se,surfaces,surfaces_se,"
               "total,total_se\n";
    }
};

/// One run of the study: scene by scene, then the tables, the plots and the report section.
class RealtimeRun {
  public:
    RealtimeRun(const RealtimeStudySpec& spec, const StudyInputs& in)
        : spec_(spec),
          ctx_(in.ctx),
          cache_(*in.cache),
          results_root_(in.results_root),
          metrics_(res_.metrics),
          arena_(in.ctx.threads > 0 ? in.ctx.threads : tbb::task_arena::automatic) {}

    StudyResult run();

  private:
    bool prepare_scene(const std::string& path, SceneRun& s);
    const FrameKernels& kernels_of(SceneRun& s, const std::string& model, int taps, bool exact);
    realtime::FrameResult render(const SceneRun& s, const FrameKernels& k, realtime::SssMethod m,
                                 double jitter, bool rotate = false);
    void find_scored_pixels(SceneRun& s) const;
    void score_frame(const SceneRun& s, const realtime::FrameResult& f, Score& sc) const;
    void approximation_row(const SceneRun& s, const std::string& method, const std::string& family,
                           const Score& sc, double seconds);
    void sweep_row(const SceneRun& s, const Score& sc);
    void score_models(SceneRun& s, SceneScores& ss);
    void run_sweep(SceneRun& s);
    void run_munoz(SceneRun& s);
    void run_jensen_buhler(SceneRun& s);
    void decompose(const SceneRun& s, const SceneScores& ss);
    void write_images(const SceneRun& s, const SceneScores& ss);
    std::string write_tables(const std::vector<SceneScores>& all);
    std::vector<PlotRequest> plot_requests(const std::vector<SceneScores>& all) const;
    StudySection section(const std::vector<SceneScores>& all,
                         const std::string& ours_vs_thesis) const;

    const RealtimeStudySpec& spec_;
    const RenderStudyContext& ctx_;
    const ArtifactCache& cache_;
    const fs::path results_root_;
    StudyResult res_;
    std::vector<Metric>& metrics_;  // res_'s
    tbb::task_arena arena_;
    RealtimeTables t_;
    // The GL twin's SSS pass, where the config names it: one context for the study, on this
    // thread (render_frame calls the pass on the thread that runs the arena's work).
#if SSSLAB_HAVE_GL
    std::unique_ptr<realtime::gl::GlContext> gl_context_;
    std::unique_ptr<realtime::gl::GlSssPass> gl_pass_;
#endif
};

StudyResult RealtimeRun::run() {
#if SSSLAB_HAVE_GL
    if (spec_.backend == "gl") {
        gl_context_ =
            realtime::gl::GlContext::create(realtime::gl::parse_gl_platform(spec_.platform));
        gl_pass_ = std::make_unique<realtime::gl::GlSssPass>(*gl_context_);
    }
#endif
    std::vector<SceneScores> all;
    for (const std::string& path : spec_.scenes) {
        SceneRun s;
        if (!prepare_scene(path, s)) {
            res_.interrupted = true;
            return res_;
        }
        find_scored_pixels(s);
        SceneScores ss;
        score_models(s, ss);
        run_sweep(s);
        if (!spec_.munoz.empty()) run_munoz(s);
        if (!spec_.jensen_buhler.empty()) run_jensen_buhler(s);
        decompose(s, ss);
        if (spec_.images && !s.mask.empty()) write_images(s, ss);
        if (!ctx_.quiet)
            std::printf(
                "  realtime %s: %d x %d, %zu medium pixels, %zu models, path tracer %s "
                "(%llu spp)\n",
                s.scene.name.c_str(), s.w, s.h, s.mask.size(), ss.scores.size(),
                s.vp->computed_now ? "rendered" : "reused",
                static_cast<unsigned long long>(s.vp->spp));
        all.push_back(std::move(ss));
    }
    const std::string ours_vs_thesis = write_tables(all);
    res_.plots = plot_requests(all);
    res_.section = section(all, ours_vs_thesis);
    return res_;
}

/// The scene's frame options, raster and pass 1, its ground truth (profiles, slabs, the path
/// tracer's render) and the screen-space reference; false when the run was interrupted.
bool RealtimeRun::prepare_scene(const std::string& path, SceneRun& s) {
    s.scene = read_scene(path);
    const Scene& scene = s.scene;
    int w = spec_.width > 0 ? spec_.width : scene.camera.width;
    int h = spec_.height > 0 ? spec_.height : scene.camera.height;
    std::int64_t spp = spec_.spp, photons = spec_.photons;
    if (ctx_.quick) {
        const double f = std::min(1.0, static_cast<double>(spec_.quick_size) / std::max(w, h));
        w = std::max(1, static_cast<int>(std::lround(w * f)));
        h = std::max(1, static_cast<int>(std::lround(h * f)));
        spp =
            std::max<std::int64_t>(12, std::llround(static_cast<double>(spp) * spec_.quick_factor));
        photons = std::max<std::int64_t>(
            1000, std::llround(static_cast<double>(photons) * spec_.quick_factor));
    }
    s.w = w;
    s.h = h;
    realtime::FrameOptions& fo = s.fo;
    fo.width = w;
    fo.height = h;
    fo.lighting.light_samples = spec_.light_samples;
    fo.lighting.environment_samples = spec_.environment_samples;
    fo.lighting.shadow_map_size = spec_.shadow_map_size;
    fo.lighting.environment_map_size = spec_.environment_map_size;
    fo.sss.mode = spec_.edge;
    fo.sss.follow_strength = realtime::default_follow_strength(scene);
    fo.sss.reject_depth = realtime::default_reject_depth(scene);
    fo.reference.samples = spec_.reference_samples;
    fo.reference.seed = ctx_.seed;
    arena_.execute([&] { s.frame = realtime::rasterize_frame(scene, fo); });

    // Ground truth: the media's profiles (and slabs for translucency), the path tracer.
    RealtimeInputOptions io;
    io.seed = ctx_.seed;
    io.profile_budget.samples = photons;
    io.slab_budget.samples = std::max<std::int64_t>(1000, photons / 10);
    io.slab_thickness_mm = slab_thicknesses(0.05, 25.6, 10);
    io.run.threads = ctx_.threads;
    io.run.results_root = results_root_;
    io.run.quiet = ctx_.quiet;
    io.run.cancel = ctx_.cancel;
    io.run.checkpoint_seconds = ctx_.checkpoint_seconds;
    s.in = realtime_inputs(scene, s.frame.media_in_view, io);
    if (s.in.interrupted) return false;
    res_.computed += s.in.computed;
    res_.reused += s.in.reused;
    SampleBudget vb;
    vb.samples = spp;
    s.vp = cached_render(scene, "realtime", w, h, vb, ctx_, cache_);
    if (!s.vp) return false;
    (s.vp->computed_now ? res_.computed : res_.reused) += 1;
    s.vp_dof = static_cast<double>(s.vp->spp / 3) - 1;  // batch statistics
    s.slabs.resize(scene.materials.size());
    for (const auto& [m, t] : s.in.slabs) {
        s.slabs[static_cast<size_t>(m)].thickness_mm = t.thickness_mm;
        s.slabs[static_cast<size_t>(m)].transmittance = t.transmittance;
    }
    // Pass 1 once: every model's frame shares the G-buffer.
    arena_.execute([&] { s.lit = realtime::light_frame(scene, s.frame, fo, s.slabs); });
    s.ref = render(s, kernels_of(s, spec_.models[0], spec_.taps, true),
                   realtime::SssMethod::kReference, 0);
    return true;
}

/// The kernels of `model` at `taps` for every medium of the scene, built on first use.
const FrameKernels& RealtimeRun::kernels_of(SceneRun& s, const std::string& model, int taps,
                                            bool exact) {
    auto& k = s.kernels[{model, taps}];
    if (!k.empty() || s.in.profiles.empty()) return k;
    const auto t0 = std::chrono::steady_clock::now();
    const approx::ModelSpec ms = approx::parse_model(model);
    for (const auto& [m, p] : s.in.profiles)
        k[m] = realtime::make_frame_material(p, ms, taps, exact);
    s.build_s[{model, taps}] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return k;
}

/// The scene's frame with kernels `k` by method `m` (on the GL twin's pass where configured).
realtime::FrameResult RealtimeRun::render(const SceneRun& s, const FrameKernels& k,
                                          realtime::SssMethod m, double jitter, bool rotate) {
    realtime::FrameOptions o = s.fo;
    o.method = m;
    o.sss.jitter = jitter;
    o.sss.rotate = rotate;
    o.sss.seed = static_cast<std::uint32_t>(ctx_.seed);
#if SSSLAB_HAVE_GL
    if (gl_pass_)
        o.separable_pass = [&](const realtime::SssGBuffer& g,
                               const std::vector<realtime::SssMaterialKernel>& taps,
                               const realtime::SssParams& p,
                               std::vector<float>& out) { gl_pass_->run(g, taps, p, out); };
#endif
    realtime::FrameResult r;
    arena_.execute([&] { r = realtime::render_frame(s.scene, s.frame, s.lit, k, o); });
    return r;
}

/// The scored pixels: every sample a medium; and the covered pixels of the diffuse surfaces.
void RealtimeRun::find_scored_pixels(SceneRun& s) const {
    const realtime::RasterizedFrame& frame = s.frame;
    const Scene& scene = s.scene;
    const int sup = frame.raster.supersample;
    for (int y = 0; y < s.h; ++y)
        for (int x = 0; x < s.w; ++x) {
            const size_t i = frame.raster.pixel_index(x, y);
            bool all_medium = true, covered = frame.raster.coverage[i] >= 1.0;
            for (int j = 0; j < sup; ++j)
                for (int q = 0; q < sup; ++q) {
                    const std::int32_t sh =
                        frame.raster.shape[frame.raster.sample_index(x * sup + q, y * sup + j)];
                    all_medium =
                        all_medium && sh >= 0 &&
                        scene.materials[static_cast<size_t>(
                                            scene.shapes[static_cast<size_t>(sh)].material)]
                                .kind == SceneMaterial::Kind::kMedium;
                }
            if (all_medium)
                s.mask.push_back(i);
            else if (covered)
                s.surfaces.push_back(i);
        }
}

/// A frame's subsurface layer against the screen-space reference and the path tracer.
void RealtimeRun::score_frame(const SceneRun& s, const realtime::FrameResult& f, Score& sc) const {
    for (int c = 0; c < 3; ++c) {
        sc.vs_reference[static_cast<size_t>(c)] =
            score(f.image, "subsurface", s.ref.image, "subsurface", s.mask, c, 0);
        sc.vs_volpath[static_cast<size_t>(c)] =
            score(f.image, "subsurface", s.vp->image, "subsurface", s.mask, c, s.vp_dof);
    }
    sc.bias_vs_reference = relative_bias(f.image, "subsurface", s.ref.image, "subsurface", s.mask);
    sc.bias_vs_volpath = relative_bias(f.image, "subsurface", s.vp->image, "subsurface", s.mask);
    for (const auto& p : f.times)
        if (p.pass == "sss") sc.sss_ms = p.ms;
    sc.frame_ms = f.total_ms();
}

/// The table of every approximation (approximations.csv): the RGB errors and the seconds of
/// the pass that replaces the SSS pass (kernels built before the frame).
void RealtimeRun::approximation_row(const SceneRun& s, const std::string& method,
                                    const std::string& family, const Score& sc, double seconds) {
    const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
    t_.approximations << s.scene.name << "," << csv_field(method) << "," << format_g(vp_rgb.rms, 6)
                      << "," << format_g(vp_rgb.rms_se, 6) << "," << format_g(seconds, 6) << ","
                      << family << "," << format_g(ref_rgb.rms, 6) << ","
                      << format_g(ref_rgb.rms_se, 6) << "," << format_g(sc.bias_vs_volpath.value, 6)
                      << "," << format_g(sc.bias_vs_volpath.se, 6) << ","
                      << format_g(sc.bias_vs_reference.value, 6) << "\n";
}

/// A row of error against frame time (error_vs_time.csv).
void RealtimeRun::sweep_row(const SceneRun& s, const Score& sc) {
    const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
    t_.sweep << s.scene.name << "," << csv_field(sc.model) << "," << sc.label << "," << sc.taps
             << "," << format_g(sc.jitter, 6) << "," << (sc.rotate ? 1 : 0) << ","
             << format_g(ref_rgb.rms, 6) << "," << format_g(ref_rgb.rms_se, 6) << ","
             << format_g(vp_rgb.rms, 6) << "," << format_g(vp_rgb.rms_se, 6) << ","
             << format_g(sc.sss_ms, 6) << "," << format_g(sc.frame_ms, 6) << "\n";
}

/// The table's models at spec.taps: scored, kept for the images, and their rows in
/// approximations.csv and error_vs_time.csv beside the reference's.
void RealtimeRun::score_models(SceneRun& s, SceneScores& ss) {
    ss.scene = s.scene.name;
    ss.pixels = s.mask.size();
    for (int c = 0; c < 3; ++c) {
        std::vector<double> v, var;
        masked(s.ref.image, "subsurface", s.mask, c, v, var);
        double q = 0;
        for (double x : v) q += x * x;
        ss.signal[static_cast<size_t>(c)] = v.empty() ? 0 : std::sqrt(q / v.size());
    }
    for (const std::string& model : spec_.models) {
        Score sc;
        sc.model = model;
        sc.label = approx::parse_model(model).label();
        sc.taps = spec_.taps;
        const auto& k = kernels_of(s, model, spec_.taps, model == spec_.models[0]);
        realtime::FrameResult f = render(s, k, realtime::SssMethod::kSeparable, 0);
        score_frame(s, f, sc);
        sc.build_s = s.build_s[{model, spec_.taps}];
        ss.scores.push_back(sc);
        s.frames.emplace(sc.label, std::move(f));
    }
    {
        Score sc;
        score_frame(s, s.ref, sc);
        approximation_row(s, "reference:2d", "screen-space reference", sc, sc.sss_ms / 1000);
    }
    for (const Score& sc : ss.scores)
        approximation_row(s, sc.model, "separable", sc, sc.sss_ms / 1000);
    // Error against frame time: every table model at its taps (ranks, d'Eon counts), then the
    // sweep (run_sweep).
    for (const Score& sc : ss.scores) sweep_row(s, sc);
}

/// Error against frame time: the sweep models over tap counts, with and without jitter (and
/// with rotated pass axes where configured).
void RealtimeRun::run_sweep(SceneRun& s) {
    // Variants of the sweep: (jitter, rotate).
    std::vector<std::pair<double, bool>> variants = {{0.0, false}};
    if (spec_.jitter > 0) variants.push_back({spec_.jitter, false});
    if (spec_.rotate) variants.push_back({0.0, true});
    for (const std::string& model : spec_.sweep_models)
        for (int taps : spec_.taps_sweep)
            for (const auto& [jit, rot] : variants) {
                if (taps == spec_.taps && jit == 0.0 && !rot &&
                    std::find(spec_.models.begin(), spec_.models.end(), model) !=
                        spec_.models.end())
                    continue;  // already a table row
                Score sc;
                sc.model = model;
                sc.label = approx::parse_model(model).label();
                sc.taps = taps;
                sc.jitter = jit;
                sc.rotate = rot;
                score_frame(s,
                            render(s, kernels_of(s, model, taps, false),
                                   realtime::SssMethod::kSeparable, jit, rot),
                            sc);
                sweep_row(s, sc);
            }
}

/// Munoz11's layered convolution in place of the SSS pass: the media's far sides lit once,
/// then every variant scored like a model.
void RealtimeRun::run_munoz(SceneRun& s) {
    const Scene& scene = s.scene;
    realtime::LitFrame back;
    arena_.execute([&] { back = light_back_frame(scene, s.fo, s.slabs); });
    const auto& k = kernels_of(s, spec_.models[0], spec_.taps, true);
    for (const std::string& text : spec_.munoz) {
        const approx::MunozOptions mo = approx::parse_munoz(text);
        MunozFrame mf;
        arena_.execute([&] {
            mf = render_munoz_frame(scene, s.frame, s.lit, back, k, s.in.profiles, mo, s.fo);
        });
        Score sc;
        score_frame(s, mf.frame, sc);
        const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
        std::string variant = approx::munoz_label(mo);  // spaces for commas
        std::replace(variant.begin(), variant.end(), ',', ' ');
        t_.munoz << scene.name << "," << variant << "," << mo.layers << ","
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
                               format_g(mo.threshold, 6) + "_d" + std::to_string(mo.downsample) +
                               (mo.split == approx::MunozSplit::equal
                                    ? std::string()
                                    : std::string("_") + approx::split_name(mo.split)) +
                               (mo.skip_invisible ? "" : "_all") +
                               (mo.kernel == approx::MunozKernel::point ? "" : "_avg");
        metrics_.push_back({scene.name + "." + metric_label(id) + ".rms_vs_volpath", "1",
                            vp_rgb.rms, vp_rgb.rms_se, true, 0});
        approximation_row(s, "munoz:" + approx::munoz_label(mo), "Munoz11", sc, mf.stats.seconds);
        if (!ctx_.quiet)
            std::printf(
                "  realtime %s: munoz %s: RGB error %.4g +- %.2g against the path "
                "tracer, %.3g s\n",
                scene.name.c_str(), approx::munoz_label(mo).c_str(), vp_rgb.rms, vp_rgb.rms_se,
                mf.stats.seconds);
    }
}

/// Jensen-Buhler's hierarchical integration in place of the SSS pass: one lit point cloud per
/// (density, candidates), shared by the variants that differ only in their threshold, bound or
/// profile; each variant's seconds are its cloud's and its queries'.
void RealtimeRun::run_jensen_buhler(SceneRun& s) {
    const Scene& scene = s.scene;
    const auto& k = kernels_of(s, spec_.models[0], spec_.taps, true);
    std::map<std::pair<double, int>, JensenBuhlerCloud> clouds;
    for (const std::string& text : spec_.jensen_buhler) {
        const approx::JensenBuhlerOptions jo = approx::parse_jensen_buhler(text);
        const std::pair<double, int> key{jo.points_per_mm2, jo.candidates_per_point};
        if (!clouds.count(key))
            arena_.execute([&] {
                clouds.emplace(key,
                               build_jensen_buhler_cloud(scene, s.frame.media_in_view, jo, s.fo,
                                                         static_cast<std::uint64_t>(ctx_.seed)));
            });
        const JensenBuhlerCloud& cloud = clouds.at(key);
        JensenBuhlerFrame jf;
        arena_.execute([&] {
            jf = render_jensen_buhler_frame(scene, s.frame, s.lit, k, s.in.profiles, cloud, jo,
                                            s.fo);
        });
        Score sc;
        score_frame(s, jf.frame, sc);
        const Rgb ref_rgb = rgb(sc.vs_reference), vp_rgb = rgb(sc.vs_volpath);
        const double seconds = cloud.seconds() + jf.query_seconds;
        std::string variant = approx::jensen_buhler_label(jo);
        std::replace(variant.begin(), variant.end(), ',', ' ');
        t_.jb << scene.name << "," << format_g(jo.max_solid_angle, 6) << "," << cloud.points << ","
              << format_g(vp_rgb.rms, 6) << "," << format_g(vp_rgb.rms_se, 6) << ","
              << format_g(seconds, 6) << "," << variant << "," << format_g(jo.points_per_mm2, 6)
              << "," << (jo.conservative ? "box" : "centre") << "," << jo.profile << ","
              << format_g(ref_rgb.rms, 6) << "," << format_g(ref_rgb.rms_se, 6) << ","
              << format_g(jf.query_seconds, 6) << "," << format_g(cloud.seconds(), 6) << ","
              << format_g(cloud.light_seconds, 6) << "," << jf.stats.nodes_visited << ","
              << jf.stats.clusters << "," << jf.stats.points << "\n";
        // Under regression: scene.jb_d<density>_t<threshold>[_box][_<profile>]
        // [_c<candidates>].rms_vs_volpath, the RGB error.
        const std::string id =
            "jb_d" + format_g(jo.points_per_mm2, 6) + "_t" + format_g(jo.max_solid_angle, 6) +
            (jo.conservative ? "_box" : "") + (jo.profile == "mc" ? "" : "_" + jo.profile) +
            (jo.candidates_per_point == 5 ? "" : "_c" + std::to_string(jo.candidates_per_point));
        metrics_.push_back({scene.name + "." + metric_label(id) + ".rms_vs_volpath", "1",
                            vp_rgb.rms, vp_rgb.rms_se, true, 0});
        approximation_row(s, "jensen_buhler:" + approx::jensen_buhler_label(jo), "Jensen-Buhler",
                          sc, seconds);
        if (!ctx_.quiet)
            std::printf(
                "  realtime %s: jensen_buhler %s: %zu points, RGB error %.4g +- %.2g "
                "against the path tracer, %.3g s (queries %.3g s)\n",
                scene.name.c_str(), approx::jensen_buhler_label(jo).c_str(), cloud.points,
                vp_rgb.rms, vp_rgb.rms_se, seconds, jf.query_seconds);
    }
}

/// The error decomposition: separability (the first model against the screen-space
/// reference), the screen-space assumption (reference against the path tracer), the lighting
/// (specular on the media, radiance of the diffuse surfaces) and the total (the first model's
/// radiance against the path tracer's).
void RealtimeRun::decompose(const SceneRun& s, const SceneScores& ss) {
    const realtime::FrameResult& first = s.frames.at(ss.scores[0].label);
    const LayeredImage& vpi = s.vp->image;
    for (int c = 0; c < 3; ++c) {
        const NoiseCorrectedRms scr =
            score(s.ref.image, "subsurface", vpi, "subsurface", s.mask, c, s.vp_dof);
        const NoiseCorrectedRms spec_err =
            score(first.image, "specular", vpi, "specular", s.mask, c, s.vp_dof);
        const NoiseCorrectedRms surf =
            score(first.image, "radiance", vpi, "radiance", s.surfaces, c, s.vp_dof);
        const NoiseCorrectedRms total =
            score(first.image, "radiance", vpi, "radiance", s.mask, c, s.vp_dof);
        t_.decomposition << s.scene.name << "," << kChannelNames[c] << "," << s.mask.size() << ","
                         << format_g(ss.signal[static_cast<size_t>(c)], 6) << ","
                         << csv_field(ss.scores[0].model) << ","
                         << format_g(ss.scores[0].vs_reference[static_cast<size_t>(c)].rms, 6)
                         << "," << format_g(scr.rms, 6) << "," << format_g(scr.rms_se, 6) << ","
                         << format_g(spec_err.rms, 6) << "," << format_g(spec_err.rms_se, 6) << ","
                         << format_g(surf.rms, 6) << "," << format_g(surf.rms_se, 6) << ","
                         << format_g(total.rms, 6) << "," << format_g(total.rms_se, 6) << "\n";
        const std::string base = s.scene.name + ".reference." + kChannelNames[c];
        metrics_.push_back({base + ".rms_vs_volpath", "1", scr.rms, scr.rms_se, true, 0});
    }
}

/// Images: the same exposure for every image of a scene (the reference's 99th percentile at
/// 0.8), differences to the reference 10 times brighter; cut-outs, and the flip viewer.
void RealtimeRun::write_images(const SceneRun& s, const SceneScores& ss) {
    const int w = s.w, h = s.h;
    const std::vector<size_t>& mask = s.mask;
    const realtime::FrameResult& ref = s.ref;
    const std::string sd = s.scene.name + "/";  // under realtime/
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
    FlipViewer fv;
    fv.id = "flip-" + s.scene.name;
    fv.width_px = std::max(256, std::min(512, w));
    fv.what = "Subsurface layer (the same exposure for all)";
    fv.diff_of = "the screen-space reference (10x)";
    fv.first = 1;  // the screen-space reference
    std::map<std::string, std::string>& files = res_.files;
    auto add_entry = [&](const std::string& name, const std::string& caption, const ImageLayer& l) {
        files[sd + name + ".png"] = png_of(l, gain);
        files[sd + "cut_" + name + ".png"] = png_of(l, gain, x0, y0, cw, chh, 3);
        LayeredImage diff(w, h);
        const ImageLayer& d = abs_difference(diff, l, ref.image.layer("subsurface"));
        files[sd + "diff_" + name + ".png"] = png_of(d, 10 * gain);
        files[sd + "cutdiff_" + name + ".png"] = png_of(d, 10 * gain, x0, y0, cw, chh, 3);
        const std::string at = "realtime/" + sd;
        fv.images.push_back({caption, at + name + ".png", at + "diff_" + name + ".png",
                             at + "cut_" + name + ".png", at + "cutdiff_" + name + ".png"});
    };
    add_entry("volpath", "path tracer (" + std::to_string(s.vp->spp) + " spp)",
              s.vp->image.layer("subsurface"));
    add_entry("reference", "screen-space 2D reference", ref.image.layer("subsurface"));
    for (const Score& sc : ss.scores)
        add_entry(sc.label, sc.model, s.frames.at(sc.label).image.layer("subsurface"));
    files[sd + "radiance_reference.png"] = png_of(ref.image.layer("radiance"), gain);
    StudySection sub;
    sub.id = "realtime-" + s.scene.name;
    sub.title = s.scene.name + ": flip between images";
    sub.viewers.push_back(std::move(fv));
    t_.viewers.push_back(std::move(sub));
}

/// Table 6.4: normalised by the table's largest per-channel error (vs the screen-space
/// reference), and per scene; its metrics; the CSV files of realtime/. Returns the rows of
/// the report's table of ours beside the thesis's.
std::string RealtimeRun::write_tables(const std::vector<SceneScores>& all) {
    double table_max = 0;
    for (const SceneScores& ss : all)
        for (const Score& sc : ss.scores)
            for (const auto& e : sc.vs_reference) table_max = std::max(table_max, e.rms);
    std::ostringstream ours_vs_thesis;
    ours_vs_thesis << "scene / thesis,model,R,G,B,sum,thesis R,thesis G,thesis B,thesis sum\n";
    for (const SceneScores& ss : all) {
        double scene_max = 0;
        for (const Score& sc : ss.scores)
            for (const auto& e : sc.vs_reference) scene_max = std::max(scene_max, e.rms);
        for (const Score& sc : ss.scores) {
            double sum_norm = 0;
            for (int c = 0; c < 3; ++c) {
                const NoiseCorrectedRms& r = sc.vs_reference[static_cast<size_t>(c)];
                const NoiseCorrectedRms& v = sc.vs_volpath[static_cast<size_t>(c)];
                const double sig = ss.signal[static_cast<size_t>(c)];
                t_.table << ss.scene << "," << csv_field(sc.model) << "," << sc.label << ","
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
                metrics_.push_back({base + ".rms_vs_reference", "1", r.rms, r.rms_se, r.rms_se > 0,
                                    r.rms_se > 0 ? 0 : 1e-4});
                metrics_.push_back({base + ".rms_vs_volpath", "1", v.rms, v.rms_se, true, 0});
            }
            for (const ThesisRow& t : thesis_table_6_4())
                if (t.ours == ss.scene && t.model == sc.model) {
                    ours_vs_thesis << csv_field(ss.scene + " / " + t.scene) << ","
                                   << csv_field(sc.model);
                    for (int c = 0; c < 3; ++c)
                        ours_vs_thesis
                            << ","
                            << format_g(sc.vs_reference[static_cast<size_t>(c)].rms / table_max, 3);
                    ours_vs_thesis << "," << format_g(sum_norm, 3) << "," << format_g(t.r, 3) << ","
                                   << format_g(t.g, 3) << "," << format_g(t.b, 3) << ","
                                   << format_g(t.sum, 3) << "\n";
                }
        }
    }
    std::ostringstream thesis;
    thesis << "thesis_scene,our_scene,model,R,G,B,sum\n";
    for (const ThesisRow& t : thesis_table_6_4())
        thesis << t.scene << "," << t.ours << ",\"" << t.model << "\"," << t.r << "," << t.g << ","
               << t.b << "," << t.sum << "\n";
    std::map<std::string, std::string>& files = res_.files;
    files["table_6_4.csv"] = t_.table.str();
    files["error_vs_time.csv"] = t_.sweep.str();
    files["decomposition.csv"] = t_.decomposition.str();
    files["thesis_table_6_4.csv"] = thesis.str();
    if (!spec_.munoz.empty()) files["munoz11.csv"] = t_.munoz.str();
    if (!spec_.jensen_buhler.empty()) files["jensen_buhler.csv"] = t_.jb.str();
    files["approximations.csv"] = t_.approximations.str();
    return ours_vs_thesis.str();
}

/// Error against time, a figure per scene (scripts/plot.py "error_vs_time"). Against the SSS
/// pass's time: the frame's other passes are the same for every model (raster and lighting
/// are measured once per scene) and take nearly all of a frame of this software renderer.
PlotRequest error_vs_time_request(const RealtimeStudySpec& spec, const SceneScores& ss) {
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
    return {js.str(),
            {"realtime/error_vs_time.csv"},
            {"realtime", ss.scene + ": error against SSS pass time", stem, caption.str()}};
}

/// The integrations over the surfaces, per scene: Munoz11's error against its parameters
/// (the paper's Figs. 5, 2 and 3 as errors) and time, Jensen-Buhler's against the octree
/// threshold, the number of points and time, and every approximation against time.
void integration_requests(const RealtimeStudySpec& spec, const SceneScores& ss,
                          std::vector<PlotRequest>& plot_requests) {
    auto request = [&](const std::string& what, const std::string& csv, const std::string& title,
                       const std::string& panels, const std::string& caption) {
        const std::string stem = "plots/realtime_" + what + "_" + ss.scene;
        std::ostringstream js;
        js << "{\"kind\": \"sweep\", \"csv\": \"realtime/" << csv
           << "\", \"scene\": " << json_string(ss.scene)
           << ", \"y\": \"rms_vs_volpath\", \"ylabel\": \"RMS error against the path "
              "tracer (RGB)\", \"title\": "
           << json_string(ss.scene + ": " + title) << ", \"out\": " << json_string(stem)
           << ", \"panels\": [" << panels << "]}";
        plot_requests.push_back(
            {js.str(),
             {"realtime/" + csv},
             {"realtime-integrations", ss.scene + ": " + title, stem, ss.scene + ": " + caption}});
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
        request("jensen_buhler", "jensen_buhler.csv", "Jensen-Buhler's hierarchical integration",
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

/// Every figure of the section, drawn before the report's other plots are.
std::vector<PlotRequest> RealtimeRun::plot_requests(const std::vector<SceneScores>& all) const {
    std::vector<PlotRequest> plot_requests;
    for (const SceneScores& ss : all) plot_requests.push_back(error_vs_time_request(spec_, ss));
    const bool integrations = !spec_.munoz.empty() || !spec_.jensen_buhler.empty();
    for (const SceneScores& ss : all) {
        if (!integrations) break;
        integration_requests(spec_, ss, plot_requests);
    }
    return plot_requests;
}

/// The report section: the tables, the figures of the plots and a flip viewer per scene.
StudySection RealtimeRun::section(const std::vector<SceneScores>& all,
                                  const std::string& ours_vs_thesis) const {
    StudySection sec;
    sec.id = "realtime";
    sec.title = "Real-time renderer against the ground truth";
    sec.paragraphs.push_back(
        "Each scene rasterized and shaded with shadow maps (realtime/frame.h), its subsurface "
        "light by the separable screen-space pass with each kernel model (" +
        std::to_string(spec_.taps) +
        " importance-sampled taps per 1D pass, as the thesis), scored over the pixels that see "
        "only a medium against the same pipeline with the exact 2D kernel (vs reference: the "
        "separability error alone) and against the path tracer's subsurface layer (vs volpath: "
        "everything, its noise taken out: the expected squared difference minus the path "
        "tracer's variance, with the metric's standard error). Absolute RMS in radiance units; "
        "Table 6.4's normalisation divides by the largest per-channel error of the table.");
    StudySection table;
    table.id = "realtime-table";
    table.title = "Table 6.4, ours beside the thesis's";
    table.paragraphs.push_back(
        "Normalised RMS against the screen-space reference (ours) and the thesis's normalised "
        "image RMS (against its ground-truth rendering, on its scenes: ours stand in for Dragon "
        "(marble), Fruit (apple), Head (skin), Ketchup and Milk (wholemilk); the thesis has no "
        "scene for each of our materials and its normalisation is over its own table, so the "
        "comparison is of the ranking and the ratios between models, not of the values).");
    table.tables.push_back(
        {"Ours beside the thesis's (realtime/thesis_table_6_4.csv)", ours_vs_thesis});
    sec.subsections.push_back(std::move(table));

    StudySection errors;
    errors.id = "realtime-errors";
    errors.title = "Every model, per scene";
    errors.paragraphs.push_back(
        "RMS over the medium's pixels in radiance units: against the screen-space reference (the "
        "separability error) and against the path tracer (noise-corrected, \u00b1 its standard "
        "error); the sss pass's and the frame's time on this machine. All columns in "
        "realtime/table_6_4.csv.");
    for (const SceneScores& ss : all) {
        std::ostringstream csv;
        csv << csv_field(ss.scene + " (" + std::to_string(ss.pixels) + " px)")
            << ",vs ref. R,G,B,vs volpath R,G,B,sss ms,frame ms\n";
        for (const Score& sc : ss.scores) {
            csv << csv_field(sc.model);
            for (const auto& e : sc.vs_reference) csv << "," << format_g(e.rms, 3);
            for (const auto& e : sc.vs_volpath)
                csv << "," << csv_field(with_error(e.rms, e.rms_se));
            csv << "," << format_g(sc.sss_ms, 3) << "," << format_g(sc.frame_ms, 4) << "\n";
        }
        errors.tables.push_back({ss.scene, csv.str()});
    }
    errors.tables.push_back(
        {"The error decomposition (realtime/decomposition.csv): "
         "separability, the screen-space assumption, lighting, total",
         t_.decomposition.str()});
    sec.subsections.push_back(std::move(errors));

    StudySection time;
    time.id = "realtime-time";
    time.title = "Error against time";
    time.paragraphs.push_back(
        "Every model of the table at " + std::to_string(spec_.taps) +
        " taps, and the swept models over their tap counts with and without jitter" +
        (spec_.rotate ? " and with rotated pass axes" : "") +
        ": the error against the time the SSS pass took, per scene (the frame times are in the "
        "table). Table: realtime/error_vs_time.csv.");
    time.plot_section = "realtime";
    time.tables.push_back(
        {"Error against frame time (realtime/error_vs_time.csv)", t_.sweep.str()});
    sec.subsections.push_back(std::move(time));

    if (!spec_.munoz.empty() || !spec_.jensen_buhler.empty()) {
        StudySection in;
        in.id = "realtime-integrations";
        in.title =
            "Integrations over the surfaces: Munoz11, Jensen-Buhler, and every approximation";
        in.paragraphs.push_back(
            "The SSS pass replaced by Munoz11's layered convolution (the media's far sides from a "
            "second raster) and by Jensen-Buhler's hierarchical integration (a Poisson-disk point "
            "cloud on every surface of the media, lit by pass 1's lights and shadow maps), scored "
            "like the models. Seconds: Munoz11's layered convolution; Jensen-Buhler's point "
            "cloud, its lighting and octree, and the queries; the separable models' and the "
            "reference's SSS pass. Tables: realtime/approximations.csv, realtime/munoz11.csv, "
            "realtime/jensen_buhler.csv.");
        in.plot_section = "realtime-integrations";
        in.tables.push_back(
            {"Every approximation against the path tracer (realtime/approximations.csv)",
             t_.approximations.str()});
        sec.subsections.push_back(std::move(in));
    }
    for (const StudySection& v : t_.viewers) sec.subsections.push_back(v);
    return sec;
}

class RealtimeStudy final : public Study {
  public:
    explicit RealtimeStudy(RealtimeStudySpec s) : spec_(std::move(s)) {}

    std::string describe() const override {
        return "realtime (" + std::to_string(spec_.scenes.size()) + " scenes, " +
               std::to_string(spec_.models.size()) +
               " models; profiles and renders reused or computed when run)";
    }
    double quick_factor() const override { return spec_.quick_factor; }
    StudyResult run(const StudyInputs& in) const override { return RealtimeRun(spec_, in).run(); }

  private:
    RealtimeStudySpec spec_;
};

std::shared_ptr<const Study> read_realtime_plugin(ConfigTable& t, const std::string& config_dir) {
    return std::make_shared<RealtimeStudy>(read_realtime_study(t, config_dir));
}

}  // namespace
}  // namespace ssslab::runner

SSSLAB_REGISTER_STUDY(realtime, ssslab::runner::read_realtime_plugin)
