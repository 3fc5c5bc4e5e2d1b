#include "experiments/runner/surface_frames.h"

#include "approx/diffusion.h"
#include "approx/radial_function.h"
#include "realtime/lighting.h"
#include "realtime/raster.h"
#include "realtime/shadow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ssslab::runner {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// M per channel at every pixel of the G-buffer (read where g.material == d).
using MaterialExitance =
    std::function<void(std::size_t d, int m, const realtime::SssGBuffer& g,
                       const realtime::SssParams& p, std::array<std::vector<float>, 3>& M)>;

/// `frame` with an integration as its SSS pass: for the d-th medium material in view (scene
/// material m) exitance(d, m, ...) gives M, which the pass hands the composite as M / albedo at
/// that material's pixels (see the file comment of surface_frames.h); other pixels pass through.
realtime::FrameResult render_integral_frame(const Scene& scene,
                                            const realtime::RasterizedFrame& frame,
                                            const realtime::LitFrame& lit,
                                            const std::map<int, realtime::FrameMaterial>& materials,
                                            const realtime::FrameOptions& fo,
                                            const MaterialExitance& exitance, const char* who) {
    realtime::FrameOptions o = fo;
    o.method = realtime::SssMethod::kSeparable;
    o.separable_pass = [&](const realtime::SssGBuffer& g,
                           const std::vector<realtime::SssMaterialKernel>&,
                           const realtime::SssParams& p, std::vector<float>& out) {
        const size_t n = g.pixels();
        out.assign(g.irradiance.begin(), g.irradiance.end());  // non-media pass through
        // The dense material index d is the d-th medium in view (render_frame's order).
        for (size_t d = 0; d < frame.media_in_view.size(); ++d) {
            const int m = frame.media_in_view[d];
            const auto fm = materials.find(m);
            if (fm == materials.end())
                throw std::invalid_argument(std::string(who) + ": no kernel for material \"" +
                                            scene.materials[static_cast<size_t>(m)].name + "\"");
            bool any = false;
            for (size_t i = 0; i < n && !any; ++i) any = g.material[i] == static_cast<int>(d);
            if (!any) continue;
            std::array<std::vector<float>, 3> M;
            exitance(d, m, g, p, M);
            const std::array<double, 3>& albedo = fm->second.albedo;
            for (size_t i = 0; i < n; ++i) {
                if (g.material[i] != static_cast<std::int32_t>(d)) continue;
                for (int c = 0; c < 3; ++c)
                    out[3 * i + c] = albedo[c] > 0 ? static_cast<float>(M[c][i] / albedo[c]) : 0.0f;
            }
        }
    };
    return realtime::render_frame(scene, frame, lit, materials, o);
}

const RadialProfile& profile_of(const Scene& scene, const std::map<int, RadialProfile>& profiles,
                                int m, const char* who) {
    const auto prof = profiles.find(m);
    if (prof == profiles.end())
        throw std::invalid_argument(std::string(who) + ": no profile for material \"" +
                                    scene.materials[static_cast<size_t>(m)].name + "\"");
    return prof->second;
}

/// An analytic profile of approx/diffusion.h (factory `name`, default options) for a homogeneous
/// medium material's coefficients per channel (lengths in mm), tabulated (RadialFunction::
/// tabulated, 4096 radii) from 1e-3 of the smallest reduced mean free path to the scene's
/// diagonal: no two points are farther apart.
approx::RadialFunction analytic_profile(const Scene& scene, const SceneMaterial& sm,
                                        const std::string& name) {
    if (sm.medium.layered())
        throw std::invalid_argument("profile " + name + ": material \"" + sm.name +
                                    "\" is layered; the diffusion models are homogeneous");
    std::array<std::shared_ptr<const approx::DiffusionProfile>, 3> ch;
    double mfp_min = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
        approx::DiffusionMedium dm = approx::diffusion_medium(sm.medium, c, LengthUnit::kMm);
        dm.thickness = std::numeric_limits<double>::infinity();  // surfaces of scene shapes
        ch[static_cast<size_t>(c)] = approx::make_diffusion_profile(name, dm);
        mfp_min = std::min(mfp_min, 1 / dm.sigma_t_reduced());
    }
    realtime::Box box;
    for (const SceneShape& s : scene.shapes) {
        if (s.mesh.triangles.empty()) continue;
        const auto b = s.mesh.bounds();
        box.add(b[0]);
        box.add(b[1]);
    }
    const double diag = box.empty() ? 0.0 : length(box.hi - box.lo) * scene.unit_mm;
    const double r_min = 1e-3 * mfp_min;
    return approx::RadialFunction::tabulated(approx::RadialFunction::from_diffusion(ch), r_min,
                                             std::max(diag, 2 * r_min), 4096);
}

}  // namespace

