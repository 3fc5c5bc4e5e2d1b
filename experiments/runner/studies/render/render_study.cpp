// [outputs.render]: ground-truth images of scene files through the runner's artifact cache, with
// the renderer's speed and its time to 1 % relative error (issue 6's benchmark). A study plugin
// (experiments/runner/study.h): its files, metrics and report section are returned as data.
//
//   [outputs.render]
//   scenes = ["../scenes/skin.toml", ...]  # relative to the config file
//   spp = 64                # samples per pixel (or seconds = ...; one of them)
//   width = 512             # optional: override every scene camera's size
//   height = 512
//   reference_factor = 4    # an independent reference with this many times the samples (0: none)
//   quick_factor = 0.125    # --quick multiplies spp (or seconds) by this (at least 16 spp) ...
//   quick_size = 64         # ... and renders at most this many pixels wide and high
//
// The renders (scene x role "main" / "reference") are artifacts of scene_renders.h.
//
// results/<name>/render/: <scene>.exr and .png (the main run), summary.csv (per scene: size, spp,
// seconds, rays/s, paths/s, the image mean per channel with its SE, the image's relative RMS
// standard error and the median pixel's, the times to 1 % both imply, and with a reference the
// measured relative RMS error, with the reference's own noise taken out, and the time to 1 % it
// implies) and <scene>_convergence.csv (error against time from the snapshots). Times to 1 %
// are extrapolations t x (e / 0.01)^2 from the measured error e (Monte Carlo error falls as
// 1 / sqrt(time)); the snapshots show whether it does. Metrics: per scene and channel the image
// means of radiance and subsurface with their SE (<scene>.<R|G|B>.radiance_mean,
// .subsurface_mean).
#include "core/film_image.h"
#include "core/format.h"
#include "core/scene.h"
#include "core/stats.h"
#include "experiments/runner/study.h"
#include "volpath/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

namespace ssslab::runner {
namespace {

struct RenderSpec {
    std::vector<std::string> scenes;  ///< resolved paths
    SampleBudget budget;              ///< samples (spp) or seconds
    int width = 0, height = 0;        ///< 0: the scene camera's
    double reference_factor = 4.0;    ///< 0: no reference
    double quick_factor = 0.125;
    int quick_size = 64;
};

// sqrt(sum (a - ref)^2 / sum ref^2) over pixels and channels of two RGB layers.
double rel_rms(const ImageLayer& a, const ImageLayer& ref) {
    double d = 0, n = 0;
    for (std::size_t i = 0; i < a.pixels().size(); ++i) {
        const double r = ref.pixels()[i], x = a.pixels()[i] - r;
        d += x * x;
        n += r * r;
    }
    return n > 0 ? std::sqrt(d / n) : 0.0;
}

// Monte Carlo error falls as 1 / sqrt(time): the time at which the error e after `seconds`
// reaches 1 %.
double t_1pct(double seconds, double e) {
    return seconds * (e / 0.01) * (e / 0.01);
}

// Per channel the image means of radiance (into mean, se) and subsurface with their standard
// errors, as metrics <scene>.<channel>.radiance_mean and .subsurface_mean.
void radiance_means(const LayeredImage& img, const std::string& scene, std::array<double, 3>& mean,
                    std::array<double, 3>& se, std::vector<Metric>& metrics) {
    const int w = img.width(), h = img.height();
    const double npix = static_cast<double>(w) * h;
    const ImageLayer& L = img.layer("radiance");
    const ImageLayer& E = img.layer("radiance.stderr");
    const ImageLayer& S = img.layer("subsurface");
    const ImageLayer& SE = img.layer("subsurface.stderr");
    for (int c = 0; c < 3; ++c) {
        double s = 0, v = 0, ss = 0, sv = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                s += L.at(x, y, c);
                v += static_cast<double>(E.at(x, y, c)) * E.at(x, y, c);
                ss += S.at(x, y, c);
                sv += static_cast<double>(SE.at(x, y, c)) * SE.at(x, y, c);
            }
        mean[static_cast<size_t>(c)] = s / npix;
        se[static_cast<size_t>(c)] = std::sqrt(v) / npix;
        const std::string base = scene + "." + std::string(1, "RGB"[c]);
        metrics.push_back({base + ".radiance_mean", "1", s / npix, std::sqrt(v) / npix, true, 0});
        metrics.push_back(
            {base + ".subsurface_mean", "1", ss / npix, std::sqrt(sv) / npix, true, 0});
    }
}

class RenderStudy final : public Study {
  public:
    explicit RenderStudy(RenderSpec s) : spec_(std::move(s)) {}

    std::string describe() const override {
        return "render (" + std::to_string(spec_.scenes.size()) +
               " scenes, rendered or reused when run)";
    }
    double quick_factor() const override { return spec_.quick_factor; }

