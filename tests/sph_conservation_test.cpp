// Conservation: no particle is ever lost or duplicated, so the fluid mass (count x particle
// mass) stays exactly what it was, even in a tank whose walls take hard hits; and an emitter
// adds the volume pi r^2 speed (end - start) it was asked for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sphfem/scene/compile.h"
#include "sphfem/sph/solver.h"

using namespace sphfem;

namespace {

constexpr double kPi = 3.14159265358979323846;

class SphConservation : public ::testing::TestWithParam<SolverKind> {};

// A block thrown at the far wall of a closed tank: it splashes, climbs and falls back.
TEST_P(SphConservation, MassIsExactlyConservedWithWalls) {
  SceneSpec s;
  s.simulation.solver = GetParam();
  s.fluid.particle_radius = 0.01;
  s.fluid.viscosity = 1e-6;
  s.fluid.max_speed = 2.5;  // WCSPH stiffness for the throw and the fall
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.4, 0.3, 0.12);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.16, 0.2, 0.12), Vec3d(1.5, 0, 0)});
  const FluidModel m = compile_fluid(s);
  auto sim = make_fluid_solver(m, Backend::Cpu);
  const int n0 = sim->count();
  const double mass0 = double(n0) * double(m.params.mass);
  long clamped = 0;
  while (sim->time() < 0.6) clamped += sim->step(0.6 - sim->time()).clamped;

  FluidSnapshot snap;
  sim->snapshot(snap);
  ASSERT_EQ(snap.n, n0);
  std::vector<std::uint32_t> ids(snap.id.begin(), snap.id.begin() + snap.n);
  std::sort(ids.begin(), ids.end());
  for (int i = 0; i < snap.n; ++i) ASSERT_EQ(ids[i], std::uint32_t(i)) << "particle ids";
  int outside = 0;
  for (int i = 0; i < snap.n; ++i) {
    const Vec3 x = snap.x[i];
    ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z));
    if (x.x < 0 || x.x > Real(0.4) || x.y < 0 || x.y > Real(0.3) || x.z < 0 || x.z > Real(0.12))
      ++outside;
  }
  const double mass = double(snap.n) * double(m.params.mass);
  std::printf("%d particles, mass %.6f kg -> %.6f kg, %ld clamp hits\n", n0, mass0, mass, clamped);
  EXPECT_EQ(mass, mass0);
  EXPECT_EQ(outside, 0);
}

// A nozzle pointing down into a tank: the emitted particles carry the volume of the jet.
TEST_P(SphConservation, EmitterAddsTheRequestedVolume) {
  SceneSpec s;
  s.simulation.solver = GetParam();
  s.fluid.particle_radius = 0.005;
  s.fluid.viscosity = 1e-6;
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.3, 0.4, 0.3);
  EmitterSpec e;
  e.position = Vec3d(0.15, 0.3, 0.15);
  e.direction = Vec3d(0, -1, 0);
  e.radius = 0.02;
  e.speed = 2.0;
  e.start = 0.05;
  e.end = 0.55;  // 1 m of jet: about 100 layers, so one layer more or less is 1 %
  s.fluid.emitters.push_back(e);
  s.simulation.duration = 0.6;
  const FluidModel m = compile_fluid(s);
  ASSERT_EQ(m.emitters.size(), 1u);
  auto sim = make_fluid_solver(m, Backend::Cpu);
  const int n0 = sim->count();
  long emitted = 0;
  while (sim->time() < 0.6) emitted += sim->step(0.6 - sim->time()).emitted;

  const double requested = kPi * e.radius * e.radius * e.speed * (e.end - e.start);
  const double volume = double(sim->count() - n0) * double(m.params.volume);
  const double layers = double(emitted) / double(m.emitters[0].disc.size());
  std::printf(
      "emitted %ld particles in %.0f layers of %zu: %.4g m^3 of %.4g m^3 requested "
      "(%+.2f %%)\n",
      emitted, layers, m.emitters[0].disc.size(), volume, requested,
      100 * (volume / requested - 1));
  EXPECT_EQ(long(sim->count() - n0), emitted);
  EXPECT_NEAR(volume / requested, 1.0, 0.02);
}

INSTANTIATE_TEST_SUITE_P(Solvers, SphConservation,
                         ::testing::Values(SolverKind::DFSPH, SolverKind::WCSPH),
                         [](const auto& i) {
                           return i.param == SolverKind::WCSPH ? "WCSPH" : "DFSPH";
                         });

}  // namespace
