// `ssslab bench --realtime`: the real-time renderer's passes on the built-in scenes (issue 13):
// the rasterizer ("raster"), the separable SSS pass on a G-buffer made from that frame ("sss"),
// and the two in sequence ("frame"), with 1 thread and all threads, each the fastest of --repeat
// runs. The SSS pass is set beside a streaming floor measured in the same run: the bytes the
// pass reads and writes (per 1D pass irradiance, view z and material in, 3 floats out; rank 1,
// so 2 passes) moved by a plain parallel loop with the same thread count.
//
// The G-buffer: view z from the frame, material = the index of the hit shape's medium material
// among the scene's medium materials (-1: a diffuse shape or nothing), irradiance (1, 1, 1)
// everywhere (the pass's cost does not depend on the values). Every medium material gets the
// same kernel: 17 taps of the rank-1 SVD of Skin1's kernel from a short MCML run on the thesis
// grid (Freude14 Table 6.1), whatever the scene's preset.
#include "approx/kernel2d.h"
#include "approx/model_spec.h"
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/material.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "experiments/cli/bench_volpath.h"
#include "experiments/cli/common.h"
#include "mcml/profile.h"
#include "realtime/raster.h"
#include "realtime/sss_pass.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::cli {

namespace {

constexpr int kTaps = 17;

/// 17 taps of the rank-1 SVD of Skin1's kernel per channel, from `photons` MCML photons per
/// channel on the thesis grid.
realtime::SssMaterialKernel skin1_kernel(std::int64_t photons, int threads) {
    const Medium skin = *find_material("Skin1");
    mcml::ProfileOptions po;
    po.seed = 1;
    po.threads = threads;
    po.budget.photons = photons;
    const mcml::ProfileRun run = mcml::simulate_profile(skin, mcml::freude14_grid(skin), po);
    const approx::KernelGrid kg = approx::KernelGrid::from_profile(run.profile, 1);
    const approx::ModelSpec spec = approx::parse_model("svd:rank=1");
    std::array<approx::ModelResult, 3> r;
    for (int c = 0; c < 3; ++c) {
        approx::ModelContext ctx;
        ctx.material = "Skin1";
        ctx.channel = c;
        r[static_cast<size_t>(c)] =
            approx::build_model(spec, approx::Kernel2D(run.profile, c, kg), ctx);
    }
    return realtime::make_material_kernel({&r[0].kernel, &r[1].kernel, &r[2].kernel}, kTaps);
}

/// The G-buffer of a frame (see the file comment).
realtime::SssGBuffer gbuffer(const Scene& s, const realtime::RasterFrame& f,
                             const std::vector<int>& medium_index) {
    realtime::SssGBuffer g;
    g.width = f.width;
    g.height = f.height;
    const size_t n = g.pixels();
    g.irradiance.assign(3 * n, 1.0f);
    g.view_z.resize(n);
    g.material.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const int shape = f.shape[i];
        g.material[i] =
            shape < 0
                ? -1
                : medium_index[static_cast<size_t>(s.shapes[static_cast<size_t>(shape)].material)];
        g.view_z[i] = static_cast<float>(f.view_z[i]);
    }
    return g;
}

/// One 1D pass's traffic: read irradiance, view z and material, write 3 floats, per pixel.
void stream_pass(const realtime::SssGBuffer& g, const std::vector<float>& in,
                 std::vector<float>& out) {
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, g.pixels(), 16384), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                const float w =
                    (g.material[i] >= 0 ? 1.0f : 0.5f) * (g.view_z[i] > 0 ? 1.0f : 0.0f);
                for (size_t c = 0; c < 3; ++c) out[3 * i + c] = in[3 * i + c] * w;
            }
        });
}

struct Row {
    std::string scene;
    int threads;
    std::string pass;
    double ms;
    double floor_ms;  ///< < 0: none
};

std::string num(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

}  // namespace

