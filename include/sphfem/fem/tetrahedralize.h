// Tetrahedralising a closed triangle surface with TetGen: the body's rest mesh from a scanned
// or modelled shape. The surface is kept (TetGen's "p": a constrained Delaunay mesh of the
// piecewise linear complex), so the mesh fills exactly the volume the surface encloses.
#pragma once

#include <string>

#include "sphfem/fem/import.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

// Quality refinement adds points wherever the surface has small features, so a scanned shape
// can end up far finer than max_volume asks: the 3,674-triangle Stanford bunny gives about
// 45k tetrahedra at quality 1.414, 23k at 2, and 6k with quality 0 and no volume limit.
struct TetgenOptions {
  double max_volume = 0.0;  // m^3, largest tetrahedron ("a"); 0 = no limit
  double quality = 1.414;   // largest radius-edge ratio ("q"); 0 = no quality refinement
  bool quiet = true;        // suppress TetGen's report on stdout ("Q")
  double peel_caps = 0.0;   // peel_flat_caps of the result below this flatness; 0 = none
};

// The TetGen command-line switches for the options, e.g. "pq1.414a1e-06Q".
std::string tetgen_switches(const TetgenOptions& o);

// Checks the surface (check_surface), meshes its inside and returns positively oriented
// tetrahedra that pass validate_mesh. Throws MeshError naming s.source and the fix when the
// surface is unfit or TetGen fails.
TetMesh tetrahedralize(const SurfaceMesh& s, const TetgenOptions& o = {});

}  // namespace sphfem
