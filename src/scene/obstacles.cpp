// Scene -> ObstaclesModel (include/sphfem/scene/obstacles.h): boxes and surface files as one
// triangle set, and the rigid poses of their paths.
#include "sphfem/scene/obstacles.h"

#include <algorithm>
#include <array>
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

using Quaternion = std::array<double, 4>;  // (w, x, y, z), unit

Quaternion axis_angle(const Vec3d& axis, double degrees) {
  const double l = norm(axis);
  if (degrees == 0 || !(l > 0)) return {1, 0, 0, 0};
  const double h = degrees * (M_PI / 360.0), s = std::sin(h) / l;
  return {std::cos(h), axis.x * s, axis.y * s, axis.z * s};
}

// The even turn from a to b (the shorter way round), at fraction s.
Quaternion slerp(const Quaternion& a, Quaternion b, double s) {
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0) {
    for (double& c : b) c = -c;
    d = -d;
  }
  double wa = 1 - s, wb = s;
  if (d < 0.9999995) {  // else the two are one: a straight blend is exact enough
    const double th = std::acos(std::min(d, 1.0)), sn = std::sin(th);
    wa = std::sin((1 - s) * th) / sn;
    wb = std::sin(s * th) / sn;
  }
  Quaternion q;
  double l = 0;
  for (int i = 0; i < 4; ++i) l += (q[i] = wa * a[i] + wb * b[i]) * q[i];
  for (double& c : q) c /= std::sqrt(l);
  return q;
}

bool same_direction(const Vec3d& a, const Vec3d& b) {
  const double la = norm(a), lb = norm(b);
  return la > 0 && lb > 0 && norm(a / la - b / lb) < 1e-12;
}

}  // namespace

Vec3d RigidPose::rotate(const Vec3d& v) const {
  const Vec3d u(q[1], q[2], q[3]);
  const Vec3d c = cross(u, v);
  return v + c * (2 * q[0]) + cross(u, c) * 2.0;
}

Vec3d RigidPose::apply(const Vec3d& p) const {
  return identity ? p : rotate(p - pivot) + pivot + t;
}

Vec3d RigidPose::inverse(const Vec3d& p) const {
  if (identity) return p;
  RigidPose back = *this;
  for (int i = 1; i < 4; ++i) back.q[i] = -q[i];
  return back.rotate(p - t - pivot) + pivot;
}

RigidPose path_pose(const std::vector<ObstacleKeySpec>& path, const Vec3d& pivot, double t) {
  RigidPose p;
  if (path.empty()) return p;
  std::size_t i = 0;
  while (i + 1 < path.size() && t >= path[i + 1].time) ++i;
  const ObstacleKeySpec& a = path[i];
  Quaternion q = axis_angle(a.axis, a.angle);
  p.t = a.translate;
  if (i + 1 < path.size() && t > a.time) {
    const ObstacleKeySpec& b = path[i + 1];
    const double s = (t - a.time) / (b.time - a.time);
    p.t = a.translate + (b.translate - a.translate) * s;
    // One axis: the angle itself goes evenly, so a key may add more than half a turn.
    if (same_direction(a.axis, b.axis) || a.angle == 0 || b.angle == 0) {
      const Vec3d axis = a.angle != 0 ? a.axis : b.axis;
      q = axis_angle(axis, a.angle + (b.angle - a.angle) * s);
    } else {
      q = slerp(q, axis_angle(b.axis, b.angle), s);
    }
  }
  std::copy(q.begin(), q.end(), p.q);
  p.pivot = pivot;
  p.identity = q == Quaternion{1, 0, 0, 0} && p.t.x == 0 && p.t.y == 0 && p.t.z == 0;
  return p;
}

bool ObstaclesModel::moving() const {
  for (const auto& p : path)
    if (!p.empty()) return true;
  return false;
}

std::vector<Vec3> ObstaclesModel::at(double t) const {
  std::vector<Vec3> out = x;
  for (int k = 0; k < count(); ++k) {
    if (!moves(k)) continue;
    const RigidPose p = pose(k, t);
    for (int i = x_offset[std::size_t(k)]; i < x_offset[std::size_t(k) + 1]; ++i)
      out[std::size_t(i)] = p.apply(x[std::size_t(i)]);
  }
  return out;
}

