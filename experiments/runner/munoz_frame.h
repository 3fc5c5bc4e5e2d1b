// Munoz11's layered convolution (approx/munoz.h) inside a real-time frame (realtime/frame.h), so
// that it is scored like the separable models: the same raster, pass 1 and composite, with the
// SSS pass replaced (FrameOptions::separable_pass) by the layered convolution of each medium
// material's front samples (the G-buffer) and back samples (a second raster of the media's far
// sides, lit by pass 1 with the whole scene's lights and shadows) [Munoz11 §4.2].
//
// Units: the G-buffer holds the irradiance that entered; an MC profile's R_d is per incident
// photon (it carries 1 - R_sp), so the layered convolution runs on R_d / (1 - R_sp), the exitance
// per entered irradiance, and hands the composite M / albedo (the composite multiplies by the
// material's albedo, FrameMaterial::albedo, then by the exit weight), so that M itself reaches the
// image through the same exit rule as every kernel model.
#pragma once

#include "approx/munoz.h"
#include "core/profile.h"
#include "core/scene.h"
#include "realtime/frame.h"

#include <map>
#include <vector>

namespace ssslab::runner {

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

}  // namespace ssslab::runner
