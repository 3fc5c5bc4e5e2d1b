#include "experiments/runner/munoz_frame.h"

#include "approx/radial_function.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ssslab::runner {

realtime::LitFrame light_back_frame(const Scene& scene, const realtime::FrameOptions& fo,
                                    const std::vector<realtime::SlabTransmittance>& slabs) {
    // Only the media are drawn (a floor in front of a far side would hide it); shape indices
    // are kept, so the G-buffer's shapes and materials are the scene's.
    Scene media = scene;
    for (SceneShape& s : media.shapes)
        if (scene.materials[static_cast<size_t>(s.material)].kind != SceneMaterial::Kind::kMedium)
            s.mesh = TriangleMesh{};
    realtime::FrameOptions o = fo;
    o.rasterizer = nullptr;  // the software raster: the GL twin has no front-face culling
    o.lighting_pass = nullptr;
    o.raster.cull_closed = true;
    o.raster.cull_front_closed = true;
    const realtime::RasterizedFrame back = realtime::rasterize_frame(media, o);
    return realtime::light_frame(scene, back, o, slabs);
}

MunozFrame render_munoz_frame(const Scene& scene, const realtime::RasterizedFrame& frame,
                              const realtime::LitFrame& lit, const realtime::LitFrame& back,
                              const std::map<int, realtime::FrameMaterial>& materials,
                              const std::map<int, RadialProfile>& profiles,
                              const approx::MunozOptions& options,
                              const realtime::FrameOptions& fo) {
    const realtime::GBuffer& bg = back.gbuffer;
    MunozFrame res;
    realtime::FrameOptions o = fo;
    o.method = realtime::SssMethod::kSeparable;
    o.separable_pass = [&](const realtime::SssGBuffer& g,
                           const std::vector<realtime::SssMaterialKernel>&,
                           const realtime::SssParams& p, std::vector<float>& out) {
        const size_t n = g.pixels();
        if (bg.width != g.width || bg.height != g.height)
            throw std::invalid_argument("render_munoz_frame: the back frame's size differs");
        out.assign(g.irradiance.begin(), g.irradiance.end());  // non-media pass through
        // The dense material index d is the d-th medium in view (render_frame's order).
        for (size_t d = 0; d < frame.media_in_view.size(); ++d) {
            const int m = frame.media_in_view[d];
            const auto prof = profiles.find(m);
            const auto fm = materials.find(m);
            if (prof == profiles.end() || fm == materials.end())
                throw std::invalid_argument("render_munoz_frame: no profile for material \"" +
                                            scene.materials[static_cast<size_t>(m)].name + "\"");
            // R_d per entered irradiance: the MC profile over 1 - R_sp.
            const approx::RadialFunction per_incident =
                approx::RadialFunction::from_profile(prof->second);
            std::array<double, 3> entry{};
            for (int c = 0; c < 3; ++c) entry[c] = 1.0 / (1.0 - prof->second.rsp[c]);
            const approx::RadialFunction rd([&per_incident, entry](double r) {
                std::array<double, 3> v = per_incident(r);
                for (int c = 0; c < 3; ++c) v[c] *= entry[c];
                return v;
            });
            approx::MunozView v;
            v.width = g.width;
            v.height = g.height;
            v.pixel_mm = 0;
            v.pixel_mm_per_depth = 2 * p.tan_half / g.height;  // Eq. 4.11's scale, per mm of z
            const float inf = std::numeric_limits<float>::infinity();
            v.front_z.assign(n, inf);
            v.back_z.assign(n, inf);
            for (int c = 0; c < 3; ++c) {
                v.front_irradiance[c].assign(n, 0.0f);
                v.back_irradiance[c].assign(n, 0.0f);
            }
            bool any = false;
            for (size_t i = 0; i < n; ++i) {
                if (g.material[i] != static_cast<std::int32_t>(d)) continue;
                any = true;
                const float zf = static_cast<float>(g.view_z[i] * p.unit_mm);
                v.front_z[i] = zf;
                for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = g.irradiance[3 * i + c];
                if (bg.material[i] != m || !std::isfinite(bg.view_z[i])) continue;
                const float zb = static_cast<float>(bg.view_z[i] * p.unit_mm);
                if (!(zb >= zf)) continue;  // another shape's far side in front: none
                v.back_z[i] = zb;
                for (int c = 0; c < 3; ++c) v.back_irradiance[c][i] = bg.irradiance[3 * i + c];
            }
            if (!any) continue;
            const approx::MunozResult r = approx::munoz_exitance(v, rd, options);
            res.stats.layers_used += r.stats.layers_used;
            res.stats.convolutions += r.stats.convolutions;
            res.stats.skipped_threshold += r.stats.skipped_threshold;
            res.stats.skipped_invisible += r.stats.skipped_invisible;
            res.stats.dz_mm = std::max(res.stats.dz_mm, r.stats.dz_mm);
            res.stats.seconds += r.stats.seconds;
            const std::array<double, 3>& albedo = fm->second.albedo;
            for (size_t i = 0; i < n; ++i) {
                if (g.material[i] != static_cast<std::int32_t>(d)) continue;
                for (int c = 0; c < 3; ++c)
                    out[3 * i + c] =
                        albedo[c] > 0 ? static_cast<float>(r.exitance[c][i] / albedo[c]) : 0.0f;
            }
        }
    };
    res.frame = realtime::render_frame(scene, frame, lit, materials, o);
    return res;
}

}  // namespace ssslab::runner
