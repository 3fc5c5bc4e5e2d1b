// `ssslab bench --render`: the scene renderer on the built-in scenes: ray queries per second,
// and the time to 1 % relative error of the median pixel and of the image (relative RMS over all
// pixel-channels), extrapolated (error ~ 1 / sqrt(time)) both from the run's own standard errors
// and from its error measured against an independent reference rendered in the same run
// (another seed, reference_factor times the samples; volpath::measured_error), which sees the
// heavy tails that the run's own batches miss.
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
                     const std::string& only, int reference_factor) {
    const std::vector<fs::path> files = list_scenes(scenes_dir, only);
    if (quick) {
        size = std::min(size, 64);  // at least 16 batches: standard errors need them
        spp = std::max(16, std::min(spp, 16));
    }
    std::printf("volpath renderer (%s), %d thread%s, %d x %d, %d spp per scene",
                volpath::render_engine_version(), threads, threads == 1 ? "" : "s", size, size,
                spp);
    if (reference_factor > 0)
        std::printf("; references of %d spp (seed 2)", reference_factor * spp);
    std::printf("\n%-10s %8s %8s %9s %9s %10s %10s %10s %10s %8s %10s\n", "scene", "wall_s",
                "Mrays/s", "paths/s", "med_relSE", "t1%pix_own", "t1%pix_ref", "t1%img_own",
                "t1%img_ref", "z2_ratio", "no_balls_s");
    auto t1 = [](double seconds, double e) { return seconds * (e / 0.01) * (e / 0.01); };
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
        const double paths = static_cast<double>(size) * size * static_cast<double>(r.spp);
        const RelativeError own = volpath::radiance_rel_error(r.image);
        std::printf("%-10s %8.2f %8.2f %9.3g %9.3f %10.3g", s.name.c_str(), r.seconds,
                    static_cast<double>(r.rays) / r.seconds * 1e-6, paths / r.seconds, own.median,
                    t1(r.seconds, own.median));
        if (reference_factor > 0) {
            volpath::RenderOptions ro = o;
            ro.seed = 2;
            ro.budget.samples = static_cast<std::int64_t>(reference_factor) * spp;
            const volpath::MeasuredError m =
                volpath::measured_error(r.image, volpath::render(s, ro).image);
            std::printf(" %10.3g %10.3g %10.3g %8.2f", t1(r.seconds, m.median_pixel),
                        t1(r.seconds, own.rms), t1(r.seconds, m.rel_rmse_corrected),
                        m.z2_median_ratio);
        } else {
            std::printf(" %10s %10.3g %10s %8s", "-", t1(r.seconds, own.rms), "-", "-");
        }
        std::printf(" %10.2f\n", no_balls);
    }
    std::printf(
        "t1%%pix, t1%%img: the extrapolated time until the median pixel's relative error of the "
        "radiance, and the image's relative RMS error over all pixel-channels, are 1 %% at this "
        "size: _own from the run's standard errors, _ref from its error against the reference "
        "(its own noise taken out; the median pixel's scaled by sqrt(z2_ratio), the median of "
        "the pixels' squared z-scores over that of a chi-square with one degree of freedom: 1 "
        "when the standard errors are honest). Mrays/s: ray queries (a flight inside a ball "
        "that no surface enters needs none). no_balls_s: the same image (to the bit) with a ray "
        "query for every flight, timed in the same run.\n");
    return 0;
}

}  // namespace ssslab::cli
