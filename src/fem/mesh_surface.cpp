// Mesh measures, validation and boundary-surface extraction.
#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "sphfem/fem/mesh.h"

namespace sphfem {

double tet_volume(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  return dot(b - a, cross(c - a, d - a)) / 6.0;
}

double tet_volume(const TetMesh& m, int t) {
  const Tet& e = m.tets[t];
  return tet_volume(m.x[e.v[0]], m.x[e.v[1]], m.x[e.v[2]], m.x[e.v[3]]);
}

double mesh_volume(const TetMesh& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.tets.size(); ++t) v += tet_volume(m, int(t));
  return v;
}

void validate_mesh(const TetMesh& m, const char* what) {
  const std::string w(what);
  if (m.tets.empty()) throw std::runtime_error(w + ": the mesh has no tetrahedra");
  const int n = int(m.x.size());
  std::vector<char> used(n, 0);
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    for (int a = 0; a < 4; ++a) {
      const int v = m.tets[t].v[a];
      if (v < 0 || v >= n)
        throw std::runtime_error(w + ": tetrahedron " + std::to_string(t) + " refers to node " +
                                 std::to_string(v) + " of " + std::to_string(n) +
                                 "; fix the mesh's element list");
      used[v] = 1;
    }
    const double vol = tet_volume(m, int(t));
    if (!(vol > 0.0))
      throw std::runtime_error(w + ": tetrahedron " + std::to_string(t) + " has volume " +
                               std::to_string(vol) +
                               " (inverted or flat); swap two of its nodes or remesh");
  }
  for (int i = 0; i < n; ++i)
    if (!used[i])
      throw std::runtime_error(w + ": node " + std::to_string(i) +
                               " belongs to no tetrahedron; remove it from the mesh");
}

std::vector<Tri> boundary_faces(const std::vector<Tet>& tets) {
  // Faces of a positively oriented tetrahedron (0 1 2 3), counter-clockwise from outside,
  // listed opposite node 0, 1, 2, 3.
  static const int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  struct Key {
    std::array<int, 3> v;  // sorted node ids
    int id;                // tet * 4 + face
  };
  std::vector<Key> keys;
  keys.reserve(tets.size() * 4);
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int f = 0; f < 4; ++f) {
      Key k;
      for (int a = 0; a < 3; ++a) k.v[a] = tets[t].v[kFace[f][a]];
      std::sort(k.v.begin(), k.v.end());
      k.id = int(t) * 4 + f;
      keys.push_back(k);
    }
  std::sort(keys.begin(), keys.end(),
            [](const Key& a, const Key& b) { return a.v != b.v ? a.v < b.v : a.id < b.id; });
  std::vector<int> once;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j].v == keys[i].v) ++j;
    if (j - i == 1) once.push_back(keys[i].id);
    i = j;
  }
  std::sort(once.begin(), once.end());
  std::vector<Tri> tris;
  tris.reserve(once.size());
  for (int id : once) {
    const Tet& t = tets[id / 4];
    const int* f = kFace[id % 4];
    tris.push_back(Tri{{t.v[f[0]], t.v[f[1]], t.v[f[2]]}});
  }
  return tris;
}

double enclosed_volume(const std::vector<Vec3d>& x, const std::vector<Tri>& tris) {
  double v = 0.0;
  for (const Tri& t : tris) v += dot(x[t.v[0]], cross(x[t.v[1]], x[t.v[2]]));
  return v / 6.0;
}

}  // namespace sphfem