approx::RadialFunction per_entered(const RadialProfile& p) {
    const approx::RadialFunction per_incident = approx::RadialFunction::from_profile(p);
    std::array<double, 3> entry{};
    for (int c = 0; c < 3; ++c) entry[c] = 1.0 / (1.0 - p.rsp[c]);
    return approx::RadialFunction([per_incident, entry](double r) {
        std::array<double, 3> v = per_incident(r);
        for (int c = 0; c < 3; ++c) v[c] *= entry[c];
        return v;
    });
}

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
    auto exitance = [&](size_t d, int m, const realtime::SssGBuffer& g,
                        const realtime::SssParams& p, std::array<std::vector<float>, 3>& M) {
        const size_t n = g.pixels();
        if (bg.width != g.width || bg.height != g.height)
            throw std::invalid_argument("render_munoz_frame: the back frame's size differs");
        const approx::RadialFunction rd =
            per_entered(profile_of(scene, profiles, m, "render_munoz_frame"));
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
        for (size_t i = 0; i < n; ++i) {
            if (g.material[i] != static_cast<std::int32_t>(d)) continue;
            const float zf = static_cast<float>(g.view_z[i] * p.unit_mm);
            v.front_z[i] = zf;
            for (int c = 0; c < 3; ++c) v.front_irradiance[c][i] = g.irradiance[3 * i + c];
            if (bg.material[i] != m || !std::isfinite(bg.view_z[i])) continue;
            const float zb = static_cast<float>(bg.view_z[i] * p.unit_mm);
            if (!(zb >= zf)) continue;  // another shape's far side in front: none
            v.back_z[i] = zb;
            for (int c = 0; c < 3; ++c) v.back_irradiance[c][i] = bg.irradiance[3 * i + c];
        }
        approx::MunozResult r = approx::munoz_exitance(v, rd, options);
        res.stats.layers_used += r.stats.layers_used;
        res.stats.convolutions += r.stats.convolutions;
        res.stats.skipped_threshold += r.stats.skipped_threshold;
        res.stats.skipped_invisible += r.stats.skipped_invisible;
        res.stats.dz_mm = std::max(res.stats.dz_mm, r.stats.dz_mm);
        res.stats.seconds += r.stats.seconds;
        M = std::move(r.exitance);
    };
    res.frame =
        render_integral_frame(scene, frame, lit, materials, fo, exitance, "render_munoz_frame");
    return res;
}

