#include "realtime/frame.h"

#include "approx/kernel2d.h"
#include "core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace ssslab::realtime {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Pass 4 with s x s samples a pixel: the box filter of every layer (radiance only unless
// all_layers), the material the pixel's samples mostly show.
void composite_supersampled(const Scene& scene, const RasterizedFrame& frame, const GBuffer& g,
                            const std::vector<int>& dense,
                            const std::vector<const FrameMaterial*>& used,
                            const std::vector<float>& scattered,
                            const std::vector<float>& scattered_se, bool all_layers,
                            LayeredImage& img) {
    const int s = frame.raster.supersample;
    const int W = frame.raster.width, H = frame.raster.height;
    ImageLayer& radiance = img.add_layer("radiance", 3);
    // Without all_layers the other layers are scratch images, not added to the result.
    LayeredImage scratch(all_layers ? 1 : W, all_layers ? 1 : H);
    LayeredImage& out = all_layers ? img : scratch;
    ImageLayer& subsurface = out.add_layer("subsurface", 3);
    ImageLayer& specular = out.add_layer("specular", 3);
    ImageLayer& depth = out.add_layer("depth", 1);
    ImageLayer& normal = out.add_layer("normal", {"X", "Y", "Z"});
    ImageLayer& irradiance = out.add_layer("irradiance", 3);
    ImageLayer& surface = out.add_layer("surface", 3);
    ImageLayer& translucency = out.add_layer("translucency", 3);
    ImageLayer& material = out.add_layer("material", 1);
    ImageLayer* sub_se =
        scattered_se.empty() || !all_layers ? nullptr : &out.add_layer("subsurface.stderr", 3);
    const double inv = 1.0 / (static_cast<double>(s) * s);
    // Rows in parallel: every pixel is computed on its own (bit-identical for any thread count).
    tbb::parallel_for(0, H, [&](int y) {
        std::vector<int> votes(scene.materials.size() + 1);
        for (int x = 0; x < W; ++x) {
            std::array<double, 3> L{}, sub{}, spec{}, irr{}, surf{}, tr{}, nrm{}, var{};
            std::fill(votes.begin(), votes.end(), 0);
            for (int j = 0; j < s; ++j)
                for (int i = 0; i < s; ++i) {
                    const size_t k = frame.raster.sample_index(x * s + i, y * s + j);
                    const std::int32_t m = g.material[k];
                    ++votes[static_cast<size_t>(m + 1)];
                    const int d = m >= 0 ? dense[static_cast<size_t>(m)] : -1;
                    for (size_t c = 0; c < 3; ++c) {
                        double ss = 0;
                        if (d >= 0) {
                            const double a = used[static_cast<size_t>(d)]->albedo[c];
                            const double ew = g.exit_weight[k];
                            ss = ew * (a * scattered[3 * k + c] + g.translucency[3 * k + c]);
                            if (!scattered_se.empty()) {
                                const double e = ew * a * scattered_se[3 * k + c];
                                var[c] += e * e;
                            }
                        }
                        sub[c] += ss;
                        spec[c] += g.specular[3 * k + c];
                        surf[c] += g.surface[3 * k + c];
                        irr[c] += g.irradiance[3 * k + c];
                        tr[c] += g.translucency[3 * k + c];
                        nrm[c] += g.normal[3 * k + c];
                        L[c] += ss + g.specular[3 * k + c] + g.surface[3 * k + c];
                    }
                }
            for (int c = 0; c < 3; ++c) {
                const size_t cc = static_cast<size_t>(c);
                radiance.at(x, y, c) = static_cast<float>(L[cc] * inv);
                subsurface.at(x, y, c) = static_cast<float>(sub[cc] * inv);
                specular.at(x, y, c) = static_cast<float>(spec[cc] * inv);
                irradiance.at(x, y, c) = static_cast<float>(irr[cc] * inv);
                surface.at(x, y, c) = static_cast<float>(surf[cc] * inv);
                translucency.at(x, y, c) = static_cast<float>(tr[cc] * inv);
                normal.at(x, y, c) = static_cast<float>(nrm[cc] * inv);
                if (sub_se) sub_se->at(x, y, c) = static_cast<float>(std::sqrt(var[cc]) * inv);
            }
            if (all_layers)
                depth.at(x, y, 0) =
                    static_cast<float>(frame.raster.depth[frame.raster.pixel_index(x, y)]);
            const auto best = std::max_element(votes.begin(), votes.end());
            material.at(x, y, 0) = static_cast<float>(best - votes.begin() - 1);
        }
    });
}

}  // namespace