ObstaclesModel compile_obstacles(const SceneSpec& scene, const std::string& file) {
  ObstaclesModel m;
  m.tri_offset.push_back(0);
  m.x_offset.push_back(0);
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
    for (std::size_t i = 0; i < o.path.size(); ++i) {
      const ObstacleKeySpec& key = o.path[i];
      const std::string k = indexed(at + ".path", i);
      if (i > 0 && !(key.time > o.path[i - 1].time))
        fail(file, k + ".time",
             "is " + num(key.time) + ", not after the previous key's " + num(o.path[i - 1].time),
             "list the path's keys in increasing time");
      if (key.angle != 0 && !(norm(key.axis) > 0))
        fail(file, k + ".axis",
             "is zero, so the rotation of " + num(key.angle) + " deg has no axis",
             "give the axis a direction, e.g. [0, 1, 0]");
    }
    // Where the obstacle is placed, and along its path: at each key and evenly between keys.
    std::vector<double> times = {0};
    for (std::size_t i = 0; i < o.path.size(); ++i) {
      const double t0 = i ? o.path[i - 1].time : o.path[i].time;
      for (int j = 1; j <= 16; ++j) times.push_back(t0 + (o.path[i].time - t0) * j / 16.0);
    }
    const Vec3d& dlo = scene.domain.lo;
    const Vec3d& dhi = scene.domain.hi;
    for (double t : times) {
      const RigidPose pose = path_pose(o.path, o.pivot, t);
      std::vector<Vec3d> placed(s.x.size());
      for (std::size_t i = 0; i < s.x.size(); ++i) placed[i] = pose.apply(s.x[i]);
      const std::pair<Vec3d, Vec3d> b = bounds(placed);
      for (int a = 0; a < 3; ++a)
        if (b.first[a] < dlo[a] || b.second[a] > dhi[a])
          fail(file,
               at + (!o.path.empty()                 ? ".path"
                     : o.shape == ObstacleShape::Box ? ".max"
                                                     : ".offset"),
               "the obstacle spans " + vec(b.first) + " to " + vec(b.second) +
                   (o.path.empty() ? "" : " at " + num(t) + " s") +
                   ", reaching outside the domain " + vec(dlo) + " to " + vec(dhi) + " on " +
                   kAxis[a],
               "move or shrink it into the domain (the tank's walls are obstacles already)");
    }
    if (scene.coupling.method != CouplingMethod::RayTraced && scene.has_fluid())
      fail(file, at,
           "the fluid meets obstacles through the ray-traced coupling only, and the scene's "
           "coupling.method is boundary_particles",
           "set coupling.method to \"raytraced\", or leave the obstacle out");
    const bool closed = o.shape == ObstacleShape::Box || closed_surface(s);
    if (closed) {
      // Faces outward, as the near-surface density reads them: an inside-out file is turned.
      double volume = 0;
      for (const Tri& t : s.tris)
        volume += dot(s.x[std::size_t(t.v[0])],
                      cross(s.x[std::size_t(t.v[1])], s.x[std::size_t(t.v[2])]));
      if (volume < 0)
        for (Tri& t : s.tris) std::swap(t.v[1], t.v[2]);
    }
    const int base = int(m.x.size());
    for (const Vec3d& p : s.x) m.x.push_back(Vec3(p));
    for (Tri t : s.tris) {
      for (int& v : t.v) v += base;
      m.tris.push_back(t);
    }
    m.tri_offset.push_back(int(m.tris.size()));
    m.x_offset.push_back(int(m.x.size()));
    m.path.push_back(o.path);
    m.pivot.push_back(o.pivot);
    m.coeffs.push_back(ContactCoeffs{Real(o.restitution), Real(o.slip)});
    m.closed.push_back(closed ? 1 : 0);
  }
  return m;
}

}  // namespace sphfem