    StudyResult run(const StudyInputs& in) const override {
        StudyResult out;
        StudySection& sec = out.section;
        sec.id = "render";
        sec.title = "Ground-truth images";
        sec.paragraphs.push_back(
            std::string("The volumetric path tracer ") + volpath::render_engine_version() +
            " on each scene. Times to 1 % are extrapolations t (e / 0.01)^2 from the measured "
            "relative error e: the run's own (image RMS of the per-pixel standard errors over the "
            "RMS radiance, and the median pixel's), and, with a reference, the measured relative "
            "RMS error against an independent run with more samples, its own noise taken out. "
            "Convergence tables show the error after 4, 8, 16, ... samples per pixel. All columns "
            "in render/summary.csv.");
        std::ostringstream summary, table;
        summary << "scene,width,height,spp,seconds,threads,rays,mrays_per_s,paths_per_s,mean_R,"
                   "se_R,mean_G,se_G,mean_B,se_B,image_rel_se,median_pixel_rel_se,t_1pct_image_s,"
                   "t_1pct_median_pixel_s,reference_spp,rel_rmse_vs_reference,reference_rel_se,"
                   "rel_rmse_corrected,t_1pct_from_reference_s,median_pixel_measured,"
                   "z2_median_ratio,t_1pct_median_pixel_from_reference_s\n";
        table << "scene,size,spp,seconds,M rays/s,image rel. SE,t to 1 % (image) s,"
                 "t to 1 % (median pixel) s\n";
        for (const std::string& path : spec_.scenes)
            if (!run_scene(path, in, out, summary, table)) {
                out.interrupted = true;
                return out;
            }
        out.files["summary.csv"] = summary.str();
        sec.tables.push_back({"Per scene (render/summary.csv)", table.str()});
        return out;
    }

  private:
    // The scene's main render and reference (through the cache), its files, metrics, rows and
    // figure; false if interrupted.
    bool run_scene(const std::string& path, const StudyInputs& in, StudyResult& out,
                   std::ostringstream& summary, std::ostringstream& table) const {
        const RenderStudyContext& ctx = in.ctx;
        const Scene scene = read_scene(path);
        int w = spec_.width > 0 ? spec_.width : scene.camera.width;
        int h = spec_.height > 0 ? spec_.height : scene.camera.height;
        SampleBudget b = spec_.budget;
        if (ctx.quick) {
            const double f = std::min(1.0, static_cast<double>(spec_.quick_size) / std::max(w, h));
            w = std::max(1, static_cast<int>(std::lround(w * f)));
            h = std::max(1, static_cast<int>(std::lround(h * f)));
            if (b.samples)
                b.samples = std::max<std::int64_t>(
                    16, std::llround(static_cast<double>(*b.samples) * spec_.quick_factor));
            if (b.seconds) b.seconds = *b.seconds * spec_.quick_factor;
        }
        std::optional<CachedRender> main = cached_render(scene, "main", w, h, b, ctx, *in.cache);
        if (!main) return false;
        (main->computed_now ? out.computed : out.reused) += 1;
        std::optional<CachedRender> ref;
        if (spec_.reference_factor > 0) {
            SampleBudget rb = b;
            if (rb.samples)
                rb.samples = std::llround(static_cast<double>(*b.samples) * spec_.reference_factor);
            if (rb.seconds) rb.seconds = *b.seconds * spec_.reference_factor;
            ref = cached_render(scene, "reference", w, h, rb, ctx, *in.cache);
            if (!ref) return false;
            (ref->computed_now ? out.computed : out.reused) += 1;
        }
        const CachedRender& R = *main;
        out.files[scene.name + ".exr"] = encode_exr(R.image, scene.name + ".exr");
        out.files[scene.name + ".png"] = encode_png_preview(R.image, "radiance");
        const double npix = static_cast<double>(w) * h;
        std::array<double, 3> mean{}, se{};
        radiance_means(R.image, scene.name, mean, se, out.metrics);
        const RelativeError own = volpath::radiance_rel_error(R.image);
        const double image_rel_se = own.rms, median_rel_se = own.median;
        const double mrays = R.seconds > 0 ? static_cast<double>(R.rays) / R.seconds * 1e-6 : 0;
        const double paths = R.seconds > 0 ? npix * static_cast<double>(R.spp) / R.seconds : 0;
        summary << scene.name << "," << w << "," << h << "," << R.spp << ","
                << format_g(R.seconds, 6) << ","
                << (ctx.threads > 0 ? std::to_string(ctx.threads) : std::string("all")) << ","
                << R.rays << "," << format_g(mrays, 6) << "," << format_g(paths, 6);
        for (int c = 0; c < 3; ++c)
            summary << "," << format_g(mean[static_cast<size_t>(c)], 6) << ","
                    << format_g(se[static_cast<size_t>(c)], 6);
        summary << "," << format_g(image_rel_se, 6) << "," << format_g(median_rel_se, 6) << ","
                << format_g(t_1pct(R.seconds, image_rel_se), 6) << ","
                << format_g(t_1pct(R.seconds, median_rel_se), 6);
        if (ref) {
            // The final image against the reference: volpath::measured_error (the image RMS and
            // the median pixel, the reference's noise taken out); the snapshots, which hold no
            // standard errors, by their RMS difference with the same correction.
            const volpath::MeasuredError me = volpath::measured_error(R.image, ref->image);
            const double ref_rel_se = me.reference.rms;
            const ImageLayer& RL = ref->image.layer("radiance");
            auto corrected = [&](double e) {
                return std::sqrt(std::max(0.0, e * e - ref_rel_se * ref_rel_se));
            };
            std::string conv = "spp,seconds,rel_rmse,rel_rmse_corrected\n";
            for (const auto& [spp, secs] : R.snapshots) {
                const double e = rel_rms(R.snapshot(spp), RL);
                conv += std::to_string(spp) + "," + format_g(secs, 6) + "," + format_g(e, 6) + "," +
                        format_g(corrected(e), 6) + "\n";
            }
            conv += std::to_string(R.spp) + "," + format_g(R.seconds, 6) + "," +
                    format_g(me.rel_rmse, 6) + "," + format_g(me.rel_rmse_corrected, 6) + "\n";
            out.files[scene.name + "_convergence.csv"] = conv;
            summary << "," << ref->spp << "," << format_g(me.rel_rmse, 6) << ","
                    << format_g(ref_rel_se, 6) << "," << format_g(me.rel_rmse_corrected, 6) << ","
                    << format_g(t_1pct(R.seconds, me.rel_rmse_corrected), 6) << ","
                    << format_g(me.median_pixel, 6) << "," << format_g(me.z2_median_ratio, 6) << ","
                    << format_g(t_1pct(R.seconds, me.median_pixel), 6);
        } else {
            summary << ",,,,,,,,";
        }
        summary << "\n";
        table << scene.name << "," << w << " x " << h << "," << R.spp << ","
              << format_f(R.seconds, 1) << "," << format_f(mrays, 2) << ","
              << format_g(image_rel_se, 3) << "," << format_g(t_1pct(R.seconds, image_rel_se), 3)
              << "," << format_g(t_1pct(R.seconds, median_rel_se), 3) << "\n";
        out.section.figures.push_back(
            {"render/" + scene.name + ".png", scene.name + ", " + std::to_string(R.spp) + " spp"});
        if (!ctx.quiet)
            std::printf(
                "  %s %s: %d x %d, %llu spp in %.1f s, %.2f M rays/s, image rel. SE %.3g -> 1 %% "
                "in %.3g s\n",
                R.computed_now ? "rendered" : "reused  ", scene.name.c_str(), w, h,
                static_cast<unsigned long long>(R.spp), R.seconds, mrays, image_rel_se,
                t_1pct(R.seconds, image_rel_se));
        return true;
    }

