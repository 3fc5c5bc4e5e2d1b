#include "experiments/runner/scene_renders.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/format.h"
#include "core/hash.h"
#include "core/provenance.h"
#include "core/scene.h"
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

const ImageLayer& CachedRender::snapshot(std::uint64_t at_spp) const {
    return snapshot_layers.layer(snapshot_layer(at_spp));
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
    out.snapshot_layers = LayeredImage(r->image.width(), r->image.height());
    for (const ImageLayer& l : r->image.layers())
        (l.name().rfind("snapshot_", 0) != 0 ? out.image : out.snapshot_layers)
            .add_layer(l.name(), l.channel_names(),
                       std::vector<float>(l.pixels().begin(), l.pixels().end()));
    out.image.metadata() = r->image.metadata();
    out.image.metadata().erase("ssslab.snapshots");
    out.seconds = r->seconds;
    out.spp = r->spp;
    out.rays = r->rays;
    out.snapshots = std::move(r->snapshots);
    out.key = n.key;
    out.computed_now = r->computed_now;
    return out;
}

}  // namespace ssslab::runner
