// Body frames: node arrays gathered per frame; the cells, fixed for the run, built once.
#include "sphfem/sim/body_frames.h"

#include <algorithm>
#include <cstdint>

namespace sphfem {

namespace {

// Body index of every element in a per-body range list (node, tet or triangle offsets).
std::vector<std::int32_t> body_of(const std::vector<int>& offset) {
  std::vector<std::int32_t> id;
  for (std::size_t b = 0; b + 1 < offset.size(); ++b)
    id.insert(id.end(), std::size_t(offset[b + 1] - offset[b]), std::int32_t(b));
  return id;
}

}  // namespace

BodyFrames::BodyFrames(const BodiesModel& m) : model_(m) {
  // Surface points: the nodes the triangles use, in node order.
  std::vector<int> point(std::size_t(m.nodes), -1);
  for (const Tri& t : m.surface)
    for (int v : t.v) point[std::size_t(v)] = 0;
  for (int i = 0; i < m.nodes; ++i)
    if (point[i] == 0) point[i] = int(surface_node_.size()), surface_node_.push_back(i);
  for (const Tri& t : m.surface) {
    for (int v : t.v) surface_cells_.connectivity.push_back(point[std::size_t(v)]);
    surface_cells_.offsets.push_back(std::int32_t(surface_cells_.connectivity.size()));
    surface_cells_.types.push_back(io::kVtkTriangle);
  }
  surface_cells_.cell_data.push_back({"body", 1, {}, body_of(m.tri_offset)});

  all_nodes_.resize(std::size_t(m.nodes));
  for (int i = 0; i < m.nodes; ++i) all_nodes_[i] = i;
  for (const Tet& t : m.tets) {
    for (int v : t.v) tet_cells_.connectivity.push_back(v);
    tet_cells_.offsets.push_back(std::int32_t(tet_cells_.connectivity.size()));
    tet_cells_.types.push_back(io::kVtkTetra);
  }
  tet_cells_.cell_data.push_back({"body", 1, {}, body_of(m.tet_offset)});
}

io::PointSet BodyFrames::points(const BodySnapshot& s, const std::vector<int>& nodes) const {
  io::PointSet ps;
  const std::size_t n = nodes.size();
  ps.positions.resize(3 * n);
  io::DataArray disp{"displacement", 3, std::vector<float>(3 * n), {}};
  io::DataArray vel{"velocity", 3, std::vector<float>(3 * n), {}};
  for (std::size_t k = 0; k < n; ++k) {
    const int i = nodes[k];
    for (int c = 0; c < 3; ++c) {
      ps.positions[3 * k + c] = float(s.x[i][c]);
      disp.values[3 * k + c] = float(s.x[i][c] - model_.x0[i][c]);
      vel.values[3 * k + c] = float(s.v[i][c]);
    }
  }
  ps.point_data = {std::move(disp), std::move(vel)};
  return ps;
}

io::PointSet BodyFrames::surface(const BodySnapshot& s) const {
  io::PointSet ps = points(s, surface_node_);
  ps.connectivity = surface_cells_.connectivity;
  ps.offsets = surface_cells_.offsets;
  ps.types = surface_cells_.types;
  ps.cell_data = surface_cells_.cell_data;
  return ps;
}

io::PointSet BodyFrames::tets(const BodySnapshot& s) const {
  io::PointSet ps = points(s, all_nodes_);
  ps.connectivity = tet_cells_.connectivity;
  ps.offsets = tet_cells_.offsets;
  ps.types = tet_cells_.types;
  ps.cell_data = tet_cells_.cell_data;
  return ps;
}

io::PointSet obstacle_surface(const ObstaclesModel& m, double t) {
  io::PointSet ps;
  for (const Vec3& p : m.at(t))
    ps.positions.insert(ps.positions.end(), {float(p.x), float(p.y), float(p.z)});
  io::DataArray which;
  which.name = "obstacle";
  for (std::size_t k = 0; k + 1 < m.tri_offset.size(); ++k)
    for (int f = m.tri_offset[k]; f < m.tri_offset[k + 1]; ++f) {
      const Tri& t = m.tris[std::size_t(f)];
      ps.connectivity.insert(ps.connectivity.end(), {t.v[0], t.v[1], t.v[2]});
      ps.offsets.push_back(std::int32_t(ps.connectivity.size()));
      ps.types.push_back(io::kVtkTriangle);
      which.ivalues.push_back(std::int32_t(k));
    }
  ps.cell_data.push_back(which);
  return ps;
}

}  // namespace sphfem
