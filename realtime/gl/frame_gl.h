// The GL twin of a whole frame (realtime/frame.h): the raster, pass 1 and the separable SSS pass
// in one context, plugged into FrameOptions' backend hooks (`rasterizer`, `lighting_pass`,
// `separable_pass`), so that `rasterize_frame`, `light_frame` and `render_frame` run the same
// sequence, with the same inputs and outputs, on either backend. The composite (pass 4: a few
// multiply-adds per pixel on the read-back layers) stays the CPU's.
#pragma once

#include "realtime/frame.h"
#include "realtime/gl/context.h"
#include "realtime/gl/lighting_gl.h"
#include "realtime/gl/raster_gl.h"
#include "realtime/gl/sss_pass_gl.h"

namespace ssslab::realtime::gl {

class GlFrameBackend {
  public:
    explicit GlFrameBackend(GlContext& context)
        : raster(context), lighting(context), sss(context) {}

    /// Points o's backend hooks at this object's passes (which must outlive o's frames).
    void install(FrameOptions& o);

    GlRaster raster;
    GlLighting lighting;
    GlSssPass sss;
    /// The last frame's times of each pass (filled by the hooks).
    GlRasterTimes raster_times;
    GlLightingTimes lighting_times;
    GlSssTimes sss_times;
};

}  // namespace ssslab::realtime::gl
