// Output frames of the deformable bodies: their surfaces (triangles, for viewing) and their
// tetrahedra (for inspecting the interior), as point sets the VTK writer takes.
#pragma once

#include <vector>

#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"
#include "sphfem/io/frame.h"
#include "sphfem/scene/obstacles.h"

namespace sphfem {

// Both frames carry the point arrays `displacement` (m, from the rest position) and
// `velocity` (m/s), and the cell array `body` (index in the scene's bodies).
class BodyFrames {
 public:
  explicit BodyFrames(const BodiesModel& model);

  // Surface triangles over the surface nodes only (VTK type 5).
  io::PointSet surface(const BodySnapshot& s) const;
  // All nodes and tetrahedra (VTK type 10), points in the model's node order.
  io::PointSet tets(const BodySnapshot& s) const;

  int surface_nodes() const { return int(surface_node_.size()); }

 private:
  io::PointSet points(const BodySnapshot& s, const std::vector<int>& nodes) const;

  const BodiesModel& model_;
  std::vector<int> surface_node_;           // global index of each surface point
  std::vector<int> all_nodes_;              // 0 .. nodes - 1
  io::PointSet surface_cells_, tet_cells_;  // connectivity, offsets, types and cell data
};

// The obstacles' triangles where they are at time t, with cell data "obstacle": each
// triangle's obstacle.
io::PointSet obstacle_surface(const ObstaclesModel& obstacles, double t = 0);

}  // namespace sphfem
