// Fluid blocks that overlap a body: the body displaces the fluid at the start instead of
// holding particles inside it, which the first steps would shoot out at metres per second.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

TEST(SimCarve, BodyInsideAFluidBlockDisplacesItsVolume) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "blocks": [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]}]},
    "domain": {"min": [0, 0, 0], "max": [0.2, 0.3, 0.2]},
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.1, 0.08, 0.1],
                "radius": 0.05, "resolution": 8,
                "material": {"density": 1000, "young": 1e6, "poisson": 0.3}}]
  })");
  const SceneSpec scene = parse_scene(j, "carve.json");
  validate_scene(scene, "carve.json");
  Simulation sim(scene, Backend::Cpu);
  const double d = 0.01, r = 0.005;
  const long lattice = 20 * 20 * 20;
  // The lattice points within a particle radius of the ball's (faceted) surface or inside it:
  // about the volume of a ball of radius 0.05 + r over d^3.
  const double expected = 4.0 / 3.0 * M_PI * std::pow(0.05 + r, 3) / (d * d * d);
  EXPECT_EQ(sim.fluid()->arrays().n + sim.carved_particles(), lattice);
  EXPECT_NEAR(double(sim.carved_particles()), expected, 0.15 * expected);
  EXPECT_EQ(sim.count_inside(), 0);
  // At rest the displaced water only settles into the gaps the faceted ball leaves: no
  // particle is faster than the column's potential energy allows (Torricelli, sqrt(2 g H)).
  double fastest = 0;
  while (sim.time() < 0.05) {
    sim.step(0.05 - sim.time());
    const FluidArrays f = sim.fluid()->arrays();
    for (int i = 0; i < f.n; ++i) fastest = std::max(fastest, double(norm(f.v[i])));
  }
  EXPECT_LT(fastest, std::sqrt(2 * 9.81 * 0.2));
}

}  // namespace
}  // namespace sphfem
