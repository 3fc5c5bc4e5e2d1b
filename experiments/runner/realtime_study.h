// [outputs.realtime]: the real-time renderer scored image against image [Freude14 Table 6.4,
// Figs. 6.11-6.22]. For every scene, every kernel model's frame (realtime/frame.h) against two
// references: the same pipeline with the exact 2D kernel (the screen-space ground truth:
// the model's separability error alone) and the path tracer's subsurface layer (the physical
// ground truth), with the path tracer's noise taken out (core/image_compare.h
// noise_corrected_rms).
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
// (scripts/plot.py "error_vs_time", drawn with plots.h draw_plots and shown in the section).
#pragma once

#include "core/batch_runner.h"
#include "core/config.h"
#include "experiments/runner/cache.h"
#include "experiments/runner/render_study.h"
#include "realtime/sss_pass.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::runner {

struct Metric;

struct RealtimeStudySpec {
    bool enabled = false;
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

/// Parse [outputs.realtime]; every scene is read and validated here.
RealtimeStudySpec read_realtime_study(ConfigTable& t, const std::string& config_dir);

struct RealtimeStudyResult {
    bool interrupted = false;
    int computed = 0, reused = 0;
    std::string html;  ///< the report section
};

/// Render every scene's frames, reuse or render the path tracer's references, write
/// <stage>/realtime/ and append the metrics (per scene, model and channel: rms_vs_reference,
/// rms_vs_volpath) to `metrics`. `results_root` holds the cache (the MCML profiles).
RealtimeStudyResult run_realtime_study(const RealtimeStudySpec& spec, const RenderStudyContext& ctx,
                                       const ArtifactCache& cache,
                                       const std::filesystem::path& results_root,
                                       const std::filesystem::path& stage,
                                       std::vector<Metric>& metrics);

}  // namespace ssslab::runner
