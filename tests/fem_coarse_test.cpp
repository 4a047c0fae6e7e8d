// The CG's coarse level (fem.preconditioner two_level) changes how the step's system is
// solved, not its answer: a stiff rubber beam (E = 10 MPa) swinging down under gravity from
// its pinned end, and a stiff ball settling on the tank's floor (nodes held by the
// walls: the filtered CG), end where block Jacobi puts them, to the solve's tolerance (here
// 1e-6), in fewer iterations: a third on the beam, 0.56 on the ball (the speed-up at the
// default tolerance is in bench/results/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/fem/solver.h"

namespace sphfem {
namespace {

struct Solved {
  std::vector<Vec3> x;
  long iterations = 0;
  double energy = 0;
};

Solved run(const TetMesh& mesh, const std::vector<std::uint8_t>& pins, const FemSettings& base,
           bool two_level, const Vec3d& spin_about, int steps) {
  Material mat;
  mat.density = 1100, mat.young = 1e7, mat.poisson = 0.4, mat.beta = 1e-4;
  FemSettings set = base;
  set.two_level = two_level;
  set.cg_tolerance = 1e-6;
  set.cg_max_iterations = 2000;
  auto solver =
      make_body_solver(compile_bodies({compile_body(mesh, mat, pins)}, set), Backend::Cpu);
  if (spin_about.x != 0 || spin_about.y != 0 || spin_about.z != 0) {
    std::vector<Vec3> v(mesh.x.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      v[i] = Vec3(cross(Vec3d(0, 20, 0), mesh.x[i] - spin_about) + Vec3d(0, -1, 0));
    solver->set_velocities(v);
  }
  Solved r;
  for (int k = 0; k < steps; ++k) r.iterations += solver->step(5e-4).cg_iterations;
  BodySnapshot b;
  solver->snapshot(b);
  r.x = b.x;
  r.energy = solver->kinetic_energy() + solver->elastic_energy();
  return r;
}

void compare(const char* what, const Solved& jacobi, const Solved& two,
             const std::vector<Vec3d>& x0) {
  double moved = 0, apart = 0;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    moved = std::max(moved, double(norm(Vec3d(jacobi.x[i]) - x0[i])));
    apart = std::max(apart, double(norm(jacobi.x[i] - two.x[i])));
  }
  std::printf(
      "[ measured ] %s: CG iterations %ld (block Jacobi) against %ld (two-level); nodes moved up "
      "to %.3g m, the two apart by %.2g m; energy %.6g against %.6g J\n",
      what, jacobi.iterations, two.iterations, moved, apart, jacobi.energy, two.energy);
  EXPECT_GT(moved, 1e-3);
  EXPECT_LT(apart, 1e-3 * moved);
  EXPECT_NEAR(two.energy, jacobi.energy, 1e-3 * jacobi.energy);
  EXPECT_LT(double(two.iterations), 0.7 * double(jacobi.iterations));
}

TEST(FemCoarse, StiffBeamSwingsAsBlockJacobiSwingsIt) {
  const TetMesh beam = make_box(Vec3d(0, 0, 0), Vec3d(0.6, 0.04, 0.04), 60, 4, 4);
  std::vector<std::uint8_t> pins(beam.x.size(), 0);
  for (std::size_t i = 0; i < pins.size(); ++i) pins[i] = beam.x[i].x < 1e-9;
  FemSettings set;
  const Solved jacobi = run(beam, pins, set, false, Vec3d(), 40);
  const Solved two = run(beam, pins, set, true, Vec3d(), 40);
  compare("beam", jacobi, two, beam.x);
}

// The same bits on one thread and two: the factor is serial, the CG's sums are the solver's.
TEST(FemCoarse, SameBitsOnOneAndTwoThreads) {
  const TetMesh beam = make_box(Vec3d(0, 0, 0), Vec3d(0.6, 0.04, 0.04), 60, 4, 4);
  std::vector<std::uint8_t> pins(beam.x.size(), 0);
  for (std::size_t i = 0; i < pins.size(); ++i) pins[i] = beam.x[i].x < 1e-9;
  set_cpu_threads(1);
  const Solved one = run(beam, pins, FemSettings(), true, Vec3d(), 20);
  set_cpu_threads(2);
  const Solved two = run(beam, pins, FemSettings(), true, Vec3d(), 20);
  set_cpu_threads(0);
  ASSERT_EQ(one.x.size(), two.x.size());
  for (std::size_t i = 0; i < one.x.size(); ++i) {
    ASSERT_EQ(one.x[i].x, two.x[i].x) << "node " << i;
    ASSERT_EQ(one.x[i].y, two.x[i].y) << "node " << i;
    ASSERT_EQ(one.x[i].z, two.x[i].z) << "node " << i;
  }
  EXPECT_EQ(one.iterations, two.iterations);
}

TEST(FemCoarse, StiffBallSettlingOnTheFloorAsBlockJacobi) {
  const TetMesh ball = make_sphere(Vec3d(0.5, 0.0805, 0.5), 0.08, 16);
  FemSettings set;
  set.box = true, set.box_lo = Vec3d(0, 0, 0), set.box_hi = Vec3d(1, 1, 1);
  const Solved jacobi = run(ball, {}, set, false, Vec3d(), 40);
  const Solved two = run(ball, {}, set, true, Vec3d(), 40);
  compare("ball on the floor", jacobi, two, ball.x);
}

}  // namespace
}  // namespace sphfem