    RenderSpec spec_;
};

// Every scene is read and validated here, so a bad scene fails the config with the scene file's
// line.
std::shared_ptr<const Study> read_render_study(ConfigTable& t, const std::string& config_dir) {
    RenderSpec s;
    s.scenes = read_scene_files(t, config_dir, volpath::check_renderable);
    if (auto v = t.optional_integer("spp", Range::closed(2, 1e9))) s.budget.samples = *v;
    if (auto v = t.optional_number("seconds", Range::left_open(0, 1e7))) s.budget.seconds = *v;
    if (!s.budget.any()) t.fail("spp", "give a budget: spp = <samples per pixel> or seconds = <s>");
    if (s.budget.samples && s.budget.seconds)
        t.fail("seconds", "give spp or seconds, not both (a render is reproducible with spp)");
    s.width = static_cast<int>(t.integer("width", 0, Range::closed(0, 16384)));
    s.height = static_cast<int>(t.integer("height", 0, Range::closed(0, 16384)));
    if ((s.width == 0) != (s.height == 0))
        t.fail("width", "give both width and height, or neither");
    s.reference_factor = t.number("reference_factor", 4.0, Range::closed(0, 1000));
    if (s.reference_factor > 0 && s.reference_factor < 1)
        t.fail("reference_factor",
               "a reference needs at least the main run's budget (>= 1), or 0 for none");
    s.quick_factor = t.number("quick_factor", 0.125, Range::left_open(0, 1));
    s.quick_size = static_cast<int>(t.integer("quick_size", 64, Range::closed(4, 16384)));
    return std::make_shared<RenderStudy>(std::move(s));
}

}  // namespace
}  // namespace ssslab::runner

SSSLAB_REGISTER_STUDY(render, ssslab::runner::read_render_study)