void check_drawable(const Scene& scene) {
    for (const SceneMaterial& m : scene.materials)
        if (m.kind == SceneMaterial::Kind::kMedium && !m.density_file.empty())
            throw InputError(m.where, "density_vdb",
                             "the real-time renderer draws homogeneous media only (one kernel per "
                             "material); material \"" +
                                 m.name + "\" reads its density from " + m.density_file);
}

const char* to_string(SssMethod m) {
    return name_of(m).data();
}

std::string sss_kernel_name(SssMethod m, const std::string& model_spec) {
    switch (m) {
        case SssMethod::kSeparable:
            return model_spec;
        case SssMethod::kReference:
            return "reference:2d";
        case SssMethod::kNone:
            return "none";
    }
    return "?";
}

FrameMaterial make_frame_material(const RadialProfile& profile, const approx::ModelSpec& model,
                                  int taps, bool exact) {
    if (model.name == "manual" && model.flag("fit"))
        throw std::invalid_argument("model \"" + model.text +
                                    "\" is fitted to a kernel study's test images; a frame "
                                    "takes models built from the kernel alone");
    const approx::KernelGrid grid = approx::KernelGrid::from_profile(profile, 1);
    std::vector<approx::Kernel2D> k;
    k.reserve(3);
    for (int c = 0; c < 3; ++c) k.emplace_back(profile, c, grid);
    FrameMaterial m;
    m.name = profile.name;
    std::array<approx::ModelResult, 3> r;
    for (int c = 0; c < 3; ++c) {
        approx::ModelContext ctx;
        ctx.material = profile.name;
        ctx.channel = c;
        r[static_cast<size_t>(c)] = approx::build_model(model, k[static_cast<size_t>(c)], ctx);
        const double entered = 1.0 - profile.rsp[static_cast<size_t>(c)];
        m.albedo[static_cast<size_t>(c)] = k[static_cast<size_t>(c)].raw_l1() / entered;
    }
    m.kernel = make_material_kernel({&r[0].kernel, &r[1].kernel, &r[2].kernel}, taps);
    if (exact) m.exact = SssExactKernel::from_kernels({&k[0], &k[1], &k[2]});
    return m;
}

RasterizedFrame rasterize_frame(const Scene& scene, const FrameOptions& o) {
    RasterizedFrame f;
    rasterize_frame(scene, o, f);
    return f;
}

void rasterize_frame(const Scene& scene, const FrameOptions& o, RasterizedFrame& f) {
    f.media_in_view.clear();
    f.lit_in_view.clear();
    const int w = o.width > 0 ? o.width : scene.camera.width;
    const int h = o.height > 0 ? o.height : scene.camera.height;
    const auto t0 = Clock::now();
    RasterOptions ro = o.raster;
    // Only the layers' composite reads coverage and depth.
    ro.pixel_layers = ro.pixel_layers && o.all_layers;
    if (o.rasterizer)
        o.rasterizer(scene, ro, w, h, f.raster);
    else
        rasterize(scene, ro, w, h, f.raster);
    f.ms = ms_since(t0);
    f.camera = RasterCamera::from_scene(scene.camera, w, h);
    // The shapes seen (in parallel blocks), then their materials.
    const std::vector<char> shapes_seen = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, f.raster.shape.size(), 65536),
        std::vector<char>(scene.shapes.size(), 0),
        [&](const tbb::blocked_range<size_t>& r, std::vector<char> seen) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                if (const std::int32_t s = f.raster.shape[i]; s >= 0)
                    seen[static_cast<size_t>(s)] = 1;
            return seen;
        },
        [](std::vector<char> a, const std::vector<char>& b) {
            for (size_t k = 0; k < a.size(); ++k) a[k] = static_cast<char>(a[k] | b[k]);
            return a;
        });
    std::vector<char> seen(scene.materials.size(), 0);
    for (size_t k = 0; k < shapes_seen.size(); ++k)
        if (shapes_seen[k]) seen[static_cast<size_t>(scene.shapes[k].material)] = 1;
    for (size_t m = 0; m < seen.size(); ++m) {
        if (!seen[m]) continue;
        f.lit_in_view.push_back(static_cast<int>(m));
        if (scene.materials[m].kind == SceneMaterial::Kind::kMedium)
            f.media_in_view.push_back(static_cast<int>(m));
    }
}

double FrameResult::total_ms() const {
    double t = 0;
    for (const PassTime& p : times) t += p.ms;
    return t;
}

LitFrame light_frame(const Scene& scene, const RasterizedFrame& frame, const FrameOptions& o,
                     const std::vector<SlabTransmittance>& slabs) {
    LitFrame lit;
    light_frame(scene, frame, o, lit, slabs);
    return lit;
}

