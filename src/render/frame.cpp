#include "sphfem/render/frame.h"

#include <cmath>

namespace sphfem::render {

std::vector<float> smooth_normals(const TriangleMesh& mesh) {
  const std::size_t nv = mesh.positions.size() / 3;
  std::vector<double> acc(3 * nv, 0.0);
  auto vertex = [&](std::uint32_t i) {
    return Vec3d(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
  };
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const std::uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    if (a >= nv || b >= nv || c >= nv) continue;
    // The cross product's length is twice the area: larger triangles weigh more.
    const Vec3d n = cross(vertex(b) - vertex(a), vertex(c) - vertex(a));
    if (!std::isfinite(n.x + n.y + n.z)) continue;
    for (std::uint32_t v : {a, b, c})
      for (int k = 0; k < 3; ++k) acc[3 * v + k] += n[k];
  }
  std::vector<float> out(3 * nv, 0.0f);
  for (std::size_t v = 0; v < nv; ++v) {
    const Vec3d n(acc[3 * v], acc[3 * v + 1], acc[3 * v + 2]);
    const double len = norm(n);
    if (!(len > 0)) continue;
    for (int k = 0; k < 3; ++k) out[3 * v + k] = float(n[k] / len);
  }
  return out;
}

bool frame_bounds(const RenderFrame& frame, Vec3d* lo, Vec3d* hi) {
  Vec3d a(1e300, 1e300, 1e300), b = -a;
  auto add = [&](double x, double y, double z) {
    if (!std::isfinite(x + y + z)) return;
    a = vmin(a, Vec3d(x, y, z));
    b = vmax(b, Vec3d(x, y, z));
  };
  if (frame.has_box) {
    add(frame.box_lo.x, frame.box_lo.y, frame.box_lo.z);
    add(frame.box_hi.x, frame.box_hi.y, frame.box_hi.z);
  }
  const double r = frame.radius;
  for (std::size_t i = 0; i + 2 < frame.particles.size(); i += 3) {
    add(frame.particles[i] - r, frame.particles[i + 1] - r, frame.particles[i + 2] - r);
    add(frame.particles[i] + r, frame.particles[i + 1] + r, frame.particles[i + 2] + r);
  }
  for (const TriangleMesh& m : frame.meshes)
    for (std::size_t i = 0; i + 2 < m.positions.size(); i += 3)
      add(m.positions[i], m.positions[i + 1], m.positions[i + 2]);
  if (a.x > b.x) return false;
  *lo = a;
  *hi = b;
  return true;
}

Vec3d body_color(int index) {
  static const Vec3d kPalette[] = {{0.92, 0.45, 0.26}, {0.95, 0.75, 0.25}, {0.55, 0.78, 0.36},
                                   {0.80, 0.40, 0.62}, {0.62, 0.52, 0.90}, {0.85, 0.85, 0.82}};
  const int n = int(sizeof kPalette / sizeof kPalette[0]);
  return kPalette[((index % n) + n) % n];
}

}  // namespace sphfem::render
