// Gmsh .msh, ASCII formats 2.x and 4.1: nodes and the tetrahedra among the elements. Lower-
// dimensional elements (surface triangles, edges, points) are skipped; other volume elements
// are an error rather than a silently smaller body.
#include <set>

#include "sphfem/fem/import.h"

namespace sphfem::import_detail {

namespace {

constexpr const char* kResave =
    "re-save it as ASCII format 2.2 or 4.1, e.g. gmsh in.msh -save -format msh22 -o out.msh";

// Linear and higher-order Lagrange tetrahedra; Gmsh lists the four corners first in each.
bool is_tet(long type) { return type == 4 || type == 11 || type == 29 || type == 30 || type == 31; }

// Hexahedra, prisms and pyramids of order 1 and 2, as format 2 does not give the dimension.
bool is_other_volume(long type) {
  static const std::set<long> kTypes = {5, 6, 7, 12, 13, 14, 17, 18, 19};
  return kTypes.count(type) > 0;
}

void add_tet(TextLines& in, TetFile& f, long id, std::size_t first_node) {
  in.need(first_node + 4, "element nodes");
  f.tet_id.push_back(id);
  for (std::size_t k = 0; k < 4; ++k)
    f.tet_nodes.push_back(in.integer(first_node + k, "node number"));
}

[[noreturn]] void not_tet(TextLines& in, long id, long type) {
  in.fail("element " + std::to_string(id) + " is a volume element of type " + std::to_string(type) +
              ", not a tetrahedron",
          "mesh the volume with tetrahedra only");
}

void next_or_fail(TextLines& in, const char* what) {
  if (!in.next()) in.fail_eof(what);
}

void expect_end(TextLines& in, const std::string& section) {
  next_or_fail(in, ("$End" + section).c_str());
  if (in.fields()[0] != "$End" + section)
    in.fail("expected $End" + section + ", found '" + in.fields()[0] + "'",
            "the counts in the section's header do not match its lines; re-export the mesh");
}

void nodes_v2(TextLines& in, TetFile& f) {
  next_or_fail(in, "the node count");
  const long n = in.integer(0, "number of nodes");
  for (long i = 0; i < n; ++i) {
    next_or_fail(in, "the last node");
    f.node_id.push_back(in.integer(0, "node number"));
    f.x.push_back(Vec3d(in.real(1, "x"), in.real(2, "y"), in.real(3, "z")));
  }
}

void elements_v2(TextLines& in, TetFile& f) {
  next_or_fail(in, "the element count");
  const long n = in.integer(0, "number of elements");
  for (long i = 0; i < n; ++i) {
    next_or_fail(in, "the last element");
    const long id = in.integer(0, "element number");
    const long type = in.integer(1, "element type");
    const long tags = in.integer(2, "number of tags");
    if (is_tet(type)) add_tet(in, f, id, 3 + std::size_t(tags));
    if (is_other_volume(type)) not_tet(in, id, type);
  }
}

void nodes_v41(TextLines& in, TetFile& f) {
  next_or_fail(in, "the node header");
  const long blocks = in.integer(0, "number of entity blocks");
  for (long b = 0; b < blocks; ++b) {
    next_or_fail(in, "the last node block");
    const long dim = in.integer(0, "entity dimension");
    const bool parametric = in.integer(2, "parametric flag") != 0;
    const long count = in.integer(3, "nodes in block");
    const std::size_t first = f.node_id.size();
    for (long i = 0; i < count; ++i) {
      next_or_fail(in, "the block's node numbers");
      f.node_id.push_back(in.integer(0, "node number"));
    }
    f.x.resize(f.node_id.size());
    for (long i = 0; i < count; ++i) {
      next_or_fail(in, "the block's coordinates");
      in.need(3 + (parametric ? std::size_t(dim) : 0), "x y z and parametric coordinates");
      f.x[first + i] = Vec3d(in.real(0, "x"), in.real(1, "y"), in.real(2, "z"));
    }
  }
}

void elements_v41(TextLines& in, TetFile& f) {
  next_or_fail(in, "the element header");
  const long blocks = in.integer(0, "number of entity blocks");
  for (long b = 0; b < blocks; ++b) {
    next_or_fail(in, "the last element block");
    const long dim = in.integer(0, "entity dimension");
    const long type = in.integer(2, "element type");
    const long count = in.integer(3, "elements in block");
    for (long i = 0; i < count; ++i) {
      next_or_fail(in, "the block's elements");
      const long id = in.integer(0, "element number");
      if (is_tet(type))
        add_tet(in, f, id, 1);
      else if (dim == 3)
        not_tet(in, id, type);
    }
  }
}

}  // namespace

TetFile read_gmsh(const std::string& path) {
  TextLines in(path);
  if (!in.next() || in.fields()[0] != "$MeshFormat")
    in.fail("no $MeshFormat section at the start", "give a Gmsh .msh file");
  next_or_fail(in, "the format line");
  const std::string version = in.fields()[0];
  const bool v2 = version.rfind("2.", 0) == 0;
  if (!v2 && version != "4.1") in.fail("Gmsh format " + version + " is not supported", kResave);
  if (in.integer(1, "file type") != 0) in.fail("the file is binary", kResave);
  expect_end(in, "MeshFormat");

  TetFile f;
  bool nodes = false, elements = false;
  while (in.next()) {
    const std::string section = in.fields()[0];
    if (section.empty() || section[0] != '$')
      in.fail("expected a section such as $Nodes, found '" + section + "'", kResave);
    const std::string name = section.substr(1);
    if (name == "Nodes") {
      v2 ? nodes_v2(in, f) : nodes_v41(in, f);
      nodes = true;
      expect_end(in, name);
    } else if (name == "Elements") {
      v2 ? elements_v2(in, f) : elements_v41(in, f);
      elements = true;
      expect_end(in, name);
    } else {
      // Sections this reader has no use for ($PhysicalNames, $Entities, $NodeData, ...).
      do next_or_fail(in, ("$End" + name).c_str());
      while (in.fields()[0] != "$End" + name);
    }
  }
  if (!nodes || !elements)
    throw MeshError(path, std::string("no $") + (nodes ? "Elements" : "Nodes") + " section",
                    "save the mesh with its nodes and elements");
  return f;
}

}  // namespace sphfem::import_detail
