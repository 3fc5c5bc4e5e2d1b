// Google Benchmark of the software rasterizer (realtime/raster.h): a frame of a few closed
// meshes and a floor, at 1 x 1 and 4 x 4 samples per pixel, on the caller's threads.
#include "realtime/raster.h"
#include "core/mesh.h"

#include <benchmark/benchmark.h>

#include <vector>

namespace ssslab::realtime {
namespace {

void BM_RasterizeFrame(benchmark::State& state) {
    const int size = static_cast<int>(state.range(0)), ss = static_cast<int>(state.range(1));
    SceneCamera sc;
    sc.position = {3, 4, 12};
    sc.target = {0, 0.5, 0};
    sc.fov_y_deg = 40;
    const RasterCamera cam = RasterCamera::from_scene(sc, size, size);
    const std::vector<TriangleMesh> meshes{
        transformed(make_quad(30, 30), {}),
        transformed(make_sphere(1.5, 5), {{1, 1, 1}, {0, 0, 0}, {-1.5, 1.5, 0}}),
        transformed(make_torus(1.2, 0.4, 256, 64), {{1, 1, 1}, {60, 0, 0}, {1.5, 1, 1.5}})};
    std::size_t triangles = 0;
    for (const TriangleMesh& m : meshes) triangles += m.triangles.size();
    RasterOptions o;
    o.supersample = ss;
    for (auto _ : state) {
        std::vector<RasterMesh> rm;
        for (std::size_t i = 0; i < meshes.size(); ++i)
            rm.push_back(project(cam, meshes[i], i > 0));
        benchmark::DoNotOptimize(rasterize(cam, rm, o));
    }
    state.counters["triangles"] = static_cast<double>(triangles);
    state.counters["samples/s"] = benchmark::Counter(
        static_cast<double>(size) * size * ss * ss * static_cast<double>(state.iterations()),
        benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RasterizeFrame)->Args({512, 1})->Args({512, 4})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ssslab::realtime

BENCHMARK_MAIN();
