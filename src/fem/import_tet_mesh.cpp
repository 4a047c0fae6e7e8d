// Tetrahedral-mesh import: the choice of reader, and the checks every imported mesh passes.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "sphfem/fem/import.h"

namespace sphfem {

namespace import_detail {

TetMesh finish_tet_mesh(const TetFile& f, const std::string& path) {
  const std::size_t nt = f.tet_id.size();
  if (nt == 0)
    throw MeshError(path, "the file has no tetrahedra",
                    "mesh the volume and export its tetrahedra (e.g. gmsh -3)");

  std::unordered_map<long, int> index;
  index.reserve(f.node_id.size());
  for (std::size_t i = 0; i < f.node_id.size(); ++i)
    if (!index.emplace(f.node_id[i], int(i)).second)
      throw MeshError(path, "node " + std::to_string(f.node_id[i]) + " is defined twice",
                      "number the nodes uniquely or re-export");

  TetMesh m;
  m.tets.resize(nt);
  std::vector<int> remap(f.x.size(), -1);
  std::vector<char> used(f.x.size(), 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      const long id = f.tet_nodes[4 * t + k];
      const auto it = index.find(id);
      if (it == index.end())
        throw MeshError(path,
                        "tet " + std::to_string(f.tet_id[t]) + " refers to node " +
                            std::to_string(id) + ", which the file does not define",
                        "export the nodes with the elements, or fix the element's node list");
      m.tets[t].v[k] = it->second;
      used[it->second] = 1;
    }

  // Orientation is checked, not repaired: a reversed element in an exported mesh means the
  // exporter and this reader disagree, and flipping it would hide that.
  for (std::size_t t = 0; t < nt; ++t) {
    const int* v = m.tets[t].v;
    double edge = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edge = std::max(edge, norm(f.x[v[a]] - f.x[v[b]]));
    const double vol = tet_volume(f.x[v[0]], f.x[v[1]], f.x[v[2]], f.x[v[3]]);
    char num[32];
    std::snprintf(num, sizeof num, "%.3g", vol);
    const std::string tet = "tet " + std::to_string(f.tet_id[t]);
    if (!(std::fabs(vol) > 1e-12 * edge * edge * edge))
      throw MeshError(path, tet + " has zero volume (" + num + " m^3): its vertices are coplanar",
                      "remove the flat element or remesh");
    if (vol < 0.0)
      throw MeshError(
          path, tet + " has negative volume (" + num + " m^3): its vertices are ordered clockwise",
          "reorder them (swap two) or re-export the mesh");
  }

  // Keep only the nodes tetrahedra use (geometry points, quadratic mid-edge nodes).
  for (std::size_t i = 0; i < f.x.size(); ++i)
    if (used[i]) {
      remap[i] = int(m.x.size());
      m.x.push_back(f.x[i]);
    }
  for (Tet& t : m.tets)
    for (int& v : t.v) v = remap[v];
  validate_mesh(m, path.c_str());
  return m;
}

}  // namespace import_detail

TetMesh load_tet_mesh(const std::string& path) {
  const std::size_t dot_at = path.find_last_of('.');
  const std::size_t slash = path.find_last_of('/');
  std::string ext, stem = path;
  if (dot_at != std::string::npos && (slash == std::string::npos || dot_at > slash)) {
    ext = path.substr(dot_at);
    stem = path.substr(0, dot_at);
  }
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  using namespace import_detail;
  if (ext == ".node" || ext == ".ele") {
    const std::string node = ext == ".node" ? path : stem + ".node";
    const std::string ele = ext == ".ele" ? path : stem + ".ele";
    return finish_tet_mesh(read_tetgen(node, ele), path);
  }
  if (ext == ".msh") return finish_tet_mesh(read_gmsh(path), path);
  throw MeshError(path, "unknown tetrahedral mesh format '" + ext + "'",
                  "give a TetGen .node/.ele pair or a Gmsh .msh file, or a surface (OBJ, PLY, "
                  "STL) to tetrahedralise");
}

}  // namespace sphfem
