// [outputs.spot_light]: the real-time renderer's direct light from spot lights (core/light.h,
// KHR_lights_punctual's cone) against the path tracer's, scene by scene: the lighting pass's
// surface layer (its shadow map, the cone's falloff; supersampled, box-filtered to pixels) and
// volpath at max_depth = 1 (direct light only, the same light sampled by next-event estimation),
// compared with core/image_compare.h: per channel the image means and their z, the block
// chi-square, and the noise-corrected RMS difference relative to the path tracer's mean. A study
// plugin (experiments/runner/study.h): its files, metrics and report section are returned as data.
//
//   [outputs.spot_light]
//   scenes = ["../scenes/lights/spot.toml"]   # scene files, relative to the config
//   width = 128, height = 128                 # 0: the scene camera's
//   spp = 256                                 # the path tracer's samples per pixel
//   supersample = 4                           # the real-time frame's samples per pixel side
//   block = 8                                 # the chi-square's blocks of pixels
//   quick_spp = 32                            # under --quick
//
// Recomputed on every run (a few seconds at these sizes).
#include "core/format.h"
#include "core/image_compare.h"
#include "core/scene.h"
#include "experiments/runner/report.h"
#include "experiments/runner/study.h"
#include "realtime/lighting.h"
#include "realtime/raster.h"
#include "volpath/render.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

namespace ssslab::runner {
namespace {

struct SpotLightSpec {
    std::vector<std::string> scenes;
    int width = 128, height = 128;
    std::int64_t spp = 256, quick_spp = 32;
    int supersample = 4, block = 8;
};

// The real-time frame's surface layer box-filtered to pixels, as an estimate without noise.
ImageEstimate realtime_surface(const Scene& scene, int w, int h, int ss, double& ms) {
    realtime::RasterOptions ro;
    ro.supersample = ss;
    const auto t0 = std::chrono::steady_clock::now();
    const realtime::RasterFrame frame = realtime::rasterize(scene, ro, w, h);
    const realtime::RasterCamera cam = realtime::RasterCamera::from_scene(scene.camera, w, h);
    realtime::LightingOptions lo;
    const realtime::GBuffer g = realtime::shade(scene, cam, frame, lo);
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ImageEstimate e;
    e.width = w;
    e.height = h;
    e.mean.assign(static_cast<std::size_t>(w) * h * 3, 0.0);
    e.var.assign(e.mean.size(), 0.0);
    e.source = "realtime";
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int j = 0; j < ss; ++j)
                    for (int i = 0; i < ss; ++i)
                        sum += g.surface[3 * frame.sample_index(x * ss + i, y * ss + j) +
                                         static_cast<std::size_t>(c)];
                e.mean[(static_cast<std::size_t>(y) * w + x) * 3 + c] = sum / (ss * ss);
            }
    return e;
}

class SpotLightStudy final : public Study {
  public:
    explicit SpotLightStudy(SpotLightSpec s) : spec_(std::move(s)) {}

    std::string describe() const override {
        return "spot_light (" + std::to_string(spec_.scenes.size()) + " scenes, computed when run)";
    }

