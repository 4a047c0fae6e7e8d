// What one picture shows, independent of how it is drawn: fluid particles, body surfaces as
// triangle meshes, and the tank. Filled from frame files (sphfem render) or from a live
// simulation (sphfem view).
#pragma once

#include <cstdint>
#include <vector>

#include "sphfem/core/vec.h"

namespace sphfem::render {

struct TriangleMesh {
  std::vector<float> positions;        // 3 per vertex
  std::vector<std::uint32_t> indices;  // 3 per triangle, counter-clockwise seen from outside
  Vec3d color{0.90, 0.45, 0.28};       // linear-ish RGB in [0, 1]
};

struct RenderFrame {
  std::vector<float> particles;  // 3 per particle, world positions
  float radius = 0.01f;          // particle radius (m)
  std::vector<TriangleMesh> meshes;
  bool has_box = false;  // draw the tank; otherwise only the floor under everything
  Vec3d box_lo, box_hi;

  std::size_t particle_count() const { return particles.size() / 3; }
};

// Area-weighted vertex normals (3 per vertex, unit length; zero for unused vertices): the
// smooth shading of a body's surface without storing normals in the frame files.
std::vector<float> smooth_normals(const TriangleMesh& mesh);

// The box holding the tank (when known), every finite particle and every mesh vertex; false
// when the frame holds nothing at all.
bool frame_bounds(const RenderFrame& frame, Vec3d* lo, Vec3d* hi);

// Colour of body `index` in a small palette chosen to stand apart from blue water.
Vec3d body_color(int index);

}  // namespace sphfem::render
