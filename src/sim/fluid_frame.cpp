// The fluid's output frame (include/sphfem/sim/fluid_frame.h).
#include "sphfem/sim/fluid_frame.h"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace sphfem {

io::PointSet fluid_frame(const FluidSnapshot& s) {
  io::PointSet ps;
  ps.positions.resize(3 * std::size_t(s.n));
  io::DataArray vel{"velocity", 3, std::vector<float>(3 * std::size_t(s.n)), {}};
  io::DataArray rho{"density", 1, std::vector<float>(s.n), {}};
  io::DataArray p{"pressure", 1, std::vector<float>(s.n), {}};
  io::DataArray id{"id", 1, {}, std::vector<std::int32_t>(s.n)};
  io::DataArray nb{"neighbors", 1, {}, std::vector<std::int32_t>(s.n)};
  for (int i = 0; i < s.n; ++i) {
    for (int c = 0; c < 3; ++c) {
      ps.positions[3 * i + c] = float(s.x[i][c]);
      vel.values[3 * i + c] = float(s.v[i][c]);
    }
    rho.values[i] = float(s.rho[i]);
    p.values[i] = float(s.p[i]);
    id.ivalues[i] = std::int32_t(s.id[i]);
    nb.ivalues[i] = s.neighbors[i];
  }
  ps.point_data = {std::move(vel), std::move(rho), std::move(p), std::move(id), std::move(nb)};
  // An empty int array would read as float; a frame with no particles keeps float arrays only.
  if (s.n == 0) ps.point_data.resize(3);
  return ps;
}

}  // namespace sphfem
