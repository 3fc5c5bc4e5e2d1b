#include "realtime/gl/gl_util.h"

#include <algorithm>
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
        throw std::runtime_error(name + " does not compile: " + log);
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

// A float texture of w x h texels of `channels` components (nearest, no mipmaps).
GLuint make_texture(int w, int h, GLenum internal, GLenum format, GLenum type, const void* data) {
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, data);
    return t;
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
