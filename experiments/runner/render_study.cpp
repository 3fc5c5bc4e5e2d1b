#include "experiments/runner/render_study.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/format.h"
#include "core/hash.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "core/stats.h"
#include "experiments/runner/report.h"
#include "experiments/runner/runner.h"
#include "volpath/render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <sstream>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

constexpr const char* kKind = "render";

struct RenderNode {
    std::string scene_path, role;  // role: "main" | "reference"
    Scene scene;
    volpath::RenderOptions options;
    std::string key, key_text;
};

// What a render depends on: the scene's content (core/scene.h add_to_key: resolved values,
// meshes, grid files), size, budget, seed, the renderer's version (which changes whenever its
// results would). The same scene description keys the renderer's checkpoints.
ContentKey render_key(const RenderNode& n) {
    ContentKey k(kKind);
    k.add("engine", volpath::render_engine_version()).add("role", n.role);
    add_to_key(k, n.scene);
    k.add("width", n.options.width)
        .add("height", n.options.height)
        .add("seed", n.options.seed)
        .add("roulette_depth", n.options.roulette_depth)
        .add("long_path_events", n.options.long_path_events)
        .add("index_matched_nee", n.options.index_matched_nee);
    if (n.options.budget.samples) k.add("spp", *n.options.budget.samples);
    if (n.options.budget.seconds) k.add("seconds", *n.options.budget.seconds);
    return k;
}

std::uint64_t derive_render_seed(std::uint64_t seed, const std::string& scene,
                                 const std::string& role) {
    const std::string h = hash_hex("render\n" + std::to_string(seed) + "\n" + scene + "\n" + role);
    return std::stoull(h.substr(0, 15), nullptr, 16);
}

struct Rendered {
    LayeredImage image{1, 1};
    double seconds = 0;
    std::uint64_t spp = 0, rays = 0;
    bool computed_now = false, resumed = false;
    std::vector<std::pair<std::uint64_t, double>> snapshots;  // spp, seconds
};

std::string snapshot_layer(std::uint64_t spp) {
    return "snapshot_" + std::to_string(spp);
}

// Stores the render with its snapshots' radiance as extra layers.
Rendered compute(const RenderNode& n, const RenderStudyContext& ctx, const ArtifactCache& cache,
                 bool& interrupted) {
    volpath::RenderOptions o = n.options;
    o.threads = ctx.threads;
    o.cancel = ctx.cancel;
    o.checkpoint_path = cache.checkpoint_prefix(kKind, n.key).string() + ".ckpt";
    o.checkpoint_seconds = ctx.checkpoint_seconds;
    o.snapshots = n.role == "main";
    o.on_resume = [&](const BatchProgress& p) {
        if (ctx.quiet) return;
        std::printf("  resuming %s (%s) from %llu%s spp (checkpoint of [%s])\n",
                    n.scene.name.c_str(), n.role.c_str(),
                    static_cast<unsigned long long>(p.samples),
                    o.budget.samples ? (" of " + std::to_string(*o.budget.samples)).c_str() : "",
                    n.key.substr(0, 16).c_str());
        std::fflush(stdout);
    };
    volpath::RenderResult r = volpath::render(n.scene, o);
    Rendered out;
    if (r.interrupted) {
        interrupted = true;
        return out;
    }
    const std::size_t pixels =
        static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height);
    std::string snaps;
    for (const BatchSnapshot& s : r.run.snapshots) {
        if (s.samples >= r.spp) continue;
        ImageLayer& l = r.image.add_layer(snapshot_layer(s.samples), 3);
        for (std::size_t i = 0; i < pixels; ++i)
            for (int c = 0; c < 3; ++c)
                l.pixels()[i * 3 + static_cast<size_t>(c)] = static_cast<float>(
                    s.mean[i * volpath::RenderLayout::kPerPixel + static_cast<size_t>(c)]);
        snaps +=
            (snaps.empty() ? "" : ",") + std::to_string(s.samples) + ":" + format_f(s.seconds, 4);
    }
    r.image.metadata()["ssslab.snapshots"] = snaps;
    r.image.metadata()["ssslab.rays"] = std::to_string(r.rays);
    std::ostringstream m;
    m << "[artifact]\nkind = \"render\"\nkey = \"" << n.key << "\"\nscene = \"" << n.scene.name
      << "\"\nrole = \"" << n.role << "\"\nengine = \"" << volpath::render_engine_version()
      << "\"\nseed = " << o.seed << "\nspp = " << r.spp << "\nrays = " << r.rays
      << "\nseconds = " << format_f(r.seconds, 4)
      << "\nresumed = " << (r.run.resumed ? "true" : "false") << "\nrevision = \"" << git_revision()
      << "\"\ndate_utc = \"" << utc_now() << "\"\n";
    std::istringstream kt(n.key_text);
    m << "\n# canonical description of the key\n";
    for (std::string line; std::getline(kt, line);) m << "# " << line << "\n";
    cache.store(
        kKind, n.key,
        {{"image.exr", encode_exr(r.image, n.key + "/image.exr")}, {"manifest.toml", m.str()}});
    out.computed_now = true;
    out.resumed = r.run.resumed;
    return out;
}

