// `ssslab bench --volpath` (experiments/cli/cmd_bench_volpath.cpp).
#pragma once

namespace ssslab::cli {

/// Time the path tracer against MCML on the same slabs; prints the tables, returns 0.
int run_volpath_bench(int threads, bool quick, int repeat);

}  // namespace ssslab::cli
