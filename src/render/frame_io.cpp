#include "sphfem/render/frame_io.h"

#include <map>

namespace sphfem::render {

namespace {

// The triangles grouped by the values of the integer cell array `group` (one group without it).
std::map<int, TriangleMesh> grouped_meshes(const io::PointSet& s, const char* group) {
  const io::DataArray* body = nullptr;
  for (const io::DataArray& a : s.cell_data)
    if (a.name == group && a.is_int() && a.components == 1 && a.ivalues.size() == s.types.size())
      body = &a;
  struct Building {
    TriangleMesh mesh;
    std::map<std::int32_t, std::uint32_t> local;  // frame vertex -> mesh vertex
  };
  std::map<int, Building> by_body;  // ordered: meshes come out by body index
  const std::size_t n = s.size();
  for (std::size_t c = 0; c < s.types.size(); ++c) {
    const std::int32_t begin = c == 0 ? 0 : s.offsets[c - 1], end = s.offsets[c];
    if (s.types[c] != io::kVtkTriangle || end - begin != 3) continue;
    Building& b = by_body[body ? body->ivalues[c] : 0];
    for (std::int32_t k = begin; k < end; ++k) {
      const std::int32_t v = s.connectivity[std::size_t(k)];
      if (v < 0 || std::size_t(v) >= n) break;
      auto [it, fresh] = b.local.emplace(v, std::uint32_t(b.mesh.positions.size() / 3));
      if (fresh)
        for (int d = 0; d < 3; ++d) b.mesh.positions.push_back(s.positions[3 * std::size_t(v) + d]);
      b.mesh.indices.push_back(it->second);
    }
    b.mesh.indices.resize(b.mesh.indices.size() / 3 * 3);  // drop a cut triangle
  }
  std::map<int, TriangleMesh> out;
  for (auto& [index, b] : by_body) out[index] = std::move(b.mesh);
  return out;
}

}  // namespace

std::vector<TriangleMesh> body_meshes(const io::PointSet& s) {
  std::vector<TriangleMesh> out;
  for (auto& [index, mesh] : grouped_meshes(s, "body")) {
    mesh.color = body_color(index);
    out.push_back(std::move(mesh));
  }
  return out;
}

std::vector<TriangleMesh> obstacle_meshes(const io::PointSet& s) {
  std::vector<TriangleMesh> out;
  for (auto& [index, mesh] : grouped_meshes(s, "obstacle")) {
    mesh.color = Vec3d(0.62, 0.62, 0.66);
    out.push_back(std::move(mesh));
  }
  return out;
}

}  // namespace sphfem::render
