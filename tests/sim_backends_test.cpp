// The CUDA backend against the CPU, stage by stage through whole steps: each SPH solver alone
// (neighbours, density, DFSPH's two solves or WCSPH's pressure, drift, the tank's samples),
// and a coupled Simulation on every paper scene at a coarser particle size in each coupling
// mode: ray-traced with the near-surface density (proximity, near-surface pressure and its
// return to the nodes), the paper's exchange alone (ray casts, joint contact solve, leak fix)
// and the boundary-particle baseline (moving samples). Both run the same steps; the two
// differ only in summation order and fused multiply-adds, amplified by the solves over the
// steps, so the tolerances are a small share of a particle spacing. Skips without a GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

constexpr int kSteps = 40;

struct Outcome {
  FluidSnapshot fluid;  // sorted by particle id
  BodySnapshot bodies;
  long crossed = 0, contacts = 0, inside = 0;
  double time = 0;
};

Outcome run(const SceneSpec& scene, Backend backend) {
  Simulation sim(scene, backend);
  Outcome o;
  for (int k = 0; k < kSteps; ++k) {
    sim.step(scene.simulation.dt_max);
    if (RayCoupling* c = sim.coupling()) {
      o.crossed += c->stats().crossed;
      o.contacts += c->stats().contacts;
      c->reset_stats();
    }
  }
  o.time = sim.time();
  FluidSnapshot s;
  sim.snapshot(s);
  std::vector<int> order(std::size_t(s.n));
  for (int i = 0; i < s.n; ++i) order[std::size_t(i)] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return s.id[a] < s.id[b]; });
  o.fluid.n = s.n;
  for (int i : order) {
    o.fluid.x.push_back(s.x[i]);
    o.fluid.v.push_back(s.v[i]);
    o.fluid.rho.push_back(s.rho[i]);
    o.fluid.id.push_back(s.id[i]);
  }
  if (sim.bodies()) {
    sim.bodies()->snapshot(o.bodies);
    o.inside = sim.count_inside();
  }
  return o;
}

// Largest differences, and the scales they are judged against.
void compare(const SceneSpec& scene, const Outcome& a, const Outcome& b) {
  const double spacing = 2 * scene.fluid.particle_radius;
  ASSERT_EQ(a.fluid.n, b.fluid.n);
  ASSERT_EQ(a.fluid.id, b.fluid.id);
  double dx = 0, dv = 0, drho = 0, vmax = 0, px = 0, py = 0, pz = 0, pscale = 0;
  for (int i = 0; i < a.fluid.n; ++i) {
    dx = std::max(dx, double(norm(a.fluid.x[i] - b.fluid.x[i])));
    dv = std::max(dv, double(norm(a.fluid.v[i] - b.fluid.v[i])));
    drho = std::max(drho, std::abs(double(a.fluid.rho[i] - b.fluid.rho[i])));
    vmax = std::max(vmax, double(norm(a.fluid.v[i])));
    const Vec3 d = a.fluid.v[i] - b.fluid.v[i];
    px += d.x, py += d.y, pz += d.z;
    pscale += norm(a.fluid.v[i]);
  }
  double dn = 0;
  for (int i = 0; i < a.bodies.n; ++i)
    dn = std::max(dn, double(norm(a.bodies.x[i] - b.bodies.x[i])));
  const double dp = std::sqrt(px * px + py * py + pz * pz);
  std::printf(
      "%d particles, %d nodes: max |dx| %.3g m (spacing %.3g), |dv| %.3g m/s (fastest %.3g), "
      "|drho| %.3g kg/m3, |d momentum| / sum |v| %.3g, nodes |dx| %.3g m; contacts %ld / %ld, "
      "crossed %ld / %ld, inside %ld / %ld\n",
      a.fluid.n, a.bodies.n, dx, spacing, dv, vmax, drho, pscale > 0 ? dp / pscale : 0.0, dn,
      a.contacts, b.contacts, a.crossed, b.crossed, a.inside, b.inside);
  EXPECT_NEAR(a.time, b.time, 1e-4 * a.time) << "the adaptive steps differ";
  EXPECT_LT(dx, 0.02 * spacing);
  EXPECT_LT(dv, 0.05 * std::max(vmax, 0.1));
  EXPECT_LT(drho, 0.01 * scene.fluid.rest_density);
  EXPECT_LT(dp, 1e-3 * pscale + 1e-9);  // total momentum: round-off, not a drift
  EXPECT_LT(dn, 0.02 * spacing);
  EXPECT_EQ(b.crossed, 0);
  EXPECT_EQ(b.inside, a.inside);
  if (a.contacts > 0) {
    EXPECT_NEAR(double(b.contacts), double(a.contacts), 0.05 * a.contacts + 2);
  }
}

bool cuda_or_skip(std::string& why) { return cuda_available(&why); }

class SphBackends : public ::testing::TestWithParam<const char*> {};

TEST_P(SphBackends, CudaMatchesCpu) {
  std::string why;
  if (!cuda_or_skip(why)) GTEST_SKIP() << why;
  nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.002},
    "fluid": {"particle_radius": 0.01,
              "blocks": [{"min": [0, 0, 0], "max": [0.2, 0.4, 0.3]}]},
    "domain": {"min": [0, 0, 0], "max": [0.8, 0.5, 0.3]}
  })");
  j["simulation"]["solver"] = GetParam();
  const SceneSpec scene = parse_scene(j, "dam.json");
  validate_scene(scene, "dam.json");
  compare(scene, run(scene, Backend::Cpu), run(scene, Backend::Cuda));
}

INSTANTIATE_TEST_SUITE_P(Solver, SphBackends, ::testing::Values("wcsph", "dfsph"));

struct Case {
  const char* scene;
  const char* mode;  // "raytraced", "raytraced_paper" or "boundary_particles"
};

class SimBackends : public ::testing::TestWithParam<Case> {};

TEST_P(SimBackends, CudaMatchesCpu) {
  std::string why;
  if (!cuda_or_skip(why)) GTEST_SKIP() << why;
  SceneSpec scene;
  try {
    scene =
        load_scene(std::string(SPHFEM_SOURCE_DIR) + "/scenes/paper/" + GetParam().scene + ".json");
  } catch (const std::exception& e) { GTEST_SKIP() << e.what(); }
  scene.fluid.particle_radius *= 2;
  const std::string mode = GetParam().mode;
  scene.coupling.method =
      mode == "boundary_particles" ? CouplingMethod::BoundaryParticles : CouplingMethod::RayTraced;
  scene.coupling.near_surface_density = mode == "raytraced";
  compare(scene, run(scene, Backend::Cpu), run(scene, Backend::Cuda));
}

std::vector<Case> cases() {
  std::vector<Case> c;
  for (const char* s :
       {"cup", "cloth", "tube_hd_hk", "tube_hd_lk", "tube_ld_hk", "tube_ld_lk", "bunny"})
    c.push_back({s, "raytraced"});
  for (const char* s : {"cup", "cloth"}) {
    c.push_back({s, "raytraced_paper"});
    c.push_back({s, "boundary_particles"});
  }
  return c;
}

INSTANTIATE_TEST_SUITE_P(Paper, SimBackends, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& i) {
                           return std::string(i.param.scene) + "_" + i.param.mode;
                         });

}  // namespace
}  // namespace sphfem
