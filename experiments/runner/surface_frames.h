// The image-space approximations that integrate a radial profile over the media's surfaces
// inside a real-time frame (realtime/frame.h), so that they are scored like the separable models:
// the same raster, pass 1 and composite, with the SSS pass (FrameOptions::separable_pass)
// replaced by
//   - Munoz11's layered convolution (approx/munoz.h) of each medium material's front samples
//     (the G-buffer) and back samples (a second raster of the media's far sides, lit by pass 1
//     with the whole scene's lights and shadows) [Munoz11 §4.2];
//   - Jensen-Buhler's hierarchical integration (approx/hierarchical.h) over a Poisson-disk point
//     cloud on every surface of the media, lit by pass 1's lights and shadow maps
//     (realtime::boundary_irradiance) [JB02; Bitterli13 §2.6.4, §3.3], evaluated at each
//     G-buffer pixel's surface point.
//
// Units (one rule for both): the G-buffer holds the irradiance that entered; an MC profile's R_d
// is per incident photon (it carries 1 - R_sp), so the integrations run on R_d / (1 - R_sp), the
// exitance per entered irradiance (approx/diffusion.h's analytic profiles are per entered power
// already), and hand the composite M / albedo (the composite multiplies by the material's albedo,
// FrameMaterial::albedo, then by the exit weight), so that M itself reaches the image through the
// same exit rule as every kernel model.
#pragma once

#include "approx/hierarchical.h"
#include "approx/munoz.h"
#include "approx/radial_function.h"
#include "core/profile.h"
#include "core/scene.h"
#include "realtime/frame.h"

#include <map>
#include <vector>

namespace ssslab::runner {

/// R_d per entered power [1/mm^2] of a material: its MC profile over 1 - R_sp.
approx::RadialFunction per_entered(const RadialProfile& p);

/// The media's far sides as pass 1 sees them: a raster of the scene's medium shapes only with the
/// front faces of closed meshes culled (RasterOptions::cull_front_closed), lit with the whole
/// scene (its shadows included) at fo's size and lighting options.
realtime::LitFrame light_back_frame(const Scene& scene, const realtime::FrameOptions& fo,
                                    const std::vector<realtime::SlabTransmittance>& slabs = {});

struct MunozFrame {
    realtime::FrameResult frame;  ///< its "sss" pass time is the layered convolution's
    approx::MunozStats stats;     ///< summed over the materials
};

/// `frame` rendered with the layered convolution as its SSS pass. `profiles`: the MC profile of
/// every medium material in view (scene material index); `materials`: their FrameMaterials (for
/// the albedo the composite applies); `back`: light_back_frame's result for the same options.
MunozFrame render_munoz_frame(const Scene& scene, const realtime::RasterizedFrame& frame,
                              const realtime::LitFrame& lit, const realtime::LitFrame& back,
                              const std::map<int, realtime::FrameMaterial>& materials,
                              const std::map<int, RadialProfile>& profiles,
                              const approx::MunozOptions& options,
                              const realtime::FrameOptions& fo);

/// The lit point clouds of the media in view, one octree per medium material (every shape of it):
/// what Jensen-Buhler variants of one density share (the threshold and profile are per query).
struct JensenBuhlerCloud {
    std::map<int, approx::PointOctree> trees;  ///< by scene material
    std::size_t points = 0;
    double sample_seconds = 0;  ///< Poisson-disk sampling
    double light_seconds = 0;   ///< realtime::boundary_irradiance
    double tree_seconds = 0;    ///< the octrees
    double seconds() const { return sample_seconds + light_seconds + tree_seconds; }
};

/// Points at options.points_per_mm2 (candidates_per_point) on every shape of each material of
/// `media` (scene material indices), seeded per shape from `seed`, lit with fo's lighting options.
JensenBuhlerCloud build_jensen_buhler_cloud(const Scene& scene, const std::vector<int>& media,
                                            const approx::JensenBuhlerOptions& options,
                                            const realtime::FrameOptions& fo, std::uint64_t seed);

struct JensenBuhlerFrame {
    realtime::FrameResult frame;      ///< its "sss" pass time is the queries'
    approx::HierarchicalStats stats;  ///< summed over the pixels
    double query_seconds = 0;
};

/// `frame` rendered with the hierarchical integration as its SSS pass: M at each medium pixel's
/// surface point (the camera ray at its view depth) from `cloud` (built for frame.media_in_view),
/// with options.profile ("mc": `profiles`; else the analytic model for the material's
/// coefficients, per channel) at options' threshold and bound.
JensenBuhlerFrame render_jensen_buhler_frame(
    const Scene& scene, const realtime::RasterizedFrame& frame, const realtime::LitFrame& lit,
    const std::map<int, realtime::FrameMaterial>& materials,
    const std::map<int, RadialProfile>& profiles, const JensenBuhlerCloud& cloud,
    const approx::JensenBuhlerOptions& options, const realtime::FrameOptions& fo);

}  // namespace ssslab::runner