    StudyResult run(const StudyInputs& in) const override {
        StudyResult out;
        StudySection& sec = out.section;
        sec.id = "spot-light";
        sec.title = "Spot lights: the real-time frame against the path tracer";
        sec.paragraphs.push_back(
            "Direct light only: the real-time lighting pass's surface layer (one shadow map per "
            "spot, the KHR_lights_punctual cone; " +
            std::to_string(spec_.supersample) + " x " + std::to_string(spec_.supersample) +
            " samples a pixel) against the path tracer at max_depth = 1 (the same light by "
            "next-event estimation). Per channel: the image means with the path tracer's "
            "standard error and their z; the chi-square of " +
            std::to_string(spec_.block) + " x " + std::to_string(spec_.block) +
            " pixel blocks over its degrees of freedom (1 within the noise); the RMS difference "
            "beyond the path tracer's noise, relative to its image mean, with its standard "
            "error. Differences show the real-time frame's own errors (the shadow map's texels "
            "at shadow edges), not the light model, which both read.");
        std::ostringstream csv;
        csv << "scene,channel,realtime_mean,volpath_mean,volpath_se,z_mean,chi2_per_dof,blocks,"
               "rel_rms,rel_rms_se,realtime_ms,volpath_s\n";
        const std::int64_t spp = in.ctx.quick ? spec_.quick_spp : spec_.spp;
        int n_scenes = 0;
        double worst_rms = 0;
        for (const std::string& path : spec_.scenes) {
            const Scene scene = read_scene(path);
            const int w = spec_.width > 0 ? spec_.width : scene.camera.width;
            const int h = spec_.height > 0 ? spec_.height : scene.camera.height;
            double rt_ms = 0;
            const ImageEstimate rt = realtime_surface(scene, w, h, spec_.supersample, rt_ms);
            volpath::RenderOptions vo;
            vo.seed = in.ctx.seed;
            vo.threads = in.ctx.threads;
            vo.width = w;
            vo.height = h;
            vo.max_depth = 1;
            vo.budget.samples = spp;
            vo.cancel = in.ctx.cancel;
            const volpath::RenderResult vp = volpath::render(scene, vo);
            if (vp.run.reason == BatchStop::kInterrupted) {
                out.interrupted = true;
                return out;
            }
            const ImageEstimate ref = estimate_with_stderr(vp.image, "radiance", path);
            const ImageComparison cmp = compare_images(rt, ref, spec_.block);
            ++out.computed;
            ++n_scenes;
            for (int c = 0; c < 3; ++c) {
                std::vector<double> a, va, b, vb;
                for (std::size_t i = static_cast<std::size_t>(c); i < rt.mean.size(); i += 3) {
                    a.push_back(rt.mean[i]);
                    va.push_back(0.0);
                    b.push_back(ref.mean[i]);
                    vb.push_back(ref.var[i]);
                }
                const NoiseCorrectedRms nr = noise_corrected_rms(a, va, b, vb);
                const ImageMean vm = image_mean(ref, c);
                const double rel = vm.mean > 0 ? nr.rms / vm.mean : 0;
                const double rel_se = vm.mean > 0 ? nr.rms_se / vm.mean : 0;
                worst_rms = std::max(worst_rms, rel);
                const std::string ch = kChannelNames[c];
                const double chi2_dof = cmp.dof[static_cast<std::size_t>(c)] > 0
                                            ? cmp.chi2[static_cast<std::size_t>(c)] /
                                                  cmp.dof[static_cast<std::size_t>(c)]
                                            : 0;
                csv << scene.name << "," << ch << "," << format_g(cmp.mean_a[c], 8) << ","
                    << format_g(vm.mean, 8) << "," << format_g(vm.se, 4) << ","
                    << format_g(cmp.z_mean[c], 4) << "," << format_g(chi2_dof, 4) << ","
                    << cmp.dof[static_cast<std::size_t>(c)] << "," << format_g(rel, 4) << ","
                    << format_g(rel_se, 3) << "," << format_g(rt_ms, 4) << ","
                    << format_g(vp.seconds, 4) << "\n";
                const std::string base = "spot_light." + scene.name + "." + ch + ".";
                out.metrics.push_back({base + "realtime_mean", "1", cmp.mean_a[c], 0, false, 1e-6});
                out.metrics.push_back({base + "volpath_mean", "1", vm.mean, vm.se, true, 0});
                out.metrics.push_back({base + "rel_rms", "1", rel, rel_se, true, 0});
            }
        }
        out.files["spot_light.csv"] = csv.str();
        sec.tables.push_back({"Per scene and channel (spot_light/spot_light.csv)", csv.str()});
        out.summary = std::to_string(n_scenes) + " scene" + (n_scenes == 1 ? "" : "s") +
                      ", largest relative RMS difference beyond the noise " +
                      format_g(worst_rms, 3);
        return out;
    }

  private:
    SpotLightSpec spec_;
};

std::shared_ptr<const Study> read_spot_light_study(ConfigTable& t, const std::string& dir) {
    SpotLightSpec s;
    s.scenes = read_scene_files(t, dir, volpath::check_renderable);
    s.width = static_cast<int>(t.integer("width", 128, Range::closed(0, 16384)));
    s.height = static_cast<int>(t.integer("height", 128, Range::closed(0, 16384)));
    s.spp = t.integer("spp", 256, Range::closed(2, 1e9));
    s.quick_spp = t.integer("quick_spp", 32, Range::closed(2, 1e9));
    s.supersample = static_cast<int>(t.integer("supersample", 4, Range::closed(1, 16)));
    s.block = static_cast<int>(t.integer("block", 8, Range::closed(1, 1024)));
    return std::make_shared<SpotLightStudy>(std::move(s));
}

}  // namespace
}  // namespace ssslab::runner

SSSLAB_REGISTER_STUDY(spot_light, ssslab::runner::read_spot_light_study)
