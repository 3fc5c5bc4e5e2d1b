// `ssslab bench --volpath` (experiments/cli/cmd_bench_volpath.cpp).
#pragma once

#include <string>

namespace ssslab::cli {

/// Time the path tracer against MCML on the same slabs; prints the tables, returns 0.
int run_volpath_bench(int threads, bool quick, int repeat);

/// Time the scene renderer on the scenes of `scenes_dir` (those whose name contains `only`) at
/// size x size with spp samples per pixel: rays/s and extrapolated time to 1 % per pixel.
int run_render_bench(int threads, bool quick, const std::string& scenes_dir, int size, int spp,
                     const std::string& only);

}  // namespace ssslab::cli
