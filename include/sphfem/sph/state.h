// The fluid's state as plain host arrays: everything a step reads that an earlier step wrote.
// What a step recomputes from it (grid, densities, neighbour lists, DFSPH factors, wall-sample
// values) is not part of it. Particle order is: the step sums neighbours in grid order, which
// follows this order, so a state loaded in another order would not give the same bits.
#pragma once

#include <cstdint>
#include <vector>

#include "sphfem/core/vec.h"

namespace sphfem {

struct FluidState {
  int n = 0;
  double time = 0;
  long steps = 0;
  std::uint32_t next_id = 0;           // the next emitted particle's id
  bool capacity_warned = false;        // the "capacity reached" warning was printed
  std::vector<double> emitter_travel;  // per emitter, the nozzle's progress since its last layer
  std::vector<Vec3> x, v;
  std::vector<std::uint32_t> id;
  std::vector<Real> warm_div, warm_dens;  // DFSPH warm starts (zero under WCSPH)
};

}  // namespace sphfem
