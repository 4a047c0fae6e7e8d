// The obstacles of a scene (SceneSpec::obstacles) as one triangle set that the fluid's rays and
// the bodies' nodes meet, and the rigid path each one may follow.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/couple/impulse.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/scene/spec.h"

namespace sphfem {

// A rigid motion: p -> R (p - pivot) + pivot + t, R the unit quaternion q = (w, x, y, z).
// The identity maps every point to itself bit for bit.
struct RigidPose {
  double q[4] = {1, 0, 0, 0};
  Vec3d t, pivot;
  bool identity = true;

  Vec3d rotate(const Vec3d& v) const;
  Vec3d apply(const Vec3d& p) const;
  Vec3d inverse(const Vec3d& p) const;
  Vec3 apply(const Vec3& p) const { return identity ? p : Vec3(apply(Vec3d(p))); }
  Vec3 inverse(const Vec3& p) const { return identity ? p : Vec3(inverse(Vec3d(p))); }
};

// The pose of a path (ObstacleSpec::path) at time t; an empty path gives the identity.
RigidPose path_pose(const std::vector<ObstacleKeySpec>& path, const Vec3d& pivot, double t);

struct ObstaclesModel {
  std::vector<Vec3> x;                // m, every obstacle's vertices as placed (path aside)
  std::vector<Tri> tris;              // indices into x; a box's faces point outward
  std::vector<int> tri_offset;        // obstacle k owns [tri_offset[k], tri_offset[k + 1])
  std::vector<int> x_offset;          // and the vertices [x_offset[k], x_offset[k + 1])
  std::vector<ContactCoeffs> coeffs;  // fluid contact, one per obstacle
  std::vector<std::uint8_t> closed;   // per obstacle: bounds a solid (box, closed surface),
                                      // its faces turned outward
  std::vector<std::vector<ObstacleKeySpec>> path;  // per obstacle; empty: it stays put
  std::vector<Vec3d> pivot;                        // per obstacle

  bool empty() const { return tris.empty(); }
  int count() const { return int(coeffs.size()); }
  bool moves(int k) const { return !path[std::size_t(k)].empty(); }
  bool moving() const;  // any obstacle has a path
  RigidPose pose(int k, double t) const {
    return path_pose(path[std::size_t(k)], pivot[std::size_t(k)], t);
  }
  // Every vertex where its obstacle is at time t (x itself for the obstacles that stay put).
  std::vector<Vec3> at(double t) const;
};

// Builds every obstacle: a box's 12 triangles, a mesh file read, scaled and offset. Throws
// SceneError naming the file, the field and the fix (a box with min not below max, a mesh file
// missing, unreadable or with more triangles than the cap, an obstacle reaching outside the
// domain anywhere along its path, path keys out of time order or turning about a zero axis,
// fluid with the boundary-particle coupling). `scene_file` names the scene in messages and
// is the folder relative paths start at.
ObstaclesModel compile_obstacles(const SceneSpec& scene, const std::string& scene_file);

}  // namespace sphfem
