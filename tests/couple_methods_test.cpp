// The two couplings side by side through Simulation: the ray-traced one (with and without the
// near-surface density) and the boundary-particle baseline exchange momentum without creating
// any, and both run every paper scene.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

using nlohmann::json;

struct Method {
  const char* name;
  CouplingMethod method;
  bool near_surface;
};

const Method kMethods[] = {{"raytraced", CouplingMethod::RayTraced, false},
                           {"raytraced_near_surface", CouplingMethod::RayTraced, true},
                           {"boundary_particles", CouplingMethod::BoundaryParticles, false}};

class CoupleMethods : public ::testing::TestWithParam<Method> {};

// Fluid + bodies + impulses the bodies have received but not yet taken into a step.
Vec3d total_momentum(Simulation& sim) {
  Vec3d p;
  FluidSnapshot f;
  sim.fluid()->snapshot(f);
  const double m = double(sim.fluid_model().params.mass);
  for (int i = 0; i < f.n; ++i) p += Vec3d(f.v[std::size_t(i)]) * m;
  BodySnapshot b;
  sim.bodies()->snapshot(b);
  const BodyArrays a = sim.bodies()->arrays();
  for (int i = 0; i < b.n; ++i)
    p += Vec3d(b.v[std::size_t(i)]) * double(sim.bodies_model().mass[std::size_t(i)]) +
         Vec3d(a.impulse[i]);
  return p;
}

// A block of water thrown at a free soft ball without gravity, far from every wall: whatever
// the coupling, fluid and ball only trade momentum. Bound: float sums over about 1,000
// particles and 300 nodes per step, and the body solve's CG tolerance (1e-8 here).
TEST_P(CoupleMethods, FluidAndBodyOnlyTradeMomentum) {
  const Method m = GetParam();
  SceneSpec s = parse_scene(json::parse(R"({
    "simulation": {"solver": "wcsph", "gravity": [0, 0, 0], "dt_max": 0.001},
    "fluid": {"particle_radius": 0.004, "viscosity": 0, "max_speed": 2,
              "blocks": [{"min": [0.05, 0.1, 0.1], "max": [0.1, 0.15, 0.15],
                          "velocity": [1, 0, 0]}]},
    "domain": {"min": [0, 0, 0], "max": [0.4, 0.25, 0.25]},
    "fem": {"cg_tolerance": 1e-8, "cg_max_iterations": 400},
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.17, 0.125, 0.125],
                "radius": 0.035, "resolution": 4,
                "material": {"density": 800, "young": 5e4, "poisson": 0.3}}]
  })"),
                            "test.json");
  s.coupling.method = m.method;
  s.coupling.near_surface_density = m.near_surface;
  s.coupling.tank_rays = false;  // the tank is out of reach; keep its infinite mass out
  validate_scene(s, "test.json");
  Simulation sim(s, Backend::Cpu);
  const Vec3d p0 = total_momentum(sim);
  Vec3d body_impulse;
  while (sim.time() < 0.08) {
    sim.step(0.08 - sim.time());
    for (const Vec3d& j : sim.coupling()->stats().body_impulse) body_impulse += j;
    sim.coupling()->reset_stats();
  }
  const Vec3d p1 = total_momentum(sim);
  const Vec3d d = p1 - p0;
  std::printf("%s: momentum %.6f -> %.6f %.2e %.2e N s; fluid gave the ball %.5f N s\n", m.name,
              p0.x, p1.x, p1.y, p1.z, body_impulse.x);
  // A real collision: the ball took a good share of the block's momentum.
  EXPECT_GT(body_impulse.x, 0.1 * p0.x);
  EXPECT_LT(std::sqrt(dot(d, d)), 2e-4 * p0.x);
}

INSTANTIATE_TEST_SUITE_P(All, CoupleMethods, ::testing::ValuesIn(kMethods),
                         [](const ::testing::TestParamInfo<Method>& i) { return i.param.name; });

// Every paper scene builds and runs its first 30 steps under both couplings (the fluid capped
// at 3,000 particles, the bodies at full size); CI time allows no more. `sphfem bench --paper`
// runs them all the way.
TEST(CoupleMethodsPaper, EverySceneRunsUnderBothCouplings) {
  const std::filesystem::path dir = std::filesystem::path(SPHFEM_SOURCE_DIR) / "scenes" / "paper";
  int ran = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() != ".json") continue;
    SceneSpec base;
    try {
      base = load_scene(e.path().string());
    } catch (const std::exception& ex) {
      // The bunny and dragon need the fetched bunny mesh (make assets).
      if (std::string(ex.what()).find("bunny") != std::string::npos) {
        std::printf("%s: skipped, %s\n", e.path().filename().c_str(), ex.what());
        continue;
      }
      throw;
    }
    for (const Method& m : {kMethods[1], kMethods[2]}) {
      SceneSpec s = base;
      s.coupling.method = m.method;
      s.fluid.max_particles = 3000;
      Simulation sim(s, Backend::Cpu);
      long contacts = 0;
      for (int step = 0; step < 30; ++step) {
        sim.step(1.0);
        contacts += sim.coupling()->stats().contacts;
        sim.coupling()->reset_stats();
      }
      FluidSnapshot f;
      sim.fluid()->snapshot(f);
      BodySnapshot b;
      sim.bodies()->snapshot(b);
      std::printf("%s %s: %d particles, %d nodes at t = %.3f s\n", e.path().filename().c_str(),
                  m.name, f.n, b.n, sim.time());
      EXPECT_GT(f.n, 0) << e.path();
      for (const Vec3& x : f.x) ASSERT_TRUE(std::isfinite(x.x + x.y + x.z)) << e.path();
      for (const Vec3& x : b.x) ASSERT_TRUE(std::isfinite(x.x + x.y + x.z)) << e.path();
      ++ran;
    }
  }
  EXPECT_GE(ran, 14);  // 7 scenes without the bunny mesh, 9 with it, two couplings each
}

}  // namespace
}  // namespace sphfem