JensenBuhlerCloud build_jensen_buhler_cloud(const Scene& scene, const std::vector<int>& media,
                                            const approx::JensenBuhlerOptions& options,
                                            const realtime::FrameOptions& fo, std::uint64_t seed) {
    JensenBuhlerCloud cloud;
    approx::PointCloudOptions po;
    po.points_per_mm2 = options.points_per_mm2;
    po.candidates_per_point = options.candidates_per_point;
    for (int m : media) {
        auto t0 = Clock::now();
        std::vector<approx::SurfacePoint> pts;
        for (size_t k = 0; k < scene.shapes.size(); ++k) {
            const SceneShape& sh = scene.shapes[k];
            if (sh.material != m || sh.mesh.triangles.empty()) continue;
            po.seed = seed * 1000003u + k;  // an independent cloud per shape
            std::vector<approx::SurfacePoint> s =
                approx::sample_surface(sh.mesh, scene.unit_mm, static_cast<std::uint32_t>(k), po);
            pts.insert(pts.end(), s.begin(), s.end());
        }
        cloud.sample_seconds += since(t0);
        if (pts.empty()) continue;
        // Pass 1's lighting at each point (world units), the irradiance that entered.
        t0 = Clock::now();
        std::vector<realtime::BoundaryPoint> bp(pts.size());
        for (size_t i = 0; i < pts.size(); ++i)
            bp[i] = {pts[i].position_mm * (1.0 / scene.unit_mm), pts[i].normal, m};
        const std::vector<std::array<double, 3>> E =
            realtime::boundary_irradiance(scene, bp, fo.lighting);
        for (size_t i = 0; i < pts.size(); ++i) pts[i].irradiance = E[i];
        cloud.light_seconds += since(t0);
        t0 = Clock::now();
        cloud.points += pts.size();
        cloud.trees.emplace(m, approx::PointOctree(std::move(pts)));
        cloud.tree_seconds += since(t0);
    }
    return cloud;
}

JensenBuhlerFrame render_jensen_buhler_frame(
    const Scene& scene, const realtime::RasterizedFrame& frame, const realtime::LitFrame& lit,
    const std::map<int, realtime::FrameMaterial>& materials,
    const std::map<int, RadialProfile>& profiles, const JensenBuhlerCloud& cloud,
    const approx::JensenBuhlerOptions& options, const realtime::FrameOptions& fo) {
    static constexpr const char* kWho = "render_jensen_buhler_frame";
    JensenBuhlerFrame res;
    approx::HierarchicalOptions ho;
    ho.max_solid_angle = options.max_solid_angle;
    ho.conservative = options.conservative;
    auto exitance = [&](size_t d, int m, const realtime::SssGBuffer& g,
                        const realtime::SssParams& p, std::array<std::vector<float>, 3>& M) {
        const auto tree = cloud.trees.find(m);
        if (tree == cloud.trees.end())
            throw std::invalid_argument(std::string(kWho) + ": no point cloud for material \"" +
                                        scene.materials[static_cast<size_t>(m)].name + "\"");
        const approx::RadialFunction rd =
            options.profile == "mc"
                ? per_entered(profile_of(scene, profiles, m, kWho))
                : analytic_profile(scene, scene.materials[static_cast<size_t>(m)], options.profile);
        // Each pixel's surface point: the camera ray through its centre at its view depth.
        const realtime::RasterCamera cam =
            realtime::RasterCamera::from_scene(scene.camera, g.width, g.height);
        const realtime::RasterCamera::SampleRays rays = cam.sample_rays(1);
        std::vector<size_t> at;
        std::vector<Vec3> x;
        for (int y = 0; y < g.height; ++y)
            for (int xx = 0; xx < g.width; ++xx) {
                const size_t i =
                    static_cast<size_t>(y) * static_cast<size_t>(g.width) + static_cast<size_t>(xx);
                if (g.material[i] != static_cast<std::int32_t>(d)) continue;
                at.push_back(i);
                x.push_back((cam.position + rays.unnormalized(xx, y) * g.view_z[i]) * p.unit_mm);
            }
        const auto t0 = Clock::now();
        approx::HierarchicalStats st;
        const std::vector<std::array<double, 3>> e = tree->second.exitance(rd, x, ho, &st);
        res.query_seconds += since(t0);
        res.stats += st;
        for (int c = 0; c < 3; ++c) M[c].assign(g.pixels(), 0.0f);
        for (size_t k = 0; k < at.size(); ++k)
            for (int c = 0; c < 3; ++c) M[c][at[k]] = static_cast<float>(e[k][c]);
    };
    res.frame = render_integral_frame(scene, frame, lit, materials, fo, exitance, kWho);
    return res;
}

}  // namespace ssslab::runner
