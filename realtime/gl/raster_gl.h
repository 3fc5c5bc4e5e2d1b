// The G-buffer's geometry in GL, the twin of realtime/raster.h's `rasterize(Scene)`: the scene's
// shapes through the same RasterCamera (clip coordinates from `project`, computed in double and
// uploaded as floats), back faces of closed shapes culled as the software rasterizer culls them,
// depth tested, one sample per pixel; out come the arrays of a RasterFrame: view_z, ray_t, shape,
// triangle, and the per-pixel coverage and depth. Coverage is the GPU's own (its fill rule and
// sub-pixel precision), which is what a shader author ships; tests/test_gl.cpp measures how far
// it is from the software rasterizer's.
//
// Depth: reversed float depth near / w (glClipControl zero-to-one, GL_GREATER, cleared to 0), so
// that the depth buffer's precision is relative, as the software rasterizer's double view depth;
// the near plane is the software's (RasterOptions::near) through the clip volume's z >= 0.
// view_z is 1 / gl_FragCoord.w (float); ray_t = view_z times the ray's length per depth, computed
// after read-back as the software rasterizer computes it (RasterCamera::sample_rays).
#pragma once

#include "core/scene.h"
#include "realtime/gl/context.h"
#include "realtime/raster.h"

#include <memory>

namespace ssslab::realtime::gl {

struct GlRasterTimes {
    double gpu_ms = 0;   ///< GL_TIME_ELAPSED of the clears and draws (meshes resident)
    double draw_ms = 0;  ///< wall time of the same, glFinish to glFinish (gl_util.h GlTimer)
    double wall_ms = 0;  ///< the whole call: uploads, draws, read-back, ray_t
};

class GlRaster {
  public:
    /// Needs OpenGL 4.5 (glClipControl); throws std::runtime_error otherwise.
    explicit GlRaster(GlContext& context);
    ~GlRaster();
    GlRaster(const GlRaster&) = delete;
    GlRaster& operator=(const GlRaster&) = delete;

    /// `rasterize(scene, options, width, height, out)` on the GPU. Supports supersampling (the
    /// same sample grid, pixels box-filtered as the software's), the perspective camera and
    /// the depth test; barycentrics and fragment counts are not filled
    /// (out.barycentric and out.fragments are left empty). Throws std::invalid_argument for
    /// options it does not support.
    void rasterize(const Scene& scene, const RasterOptions& options, int width, int height,
                   RasterFrame& out, GlRasterTimes* times = nullptr);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ssslab::realtime::gl
