// The slip coefficient acts with the near-surface density too: a body sliding over water with
// no slip drags the water along and is slowed by it, momentum exchanged, not created; with
// free slip it slides past. Without gravity and away from the tank's walls, nothing else
// takes momentum.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

struct Slide {
  double fluid_px = 0, body_px = 0, body_px0 = 0;
};

// A soft plate moving at 0.5 m/s along x, its underside 2 mm above a floating layer of water.
Slide slide(double slip) {
  nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002, "gravity": [0, 0, 0]},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0.05, 0.02, 0.03], "max": [0.35, 0.08, 0.17]}]},
    "domain": {"min": [0, 0, 0], "max": [0.4, 0.2, 0.2]},
    "bodies": [{"name": "plate", "shape": "box", "position": [0.15, 0.092, 0.1],
                "size": [0.1, 0.02, 0.1], "resolution": 4, "velocity": [0.5, 0, 0],
                "material": {"density": 500, "young": 1e6, "poisson": 0.3}}]
  })");
  j["bodies"][0]["slip"] = slip;
  const SceneSpec scene = parse_scene(j, "slide.json");
  validate_scene(scene, "slide.json");
  Simulation sim(scene, Backend::Cpu);
  auto body_px = [&] {
    BodySnapshot b;
    sim.bodies()->snapshot(b);
    double p = 0;
    for (int i = 0; i < b.n; ++i) p += double(sim.bodies_model().mass[std::size_t(i)]) * b.v[i].x;
    return p;
  };
  Slide s;
  s.body_px0 = body_px();
  while (sim.time() < 0.1 - 1e-9) sim.step(0.1 - sim.time());
  FluidSnapshot f;
  sim.snapshot(f);
  for (int i = 0; i < f.n; ++i) s.fluid_px += double(sim.fluid_model().params.mass) * f.v[i].x;
  s.body_px = body_px();
  return s;
}

TEST(CoupleSlip, NoSlipDragsTheWaterWithTheNearSurfaceDensity) {
  const Slide stick = slide(0.0), free = slide(1.0);
  std::printf("slip 0: water %.4g, plate %.4g -> %.4g N s; slip 1: water %.4g, plate %.4g N s\n",
              stick.fluid_px, stick.body_px0, stick.body_px, free.fluid_px, free.body_px);
  // No slip: the water gains a good part of the plate's momentum, which the plate loses.
  EXPECT_GT(stick.fluid_px, 0.1 * stick.body_px0);
  EXPECT_LT(stick.body_px, stick.body_px0 - 0.1 * stick.body_px0);
  // Momentum exchanged, not created (to the FEM solve's tolerance).
  EXPECT_NEAR(stick.fluid_px + stick.body_px, stick.body_px0, 0.02 * stick.body_px0);
  // Free slip: the water is hardly moved along x.
  EXPECT_LT(std::fabs(free.fluid_px), 0.2 * stick.fluid_px);
  EXPECT_NEAR(free.fluid_px + free.body_px, free.body_px0, 0.02 * free.body_px0);
}

}  // namespace
}  // namespace sphfem
