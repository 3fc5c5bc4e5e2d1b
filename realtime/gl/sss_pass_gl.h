// The separable screen-space SSS pass in GLSL (`shaders/sss_pass.frag`), the GL twin of
// realtime/sss_pass.h: the same plain-data inputs (SssGBuffer, SssMaterialKernel, SssParams),
// uploaded as they are, and the same output. Every rule of the CPU pass (taps, kernel scale,
// narrow kernels, clamp-to-edge, follow-surface, rejection, jitter, rotation) is the shader's; it
// is held to the CPU pass by tests/test_gl.cpp.
#pragma once

#include "realtime/gl/context.h"
#include "realtime/sss_pass.h"

#include <memory>
#include <vector>

namespace ssslab::realtime::gl {

/// Times of one run of the pass.
struct GlSssTimes {
    double gpu_ms = 0;       ///< GL_TIME_ELAPSED of the pass's draws (inputs resident)
    double draw_ms = 0;      ///< wall time of the draws, glFinish to glFinish (gl_util.h GlTimer)
    double upload_ms = 0;    ///< wall time to upload the G-buffer and the taps
    double readback_ms = 0;  ///< wall time to read the result back
    double wall_ms = 0;      ///< wall time of the whole call
};

class GlSssPass {
  public:
    /// Programs are compiled on first use, per variant (edge mode, jitter, rotation, phase), in
    /// this context (made current by every call).
    explicit GlSssPass(GlContext& context);
    ~GlSssPass();
    GlSssPass(const GlSssPass&) = delete;
    GlSssPass& operator=(const GlSssPass&) = delete;

    /// realtime::sss_pass on the GPU: out is RGB interleaved as the G-buffer's irradiance. Throws
    /// std::invalid_argument for what sss_pass refuses, std::runtime_error when GL fails (a
    /// shader that does not compile names the compiler's message).
    void run(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
             const SssParams& p, std::vector<float>& out, GlSssTimes* times = nullptr);
    /// The same, `repeat` times on inputs uploaded once (for timing): each run's draw times
    /// (gpu_ms, draw_ms).
    std::vector<GlSssTimes> time_runs(const SssGBuffer& g,
                                      const std::vector<SssMaterialKernel>& materials,
                                      const SssParams& p, int repeat);

    struct Impl;  ///< the GL objects (sss_pass_gl.cpp)

  private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace ssslab::realtime::gl
