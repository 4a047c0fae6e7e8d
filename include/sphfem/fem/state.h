// The bodies' state as plain host arrays: everything a step reads that an earlier step wrote
// (positions, velocities, the impulses waiting for the next step, and the warm starts of the
// rotation extraction and of CG, which change a step's bits).
#pragma once

#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/fem/mat3.h"

namespace sphfem {

struct BodyState {
  int nodes = 0, elements = 0;
  double time = 0;
  long steps = 0;
  bool warm = false;  // dv holds the last step's velocity change (the CG start)
  std::vector<Vec3> x, v, dv, impulse;
  std::vector<Quat> rotation;  // per element, the last extracted rotation
};

}  // namespace sphfem
