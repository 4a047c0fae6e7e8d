// Small owners of OpenGL objects for the renderer: a linked shader program with uniform
// setters, and 2D textures/framebuffers. Needs a current OpenGL 3.3 core context.
#pragma once

#include <epoxy/gl.h>

#include <array>
#include <string>

#include "sphfem/core/vec.h"

namespace sphfem::render::gl {

class Program {
 public:
  Program() = default;
  // Compiles and links; throws std::runtime_error with the driver's log on failure.
  Program(const std::string& name, const std::string& vertex, const std::string& fragment);
  ~Program();
  Program(Program&& o) noexcept;
  Program& operator=(Program&& o) noexcept;
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  void use() const { glUseProgram(id_); }
  // Setters for the program in use; a name the linker optimised away is ignored.
  void set(const char* name, int v) const;
  void set(const char* name, int x, int y) const;
  void set(const char* name, float v) const;
  void set(const char* name, float x, float y) const;
  void set(const char* name, const Vec3d& v) const;
  void set(const char* name, float x, float y, float z, float w) const;
  void set(const char* name, const std::array<float, 16>& column_major) const;

 private:
  GLint loc(const char* name) const { return glGetUniformLocation(id_, name); }
  GLuint id_ = 0;
};

// A 2D texture of one internal format, nearest filtering unless `linear`, clamped at the edges.
class Texture {
 public:
  Texture() = default;
  ~Texture() { release(); }
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  // (Re)allocates storage when the size or format changes.
  void allocate(int width, int height, GLenum internal_format, GLenum format, GLenum type,
                bool linear = false);
  void bind(int unit) const;
  GLuint id() const { return id_; }

 private:
  void release();
  GLuint id_ = 0;
  int w_ = 0, h_ = 0;
  GLenum fmt_ = 0;
};

// A framebuffer over one colour texture and an optional depth texture.
class Framebuffer {
 public:
  Framebuffer() = default;
  ~Framebuffer();
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;
  // Throws std::runtime_error naming `what` when the driver rejects the combination.
  void attach(const char* what, const Texture& color, const Texture* depth);
  GLuint id() const { return id_; }

 private:
  GLuint id_ = 0;
};

}  // namespace sphfem::render::gl
