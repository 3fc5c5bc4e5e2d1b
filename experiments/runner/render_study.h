// [outputs.render]: ground-truth images of scene files through the runner's artifact graph, with
// the renderer's speed and its time to 1 % relative error (issue 6's benchmark).
//
//   [outputs.render]
//   scenes = ["../scenes/skin.toml", ...]  # relative to the config file
//   spp = 64                # samples per pixel (or seconds = ...; one of them)
//   width = 512             # optional: override every scene camera's size
//   height = 512
//   reference_factor = 4    # an independent reference with this many times the samples (0: none)
//   quick_factor = 0.125    # --quick multiplies spp (or seconds) by this (at least 16 spp) ...
//   quick_size = 64         # ... and renders at most this many pixels wide and high
//
// Every render (scene x role main/reference) is an artifact: results/cache/render/<key>/ holds
// image.exr (the layers of volpath/render.h plus the main run's radiance after 4, 8, 16, ... spp
// as layers "snapshot_<spp>") and manifest.toml (seconds, rays, spp, seed). The key covers the
// scene file's text, every OBJ and OpenVDB file it reads, the size, budget, seed, role and the
// renderer's version. Unfinished renders checkpoint beside the entry and resume.
//
// results/<name>/render/: <scene>.exr and .png (the main run), summary.csv (per scene: size, spp,
// seconds, rays/s, paths/s, the image mean per channel with its SE, the image's relative RMS
// standard error and the median pixel's, the times to 1 % both imply, and with a reference the
// measured relative RMS error, with the reference's own noise taken out, and the time to 1 % it
// implies) and <scene>_convergence.csv (error against time from the snapshots). Times to 1 %
// are extrapolations t x (e / 0.01)^2 from the measured error e (Monte Carlo error falls as
// 1 / sqrt(time)); the snapshots show whether it does.
#pragma once

#include "core/batch_runner.h"
#include "core/config.h"
#include "core/film_image.h"
#include "core/scene.h"
#include "experiments/runner/cache.h"

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::runner {

struct Metric;

struct RenderStudySpec {
    bool enabled = false;
    std::vector<std::string> scenes;  ///< resolved paths
    SampleBudget budget;              ///< samples (spp) or seconds
    int width = 0, height = 0;        ///< 0: the scene camera's
    double reference_factor = 4.0;    ///< 0: no reference
    double quick_factor = 0.125;
    int quick_size = 64;
};

/// The scene files of a study's `scenes` key (relative to `config_dir`), each read, validated
/// and passed to `check` (which throws InputError for what the study cannot use), their names
/// unique (they name the output files). Resolved paths, in order.
std::vector<std::string> read_scene_files(ConfigTable& t, const std::string& config_dir,
                                          const std::function<void(const Scene&)>& check);

/// Parse [outputs.render] (`config_dir` resolves the scene paths); every scene is read and
/// validated here, so a bad scene fails the config with the scene file's line.
RenderStudySpec read_render_study(ConfigTable& t, const std::string& config_dir);

struct RenderStudyContext {
    std::uint64_t seed = 1;
    bool quick = false;
    int threads = 0;
    bool quiet = false;
    double checkpoint_seconds = 30;
    const std::atomic<bool>* cancel = nullptr;
};

struct RenderStudyResult {
    bool interrupted = false;
    int computed = 0, reused = 0;
    std::string html;  ///< the report section
};

/// Render (or reuse) every scene and write <stage>/render/; metrics (per scene and channel the
/// image means of radiance and subsurface, with their SE) are appended to `metrics`.
RenderStudyResult run_render_study(const RenderStudySpec& spec, const RenderStudyContext& ctx,
                                   const ArtifactCache& cache, const std::filesystem::path& stage,
                                   std::vector<Metric>& metrics);

/// A path-traced image of a scene through the cache: the render of `role` (which, with the
/// context's seed and the scene's name, derives its seed, as the render study's "main" and
/// "reference"), at width x height with `budget`, loaded if cached and rendered (checkpointing,
/// resumable) if not. The image has the layers of volpath/render.h; nullopt if interrupted.
struct CachedRender {
    LayeredImage image{1, 1};
    double seconds = 0;
    std::uint64_t spp = 0;
    std::string key;
    bool computed_now = false;
};
std::optional<CachedRender> cached_render(const Scene& scene, const std::string& role, int width,
                                          int height, const SampleBudget& budget,
                                          const RenderStudyContext& ctx,
                                          const ArtifactCache& cache);

}  // namespace ssslab::runner
