// The static obstacles of a scene (SceneSpec::obstacles) as one triangle set that the fluid's
// rays and the bodies' nodes meet.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/couple/impulse.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/scene/spec.h"

namespace sphfem {

struct ObstaclesModel {
  std::vector<Vec3> x;                // m, every obstacle's vertices in the scene
  std::vector<Tri> tris;              // indices into x; a box's faces point outward
  std::vector<int> tri_offset;        // obstacle k owns [tri_offset[k], tri_offset[k + 1])
  std::vector<ContactCoeffs> coeffs;  // fluid contact, one per obstacle
  std::vector<std::uint8_t> closed;   // per obstacle: bounds a solid (box, closed surface)
  bool empty() const { return tris.empty(); }
};

// Builds every obstacle: a box's 12 triangles, a mesh file read, scaled and offset. Throws
// SceneError naming the file, the field and the fix (a box with min not below max, a mesh file
// missing, unreadable or with more triangles than the cap, an obstacle reaching outside the
// domain, fluid with the boundary-particle coupling). `scene_file` names the scene in messages and
// is the folder relative paths start at.
ObstaclesModel compile_obstacles(const SceneSpec& scene, const std::string& scene_file);

}  // namespace sphfem
