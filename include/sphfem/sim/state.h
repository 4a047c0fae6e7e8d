// A simulation's whole state, apart from its compiled model: the fluid's and the bodies' plain
// images (sph/state.h, fem/state.h) and the clock of a scene without fluid. Loading it into a
// Simulation of the same scene continues the run bit for bit; its hash pins a run's result.
#pragma once

#include <cstdint>
#include <string>

#include "sphfem/fem/state.h"
#include "sphfem/sph/state.h"

namespace sphfem {

struct SimState {
  bool has_fluid = false, has_bodies = false;
  double time = 0;  // of the bodies alone, without fluid
  FluidState fluid;
  BodyState bodies;
};

// FNV-1a (64 bits) over every value of the state, in a fixed order: equal states, equal hashes,
// on any machine of the same byte order and precision.
std::uint64_t state_hash(const SimState& s);
std::string hash_hex(std::uint64_t h);

}  // namespace sphfem