void light_frame(const Scene& scene, const RasterizedFrame& frame, const FrameOptions& o,
                 LitFrame& lit, const std::vector<SlabTransmittance>& slabs) {
    const auto t0 = Clock::now();
    lit.stats = {};
    if (o.lighting_pass)
        o.lighting_pass(scene, frame.camera, frame.raster, o.lighting, slabs, &lit.stats,
                        lit.gbuffer);
    else
        shade(scene, frame.camera, frame.raster, o.lighting, slabs, &lit.stats, lit.gbuffer);
    lit.ms = ms_since(t0);
}

FrameResult render_frame(const Scene& scene, const RasterizedFrame& frame,
                         const std::map<int, FrameMaterial>& materials, const FrameOptions& o,
                         const std::vector<SlabTransmittance>& slabs) {
    return render_frame(scene, frame, light_frame(scene, frame, o, slabs), materials, o);
}

namespace {

// The kernels of the media in view, in order, and per scene material its index among them (-1:
// not in view); std::invalid_argument for a medium in view without a kernel.
std::vector<const FrameMaterial*> kernels_in_view(const Scene& scene, const RasterizedFrame& frame,
                                                  const std::map<int, FrameMaterial>& materials,
                                                  std::vector<int>& dense) {
    dense.assign(scene.materials.size(), -1);
    std::vector<const FrameMaterial*> used;
    for (const int m : frame.media_in_view) {
        const auto it = materials.find(m);
        if (it == materials.end())
            throw std::invalid_argument("render_frame: no kernel for material \"" +
                                        scene.materials[static_cast<size_t>(m)].name +
                                        "\", which is in view");
        dense[static_cast<size_t>(m)] = static_cast<int>(used.size());
        used.push_back(&it->second);
    }
    return used;
}

}  // namespace

