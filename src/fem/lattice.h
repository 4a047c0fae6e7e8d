// Structured-lattice helpers shared by the mesh generators (src/fem/mesh_*.cpp).
#pragma once

#include <vector>

#include "sphfem/fem/mesh.h"

namespace sphfem::lattice {

// Emits the six Kuhn tetrahedra of one hexahedral cell, all sharing the diagonal from corner
// c[0][0][0] to c[1][1][1]; positively oriented when the lattice axes are right-handed and
// the vertex map preserves orientation.
void kuhn_cell(const int c[2][2][2], std::vector<Tet>& out);

// Node id of lattice point (i, j, k) in an (nx+1) x (ny+1) x (nz+1) vertex grid.
inline int node(int i, int j, int k, int nx, int ny) { return i + (nx + 1) * (j + (ny + 1) * k); }

// Removes nodes that no tetrahedron uses and renumbers the rest in their original order.
void drop_unused_nodes(TetMesh& m);

// Throws std::logic_error when a generator produced a tetrahedron of non-positive volume
// (a resolution too coarse for the vertex map).
void check_generated(const TetMesh& m, const char* generator);

}  // namespace sphfem::lattice
