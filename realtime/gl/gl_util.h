// What every pass of the GL twin needs (internal to realtime/gl): errors as exceptions, shader
// programs that name the compiler's message, plain textures, wall-clock milliseconds. Include
// after <glad/gl.h>.
#pragma once

#include <glad/gl.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ssslab::realtime::gl {

/// Milliseconds since t0.
double ms_since(std::chrono::steady_clock::time_point t0);
/// Throws std::runtime_error naming `what` if GL has recorded an error.
void check_gl(const char* what);
/// A shader that does not compile: the message names the shader, `log` is the compiler's own.
struct GlShaderError : std::runtime_error {
    GlShaderError(const std::string& what, std::string compiler_log)
        : std::runtime_error(what), log(std::move(compiler_log)) {}
    std::string log;
};

/// A linked program of a vertex and a fragment shader; a shader that does not compile throws
/// GlShaderError, a program that does not link std::runtime_error, with the compiler's log,
/// named `name`.
GLuint link_program(const std::string& vert, const std::string& frag, const std::string& name);
/// A w x h texture (nearest, clamp-to-edge, no mipmaps) of `internal` format from data (or
/// uninitialised when null). The texture units' bindings are left as they were.
GLuint make_texture(int w, int h, GLenum internal, GLenum format, GLenum type, const void* data);

/// Binds `texture` to texture unit `unit` and points sampler `name` of `program` (current) at
/// it.
void bind_texture(GLuint program, const char* name, int unit, GLuint texture,
                  GLenum target = GL_TEXTURE_2D);

/// Throws std::runtime_error unless the current context has OpenGL major.minor or later; `what`
/// names the pass and what it needs ("the GL raster needs OpenGL 4.5 (glClipControl)").
void require_gl(int major, int minor, const std::string& what);

/// A framebuffer drawing into `colors` (attached at 0, 1, ..., in order) and, with `depth`, a
/// w x h GL_DEPTH_COMPONENT32F renderbuffer; std::runtime_error naming `what` when incomplete.
struct GlFramebuffer {
    GLuint fbo = 0, depth = 0;
};
GlFramebuffer make_framebuffer(int w, int h, const std::vector<GLuint>& colors, bool depth,
                               const std::string& what);
void release_framebuffer(const GlFramebuffer& f);

/// An ID pass with reversed float depth (the G-buffer's raster and the shadow maps): clip depth
/// zero-to-one, GL_GREATER, depth cleared to 0, colour attachment 0 (a float depth layer) cleared
/// to +inf and attachments 1..int_layers (integer ids) to -1, blending off. end_id_pass restores
/// the clip depth and turns the depth test and culling off.
void begin_id_pass(int int_layers);
void end_id_pass();

/// A mesh's vertex buffer (floats, any number per vertex) and index buffer, the latter bound to
/// `vao`; `count` indices.
struct GlMesh {
    GLuint vbo = 0, ibo = 0;
    GLsizei count = 0;
};
GlMesh upload_mesh(GLuint vao, const std::vector<float>& vertices,
                   std::span<const std::array<std::uint32_t, 3>> triangles);
void release_mesh(const GlMesh& mesh);
/// Draws a mesh of upload_mesh (its VAO bound), `components` floats a vertex as attribute 0.
void draw_mesh(const GlMesh& mesh, int components);

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
