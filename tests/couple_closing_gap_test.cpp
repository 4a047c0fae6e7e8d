// Closing gaps. A soft plate hanging from its pinned top edge swings through resting water
// with its free edge 1 mm over the floor; and a heavy cantilever plate slams onto the floor
// through a thin layer of water, squeezing it out. Particles caught between a plate and the
// floor must be pushed out, not shot out: no energy is created, and the swinging plate's water
// stays within a few times the plate's own speed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

struct Run {
  double fluid_max = 0, node_max = 0, dt_min = 1;
  double created = 0;  // largest energy above the start's, J (0: never above)
  double start = 0;    // total energy at the start, J
  long crossed = 0;
};

// Kinetic + elastic + gravitational energy of water and plate, J.
double total_energy(Simulation& sim, double g) {
  const FluidArrays f = sim.fluid()->arrays();
  double e = 0;
  for (int i = 0; i < f.n; ++i)
    e += double(f.mass) * (0.5 * double(norm2(f.v[i])) + g * double(f.x[i].y));
  BodySolver& b = *sim.bodies();
  const BodyArrays a = b.arrays();
  for (int i = 0; i < a.nodes; ++i) e += double(a.mass[i]) * g * double(a.x[i].y);
  return e + b.kinetic_energy() + b.elastic_energy();
}

Run run(nlohmann::json j, bool near_surface, double duration) {
  j["coupling"]["near_surface_density"] = near_surface;
  const SceneSpec scene = parse_scene(j, "gap.json");
  validate_scene(scene, "gap.json");
  Simulation sim(scene, Backend::Cpu);
  const double g = 9.81;
  Run r;
  r.start = total_energy(sim, g);
  while (sim.time() < duration) {
    const StepInfo info = sim.step(duration - sim.time());
    // The last step of the run is cut short to end on time; it says nothing of the speeds.
    if (sim.time() < duration - 1e-9) r.dt_min = std::min(r.dt_min, info.dt);
    const FluidArrays f = sim.fluid()->arrays();
    const BodyArrays b = sim.bodies()->arrays();
    for (int i = 0; i < f.n; ++i) r.fluid_max = std::max(r.fluid_max, double(norm(f.v[i])));
    for (int i = 0; i < b.nodes; ++i)
      if (!b.pinned[i]) r.node_max = std::max(r.node_max, double(norm(b.v[i])));
    r.created = std::max(r.created, total_energy(sim, g) - r.start);
    r.crossed += sim.coupling()->stats().crossed;
    sim.coupling()->reset_stats();
  }
  std::printf(
      "fastest particle %.3f m/s, fastest plate node %.3f m/s, smallest dt %.3g s, energy "
      "%.4f J, at most %.2e J above it, %ld crossed, %ld steps\n",
      r.fluid_max, r.node_max, r.dt_min, r.start, r.created, r.crossed, sim.steps());
  return r;
}

const char* kSwing = R"({
  "simulation": {"solver": "dfsph", "dt_max": 0.001},
  "fluid": {"particle_radius": 0.004, "viscosity": 1e-5,
            "blocks": [{"min": [0, 0, 0], "max": [0.08, 0.05, 0.08]},
                       {"min": [0.1, 0, 0], "max": [0.24, 0.05, 0.08]}]},
  "domain": {"min": [0, 0, 0], "max": [0.24, 0.12, 0.08]},
  "bodies": [{"name": "plate", "shape": "box", "position": [0.09, 0.0535, 0.04],
              "size": [0.008, 0.105, 0.064], "resolution": 16, "velocity": [2.0, 0, 0],
              "material": {"density": 1200, "young": 2e5, "poisson": 0.3, "damping_beta": 0.001},
              "pinned": {"boxes": [{"min": [0, 0.105, 0], "max": [0.24, 0.12, 0.08]}]}}]
})";

const char* kSlam = R"({
  "simulation": {"solver": "dfsph", "dt_max": 0.001},
  "fluid": {"particle_radius": 0.004, "viscosity": 1e-5,
            "blocks": [{"min": [0, 0, 0], "max": [0.24, 0.024, 0.08]}]},
  "domain": {"min": [0, 0, 0], "max": [0.24, 0.12, 0.08]},
  "bodies": [{"name": "plate", "shape": "box", "position": [0.11, 0.04, 0.04],
              "size": [0.2, 0.012, 0.064], "resolution": 16, "velocity": [0, -1.0, 0],
              "material": {"density": 6000, "young": 3e5, "poisson": 0.3, "damping_beta": 0.001},
              "pinned": {"boxes": [{"min": [0, 0, 0], "max": [0.025, 0.2, 0.08]}]}}]
})";

void expect_swing(bool near_surface) {
  const Run r = run(nlohmann::json::parse(kSwing), near_surface, 0.4);
  EXPECT_LE(r.fluid_max, 3 * r.node_max);
  EXPECT_LE(r.created, 1e-3 * r.start);
  EXPECT_EQ(r.crossed, 0);
}

// The water squeezed from under the plate may leave faster than the plate (a film's outflow is
// its closing speed times its half-width over its thickness), but it takes its energy from the
// plate: nothing is created.
void expect_slam(bool near_surface) {
  const Run r = run(nlohmann::json::parse(kSlam), near_surface, 0.3);
  EXPECT_LE(r.created, 1e-3 * r.start);
  EXPECT_EQ(r.crossed, 0);
}

TEST(CoupleClosingGap, PlateSwingingOverTheFloor) { expect_swing(true); }
TEST(CoupleClosingGap, PlateSwingingOverTheFloorPaperMode) { expect_swing(false); }
TEST(CoupleClosingGap, PlateSlammingOntoTheFloor) { expect_slam(true); }
TEST(CoupleClosingGap, PlateSlammingOntoTheFloorPaperMode) { expect_slam(false); }

}  // namespace
}  // namespace sphfem
