// Screen-space fluid rendering over OpenGL 3.3 core (van der Laan, Green & Sainz, "Screen
// Space Fluid Rendering with Curvature Flow", I3D 2009; Green, "Screen Space Fluid
// Rendering for Games", GDC 2010). The fluid is never meshed: each frame is five passes over
// the particles and the screen.
//
//   scene    sky, floor, tank walls and edges, bodies (lit, smooth normals) -> colour + depth
//   depth    particles as point sprites shaped into spheres -> nearest eye depth
//   thickness  the same sprites, blended additively -> length of water along each view ray
//   smooth   separable bilateral filter on depth, several sweeps -> a continuous surface
//   normals  finite differences of the smoothed depth in eye space
//   composite  Fresnel (Schlick) mix of the sky's reflection and the scene seen through the
//              water: offset by normal x thickness, absorbed per channel (Beer-Lambert)
//
// Why this and not a mesh (marching cubes): the cost is per pixel and per particle, with no
// grid over the domain, so it follows the frame size, not the tank size; and it runs on
// Mesa's llvmpipe on a CPU-only machine. Bilateral smoothing (instead of the paper's
// curvature flow) converges in a fixed number of sweeps and keeps silhouettes in place.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/render/camera.h"
#include "sphfem/render/frame.h"
#include "sphfem/render/matrices.h"

namespace sphfem::render {

struct FluidStyle {
  bool surface = true;     // the screen-space water surface
  bool particles = false;  // lit spheres instead of the surface (takes precedence)
  bool meshes = true;      // bodies as lit triangles
  bool wireframe = false;  // bodies' triangle edges on top
  bool floor = true;
  bool tank = true;  // far walls and edges of the domain box, when the frame has one
  // Bilateral sweeps on the depth (each one horizontal and one vertical); 0 draws the raw
  // spheres' depth.
  int smoothing_iterations = 4;
  double smoothing_radius = 3.0;  // filter half-width, in particle radii
  double smoothing_max_px = 20;   // and at most this many pixels
  // Beer-Lambert coefficients (1/m) per channel; all zero: chosen from the tank height so
  // that a quarter of it reads as deep water whatever the scale of the scene.
  Vec3d absorption{0, 0, 0};
  double refraction = 0.3;             // background offset per projected thickness
  Vec3d light_dir{-0.35, 0.85, 0.40};  // towards the light, world space
};

// Needs a current OpenGL 3.3 core context (EGL headless or a window) for its whole life.
class FluidRenderer {
 public:
  // Compiles the shaders; throws std::runtime_error with the driver's message on failure.
  FluidRenderer();
  ~FluidRenderer();
  FluidRenderer(const FluidRenderer&) = delete;
  FluidRenderer& operator=(const FluidRenderer&) = delete;

  // Draws the frame into framebuffer `target` (0 = the window's) over camera.width x
  // camera.height pixels.
  void render(const RenderFrame& frame, const Camera& camera, const FluidStyle& style,
              unsigned target);

  // One line of text with a translucent dark band behind it, top-left corner at pixel
  // (x, y) counted from the top-left of a width x height framebuffer.
  void draw_text(const std::string& text, int x, int y, int scale, unsigned target, int width,
                 int height);

  // Results of the last render's passes, rows top to bottom (for tests and inspection).
  std::vector<float> fluid_depth() const;     // raw sphere eye depth, 0 = no fluid
  std::vector<float> smoothed_depth() const;  // after the bilateral sweeps
  std::vector<float> normals() const;         // 3 per pixel, eye space; 0 where no fluid
  std::vector<float> thickness() const;       // m, after its blur

  // The matrices of the last render.
  const Mat4& view() const;
  const Mat4& projection() const;
  // "renderer, version" of the context, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core
  // Profile) Mesa 22.3.6".
  std::string device() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sphfem::render
