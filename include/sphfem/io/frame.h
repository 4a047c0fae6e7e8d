// A neutral in-memory description of one output frame: points, their arrays and optional cells.
// Writers (vtu.h, ply.h) take it so the simulation never depends on a file format.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sphfem::io {

// One named array of `components` values per point (or per cell). Float data lives in
// `values`; an integer array uses `ivalues` instead, which wins whenever it is non-empty.
struct DataArray {
  std::string name;
  int components = 1;
  std::vector<float> values;
  std::vector<std::int32_t> ivalues;

  bool is_int() const { return !ivalues.empty(); }
  std::size_t size() const { return is_int() ? ivalues.size() : values.size(); }
};

// Points with optional cells in VTK convention: `offsets[i]` is the end of cell i in
// `connectivity` and `types[i]` its VTK cell type. No cells means a plain point cloud.
struct PointSet {
  std::vector<float> positions;  // 3 per point, interleaved xyz
  std::vector<DataArray> point_data;
  std::vector<std::int32_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  std::vector<DataArray> cell_data;

  std::size_t size() const { return positions.size() / 3; }
  // Cells as written: a cloud gets one vertex cell per point so viewers draw it.
  std::size_t num_cells() const { return types.empty() ? size() : types.size(); }
};

// VTK cell types the writers care about.
constexpr std::uint8_t kVtkVertex = 1;
constexpr std::uint8_t kVtkTriangle = 5;
constexpr std::uint8_t kVtkTetra = 10;

// Throws std::invalid_argument naming the first inconsistency (array sizes, cell offsets,
// out-of-range indices). Writers call it before touching the disk.
void validate(const PointSet& frame);

}  // namespace sphfem::io
