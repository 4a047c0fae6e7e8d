// Scene -> ObstaclesModel (include/sphfem/scene/obstacles.h): boxes and surface files as one
// static triangle set.
#include "sphfem/scene/obstacles.h"

#include <cmath>
#include <cstdint>

#include "scene/messages.h"
#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

using namespace scene_text;

// Triangles one obstacle may have: a surface this fine is a modelling mistake, and each
// triangle costs BVH memory and samples.
constexpr double kMaxObstacleTris = 4e6;

// A box's 8 corners and 12 outward triangles.
SurfaceMesh box_surface(const Vec3d& lo, const Vec3d& hi) {
  SurfaceMesh s;
  for (int k = 0; k < 8; ++k)
    s.x.push_back(Vec3d(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
  // Quads by corner index (bit 0 = x, bit 1 = y, bit 2 = z), counter-clockwise from outside.
  const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    s.tris.push_back(Tri{{q[0], q[1], q[2]}});
    s.tris.push_back(Tri{{q[0], q[2], q[3]}});
  }
  return s;
}

bool closed_surface(const SurfaceMesh& s) {
  try {
    check_surface(s);
    return true;
  } catch (const MeshError&) { return false; }
}

}  // namespace

ObstaclesModel compile_obstacles(const SceneSpec& scene, const std::string& file) {
  ObstaclesModel m;
  m.tri_offset.push_back(0);
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    const ObstacleSpec& o = scene.obstacles[k];
    const std::string at = indexed("obstacles", k);
    SurfaceMesh s;
    if (o.shape == ObstacleShape::Box) {
      for (int a = 0; a < 3; ++a)
        if (!(o.lo[a] < o.hi[a]))
          fail(file, at + ".max",
               std::string("must be above min on ") + kAxis[a] + " (min " + vec(o.lo) + ", max " +
                   vec(o.hi) + ")",
               "give the box a positive extent on every axis");
      s = box_surface(o.lo, o.hi);
    } else {
      if (o.file.empty())
        fail(file, at + ".file", "a mesh obstacle needs a file",
             "name an OBJ, PLY or STL surface, or use \"shape\": \"box\"");
      try {
        s = load_surface(resolve_path(o.file, file));
      } catch (const MeshError& e) {
        throw SceneError(one_line(display_file(file) + ": " + at + ".file: " + e.what()));
      }
      if (double(s.tris.size()) > kMaxObstacleTris)
        fail(file, at + ".file",
             "the surface has " + std::to_string(s.tris.size()) + " triangles, more than the " +
                 num(kMaxObstacleTris) + " an obstacle may have",
             "simplify the mesh (e.g. MeshLab's quadric edge collapse)");
      transform(s, o.scale, o.offset);
    }
    const std::pair<Vec3d, Vec3d> b = bounds(s.x);
    const Vec3d& dlo = scene.domain.lo;
    const Vec3d& dhi = scene.domain.hi;
    for (int a = 0; a < 3; ++a)
      if (b.first[a] < dlo[a] || b.second[a] > dhi[a])
        fail(file, at + (o.shape == ObstacleShape::Box ? ".max" : ".offset"),
             "the obstacle spans " + vec(b.first) + " to " + vec(b.second) +
                 ", reaching outside the domain " + vec(dlo) + " to " + vec(dhi) + " on " +
                 kAxis[a],
             "move or shrink it into the domain (the tank's walls are obstacles already)");
    if (scene.coupling.method != CouplingMethod::RayTraced && scene.has_fluid())
      fail(file, at,
           "the fluid meets obstacles through the ray-traced coupling only, and the scene's "
           "coupling.method is boundary_particles",
           "set coupling.method to \"raytraced\", or leave the obstacle out");
    const int base = int(m.x.size());
    for (const Vec3d& p : s.x) m.x.push_back(Vec3(p));
    for (Tri t : s.tris) {
      for (int& v : t.v) v += base;
      m.tris.push_back(t);
    }
    m.tri_offset.push_back(int(m.tris.size()));
    m.coeffs.push_back(ContactCoeffs{Real(o.restitution), Real(o.slip)});
    m.closed.push_back(o.shape == ObstacleShape::Box || closed_surface(s) ? 1 : 0);
  }
  return m;
}

}  // namespace sphfem
