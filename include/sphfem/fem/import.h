// Importing bodies from files: triangle surfaces (OBJ, PLY, STL through Assimp) to be
// tetrahedralised, and ready-made tetrahedral meshes (TetGen .node/.ele, Gmsh .msh).
//
// Every problem is a MeshError whose message is one line, "<file>: <what>; <fix>", so a user
// can tell which file is wrong and what to do about it without reading the code.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

struct MeshError : std::runtime_error {
  MeshError(const std::string& file, const std::string& what, const std::string& fix)
      : std::runtime_error(file + ": " + what + "; " + fix) {}
};

// A triangle surface with shared vertices. `source` names the file it came from (used in
// error messages); it is empty for surfaces built in code.
struct SurfaceMesh {
  std::vector<Vec3d> x;
  std::vector<Tri> tris;
  std::string source;
};

// --- surfaces ---

// Reads any triangle or polygon surface Assimp reads (OBJ, PLY, STL ASCII and binary, ...):
// polygons are triangulated, all meshes of the file are merged, and vertices at the same
// position become one, so a closed surface comes out closed whatever the file's per-face
// normals or texture seams. Throws MeshError for a missing or unreadable file, or one without
// triangles. It does not check the surface: see check_surface.
SurfaceMesh load_surface(const std::string& path);

// x -> scale * x + offset for every vertex (e.g. a file in millimetres: scale 0.001).
void transform(SurfaceMesh& s, double scale, const Vec3d& offset);

// Axis-aligned bounds of the vertices; {lo, hi}.
std::pair<Vec3d, Vec3d> bounds(const std::vector<Vec3d>& x);

// Throws MeshError unless the surface bounds a solid: no degenerate triangles; every edge
// shared by exactly two triangles (not open, no non-manifold edges) and every vertex's
// triangles one fan (no non-manifold vertices); neighbours consistently oriented; and no two
// triangles intersecting. An inside-out surface (all normals inward) passes.
void check_surface(const SurfaceMesh& s);

// The first pair of triangles (i < j) that meet other than in the vertices or the edge they
// share, or {-1, -1}; triangles without a common vertex must not even touch. Triangles are
// paired through a uniform grid over their bounds. Distances are judged to 1e-9 of the
// bounding-box diagonal: neighbours overlapping by less only touch, others closer than that
// touch.
// Zero-area triangles have no plane to test against; check_surface rejects them first.
std::pair<int, int> find_self_intersection(const SurfaceMesh& s);
// Pairs of triangles that intersect other than where they must touch (the test above); for
// surfaces in motion (bodies' contact gauges).
long count_self_intersections(const SurfaceMesh& s);

// --- tetrahedral meshes ---

// Reads a tetrahedral mesh, by extension: ".node" or ".ele" (TetGen; the other file of the
// pair beside it, numbered from 0 or 1 as the files say) or ".msh" (Gmsh, ASCII format 2.x or
// 4.1). Quadratic tetrahedra keep their corners; nodes no tetrahedron uses are dropped.
// Throws MeshError naming the file's own element number for an inverted or flat tetrahedron:
// an imported mesh is not silently repaired.
TetMesh load_tet_mesh(const std::string& path);

namespace import_detail {

// A text mesh file read line by line as whitespace-separated fields, skipping blank lines and
// '#' comments; its errors name the file and the line.
class TextLines {
 public:
  explicit TextLines(const std::string& path);  // throws MeshError when it cannot be opened
  bool next();                                  // the next non-blank line; false at the end
  const std::vector<std::string>& fields() const { return fields_; }
  // Field i as a number; throws MeshError when the line is shorter or the field is no number.
  long integer(std::size_t i, const char* what) const;
  double real(std::size_t i, const char* what) const;
  void need(std::size_t count, const char* what) const;  // at least `count` fields
  [[noreturn]] void fail(const std::string& what, const std::string& fix) const;
  [[noreturn]] void fail_eof(const char* expected) const;  // the file ends too early
  const std::string& path() const { return path_; }
  // Lines after the current one: an upper bound for the records a header may announce.
  std::size_t lines_left() const { return lines_.size() - line_; }

 private:
  std::string path_;
  std::vector<std::string> lines_;
  std::size_t line_ = 0;  // 1-based number of the current line; 0 before the first
  std::vector<std::string> fields_;
};

// What a tetrahedral-mesh file says, in its own numbering; the format readers fill it and
// finish_tet_mesh turns it into a checked TetMesh.
struct TetFile {
  std::vector<long> node_id;  // file's number of each node
  std::vector<Vec3d> x;
  std::vector<long> tet_id;     // file's number of each tetrahedron
  std::vector<long> tet_nodes;  // four node numbers (file numbering) per tetrahedron
};

TetFile read_tetgen(const std::string& node_path, const std::string& ele_path);
TetFile read_gmsh(const std::string& path);
TetMesh finish_tet_mesh(const TetFile& f, const std::string& path);

}  // namespace import_detail

}  // namespace sphfem
