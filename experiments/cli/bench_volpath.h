// `ssslab bench --volpath`, `--render` and `--realtime` (experiments/cli/cmd_bench_*.cpp), and
// the timing helpers the benchmarks share.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::cli {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Wall seconds of the fastest of `repeat` (>= 1) calls of f: interference from other processes
/// only ever slows a run.
template <class F>
double best_seconds(int repeat, F&& f) {
    double best = 0;
    for (int k = 0; k < repeat; ++k) {
        const auto t0 = Clock::now();
        f();
        const double s = seconds_since(t0);
        if (k == 0 || s < best) best = s;
    }
    return best;
}

/// The .toml files of `scenes_dir` whose stem contains `only`, sorted; InputError (naming
/// --scenes) when the folder does not exist.
std::vector<std::filesystem::path> list_scenes(const std::string& scenes_dir,
                                               const std::string& only);

/// Time the path tracer against MCML on the same slabs; prints the tables, returns 0.
int run_volpath_bench(int threads, bool quick, int repeat);

/// Time the scene renderer on the scenes of `scenes_dir` (those whose name contains `only`) at
/// size x size with spp samples per pixel: rays/s and extrapolated times to 1 % of the median
/// pixel and of the image, from the run's own errors and (reference_factor > 0) from its error
/// against a reference of reference_factor x spp rendered in the same run.
int run_render_bench(int threads, bool quick, const std::string& scenes_dir, int size, int spp,
                     const std::string& only, int reference_factor);

}  // namespace ssslab::cli

namespace ssslab::cli {

/// Time the real-time renderer's passes (rasterizer, SSS pass) on the scenes of `scenes_dir`
/// (those whose name contains `only`) at width x height, 1 thread and `threads`, fastest of
/// `repeat`, against a streaming floor; the table on stdout, and a CSV (+ .toml) when `csv`.
/// backend "gl": also the passes the GL twin has, on `platform` (auto, osmesa, egl), timed in the
/// same run and checked against the CPU's results. integrations: also Munoz11's layered
/// convolution (4 layers; 4 layers with t = 0.1 % and layers at 50 %, the paper's optimised
/// setting) and Jensen-Buhler (4 points per mm^2, threshold 0.03 sr: the lit cloud and the
/// queries) in place of the SSS pass, all threads, each scene with its lights.
int run_realtime_bench(int threads, bool quick, const std::string& scenes_dir, int width,
                       int height, int repeat, const std::string& only, const std::string& csv,
                       const std::string& backend = "software",
                       const std::string& platform = "auto", bool integrations = false);

}  // namespace ssslab::cli
