// Flat boundary caps and ears. A cap lies in the skin of a nearly flat stretch of surface (all
// four nodes on it): a contact plane pressed onto that stretch puts all four nodes on the
// plane and the element at zero volume, whatever the material; TetGen leaves such caps where
// a scanned surface is almost flat, and its quality bound does not remove them (the bunny's
// base keeps 6-8 at any radius-edge or dihedral bound). An ear's tip is held by it alone, so
// a contact push turns it inside out.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "sphfem/fem/mesh.h"

namespace sphfem {
namespace {

constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

using FaceKey = std::array<int, 3>;

FaceKey face_key(const Tet& t, int k) {
  FaceKey f{t.v[kFace[k][0]], t.v[kFace[k][1]], t.v[kFace[k][2]]};
  std::sort(f.begin(), f.end());
  return f;
}

// Height of node k over the face opposite it.
double tip_height(const TetMesh& m, const Tet& t, int k) {
  const Vec3d& a = m.x[t.v[kFace[k][0]]];
  const Vec3d n = cross(m.x[t.v[kFace[k][1]]] - a, m.x[t.v[kFace[k][2]]] - a);
  const double area2 = norm(n);
  return area2 > 0 ? std::fabs(dot(m.x[t.v[k]] - a, n)) / area2 : 0.0;
}

// Smallest height of the tetrahedron over the smaller of its longest edge and `scale`: 0.82
// for a regular one (of edges up to `scale`), 0 flat.
double flatness(const TetMesh& m, const Tet& t, double scale) {
  double edge = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) edge = std::max(edge, norm(m.x[t.v[a]] - m.x[t.v[b]]));
  double height = edge;
  for (int k = 0; k < 4; ++k) height = std::min(height, tip_height(m, t, k));
  edge = std::min(edge, scale);
  return edge > 0 ? height / edge : 0.0;
}

}  // namespace

int peel_flat_caps(TetMesh& m, double max_flatness) {
  if (!(max_flatness > 0)) return 0;
  int peeled = 0;
  // Heights are measured against the surface's median edge too: a large element of a coarse
  // mesh, flat for its size but thick in the surface's own terms, is a piece of the shape, not
  // a cap in its skin (without this, a block meshed without inner nodes lost 11 % of its volume
  // as each peeled layer laid bare the next).
  std::vector<double> edges;
  {
    std::map<FaceKey, int> faces;
    for (const Tet& t : m.tets)
      for (int k = 0; k < 4; ++k) ++faces[face_key(t, k)];
    for (const auto& [f, count] : faces)
      if (count == 1)
        for (int a = 0; a < 3; ++a) edges.push_back(norm(m.x[f[a]] - m.x[f[(a + 1) % 3]]));
  }
  if (edges.empty()) return 0;
  std::nth_element(edges.begin(), edges.begin() + std::ptrdiff_t(edges.size() / 2), edges.end());
  const double scale = edges[edges.size() / 2];
  // Passes until none is left: no two elements peeled in one pass share a node, so every test
  // made at the pass's start holds, and a cap held back by a neighbour goes in a later pass.
  for (int pass = 0; pass < 64; ++pass) {
    std::map<FaceKey, int> faces;
    std::vector<int> uses(m.x.size(), 0);
    for (const Tet& t : m.tets) {
      for (int k = 0; k < 4; ++k) ++faces[face_key(t, k)];
      for (int v : t.v) ++uses[std::size_t(v)];
    }
    std::set<std::pair<int, int>> boundary_edges;
    for (const auto& [f, count] : faces)
      if (count == 1)
        for (int a = 0; a < 3; ++a)
          for (int b = a + 1; b < 3; ++b) boundary_edges.insert({f[a], f[b]});
    std::vector<char> touched(m.x.size(), 0);
    std::vector<Tet> kept;
    kept.reserve(m.tets.size());
    int now = 0;
    for (const Tet& t : m.tets) {
      bool on_boundary[4];
      int n = 0;
      for (int k = 0; k < 4; ++k) n += (on_boundary[k] = faces[face_key(t, k)] == 1);
      bool peel = n == 2 || n == 3;
      for (int v : t.v) peel = peel && !touched[std::size_t(v)];
      double size = 1.0;  // against max_flatness
      if (peel && n == 2) {
        // The two inner faces share the edge of the nodes opposite the surface faces; it becomes
        // a surface edge, so it must not be one already (the surface stays manifold).
        int a = -1, b = -1;
        for (int k = 0; k < 4; ++k)
          if (on_boundary[k]) (a < 0 ? a : b) = t.v[k];
        peel = !boundary_edges.count({std::min(a, b), std::max(a, b)});
        size = flatness(m, t, scale);
      } else if (peel && n == 3) {
        // An ear: the node shared by the three surface faces leaves with the element (held by
        // another element it would pinch the surface). That node has no other support, so a
        // push turns the element inside out whatever its shape: an ear is peeled when it
        // stands lower than the share of the surface's median edge, a bump below the
        // surface's own detail.
        for (int k = 0; k < 4; ++k)
          if (!on_boundary[k]) {
            peel = uses[std::size_t(t.v[k])] == 1;
            size = tip_height(m, t, k) / scale;
          }
      }
      if (peel && size < max_flatness) {
        for (int v : t.v) touched[std::size_t(v)] = 1;
        ++now;
      } else {
        kept.push_back(t);
      }
    }
    m.tets.swap(kept);
    peeled += now;
    if (now == 0) break;
  }
  if (peeled == 0) return 0;
  // Nodes no element holds any more (the tips of peeled three-face caps) are dropped.
  std::vector<int> remap(m.x.size(), -1);
  for (const Tet& t : m.tets)
    for (int v : t.v) remap[std::size_t(v)] = 0;
  std::vector<Vec3d> x;
  for (std::size_t i = 0; i < m.x.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = int(x.size());
      x.push_back(m.x[i]);
    }
  m.x.swap(x);
  for (Tet& t : m.tets)
    for (int& v : t.v) v = remap[std::size_t(v)];
  return peeled;
}

}  // namespace sphfem
