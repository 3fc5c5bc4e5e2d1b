#include "realtime/gl/gl_util.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace ssslab::realtime::gl {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void check_gl(const char* what) {
    const GLenum e = glGetError();
    if (e != GL_NO_ERROR)
        throw std::runtime_error(std::string("OpenGL error 0x") + std::to_string(e) + " in " +
                                 what);
}

static GLuint compile(GLenum type, const std::string& source, const std::string& name) {
    const GLuint s = glCreateShader(type);
    const char* src = source.c_str();
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
        glGetShaderInfoLog(s, len, nullptr, log.data());
        glDeleteShader(s);
        throw GlShaderError(name + " does not compile: " + log, log);
    }
    return s;
}

GLuint link_program(const std::string& vert, const std::string& frag, const std::string& name) {
    const GLuint vs = compile(GL_VERTEX_SHADER, vert, name + " (vertex)");
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, frag, name);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
        glGetProgramInfoLog(p, len, nullptr, log.data());
        glDeleteProgram(p);
        throw std::runtime_error(name + " does not link: " + log);
    }
    return p;
}

GLuint make_texture(int w, int h, GLenum internal, GLenum format, GLenum type, const void* data) {
    // Made on the active unit, whose binding is put back: a texture made between draws must not
    // replace an input a program was given (the GL lighting makes a shadow map's targets the
    // first time a map size comes up, with the light pass's inputs bound).
    GLint previous = 0;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &previous);
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, data);
    glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(previous));
    return t;
}

void bind_texture(GLuint program, const char* name, int unit, GLuint texture, GLenum target) {
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
    glBindTexture(target, texture);
    glUniform1i(glGetUniformLocation(program, name), unit);
}

void require_gl(int major, int minor, const std::string& what) {
    GLint have_major = 0, have_minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &have_major);
    glGetIntegerv(GL_MINOR_VERSION, &have_minor);
    if (have_major * 10 + have_minor < major * 10 + minor)
        throw std::runtime_error(what + ", this context has " + std::to_string(have_major) + "." +
                                 std::to_string(have_minor));
}

GlFramebuffer make_framebuffer(int w, int h, const std::vector<GLuint>& colors, bool depth,
                               const std::string& what) {
    GlFramebuffer f;
    glGenFramebuffers(1, &f.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, f.fbo);
    std::vector<GLenum> bufs;
    for (size_t k = 0; k < colors.size(); ++k) {
        bufs.push_back(static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + k));
        glFramebufferTexture2D(GL_FRAMEBUFFER, bufs.back(), GL_TEXTURE_2D, colors[k], 0);
    }
    glDrawBuffers(static_cast<GLsizei>(bufs.size()), bufs.data());
    if (depth) {
        glGenRenderbuffers(1, &f.depth);
        glBindRenderbuffer(GL_RENDERBUFFER, f.depth);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, f.depth);
    }
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        release_framebuffer(f);
        throw std::runtime_error(what + ": the framebuffer is incomplete");
    }
    check_gl(what.c_str());
    return f;
}

void release_framebuffer(const GlFramebuffer& f) {
    glDeleteRenderbuffers(1, &f.depth);
    glDeleteFramebuffers(1, &f.fbo);
}

void begin_id_pass(int int_layers) {
    glDisable(GL_BLEND);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);  // reversed depth: near / w
    glDepthMask(GL_TRUE);
    const float inf = std::numeric_limits<float>::infinity();
    const float clear_z[4] = {inf, 0, 0, 0};
    const GLint clear_none[4] = {-1, 0, 0, 0};
    const float clear_depth = 0;
    glClearBufferfv(GL_COLOR, 0, clear_z);
    for (int k = 1; k <= int_layers; ++k) glClearBufferiv(GL_COLOR, k, clear_none);
    glClearBufferfv(GL_DEPTH, 0, &clear_depth);
}

void end_id_pass() {
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
}

GlMesh upload_mesh(GLuint vao, const std::vector<float>& vertices,
                   std::span<const std::array<std::uint32_t, 3>> triangles) {
    GlMesh m;
    m.count = static_cast<GLsizei>(3 * triangles.size());
    glGenBuffers(1, &m.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
                 vertices.data(), GL_STATIC_DRAW);
    glGenBuffers(1, &m.ibo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(triangles.size() * 3 * sizeof(std::uint32_t)),
                 triangles.data(), GL_STATIC_DRAW);
    return m;
}

void release_mesh(const GlMesh& m) {
    glDeleteBuffers(1, &m.vbo);
    glDeleteBuffers(1, &m.ibo);
}

void draw_mesh(const GlMesh& m, int components) {
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glVertexAttribPointer(0, components, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ibo);
    glDrawElements(GL_TRIANGLES, m.count, GL_UNSIGNED_INT, nullptr);
}

GlTimer::GlTimer() {
    glGenQueries(1, &query_);
}
GlTimer::~GlTimer() {
    glDeleteQueries(1, &query_);
}
void GlTimer::begin() {
    glFinish();
    t0_ = std::chrono::steady_clock::now();
    glBeginQuery(GL_TIME_ELAPSED, query_);
}
void GlTimer::end() {
    glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    wall_ms_ = ms_since(t0_);
}
double GlTimer::gpu_ms() {
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &ns);
    return static_cast<double>(ns) * 1e-6;
}

}  // namespace ssslab::realtime::gl
