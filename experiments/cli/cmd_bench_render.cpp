// `ssslab bench --render`: the scene renderer on the built-in scenes: ray queries per second,
// and the time to 1 % relative standard error per pixel (median over the pixels that see
// anything), extrapolated from the measured variance (error ~ 1 / sqrt(time)).
#include "core/error.h"
#include "core/scene.h"
#include "core/stats.h"
#include "experiments/cli/bench_volpath.h"
#include "volpath/render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

namespace ssslab::cli {

namespace fs = std::filesystem;

std::vector<fs::path> list_scenes(const std::string& scenes_dir, const std::string& only) {
    if (!fs::is_directory(scenes_dir))
        throw InputError(
            {"<command line>", 0, 0}, "--scenes",
            "no scene folder " + scenes_dir + " (run from the source tree or give --scenes)");
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(scenes_dir))
        if (e.path().extension() == ".toml" &&
            (only.empty() || e.path().stem().string().find(only) != std::string::npos))
            files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

int run_render_bench(int threads, bool quick, const std::string& scenes_dir, int size, int spp,
                     const std::string& only) {
    const std::vector<fs::path> files = list_scenes(scenes_dir, only);
    if (quick) {
        size = std::min(size, 64);  // at least 16 batches: standard errors need them
        spp = std::max(16, std::min(spp, 16));
    }
    std::printf("volpath renderer (%s), %d thread%s, %d x %d, %d spp per scene\n",
                volpath::render_engine_version(), threads, threads == 1 ? "" : "s", size, size,
                spp);
    std::printf("%-10s %9s %12s %12s %10s %12s %14s %12s\n", "scene", "wall_s", "Mrays/s",
                "paths/s", "med_relSE", "t_1%_pixel_s", "image mean relSE", "no_balls_s");
    for (const fs::path& f : files) {
        const Scene s = read_scene(f.string());
        volpath::RenderOptions o;
        o.threads = threads;
        o.width = o.height = size;
        o.budget.samples = spp;
        // The same image with every boundary query made, for the ratio (same bits).
        volpath::RenderOptions all_queries = o;
        all_queries.skip_queries_in_balls = false;
        const double no_balls = volpath::render(s, all_queries).seconds;
        const volpath::RenderResult r = volpath::render(s, o);
        const RelativeError err = volpath::radiance_rel_error(r.image);
        const double med = err.median;
        const double t1 = r.seconds * (med / 0.01) * (med / 0.01);
        const double paths = static_cast<double>(size) * size * static_cast<double>(r.spp);
        std::printf("%-10s %9.2f %12.2f %12.3g %10.3f %12.3g %14.2e %12.2f\n", s.name.c_str(),
                    r.seconds, static_cast<double>(r.rays) / r.seconds * 1e-6, paths / r.seconds,
                    med, t1, err.mean, no_balls);
    }
    std::printf(
        "t_1%%_pixel: the extrapolated time until the median pixel's relative standard error of "
        "the radiance is 1 %% at this size. Mrays/s: ray queries (a flight inside a ball that "
        "no surface enters needs none). no_balls_s: the same image (to the bit) with a ray "
        "query for every flight, timed in the same run.\n");
    return 0;
}

}  // namespace ssslab::cli
