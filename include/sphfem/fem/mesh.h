// Tetrahedral meshes: the rest shape of a deformable body, procedural generators for the
// shapes the scenes use, and extraction of the boundary surface.
//
// Every generator meshes a structured lattice whose hexahedral cells are split into the six
// Kuhn (Freudenthal) tetrahedra around the cell's main diagonal. The split is the same in
// every cell, so neighbouring cells agree on the diagonal of their shared face and the mesh
// is conforming without a parity rule. Round shapes move the lattice vertices by a
// continuous, orientation-preserving map (concentric squares to circles, concentric cubes to
// spheres, polar coordinates for tubes), which keeps every tetrahedron positively oriented.
#pragma once

#include <vector>

#include "sphfem/core/vec.h"

namespace sphfem {

// Four node indices; positive orientation: dot(x1 - x0, cross(x2 - x0, x3 - x0)) > 0.
struct Tet {
  int v[4];
};

// Three node indices, counter-clockwise seen from outside.
struct Tri {
  int v[3];
};

struct TetMesh {
  std::vector<Vec3d> x;  // rest positions, m
  std::vector<Tet> tets;
};

// --- generators (all tetrahedra positively oriented) ---

// Axis-aligned box [lo, hi] of nx * ny * nz cells, six tetrahedra per cell.
TetMesh make_box(const Vec3d& lo, const Vec3d& hi, int nx, int ny, int nz);

// Cloth: a one-cell-thick slab in the x-z plane centred on `center`, `thickness` along y,
// nx * nz cells.
TetMesh make_cloth(const Vec3d& center, double size_x, double size_z, double thickness, int nx,
                   int nz);

// Hollow cylinder along +y from the centre of its bottom ring `base`: radii r_in < r_out,
// `segments` cells around, `layers` cells through the wall, `rings` cells along the length.
TetMesh make_tube(const Vec3d& base, double r_in, double r_out, double length, int segments,
                  int layers, int rings);

// Open-top cup along +y from the centre of its base: wall between r_in and r_out, solid
// bottom of thickness `bottom`, total height `height`; `cells` lattice cells across the
// outer diameter (the cell size sets the wall and bottom layer counts).
TetMesh make_cup(const Vec3d& base, double r_in, double r_out, double height, double bottom,
                 int cells);

// Solid ball: a cube lattice of `cells`^3 cells mapped onto the ball (each cube shell of the
// lattice onto a sphere), 6 * cells^3 tetrahedra.
TetMesh make_sphere(const Vec3d& center, double radius, int cells);

// --- measures and checks ---

double tet_volume(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);  // signed
double tet_volume(const TetMesh& m, int t);
double mesh_volume(const TetMesh& m);  // sum of signed tetrahedron volumes

// Throws std::runtime_error naming the first problem: a node index out of range, a
// tetrahedron of zero or negative volume, or a node that belongs to no tetrahedron.
void validate_mesh(const TetMesh& m, const char* what);

// Boundary triangles: faces that belong to exactly one tetrahedron, oriented outward, in a
// fixed order (by tetrahedron, then local face).
std::vector<Tri> boundary_faces(const std::vector<Tet>& tets);

// Removes the flat caps and ears of the boundary: elements with two faces on it whose smallest
// height is under max_flatness times the smaller of their longest edge and the surface's
// median edge (0.82 for a regular tetrahedron), and elements with three whose tip no other
// element holds and stands lower than max_flatness times the median edge; in passes until
// none is left, keeping the surface closed and manifold; the ears' tips are dropped. A contact
// plane pressed on a nearly flat stretch of surface flattens a cap to zero volume, and a push
// on an ear's tip turns it inside out. Returns the number removed (0 when max_flatness <= 0).
int peel_flat_caps(TetMesh& m, double max_flatness);

// Renumbers the nodes along a Morton (Z-order) curve of their positions and the elements by
// their lowest node, each tie kept in its old order; orientations unchanged. A mesher's order
// scatters an element's nodes over the whole array, so the threads' static shares of the
// elements and of the nodes overlap little and every pass moves cache lines between cores
// (docs/design.md, "Node order").
void order_for_locality(TetMesh& m);

// Volume enclosed by a closed, outward-oriented triangle surface (divergence theorem).
double enclosed_volume(const std::vector<Vec3d>& x, const std::vector<Tri>& tris);

}  // namespace sphfem
