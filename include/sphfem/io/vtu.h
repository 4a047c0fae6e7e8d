// VTK XML UnstructuredGrid (.vtu) frames in raw appended binary, the form ParaView reads fastest.
#pragma once

#include <string>

#include "sphfem/io/frame.h"

namespace sphfem::io {

// Writes `frame` atomically (see atomic_file.h): Float32 points, Float32/Int32 point and cell
// arrays, Int32 connectivity/offsets, UInt8 types, UInt64 block headers, little endian.
// A frame without cells gets one VTK_VERTEX cell per point.
void write_vtu(const std::string& path, const PointSet& frame);

// Reads positions and point arrays back from a file written by write_vtu (cells are skipped).
// Throws std::runtime_error naming the path when the file is not in that form.
PointSet read_vtu_points(const std::string& path);

// Reads the whole frame back: points, point arrays, cells (connectivity, offsets, types) and
// cell arrays; a point cloud's vertex cells read back as no cells. Throws like
// read_vtu_points, and also when the cells do not index the points.
PointSet read_vtu(const std::string& path);

}  // namespace sphfem::io
