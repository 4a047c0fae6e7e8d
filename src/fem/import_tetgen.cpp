// TetGen's .node/.ele pair. Nodes carry their own numbers (the first one sets whether the
// files count from 0 or 1) and elements refer to those, so both bases read the same way.
#include <algorithm>

#include "sphfem/fem/import.h"

namespace sphfem::import_detail {

TetFile read_tetgen(const std::string& node_path, const std::string& ele_path) {
  TetFile f;

  TextLines node(node_path);
  if (!node.next()) node.fail_eof("its header");
  const long n = node.integer(0, "number of nodes");
  if (node.fields().size() > 1 && node.integer(1, "dimension") != 3)
    node.fail("the mesh is " + node.fields()[1] + "-dimensional", "give a 3D TetGen mesh");
  if (n < 0) node.fail("negative node count", "fix the header");
  // Reserve no more than the file has lines: a count in a damaged header must not allocate
  // (found by fuzzing: a count of 1e18 threw std::length_error).
  f.node_id.reserve(std::size_t(std::min<long>(n, long(node.lines_left()))));
  f.x.reserve(f.node_id.capacity());
  for (long i = 0; i < n; ++i) {
    if (!node.next()) node.fail_eof(("node " + std::to_string(n) + " of the header").c_str());
    f.node_id.push_back(node.integer(0, "node number"));
    f.x.push_back(Vec3d(node.real(1, "x"), node.real(2, "y"), node.real(3, "z")));
  }

  TextLines ele(ele_path);
  if (!ele.next()) ele.fail_eof("its header");
  const long m = ele.integer(0, "number of tetrahedra");
  const long corners = ele.fields().size() > 1 ? ele.integer(1, "nodes per tetrahedron") : 4;
  if (corners != 4 && corners != 10)
    ele.fail("tetrahedra with " + std::to_string(corners) + " nodes", "give 4- or 10-node tets");
  if (m < 0) ele.fail("negative tetrahedron count", "fix the header");
  f.tet_id.reserve(std::size_t(std::min<long>(m, long(ele.lines_left()))));
  f.tet_nodes.reserve(4 * f.tet_id.capacity());
  for (long t = 0; t < m; ++t) {
    if (!ele.next()) ele.fail_eof(("tetrahedron " + std::to_string(m) + " of the header").c_str());
    ele.need(1 + corners, "tetrahedron number and its nodes");
    f.tet_id.push_back(ele.integer(0, "tetrahedron number"));
    for (int k = 1; k <= 4; ++k) f.tet_nodes.push_back(ele.integer(k, "node number"));  // corners
  }
  return f;
}

}  // namespace sphfem::import_detail
