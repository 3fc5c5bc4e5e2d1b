// What every pass of the GL twin needs (internal to realtime/gl): errors as exceptions, shader
// programs that name the compiler's message, plain textures, wall-clock milliseconds. Include
// after <glad/gl.h>.
#pragma once

#include <glad/gl.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace ssslab::realtime::gl {

/// Milliseconds since t0.
double ms_since(std::chrono::steady_clock::time_point t0);
/// Throws std::runtime_error naming `what` if GL has recorded an error.
void check_gl(const char* what);
/// A linked program of a vertex and a fragment shader; a shader that does not compile or a
/// program that does not link throws std::runtime_error with the compiler's log, named `name`.
GLuint link_program(const std::string& vert, const std::string& frag, const std::string& name);
/// A w x h texture (nearest, clamp-to-edge, no mipmaps) of `internal` format from data (or
/// uninitialised when null).
GLuint make_texture(int w, int h, GLenum internal, GLenum format, GLenum type, const void* data);

/// A mesh's vertex buffer (floats, any number per vertex) and index buffer, the latter bound to
/// `vao`; `count` indices.
struct GlMesh {
    GLuint vbo = 0, ibo = 0;
    GLsizei count = 0;
};
GlMesh upload_mesh(GLuint vao, const std::vector<float>& vertices,
                   std::span<const std::array<std::uint32_t, 3>> triangles);
void release_mesh(const GlMesh& mesh);

/// Times a stretch of GL commands two ways: GL_TIME_ELAPSED, what the GPU reports, and the wall
/// time from a glFinish before it to a glFinish after it, what the caller waits. On llvmpipe the
/// timer query does not see the rasterization, which runs deferred in its own threads (it
/// measured 0.00 ms and, once, hours), so the wall time is the one to read there.
class GlTimer {
  public:
    GlTimer();
    ~GlTimer();
    GlTimer(const GlTimer&) = delete;
    GlTimer& operator=(const GlTimer&) = delete;
    void begin();
    void end();
    double gpu_ms();  ///< the query's result (waits for it)
    double wall_ms() const { return wall_ms_; }

  private:
    GLuint query_ = 0;
    std::chrono::steady_clock::time_point t0_;
    double wall_ms_ = 0;
};

}  // namespace ssslab::realtime::gl