Rendered load(const fs::path& dir) {
    Rendered out;
    out.image = read_exr((dir / "image.exr").string());
    auto doc = ConfigDocument::parse_file((dir / "manifest.toml").string());
    ConfigTable a = doc->root().require_table("artifact");
    out.seconds = a.number("seconds");
    out.spp = static_cast<std::uint64_t>(a.integer("spp"));
    out.rays = static_cast<std::uint64_t>(a.integer("rays"));
    const auto it = out.image.metadata().find("ssslab.snapshots");
    if (it != out.image.metadata().end()) {
        std::istringstream is(it->second);
        for (std::string item; std::getline(is, item, ',');) {
            const auto colon = item.find(':');
            if (colon == std::string::npos) continue;
            out.snapshots.push_back(
                {std::stoull(item.substr(0, colon)), std::stod(item.substr(colon + 1))});
        }
    }
    return out;
}

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

// The image's own relative RMS standard error sqrt(sum SE^2 / sum L^2) and the median pixel's
// relative SE (over pixel-channels that see anything).
void own_error(const LayeredImage& im, double& image_rel_se, double& median_rel_se) {
    const RelativeError r = volpath::radiance_rel_error(im);
    image_rel_se = r.rms;
    median_rel_se = r.median;
}

double t_1pct(double seconds, double e) {
    return seconds * (e / 0.01) * (e / 0.01);
}

// The node's image from the cache, rendered first if the cache lacks it; nullopt if
// interrupted (its checkpoint is kept).
std::optional<Rendered> render_node(RenderNode& n, const RenderStudyContext& ctx,
                                    const ArtifactCache& cache) {
    const ContentKey k = render_key(n);
    n.key = k.hex();
    n.key_text = k.text();
    if (auto dir = cache.find(kKind, n.key)) return load(*dir);
    if (!ctx.quiet) {
        std::printf("  rendering %s (%s, %d x %d, %s) ...\n", n.scene.name.c_str(), n.role.c_str(),
                    n.options.width, n.options.height,
                    n.options.budget.samples
                        ? (std::to_string(*n.options.budget.samples) + " spp").c_str()
                        : (format_g(*n.options.budget.seconds, 6) + " s").c_str());
        std::fflush(stdout);
    }
    bool interrupted = false;
    compute(n, ctx, cache, interrupted);
    if (interrupted) return std::nullopt;
    Rendered r = load(*cache.find(kKind, n.key));
    r.computed_now = true;
    return r;
}

}  // namespace

