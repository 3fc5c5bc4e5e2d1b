// Google Benchmark of the separable SSS pass (realtime/sss_pass.h) at 1920 x 1080: a sphere of
// medium (view z from the sphere, a third of the image wide) on no medium, 17 taps of a
// Gaussian-like kernel of 3 mm support at about 20 px a mm (the skin scene's scale), rank 1,
// follow-surface with and without jitter, one thread and two (Args: threads, jitter, sphere
// radius; radius 0: no medium, the pass's fixed cost). `ssslab bench --realtime`
// is the figure against the memory floor; this one isolates the pass for profiling.
#include "realtime/sss_pass.h"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <vector>

namespace ssslab::realtime {
namespace {

SssGBuffer sphere_gbuffer(int w, int h, double radius) {
    SssGBuffer g(w, h);
    const double tan_half = std::tan(15.0 * 3.14159265358979 / 180.0), dist = 95;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            // Ray direction through the pixel centre (camera looking down -z).
            const double u = (2 * (x + 0.5) / w - 1) * tan_half * w / h;
            const double v = (1 - 2 * (y + 0.5) / h) * tan_half;
            const double dd = u * u + v * v + 1, b = dist, c = dist * dist - radius * radius;
            const double disc = b * b - dd * c;
            for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = 1.0f;
            if (disc < 0) {
                g.material[i] = -1;
                g.view_z[i] = std::numeric_limits<float>::infinity();
            } else {
                g.material[i] = 0;
                g.view_z[i] = static_cast<float>((b - std::sqrt(disc)) / dd);  // t * 1 along z
            }
        }
    return g;
}

SssMaterialKernel gaussian_kernel(int count, double support_mm) {
    SssTerm t;
    std::vector<double> wsum(3, 0.0);
    for (int i = 0; i < count; ++i) {
        const double u = 2.0 * i / (count - 1) - 1;
        const double o = support_mm * (u < 0 ? -u * u : u * u);
        t.taps.offset_mm.push_back(o);
        for (int ch = 0; ch < 3; ++ch) {
            const double s = 0.3 * (ch + 1);
            t.taps.weight[ch].push_back(std::exp(-0.5 * o * o / (s * s)) + 1e-3);
            wsum[static_cast<size_t>(ch)] += t.taps.weight[ch].back();
        }
    }
    for (int ch = 0; ch < 3; ++ch)
        for (double& v : t.taps.weight[ch]) v /= wsum[static_cast<size_t>(ch)];
    t.taps.support_mm = support_mm;
    return SssMaterialKernel{{t}};
}

void BM_SssPass(benchmark::State& state) {
    const int threads = static_cast<int>(state.range(0));
    const bool jitter = state.range(1) != 0;
    const int w = 1920, h = 1080;
    const SssGBuffer g = sphere_gbuffer(w, h, static_cast<double>(state.range(2)));
    const std::vector<SssMaterialKernel> mats = {gaussian_kernel(17, 3.0)};
    SssParams p;
    p.tan_half = std::tan(15.0 * 3.14159265358979 / 180.0);
    p.aspect = static_cast<double>(w) / h;
    p.unit_mm = 1;
    p.jitter = jitter ? 0.33 : 0;
    tbb::task_arena arena(threads);
    for (auto _ : state) arena.execute([&] { benchmark::DoNotOptimize(sss_pass(g, mats, p)); });
    size_t medium = 0;
    for (int32_t m : g.material) medium += m >= 0;
    state.counters["medium_px"] = static_cast<double>(medium);
}
BENCHMARK(BM_SssPass)
    ->Args({1, 0, 16})
    ->Args({2, 0, 16})
    ->Args({1, 1, 16})
    ->Args({1, 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace ssslab::realtime

BENCHMARK_MAIN();
