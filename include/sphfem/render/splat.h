// A software picture of the fluid: every particle a ray-cast sphere in a tank drawn with its
// floor, far walls and edges. Deterministic: the same input gives the same bytes whatever the
// OpenMP thread count.
#pragma once

#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/render/camera.h"
#include "sphfem/render/image.h"

namespace sphfem::render {

struct RenderStyle {
  bool floor = true;  // tank floor with a faint grid and the water's shadow
  bool walls = true;  // the far walls seen through the open front
  bool edges = true;  // the 12 edges of the box; those hidden by water drawn faintly
  // Water darkens with depth below its surface over this length (m); 0 = a quarter of the box
  // height, so the tank's depth reads at a glance.
  double absorption_length = 0;
  // Speed (m/s) where white foam starts, and where it is complete: a pour's jet stays water,
  // the splash where it lands turns white.
  double foam_start = 1.5, foam_full = 4.0;
  double specular = 0.45;  // strength of the Blinn-Phong highlight
  // Samples per pixel along each axis (1 to 4); 2 smooths sphere outlines and the moire of
  // small, regularly spaced particles for four times the work.
  int supersample = 2;
};

// Renders particles of world radius `radius` at `positions_xyz` (3 floats each) inside the box
// [box_lo, box_hi] (y up). `speed`, when given, holds one value per particle and turns fast
// water into foam. Particles crossing the camera's eye plane are left out.
Image render_particles(const Camera& camera, const std::vector<float>& positions_xyz,
                       const std::vector<float>* speed, float radius, const Vec3d& box_lo,
                       const Vec3d& box_hi, const RenderStyle& style = {});

}  // namespace sphfem::render
