// Tube, cup and sphere generators: a lattice whose vertices are moved onto the round shape.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fem/lattice.h"

namespace sphfem {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Distance from 0 to the interval [a, b] (0 when it contains 0).
double interval_min_abs(double a, double b) {
  if (a <= 0.0 && b >= 0.0) return 0.0;
  return std::min(std::fabs(a), std::fabs(b));
}

}  // namespace

TetMesh make_tube(const Vec3d& base, double r_in, double r_out, double length, int segments,
                  int layers, int rings) {
  if (!(r_in > 0.0 && r_out > r_in && length > 0.0) || segments < 6 || layers < 1 || rings < 1)
    throw std::invalid_argument(
        "make_tube: need 0 < r_in < r_out, length > 0, segments >= 6, layers >= 1, rings >= 1");
  // Lattice axes (radial i, axial j, angular k) map to (r cos t, y, r sin t); the Jacobian
  // determinant of that map is +r, so Kuhn tetrahedra stay positively oriented.
  TetMesh m;
  auto id = [&](int i, int j, int k) { return i + (layers + 1) * (j + (rings + 1) * k); };
  m.x.resize(std::size_t(layers + 1) * (rings + 1) * segments);
  for (int k = 0; k < segments; ++k) {
    const double t = 2.0 * kPi * k / segments;
    for (int j = 0; j <= rings; ++j)
      for (int i = 0; i <= layers; ++i) {
        const double r = r_in + (r_out - r_in) * i / layers;
        m.x[id(i, j, k)] = base + Vec3d(r * std::cos(t), length * j / rings, r * std::sin(t));
      }
  }
  for (int k = 0; k < segments; ++k)
    for (int j = 0; j < rings; ++j)
      for (int i = 0; i < layers; ++i) {
        int c[2][2][2];
        for (int a = 0; a < 8; ++a)
          c[a & 1][(a >> 1) & 1][a >> 2] =
              id(i + (a & 1), j + ((a >> 1) & 1), (k + (a >> 2)) % segments);
        lattice::kuhn_cell(c, m.tets);
      }
  lattice::check_generated(m, "make_tube");
  return m;
}

TetMesh make_cup(const Vec3d& base, double r_in, double r_out, double height, double bottom,
                 int cells) {
  if (!(r_in > 0.0 && r_out > r_in && bottom > 0.0 && height > bottom) || cells < 4)
    throw std::invalid_argument(
        "make_cup: need 0 < r_in < r_out, 0 < bottom < height and at least 4 cells");
  // A square lattice of cells x cells in x-z: each square ring of the lattice (constant
  // L-infinity norm s) goes onto a circle of radius rho(s), piecewise linear in s so that the
  // outer `rings` lattice rings span the wall [r_in, r_out] and the rest fills the bottom disc.
  const int n = cells;
  const double half = 0.5 * n, h = r_out / half;
  const int rings = std::clamp(int(std::lround((r_out - r_in) / h)), 1, (n - 1) / 2);
  const double s_in = (half - rings) / half;
  const int nb = std::max(1, int(std::lround(bottom / h)));
  const int nw = std::max(1, int(std::lround((height - bottom) / h)));
  const int ny = nb + nw;
  TetMesh m;
  m.x.resize(std::size_t(n + 1) * (ny + 1) * (n + 1));
  for (int kb = 0; kb <= n; ++kb)
    for (int j = 0; j <= ny; ++j)
      for (int ia = 0; ia <= n; ++ia) {
        const double u = ia - half, w = kb - half;
        const double s = std::max(std::fabs(u), std::fabs(w)) / half, l2 = std::hypot(u, w);
        const double rho =
            s <= s_in ? r_in * s / s_in : r_in + (s - s_in) / (1.0 - s_in) * (r_out - r_in);
        const double y = j <= nb ? bottom * j / nb : bottom + (height - bottom) * (j - nb) / nw;
        const double f = l2 > 0.0 ? rho / l2 : 0.0;
        m.x[lattice::node(ia, j, kb, n, ny)] = base + Vec3d(u * f, y, w * f);
      }
  for (int kb = 0; kb < n; ++kb)
    for (int j = 0; j < ny; ++j)
      for (int ia = 0; ia < n; ++ia) {
        const double inner = std::max(interval_min_abs(ia - half, ia + 1 - half),
                                      interval_min_abs(kb - half, kb + 1 - half));
        if (j >= nb && inner < half - rings - 1e-9) continue;  // the cup's hollow
        int c[2][2][2];
        for (int a = 0; a < 8; ++a)
          c[a & 1][(a >> 1) & 1][a >> 2] =
              lattice::node(ia + (a & 1), j + ((a >> 1) & 1), kb + (a >> 2), n, ny);
        lattice::kuhn_cell(c, m.tets);
      }
  lattice::drop_unused_nodes(m);
  lattice::check_generated(m, "make_cup");
  return m;
}

TetMesh make_sphere(const Vec3d& center, double radius, int cells) {
  if (!(radius > 0.0) || cells < 2)
    throw std::invalid_argument("make_sphere: need radius > 0 and at least 2 cells");
  // Concentric cube shells |u|_inf = s go onto spheres of radius R s / half: the map
  // u -> u |u|_inf / |u|_2 is continuous, homogeneous and orientation-preserving.
  const int n = cells;
  const double half = 0.5 * n;
  TetMesh m = make_box(Vec3d(-half, -half, -half), Vec3d(half, half, half), n, n, n);
  for (Vec3d& u : m.x) {
    const double s = std::max({std::fabs(u.x), std::fabs(u.y), std::fabs(u.z)});
    const double l2 = norm(u);
    u = center + (l2 > 0.0 ? u * (radius * s / (half * l2)) : Vec3d());
  }
  lattice::check_generated(m, "make_sphere");
  return m;
}

}  // namespace sphfem
