// Google Benchmark micro-benchmarks of the MCML engine's inner kernels. The end-to-end figures
// (photons/ms, ns per event) come from `ssslab bench`.
#include "core/fastmath.h"
#include "core/philox.h"
#include "core/rng.h"
#include "core/ziggurat.h"
#include "mcml/transport.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace ssslab {
namespace {

void BM_PhiloxUniform(benchmark::State& state) {
    RngStream rng(1, rng_domain::kTest, 0);
    for (auto _ : state) benchmark::DoNotOptimize(rng.uniform());
}
BENCHMARK(BM_PhiloxUniform);

void BM_PhiloxGroup(benchmark::State& state) {
    std::uint64_t out[2 * kPhiloxGroup];
    std::uint32_t c = 0;
    const auto path = static_cast<PhiloxPath>(state.range(0));
    if (!philox_path_available(path)) {
        state.SkipWithError("this CPU lacks the path");
        return;
    }
    for (auto _ : state) {
        philox4x32_10_group_on(path, 1, 2, c, 3, 4, 5, out);
        benchmark::DoNotOptimize(out);
        c += kPhiloxGroup;
    }
    state.SetLabel(to_string(path));
    state.SetItemsProcessed(state.iterations() * kPhiloxGroup);
}
BENCHMARK(BM_PhiloxGroup)->Arg(0)->Arg(1)->Arg(2);

void BM_ExpZiggurat(benchmark::State& state) {
    RngStream rng(1, rng_domain::kTest, 0);
    for (auto _ : state) benchmark::DoNotOptimize(ExpZiggurat::sample(rng));
}
BENCHMARK(BM_ExpZiggurat);

void BM_ExpByLog(benchmark::State& state) {
    RngStream rng(1, rng_domain::kTest, 0);
    for (auto _ : state) benchmark::DoNotOptimize(-std::log(rng.uniform()));
}
BENCHMARK(BM_ExpByLog);

void BM_SinCos2Pi(benchmark::State& state) {
    double u = 0.1234, s, c;
    for (auto _ : state) {
        sincos_2pi(u, &s, &c);
        benchmark::DoNotOptimize(s);
        benchmark::DoNotOptimize(c);
        u = u + 0.618033988749895 >= 1 ? u - 0.381966011250105 : u + 0.618033988749895;
    }
}
BENCHMARK(BM_SinCos2Pi);

void BM_LibmSinCos(benchmark::State& state) {
    double u = 0.1234, s, c;
    for (auto _ : state) {
        ::sincos(6.283185307179586 * u, &s, &c);
        benchmark::DoNotOptimize(s);
        benchmark::DoNotOptimize(c);
        u = u + 0.618033988749895 >= 1 ? u - 0.381966011250105 : u + 0.618033988749895;
    }
}
BENCHMARK(BM_LibmSinCos);

template <bool kCompat>
void BM_SpinDirection(benchmark::State& state) {
    RngStream rng(1, rng_domain::kTest, 0);
    const double g = static_cast<double>(state.range(0)) / 100.0;
    double ux = 0.3, uy = -0.5, uz = std::sqrt(1 - 0.34);
    for (auto _ : state) {
        mcml::spin_direction<kCompat>(g, ux, uy, uz, rng);
        benchmark::DoNotOptimize(uz);
    }
}
BENCHMARK(BM_SpinDirection<false>)->Arg(0)->Arg(75);
BENCHMARK(BM_SpinDirection<true>)->Arg(0)->Arg(75);

}  // namespace
}  // namespace ssslab

BENCHMARK_MAIN();
