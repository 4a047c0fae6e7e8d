// Hydrostatic tank: after settling, pressure follows rho g (H - y), density stays within 1 %
// of rest, and the walls alone (not the last-resort clamp) keep every particle in the tank.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "sph_profile.h"
#include "sphfem/scene/compile.h"
#include "sphfem/sph/solver.h"

using namespace sphfem;

namespace {

SceneSpec tank(SolverKind solver) {
  SceneSpec s;
  s.simulation.solver = solver;
  s.simulation.dt_max = 2e-3;
  s.fluid.particle_radius = 0.01;
  s.fluid.viscosity = 1e-3;  // damps sloshing so the tank settles within the test time
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.2, 0.6, 0.2);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.2, 0.4, 0.2), Vec3d()});
  return s;
}

struct Result {
  double l2_pressure_error, max_compression, height;
  int clamped, outside;
};

Result settle(SolverKind solver, double seconds) {
  const SceneSpec s = tank(solver);
  const FluidModel m = compile_fluid(s);
  auto sim = make_fluid_solver(m, Backend::Cpu);
  Result r{};
  while (sim->time() < seconds) r.clamped += sim->step(seconds - sim->time()).clamped;
  // Average the last 0.1 s of snapshots to tame SPH pressure noise. A vertical line through
  // the middle of the tank, one particle spacing wide.
  test::PressureProfile profile(20, 0.4, 0.1, 0.1, 0.02);
  FluidSnapshot snap;
  for (double t_end = sim->time() + 0.1; sim->time() < t_end - 1e-9;) {
    r.clamped += sim->step(t_end - sim->time()).clamped;
    if (sim->steps() % 10) continue;
    sim->snapshot(snap);
    profile.add(snap);
    for (int i = 0; i < snap.n; ++i) {
      const Vec3 x = snap.x[i];
      r.max_compression = std::max(r.max_compression, double(snap.rho[i]) / 1000.0 - 1.0);
      if (x.x < 0 || x.x > 0.2 || x.y < 0 || x.y > 0.6 || x.z < 0 || x.z > 0.2) ++r.outside;
    }
  }
  // Free surface: the top particle centres plus half a spacing.
  r.height = profile.surface(0.01);
  r.l2_pressure_error = profile.against(r.height).l2;
  return r;
}

class SphHydrostatic : public ::testing::TestWithParam<SolverKind> {};

TEST_P(SphHydrostatic, PressureFollowsDepthAndNothingLeaves) {
  const Result r = settle(GetParam(), 1.5);
  std::printf("pressure L2 error %.4f, max compression %.4f, surface %.4f m, clamped %d\n",
              r.l2_pressure_error, r.max_compression, r.height, r.clamped);
  EXPECT_LT(r.l2_pressure_error, 0.03);
  EXPECT_LT(r.max_compression, 0.01);
  EXPECT_EQ(r.outside, 0);
  EXPECT_EQ(r.clamped, 0) << "the wall samples let particles reach the last-resort clamp";
}

INSTANTIATE_TEST_SUITE_P(Solvers, SphHydrostatic,
                         ::testing::Values(SolverKind::WCSPH, SolverKind::DFSPH),
                         [](const auto& i) {
                           return i.param == SolverKind::WCSPH ? "WCSPH" : "DFSPH";
                         });

}  // namespace
