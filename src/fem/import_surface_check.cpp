// Checks that a triangle surface bounds a solid before it is tetrahedralised: TetGen's own
// failures on bad input name no triangle, so the problems are found and located here.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <utility>

#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

std::string where(const Vec3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p.x, p.y, p.z);
  return buf;
}

std::string vertex(const SurfaceMesh& s, int v) {
  return "vertex " + std::to_string(v) + " " + where(s.x[v]);
}

std::string name_of(const SurfaceMesh& s) { return s.source.empty() ? "surface" : s.source; }

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

void check_surface(const SurfaceMesh& s) {
  const std::string file = name_of(s);
  const int n = int(s.x.size());
  if (s.tris.empty()) throw MeshError(file, "the surface has no triangles", "export the surface");
  for (std::size_t t = 0; t < s.tris.size(); ++t)
    for (int v : s.tris[t].v)
      if (v < 0 || v >= n)
        throw MeshError(file,
                        "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                            " of " + std::to_string(n),
                        "fix the face list or re-export");

  // Degenerate triangles: zero area relative to the model's size.
  const auto [lo, hi] = bounds(s.x);
  const double diag = norm(hi - lo);
  for (std::size_t t = 0; t < s.tris.size(); ++t) {
    const int* v = s.tris[t].v;
    const double area2 = norm(cross(s.x[v[1]] - s.x[v[0]], s.x[v[2]] - s.x[v[0]]));
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0] || !(area2 > 1e-14 * diag * diag))
      throw MeshError(file,
                      "triangle " + std::to_string(t) + " at " + vertex(s, v[0]) + " has zero area",
                      "remove degenerate faces, e.g. in MeshLab: Filters > Cleaning and "
                      "Repairing > Remove Zero Area Faces");
  }

  // Directed edges (a, b) with the triangle they come from, sorted by undirected edge.
  struct Edge {
    int lo, hi, tri;
    bool forward;  // a < b
  };
  std::vector<Edge> edges;
  edges.reserve(s.tris.size() * 3);
  for (std::size_t t = 0; t < s.tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = s.tris[t].v[k], b = s.tris[t].v[(k + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b), int(t), a < b});
    }
  std::sort(edges.begin(), edges.end(), [](const Edge& p, const Edge& q) {
    return p.lo != q.lo ? p.lo < q.lo : (p.hi != q.hi ? p.hi < q.hi : p.tri < q.tri);
  });

  // Edge multiplicities: more than two triangles is non-manifold, one is a hole. Non-manifold
  // edges come first since a fin or a doubled face also leaves boundary edges behind.
  int open = 0, first_open = -1;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    if (j - i > 2)
      throw MeshError(file,
                      "the surface is not manifold: the edge from " + vertex(s, edges[i].lo) +
                          " to vertex " + std::to_string(edges[i].hi) + " is shared by " +
                          std::to_string(j - i) + " triangles",
                      "split or remove the extra faces so every edge joins two, e.g. in "
                      "MeshLab: Filters > Cleaning and Repairing > Repair non Manifold Edges");
    if (j - i == 1 && open++ == 0) first_open = edges[i].lo;
    i = j;
  }
  if (open > 0)
    throw MeshError(file,
                    "the surface is open: " + std::to_string(open) + " boundary edges, first at " +
                        vertex(s, first_open),
                    "close the holes, e.g. in MeshLab: Filters > Remeshing, Simplification and "
                    "Reconstruction > Close Holes");

  // Orientation: the two triangles on an edge must run along it in opposite directions.
  for (std::size_t i = 0; i < edges.size(); i += 2)
    if (edges[i].forward == edges[i + 1].forward)
      throw MeshError(file,
                      "the surface is not consistently oriented: triangles " +
                          std::to_string(edges[i].tri) + " and " +
                          std::to_string(edges[i + 1].tri) +
                          " face opposite ways across the "
                          "edge at " +
                          vertex(s, edges[i].lo),
                      "make the normals agree, e.g. in MeshLab: Filters > Normals, Curvatures "
                      "and Orientation > Re-Orient all faces coherently");

  // Non-manifold vertices (two solids touching in a point): the triangles around a vertex,
  // joined across the edges they share there, must form a single fan.
  std::vector<int> parent(s.tris.size() * 3);
  std::iota(parent.begin(), parent.end(), 0);
  auto slot = [&](int tri, int v) {
    const int* t = s.tris[tri].v;
    return tri * 3 + (t[0] == v ? 0 : (t[1] == v ? 1 : 2));
  };
  for (std::size_t i = 0; i < edges.size(); i += 2)
    for (int v : {edges[i].lo, edges[i].hi}) {
      const int a = find_root(parent, slot(edges[i].tri, v));
      const int b = find_root(parent, slot(edges[i + 1].tri, v));
      parent[a] = b;
    }
  std::vector<int> fan(n, -1);  // root of the first fan seen at each vertex
  for (std::size_t t = 0; t < s.tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = s.tris[t].v[k];
      const int r = find_root(parent, int(t) * 3 + k);
      if (fan[v] < 0) fan[v] = r;
      if (fan[v] != r)
        throw MeshError(
            file,
            "the surface is not manifold at " + vertex(s, v) + ": separate sheets touch there",
            "move the parts apart or merge them, e.g. in MeshLab: Filters > "
            "Cleaning and Repairing > Split Vertices on non Manifold Vertices");
    }

  const auto [a, b] = find_self_intersection(s);
  if (a >= 0)
    throw MeshError(file,
                    "the surface intersects itself: triangles " + std::to_string(a) + " and " +
                        std::to_string(b) + " cross or touch near " + vertex(s, s.tris[a].v[0]),
                    "remove the intersections, e.g. in MeshLab: Filters > Cleaning and "
                    "Repairing > Select Self Intersecting Faces, then fix or remesh them");
}

}  // namespace sphfem