std::vector<std::string> read_scene_files(ConfigTable& t, const std::string& config_dir,
                                          const std::function<void(const Scene&)>& check) {
    const auto scenes = t.string_list("scenes");
    if (scenes.empty()) t.fail("scenes", "expected at least one scene file");
    std::set<std::string> names;
    std::vector<std::string> out;
    for (size_t i = 0; i < scenes.size(); ++i) {
        const std::string& f = scenes[i];
        const fs::path p = fs::path(f).is_absolute() ? fs::path(f) : fs::path(config_dir) / f;
        if (!fs::exists(p)) t.fail_item("scenes", i, "no scene file " + p.string());
        const Scene sc = read_scene(p.string());
        check(sc);
        if (!names.insert(sc.name).second)
            t.fail_item("scenes", i,
                        "two scenes are named \"" + sc.name + "\" (they name the output files)");
        out.push_back(p.lexically_normal().string());
    }
    return out;
}

RenderStudySpec read_render_study(ConfigTable& t, const std::string& config_dir) {
    RenderStudySpec s;
    s.enabled = true;
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
    return s;
}

namespace {

// The image of a render without its snapshot layers, written as <stage>/render/<name>.exr with
// a PNG preview; returned.
LayeredImage write_render_image(const LayeredImage& image, const std::string& name,
                                const fs::path& stage) {
    LayeredImage img(image.width(), image.height());
    for (const ImageLayer& l : image.layers())
        if (l.name().rfind("snapshot_", 0) != 0)
            img.add_layer(l.name(), l.channel_names(),
                          std::vector<float>(l.pixels().begin(), l.pixels().end()));
    img.metadata() = image.metadata();
    img.metadata().erase("ssslab.snapshots");
    write_exr(img, (stage / "render" / (name + ".exr")).string());
    write_png_preview(img, "radiance", (stage / "render" / (name + ".png")).string());
    return img;
}

// Per channel the image means of radiance (into mean, se) and subsurface with their standard
// errors, as metrics <scene>.<channel>.radiance_mean and .subsurface_mean.
void radiance_means(const LayeredImage& img, const std::string& scene, std::array<double, 3>& mean,
                    std::array<double, 3>& se, std::vector<Metric>& metrics) {
    const int w = img.width(), h = img.height();
    const double npix = static_cast<double>(w) * h;
    const ImageLayer& L = img.layer("radiance");
    const ImageLayer& E = img.layer("radiance.stderr");
    for (int c = 0; c < 3; ++c) {
        double s = 0, v = 0, ss = 0, sv = 0;
        const ImageLayer& S = img.layer("subsurface");
        const ImageLayer& SE = img.layer("subsurface.stderr");
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

}  // namespace

RenderStudyResult run_render_study(const RenderStudySpec& spec, const RenderStudyContext& ctx,
                                   const ArtifactCache& cache, const fs::path& stage,
                                   std::vector<Metric>& metrics) {
    RenderStudyResult res;
    std::ostringstream summary, html;
    summary << "scene,width,height,spp,seconds,threads,rays,mrays_per_s,paths_per_s,mean_R,se_R,"
               "mean_G,se_G,mean_B,se_B,image_rel_se,median_pixel_rel_se,t_1pct_image_s,"
               "t_1pct_median_pixel_s,reference_spp,rel_rmse_vs_reference,reference_rel_se,"
               "rel_rmse_corrected,t_1pct_from_reference_s,median_pixel_measured,"
               "z2_median_ratio,t_1pct_median_pixel_from_reference_s\n";
    html << "<h2 id=\"render\">Ground-truth images</h2>\n<p>The volumetric path tracer "
         << esc(volpath::render_engine_version())
         << " on each scene. Times to 1 % are extrapolations t (e / 0.01)<sup>2</sup> from the "
            "measured relative error e: the run's own (image RMS of the per-pixel standard errors "
            "over the RMS radiance, and the median pixel's), and, with a reference, the measured "
            "relative RMS error against an independent run with more samples, its own noise taken "
            "out. Convergence tables show the error after 4, 8, 16, ... samples per pixel.</p>\n";
    std::string table_rows;
    for (const std::string& path : spec.scenes) {
        const Scene scene = read_scene(path);
        RenderNode main, ref;
        main.scene_path = ref.scene_path = path;
        main.role = "main";
        ref.role = "reference";
        int w = spec.width > 0 ? spec.width : scene.camera.width;
        int h = spec.height > 0 ? spec.height : scene.camera.height;
        SampleBudget b = spec.budget;
        if (ctx.quick) {
            const double f = std::min(1.0, static_cast<double>(spec.quick_size) / std::max(w, h));
            w = std::max(1, static_cast<int>(std::lround(w * f)));
            h = std::max(1, static_cast<int>(std::lround(h * f)));
            if (b.samples)
                b.samples = std::max<std::int64_t>(
                    16, std::llround(static_cast<double>(*b.samples) * spec.quick_factor));
            if (b.seconds) b.seconds = *b.seconds * spec.quick_factor;
        }
        for (RenderNode* n : {&main, &ref}) {
            n->scene = scene;
            n->options.width = w;
            n->options.height = h;
            n->options.budget = b;
            n->options.seed = derive_render_seed(ctx.seed, scene.name, n->role);
        }
        if (ref.options.budget.samples)
            ref.options.budget.samples =
                std::llround(static_cast<double>(*b.samples) * spec.reference_factor);
        if (ref.options.budget.seconds)
            ref.options.budget.seconds = *b.seconds * spec.reference_factor;
        std::vector<RenderNode*> nodes = {&main};
        if (spec.reference_factor > 0) nodes.push_back(&ref);
        std::vector<Rendered> done;
        for (RenderNode* n : nodes) {
            std::optional<Rendered> got = render_node(*n, ctx, cache);
            if (!got) {
                res.interrupted = true;
                return res;
            }
            (got->computed_now ? res.computed : res.reused) += 1;
            done.push_back(std::move(*got));
        }
        const Rendered& R = done[0];
        // Outputs: the main image without its snapshot layers, a preview, the tables.
        const LayeredImage img = write_render_image(R.image, scene.name, stage);
        const double npix = static_cast<double>(w) * h;
        std::array<double, 3> mean{}, se{};
        radiance_means(img, scene.name, mean, se, metrics);
        double image_rel_se = 0, median_rel_se = 0;
        own_error(img, image_rel_se, median_rel_se);
        const double mrays = R.seconds > 0 ? static_cast<double>(R.rays) / R.seconds * 1e-6 : 0;
        const double paths = R.seconds > 0 ? npix * static_cast<double>(R.spp) / R.seconds : 0;
        std::ostringstream row;
        row << scene.name << "," << w << "," << h << "," << R.spp << "," << format_g(R.seconds, 6)
            << "," << (ctx.threads > 0 ? std::to_string(ctx.threads) : std::string("all")) << ","
            << R.rays << "," << format_g(mrays, 6) << "," << format_g(paths, 6);
        for (int c = 0; c < 3; ++c)
            row << "," << format_g(mean[static_cast<size_t>(c)], 6) << ","
                << format_g(se[static_cast<size_t>(c)], 6);
        row << "," << format_g(image_rel_se, 6) << "," << format_g(median_rel_se, 6) << ","
            << format_g(t_1pct(R.seconds, image_rel_se), 6) << ","
            << format_g(t_1pct(R.seconds, median_rel_se), 6);
        std::string conv = "spp,seconds,rel_rmse,rel_rmse_corrected\n";
        if (done.size() > 1) {
            // The final image against the reference: volpath::measured_error (the image RMS
            // and the median pixel, the reference's noise taken out); the snapshots, which
            // hold no standard errors, by their RMS difference with the same correction.
            const Rendered& F = done[1];
            const volpath::MeasuredError me = volpath::measured_error(R.image, F.image);
            const double ref_rel_se = me.reference.rms;
            const ImageLayer& RL = F.image.layer("radiance");
            auto corrected = [&](double e) {
                return std::sqrt(std::max(0.0, e * e - ref_rel_se * ref_rel_se));
            };
            for (const auto& [spp, secs] : R.snapshots) {
                const double e = rel_rms(R.image.layer(snapshot_layer(spp)), RL);
                conv += std::to_string(spp) + "," + format_g(secs, 6) + "," + format_g(e, 6) + "," +
                        format_g(corrected(e), 6) + "\n";
            }
            conv += std::to_string(R.spp) + "," + format_g(R.seconds, 6) + "," +
                    format_g(me.rel_rmse, 6) + "," + format_g(me.rel_rmse_corrected, 6) + "\n";
            row << "," << F.spp << "," << format_g(me.rel_rmse, 6) << "," << format_g(ref_rel_se, 6)
                << "," << format_g(me.rel_rmse_corrected, 6) << ","
                << format_g(t_1pct(R.seconds, me.rel_rmse_corrected), 6) << ","
                << format_g(me.median_pixel, 6) << "," << format_g(me.z2_median_ratio, 6) << ","
                << format_g(t_1pct(R.seconds, me.median_pixel), 6);
            write_file_atomic(stage / "render" / (scene.name + "_convergence.csv"), conv);
        } else {
            row << ",,,,,,,,";
        }
        summary << row.str() << "\n";
        table_rows += "<tr><td>" + esc(scene.name) + "</td><td>" + std::to_string(w) + " x " +
                      std::to_string(h) + "</td><td>" + std::to_string(R.spp) + "</td><td>" +
                      format_f(R.seconds, 1) + "</td><td>" + format_f(mrays, 2) + "</td><td>" +
                      format_g(image_rel_se, 3) + "</td><td>" +
                      format_g(t_1pct(R.seconds, image_rel_se), 3) + "</td><td>" +
                      format_g(t_1pct(R.seconds, median_rel_se), 3) + "</td></tr>\n";
        html << "<figure><img src=\"render/" << esc(scene.name) << ".png\" alt=\""
             << esc(scene.name) << "\" style=\"max-width:256px\"><figcaption>" << esc(scene.name)
             << ", " << R.spp << " spp</figcaption></figure>\n";
        if (!ctx.quiet)
            std::printf(
                "  %s %s: %d x %d, %llu spp in %.1f s, %.2f M rays/s, image rel. SE %.3g -> 1 %% "
                "in %.3g s\n",
                R.computed_now ? "rendered" : "reused  ", scene.name.c_str(), w, h,
                static_cast<unsigned long long>(R.spp), R.seconds, mrays, image_rel_se,
                t_1pct(R.seconds, image_rel_se));
    }
    write_file_atomic(stage / "render" / "summary.csv", summary.str());
    html << "<table><tr><th>scene</th><th>size</th><th>spp</th><th>seconds</th><th>M "
            "rays/s</th><th>image rel. "
            "SE</th><th>t to 1 % (image), s</th><th>t to 1 % (median pixel), s</th></tr>\n"
         << table_rows << "</table>\n<p>All columns in <code>render/summary.csv</code>.</p>\n";
    res.html = html.str();
    return res;
}

std::optional<CachedRender> cached_render(const Scene& scene, const std::string& role, int width,
                                          int height, const SampleBudget& budget,
                                          const RenderStudyContext& ctx,
                                          const ArtifactCache& cache) {
    RenderNode n;
    n.scene_path = scene.path;
    n.role = role;
    n.scene = scene;
    n.options.width = width;
    n.options.height = height;
    n.options.budget = budget;
    n.options.seed = derive_render_seed(ctx.seed, scene.name, role);
    std::optional<Rendered> r = render_node(n, ctx, cache);
    if (!r) return std::nullopt;
    CachedRender out;
    out.image = LayeredImage(r->image.width(), r->image.height());
    for (const ImageLayer& l : r->image.layers())
        if (l.name().rfind("snapshot_", 0) != 0)
            out.image.add_layer(l.name(), l.channel_names(),
                                std::vector<float>(l.pixels().begin(), l.pixels().end()));
    out.image.metadata() = r->image.metadata();
    out.image.metadata().erase("ssslab.snapshots");
    out.seconds = r->seconds;
    out.spp = r->spp;
    out.key = n.key;
    out.computed_now = r->computed_now;
    return out;
}

}  // namespace ssslab::runner
