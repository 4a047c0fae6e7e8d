#include "gl_program.h"

#include <cstdio>
#include <stdexcept>
#include <utility>
#include <vector>

namespace sphfem::render::gl {
namespace {

GLuint compile(const std::string& name, GLenum stage, const std::string& source) {
  const GLuint s = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(std::size_t(n > 0 ? n : 1), '\0');
    glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error("shader '" + name + "' (" +
                             (stage == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                             ") does not compile: " + log.data());
  }
  return s;
}

}  // namespace

Program::Program(const std::string& name, const std::string& vertex, const std::string& fragment) {
  const GLuint vs = compile(name, GL_VERTEX_SHADER, vertex);
  GLuint fs = 0;
  try {
    fs = compile(name, GL_FRAGMENT_SHADER, fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  id_ = glCreateProgram();
  glAttachShader(id_, vs);
  glAttachShader(id_, fs);
  glLinkProgram(id_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(id_, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(std::size_t(n > 0 ? n : 1), '\0');
    glGetProgramInfoLog(id_, GLsizei(log.size()), nullptr, log.data());
    glDeleteProgram(id_);
    id_ = 0;
    throw std::runtime_error("shader program '" + name + "' does not link: " + log.data());
  }
}

Program::~Program() {
  if (id_) glDeleteProgram(id_);
}

Program::Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0)) {}

Program& Program::operator=(Program&& o) noexcept {
  if (this != &o) {
    if (id_) glDeleteProgram(id_);
    id_ = std::exchange(o.id_, 0);
  }
  return *this;
}

void Program::set(const char* name, int v) const { glUniform1i(loc(name), v); }
void Program::set(const char* name, int x, int y) const { glUniform2i(loc(name), x, y); }
void Program::set(const char* name, float v) const { glUniform1f(loc(name), v); }
void Program::set(const char* name, float x, float y) const { glUniform2f(loc(name), x, y); }
void Program::set(const char* name, const Vec3d& v) const {
  glUniform3f(loc(name), float(v.x), float(v.y), float(v.z));
}
void Program::set(const char* name, float x, float y, float z, float w) const {
  glUniform4f(loc(name), x, y, z, w);
}
void Program::set(const char* name, const std::array<float, 16>& m) const {
  glUniformMatrix4fv(loc(name), 1, GL_FALSE, m.data());
}

void Texture::allocate(int width, int height, GLenum internal_format, GLenum format, GLenum type,
                       bool linear) {
  if (id_ && w_ == width && h_ == height && fmt_ == internal_format) return;
  release();
  glGenTextures(1, &id_);
  glBindTexture(GL_TEXTURE_2D, id_);
  glTexImage2D(GL_TEXTURE_2D, 0, GLint(internal_format), width, height, 0, format, type, nullptr);
  const GLint filter = linear ? GL_LINEAR : GL_NEAREST;
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, 0);
  w_ = width;
  h_ = height;
  fmt_ = internal_format;
}

void Texture::bind(int unit) const {
  glActiveTexture(GLenum(GL_TEXTURE0 + unit));
  glBindTexture(GL_TEXTURE_2D, id_);
}

void Texture::release() {
  if (id_) glDeleteTextures(1, &id_);
  id_ = 0;
  w_ = h_ = 0;
  fmt_ = 0;
}

Framebuffer::~Framebuffer() {
  if (id_) glDeleteFramebuffers(1, &id_);
}

void Framebuffer::attach(const char* what, const Texture& color, const Texture* depth) {
  if (!id_) glGenFramebuffers(1, &id_);
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color.id(), 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                         depth ? depth->id() : 0, 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%x", unsigned(status));
    throw std::runtime_error(std::string("the OpenGL driver rejects the ") + what +
                             " framebuffer (status " + code + ")");
  }
}

}  // namespace sphfem::render::gl
