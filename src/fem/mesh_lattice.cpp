// Box and cloth generators, and the Kuhn split they share with the round shapes.
#include <stdexcept>
#include <string>
#include <utility>

#include "fem/lattice.h"

namespace sphfem {

namespace lattice {

void kuhn_cell(const int c[2][2][2], std::vector<Tet>& out) {
  // Axis orders of the six monotone paths from corner 000 to 111; the last three are odd
  // permutations, whose path tetrahedra come out negatively oriented and get two nodes swapped.
  static const int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  for (int p = 0; p < 6; ++p) {
    int d[3] = {0, 0, 0};
    Tet t;
    t.v[0] = c[0][0][0];
    for (int s = 0; s < 3; ++s) {
      d[kPerm[p][s]] = 1;
      t.v[s + 1] = c[d[0]][d[1]][d[2]];
    }
    if (p >= 3) std::swap(t.v[2], t.v[3]);
    out.push_back(t);
  }
}

void drop_unused_nodes(TetMesh& m) {
  std::vector<int> map(m.x.size(), -1);
  for (const Tet& t : m.tets)
    for (int a = 0; a < 4; ++a) map[t.v[a]] = 0;
  int n = 0;
  for (std::size_t i = 0; i < map.size(); ++i)
    if (map[i] == 0) {
      map[i] = n;
      m.x[n++] = m.x[i];
    }
  m.x.resize(n);
  for (Tet& t : m.tets)
    for (int a = 0; a < 4; ++a) t.v[a] = map[t.v[a]];
}

void check_generated(const TetMesh& m, const char* generator) {
  for (std::size_t t = 0; t < m.tets.size(); ++t)
    if (!(tet_volume(m, int(t)) > 0.0))
      throw std::logic_error(std::string(generator) + ": tetrahedron " + std::to_string(t) +
                             " is not positively oriented; raise the resolution");
}

}  // namespace lattice

TetMesh make_box(const Vec3d& lo, const Vec3d& hi, int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1 || !(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
    throw std::invalid_argument("make_box: need hi > lo and at least one cell per axis");
  TetMesh m;
  m.x.reserve(std::size_t(nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        m.x.push_back(Vec3d(lo.x + (hi.x - lo.x) * i / nx, lo.y + (hi.y - lo.y) * j / ny,
                            lo.z + (hi.z - lo.z) * k / nz));
  m.tets.reserve(std::size_t(6) * nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int c[2][2][2];
        for (int a = 0; a < 8; ++a)
          c[a & 1][(a >> 1) & 1][a >> 2] =
              lattice::node(i + (a & 1), j + ((a >> 1) & 1), k + (a >> 2), nx, ny);
        lattice::kuhn_cell(c, m.tets);
      }
  return m;
}

TetMesh make_cloth(const Vec3d& center, double size_x, double size_z, double thickness, int nx,
                   int nz) {
  const Vec3d h(0.5 * size_x, 0.5 * thickness, 0.5 * size_z);
  return make_box(center - h, center + h, nx, 1, nz);
}

}  // namespace sphfem
