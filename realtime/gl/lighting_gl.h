// Pass 1 of the real-time renderer in GL, the twin of realtime/lighting.h's `shade`: the same
// G-buffer (GBuffer, read back) from the same inputs (Scene, RasterCamera, RasterFrame,
// LightingOptions, SlabTransmittance), the light samples and the shadow views fitted to the
// receivers from the same C++ objects (`plan_lights`, `LightPlan::views`), the
// BoundaryTransmittance tables uploaded as the CPU tabulates them. Three programs
// (shaders/lighting_*.{glsl,frag}, shadow.{vert,frag}):
//
//   receiver pass  one full-screen draw: facet normal, material, kind of receiver, exit weight,
//                  a smooth boundary's mirror reflection, what is seen directly
//   shadow maps    per view of a light sample: the scene's shapes from the light, both sides,
//                  ShadowView::to_clip in the vertex shader (reversed depth as the G-buffer)
//   light pass     per view of a light sample: what it adds to irradiance, specular, surface,
//                  translucency and thickness, blended additively in the CPU's light order
//
// Where the two differ: arithmetic in float (the CPU computes receivers, projections and
// boundary terms in double and rounds the sums to float), the GPU's own rasterization of the
// shadow maps (its fill rule; both sides drawn, as the CPU's), and the receivers' box that the
// maps are fitted to, which is computed on the CPU from the read-back kinds (an engine would
// reduce it on the GPU [Lauritzen 2011, sample distribution shadow maps]). tests/test_gl.cpp
// measures the difference per layer.
#pragma once

#include "core/scene.h"
#include "realtime/gl/context.h"
#include "realtime/lighting.h"
#include "realtime/raster.h"

#include <memory>
#include <vector>

namespace ssslab::realtime::gl {

struct GlLightingTimes {
    double shadow_gpu_ms = 0, shadow_wall_ms = 0;    ///< the shadow maps' draws
    double shading_gpu_ms = 0, shading_wall_ms = 0;  ///< receiver and light passes' draws
    double upload_ms = 0, readback_ms = 0;           ///< wall time of the transfers
    double wall_ms = 0;                              ///< the whole call
    int shadow_maps = 0;
};

class GlLighting {
  public:
    /// Programs compiled in this context (made current by every call).
    explicit GlLighting(GlContext& context);
    ~GlLighting();
    GlLighting(const GlLighting&) = delete;
    GlLighting& operator=(const GlLighting&) = delete;

    /// realtime::shade on the GPU (same arguments, same checks). LightingStats: shadow_ms is
    /// the maps' wall time (glFinish to glFinish), shading_ms the rest of the call.
    void shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
               const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
               LightingStats* stats, GBuffer& out, GlLightingTimes* times = nullptr);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ssslab::realtime::gl