int run_realtime_bench(int threads, bool quick, const std::string& scenes_dir, int width,
                       int height, int repeat, const std::string& only, const std::string& csv) {
    const std::vector<std::filesystem::path> files = list_scenes(scenes_dir, only);
    // MCML and the kernel build are set-up, not timed; the timed work runs in explicit arenas.
    const std::int64_t photons = quick ? 2'000 : 20'000;
    auto t0 = Clock::now();
    const std::vector<realtime::SssMaterialKernel> kernel = {skin1_kernel(photons, threads)};
    std::printf(
        "real-time passes, %d x %d, 1 and %d threads, fastest of %d run%s; SSS kernel: Skin1 "
        "svd:rank=1, %d taps (%lld MCML photons per channel, %.2f s set-up)\n",
        width, height, threads, repeat, repeat == 1 ? "" : "s", kTaps,
        static_cast<long long>(photons), seconds_since(t0));
    std::vector<int> counts = {1};
    if (threads > 1) counts.push_back(threads);

    std::vector<Row> rows;
    std::printf("%-10s %11s %7s %-7s %10s %10s %7s\n", "scene", "W x H", "threads", "pass", "ms",
                "floor_ms", "ratio");
    for (const auto& file : files) {
        const Scene s = read_scene(file.string());
        std::vector<int> medium_index;
        int media = 0;
        for (const auto& m : s.materials)
            medium_index.push_back(m.kind == SceneMaterial::Kind::kMedium ? media++ : -1);
        const std::vector<realtime::SssMaterialKernel> kernels(static_cast<size_t>(media),
                                                               kernel[0]);
        size_t triangles = 0;
        for (const auto& sh : s.shapes) triangles += sh.mesh.triangles.size();
        realtime::SssParams p;
        p.tan_half = std::tan(s.camera.fov_y_deg * std::numbers::pi / 360.0);
        p.aspect = static_cast<double>(width) / height;
        p.unit_mm = s.unit_mm;
        for (int t : counts) {
            tbb::task_arena arena(t);
            arena.execute([&] {
                realtime::RasterFrame f;
                const double raster =
                    best_seconds(repeat, [&] { f = realtime::rasterize(s, {}, width, height); });
                const realtime::SssGBuffer g = gbuffer(s, f, medium_index);
                std::vector<float> out;
                const double sss =
                    best_seconds(repeat, [&] { out = realtime::sss_pass(g, kernels, p); });
                std::vector<float> a(g.irradiance.size()), b(g.irradiance.size());
                const double floor = best_seconds(repeat, [&] {
                    stream_pass(g, g.irradiance, a);
                    stream_pass(g, a, b);
                });
                const double frame = best_seconds(repeat, [&] {
                    const realtime::RasterFrame ff = realtime::rasterize(s, {}, width, height);
                    out = realtime::sss_pass(gbuffer(s, ff, medium_index), kernels, p);
                });
                rows.push_back({s.name, t, "raster", raster * 1e3, -1});
                rows.push_back({s.name, t, "sss", sss * 1e3, floor * 1e3});
                rows.push_back({s.name, t, "frame", frame * 1e3, -1});
            });
            for (size_t k = rows.size() - 3; k < rows.size(); ++k) {
                const Row& r = rows[k];
                char size[32], fl[32] = "", ratio[32] = "";
                std::snprintf(size, sizeof size, "%dx%d", width, height);
                if (r.floor_ms >= 0) {
                    std::snprintf(fl, sizeof fl, "%.3f", r.floor_ms);
                    std::snprintf(ratio, sizeof ratio, "%.2f", r.ms / r.floor_ms);
                }
                std::printf("%-10s %11s %7d %-7s %10.3f %10s %7s\n", r.scene.c_str(), size,
                            r.threads, r.pass.c_str(), r.ms, fl, ratio);
            }
        }
        std::printf("%-10s %zu triangles, %d medium material%s\n", "", triangles, media,
                    media == 1 ? "" : "s");
    }
    std::printf(
        "raster: realtime::rasterize of the scene (1 sample per pixel); sss: the separable SSS "
        "pass (follow-surface, no jitter) on the frame's G-buffer (irradiance 1); frame: both "
        "and the G-buffer fill in sequence. floor_ms: a parallel loop streaming the bytes the SSS "
        "pass reads and writes (2 x (20 B in, 12 B out) per pixel); ratio = ms / floor_ms.\n");

    if (!csv.empty()) {
        std::ostringstream o;
        o << "scene,width,height,threads,pass,ms,floor_ms\n";
        for (const Row& r : rows)
            o << r.scene << ',' << width << ',' << height << ',' << r.threads << ',' << r.pass
              << ',' << num(r.ms) << ',' << (r.floor_ms >= 0 ? num(r.floor_ms) : "") << '\n';
        write_with_provenance(csv, o.str(),
                              "ssslab bench --realtime: provenance of " + csv +
                                  " (timings depend on the machine: see host_threads)");
        std::printf("wrote %s (+ .toml)\n", csv.c_str());
    }
    return 0;
}

}  // namespace ssslab::cli
