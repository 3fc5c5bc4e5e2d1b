// Path-traced images of scene files through the runner's artifact cache, for the studies that
// need them (the render study, studies/render/; the realtime study's ground truth; the stiff
// sweep), and the scene files of a study's `scenes` key.
//
// Every render (scene x role: "main", "reference", ...) is an artifact: results/cache/render/<key>/
// holds image.exr (the layers of volpath/render.h plus, for the role "main", the radiance after
// 4, 8, 16, ... spp as layers "snapshot_<spp>") and manifest.toml (seconds, rays, spp, seed). The
// key covers the scene file's text, every OBJ and OpenVDB file it reads, the size, budget, seed,
// role and the renderer's version. Unfinished renders checkpoint beside the entry and resume.
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

/// The scene files of a study's `scenes` key (relative to `config_dir`), each read, validated
/// and passed to `check` (which throws InputError for what the study cannot use), their names
/// unique (they name the output files). Resolved paths, in order.
std::vector<std::string> read_scene_files(ConfigTable& t, const std::string& config_dir,
                                          const std::function<void(const Scene&)>& check);

/// What a study takes of the run (study.h StudyInputs).
struct RenderStudyContext {
    std::uint64_t seed = 1;
    bool quick = false;
    int threads = 0;
    bool quiet = false;
    double checkpoint_seconds = 30;
    const std::atomic<bool>* cancel = nullptr;
};

/// A path-traced image of a scene through the cache: the render of `role` (which, with the
/// context's seed and the scene's name, derives its seed, as the render study's "main" and
/// "reference"), at width x height with `budget`, loaded if cached and rendered (checkpointing,
/// resumable) if not. The image has the layers of volpath/render.h; nullopt if interrupted.
struct CachedRender {
    LayeredImage image{1, 1};
    double seconds = 0;
    std::uint64_t spp = 0, rays = 0;
    std::string key;
    bool computed_now = false;
    /// The role "main"'s snapshots: (spp, seconds) in order, their radiance layers in
    /// snapshot_layers (snapshot(spp)).
    std::vector<std::pair<std::uint64_t, double>> snapshots;
    LayeredImage snapshot_layers{1, 1};
    const ImageLayer& snapshot(std::uint64_t at_spp) const;
};
std::optional<CachedRender> cached_render(const Scene& scene, const std::string& role, int width,
                                          int height, const SampleBudget& budget,
                                          const RenderStudyContext& ctx,
                                          const ArtifactCache& cache);

}  // namespace ssslab::runner
