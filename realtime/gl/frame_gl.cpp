#include "realtime/gl/frame_gl.h"

#include <stdexcept>

namespace ssslab::realtime::gl {

void GlFrameBackend::install(FrameOptions& o) {
    o.rasterizer = [this](const Scene& scene, const RasterOptions& ro, int w, int h,
                          RasterFrame& out) {
        raster.rasterize(scene, ro, w, h, out, &raster_times);
    };
    o.lighting_pass = [this](const Scene& scene, const RasterCamera& camera,
                             const RasterFrame& frame, const LightingOptions& lo,
                             const std::vector<SlabTransmittance>& slabs, LightingStats* stats,
                             GBuffer& out) {
        lighting.shade(scene, camera, frame, lo, slabs, stats, out, &lighting_times);
    };
    o.separable_pass = [this](const SssGBuffer& g, const std::vector<SssMaterialKernel>& m,
                              const SssParams& p,
                              std::vector<float>& out) { sss.run(g, m, p, out, &sss_times); };
}

}  // namespace ssslab::realtime::gl