FrameResult render_frame(const Scene& scene, const RasterizedFrame& frame, const LitFrame& lit,
                         const std::map<int, FrameMaterial>& materials, const FrameOptions& o) {
    FrameResult res;
    res.times.push_back({"raster", frame.ms});
    res.lighting = lit.stats;
    res.times.push_back({"shadow maps", lit.stats.shadow_ms});
    res.times.push_back({"lighting", std::max(0.0, lit.ms - lit.stats.shadow_ms)});
    const GBuffer& g = lit.gbuffer;

    // Passes 2-3: one kernel per medium in view, indexed densely.
    std::vector<int> dense;
    const std::vector<const FrameMaterial*> used = kernels_in_view(scene, frame, materials, dense);
    const size_t n = g.samples();
    // The pass's inputs and output: scratch of the calling thread, kept between frames (fresh
    // 1080p arrays would fault in 64 MB of pages a frame). The result does not depend on it.
    // (References: the composite's worker threads must see this thread's arrays, not theirs.)
    static thread_local SssGBuffer scratch_g;
    static thread_local std::vector<float> scratch_out;
    SssGBuffer& sg = scratch_g;
    std::vector<float>& scattered = scratch_out;
    sg.width = g.width;
    sg.height = g.height;
    sg.irradiance.resize(3 * n);  // every entry is written below
    sg.view_z.resize(n);
    sg.material.resize(n);
    // Copied in parallel blocks: the G-buffer's irradiance and view z, and the dense kernel
    // index of each sample's material (-1: no medium).
    const bool any_medium = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 16384), false,
        [&](const tbb::blocked_range<size_t>& r, bool any) {
            std::copy(g.irradiance.begin() + static_cast<std::ptrdiff_t>(3 * r.begin()),
                      g.irradiance.begin() + static_cast<std::ptrdiff_t>(3 * r.end()),
                      sg.irradiance.begin() + static_cast<std::ptrdiff_t>(3 * r.begin()));
            std::copy(g.view_z.begin() + static_cast<std::ptrdiff_t>(r.begin()),
                      g.view_z.begin() + static_cast<std::ptrdiff_t>(r.end()),
                      sg.view_z.begin() + static_cast<std::ptrdiff_t>(r.begin()));
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const std::int32_t m = g.material[i];
                sg.material[i] = m < 0 ? -1 : dense[static_cast<size_t>(m)];
                any = any || sg.material[i] >= 0;
            }
            return any;
        },
        [](bool a, bool b) { return a || b; });
    SssParams p = o.sss;
    p.tan_half = frame.camera.tan_half;
    p.aspect = frame.camera.aspect;
    p.unit_mm = scene.unit_mm;
    std::vector<float> scattered_se;
    const bool run = any_medium && o.method != SssMethod::kNone;
    std::vector<SssMaterialKernel> taps;
    std::vector<SssExactKernel> exact;
    for (const FrameMaterial* fm : used) {
        if (!run) break;
        if (o.method == SssMethod::kSeparable) {
            taps.push_back(fm->kernel);
        } else {
            if (!fm->exact)
                throw std::invalid_argument("render_frame: material \"" + fm->name +
                                            "\" has no exact kernel for the reference");
            exact.push_back(*fm->exact);
        }
    }
    auto t0 = Clock::now();  // the pass alone: its inputs are ready, as on a GPU
    if (!run) {
        scattered.assign(sg.irradiance.begin(), sg.irradiance.end());  // no pass to run
    } else if (o.method == SssMethod::kSeparable) {
        if (o.separable_pass)
            o.separable_pass(sg, taps, p, scattered);
        else
            sss_pass(sg, taps, p, scattered);
    } else {
        SssReferenceResult r = sss_reference(sg, exact, p, o.reference);
        scattered = std::move(r.irradiance);
        scattered_se = std::move(r.standard_error);
        res.sss_exact_pixels = r.exact_pixels;
        res.sss_sampled_pixels = r.sampled_pixels;
    }
    res.times.push_back({"sss", run ? ms_since(t0) : 0.0});

    // Pass 4: composite per sample, then the box filter to pixels.
    t0 = Clock::now();
    const int s = frame.raster.supersample;
    const int W = frame.raster.width, H = frame.raster.height;
    LayeredImage& img = res.image = LayeredImage(W, H);
    // The subsurface term of sample k, channel c (and its variance's share for the reference).
    auto subsurface_of = [&](std::size_t k, std::size_t c) -> float {
        const std::int32_t m = g.material[k];
        const int d = m >= 0 ? dense[static_cast<std::size_t>(m)] : -1;
        if (d < 0) return 0.f;
        const double a = used[static_cast<std::size_t>(d)]->albedo[c];
        return static_cast<float>(g.exit_weight[k] *
                                  (a * scattered[3 * k + c] + g.translucency[3 * k + c]));
    };
    if (s == 1) {
        // One sample a pixel: the layers are the G-buffer's own arrays; only radiance and
        // subsurface are computed.
        ImageLayer& radiance = img.add_layer("radiance", 3);
        ImageLayer* subsurface = o.all_layers ? &img.add_layer("subsurface", 3) : nullptr;
        const std::span<float> L = radiance.pixels();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t k = r.begin(); k != r.end(); ++k)
                                  for (std::size_t c = 0; c < 3; ++c) {
                                      const float ss = subsurface_of(k, c);
                                      if (subsurface) subsurface->pixels()[3 * k + c] = ss;
                                      L[3 * k + c] =
                                          ss + g.specular[3 * k + c] + g.surface[3 * k + c];
                                  }
                          });
        if (o.all_layers) {
            img.add_layer("specular", 3, g.specular);
            std::vector<float> depth(n), material(n);
            for (std::size_t k = 0; k < n; ++k) {
                depth[k] = static_cast<float>(frame.raster.depth[k]);
                material[k] = static_cast<float>(g.material[k]);
            }
            img.add_layer("depth", 1, std::move(depth));
            img.add_layer("normal", {"X", "Y", "Z"}, g.normal);
            img.add_layer("irradiance", 3, g.irradiance);
            img.add_layer("surface", 3, g.surface);
            img.add_layer("translucency", 3, g.translucency);
            img.add_layer("material", 1, std::move(material));
            if (!scattered_se.empty()) {
                ImageLayer& se = img.add_layer("subsurface.stderr", 3);
                for (std::size_t k = 0; k < n; ++k) {
                    const std::int32_t m = g.material[k];
                    const int d = m >= 0 ? dense[static_cast<std::size_t>(m)] : -1;
                    if (d < 0) continue;
                    for (std::size_t c = 0; c < 3; ++c)
                        se.pixels()[3 * k + c] = static_cast<float>(
                            g.exit_weight[k] * used[static_cast<std::size_t>(d)]->albedo[c] *
                            scattered_se[3 * k + c]);
                }
            }
        }
        res.times.push_back({"composite", ms_since(t0)});
    } else {
        composite_supersampled(scene, frame, g, dense, used, scattered, scattered_se, o.all_layers,
                               img);
        res.times.push_back({"composite", ms_since(t0)});
    }
    auto& md = img.metadata();
    md["ssslab.engine"] = "realtime";
    md["ssslab.scene"] = scene.name;
    md["ssslab.sss_method"] = to_string(o.method);
    md["ssslab.supersample"] = std::to_string(s);
    return res;
}

}  // namespace ssslab::realtime
