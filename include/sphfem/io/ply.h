// Binary little-endian PLY frames, for tools that prefer PLY over VTK (Blender, MeshLab).
#pragma once

#include <string>

#include "sphfem/io/frame.h"

namespace sphfem::io {

// Writes `frame` atomically: a vertex element with float x,y,z and one property per array
// component (scalar `name`; 2 or 3 components `name_x,name_y[,name_z]`; otherwise `name_0..`),
// float or int as the array is. When every cell is a triangle a `face` element follows with
// `list uchar int vertex_indices`. Cell arrays and non-triangle cells are not written.
void write_ply(const std::string& path, const PointSet& frame);

// Reads positions and vertex arrays from a file written by write_ply, regrouping `name_x..`
// and `name_0..` runs into vector arrays. Faces are skipped.
PointSet read_ply_points(const std::string& path);

}  // namespace sphfem::io
