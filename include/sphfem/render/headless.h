// Pictures without a window or display server: an EGL context on the surfaceless platform
// (EGL_MESA_platform_surfaceless), or failing that the first EGL device
// (EGL_EXT_platform_device), rendering into an offscreen framebuffer. On a machine without
// a GPU, Mesa's llvmpipe runs the same shaders on the CPU.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "sphfem/render/camera.h"
#include "sphfem/render/fluid_gl.h"
#include "sphfem/render/frame.h"
#include "sphfem/render/image.h"

namespace sphfem::render {

// No OpenGL 3.3 core context could be made here; what() says which step failed.
struct GlUnavailable : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class HeadlessRenderer {
 public:
  // Creates the context and compiles the shaders. Throws GlUnavailable when EGL or the
  // context cannot be had (also in a build without OpenGL), std::runtime_error when a
  // shader fails.
  HeadlessRenderer();
  ~HeadlessRenderer();
  HeadlessRenderer(const HeadlessRenderer&) = delete;
  HeadlessRenderer& operator=(const HeadlessRenderer&) = delete;

  // The frame at camera.width x camera.height, rows top to bottom.
  Image render(const RenderFrame& frame, const Camera& camera, const FluidStyle& style = {});

  // The pass results and matrices of the last render() (this renderer's context is made
  // current for reading them), and the device's name.
  const FluidRenderer& passes() const;
  std::string device() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sphfem::render
