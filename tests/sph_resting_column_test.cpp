// A column of nearly inviscid water at rest in a closed box must come to rest: its kinetic
// energy decays and its centre of mass stops. A solver whose warm start follows its own
// corrections too fast feeds the column's lowest compression mode (an integral controller on
// a mass): the column then breathes at ~30 Hz without end (docs/validation.md, "Soak").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sphfem/scene/compile.h"
#include "sphfem/sph/solver.h"

using namespace sphfem;

namespace {

SceneSpec column() {
  SceneSpec s;
  s.simulation.solver = SolverKind::DFSPH;
  s.simulation.dt_max = 2e-3;
  s.fluid.particle_radius = 0.004;
  s.fluid.viscosity = 1e-5;  // too weak to damp the mode within the test: the solver must
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.096, 0.4, 0.096);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.096, 0.272, 0.096), Vec3d()});
  return s;
}

struct Window {
  double kinetic = 0;  // mean kinetic energy, J
  double rise = 0;     // largest |vertical momentum| / mass, m/s
  int samples = 0;
};

TEST(SphRestingColumn, ComesToRest) {
  const FluidModel m = compile_fluid(column());
  auto sim = make_fluid_solver(m, Backend::Cpu);
  const double mass = double(m.params.mass) * sim->count();
  // Two windows after the column has settled onto the floor: 1.5-2 s and 2.5-3 s.
  Window early, late;
  while (sim->time() < 3.0 - 1e-9) {
    sim->step(3.0 - sim->time());
    const double t = sim->time();
    Window* w = t >= 1.5 && t < 2.0 ? &early : t >= 2.5 ? &late : nullptr;
    if (!w) continue;
    const FluidArrays a = sim->arrays();
    double ke = 0, py = 0;
    for (int i = 0; i < a.n; ++i) {
      ke += 0.5 * double(a.mass) * double(norm2(a.v[i]));
      py += double(a.mass) * double(a.v[i].y);
    }
    w->kinetic += ke;
    w->rise = std::max(w->rise, std::abs(py) / mass);
    ++w->samples;
  }
  ASSERT_GT(early.samples, 0);
  ASSERT_GT(late.samples, 0);
  early.kinetic /= early.samples;
  late.kinetic /= late.samples;
  std::printf(
      "%d particles; kinetic energy %.3g J (1.5-2 s), %.3g J (2.5-3 s); centre of mass "
      "speed up to %.3g mm/s (1.5-2 s), %.3g mm/s (2.5-3 s)\n",
      sim->count(), early.kinetic, late.kinetic, early.rise * 1e3, late.rise * 1e3);
  EXPECT_LT(late.kinetic, 0.5 * early.kinetic) << "the column keeps moving: no decay";
  // 1 mm/s: a tenth of the breathing's 14 mm/s; settling of the lattice moves the centre of
  // mass by far less.
  EXPECT_LT(late.rise, 1e-3) << "the column's centre of mass still moves";
}

}  // namespace
