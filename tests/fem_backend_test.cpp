// The CUDA backend runs the same stages as the CPU: after steps of a spinning, damped ball
// falling in the tank (clear of the walls, where per-node contact is discontinuous),
// positions and velocities agree to single-precision round-off amplified by the solves (the
// CG's dot products sum in a different order). Skips without a usable GPU.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "sphfem/fem/solver.h"

using namespace sphfem;

TEST(FemBackend, CudaMatchesCpu) {
  std::string why;
  if (!cuda_available(&why)) GTEST_SKIP() << why;
  Material mat;
  mat.young = 1e5, mat.poisson = 0.3, mat.alpha = 0.5, mat.beta = 1e-3;
  FemSettings set;
  set.box = true, set.box_lo = Vec3d(0, 0, 0), set.box_hi = Vec3d(1, 1, 1);
  set.cg_tolerance = 1e-6;
  set.cg_max_iterations = 500;
  const TetMesh ball = make_sphere(Vec3d(0.5, 0.5, 0.5), 0.1, 6);
  const BodiesModel model = compile_bodies({compile_body(ball, mat)}, set);
  auto cpu = make_body_solver(model, Backend::Cpu);
  auto gpu = make_body_solver(model, Backend::Cuda);
  std::vector<Vec3> v(ball.x.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = Vec3(cross(Vec3d(3, 1, -2), ball.x[i] - Vec3d(0.5, 0.5, 0.5)));
  cpu->set_velocities(v);
  gpu->set_velocities(v);
  for (int k = 0; k < 40; ++k) {
    cpu->step(0.002);
    gpu->step(0.002);
  }
  BodySnapshot a, b;
  cpu->snapshot(a);
  gpu->snapshot(b);
  double dx = 0, dv = 0, vmax = 0;
  for (int i = 0; i < a.n; ++i) {
    dx = std::max(dx, double(norm(a.x[i] - b.x[i])));
    dv = std::max(dv, double(norm(a.v[i] - b.v[i])));
    vmax = std::max(vmax, double(norm(a.v[i])));
  }
  EXPECT_LT(dx, 1e-5);  // m, on a 0.2 m ball
  EXPECT_LT(dv, 1e-3 * vmax);
  EXPECT_NEAR(cpu->kinetic_energy(), gpu->kinetic_energy(), 1e-3 * cpu->kinetic_energy());
  EXPECT_NEAR(cpu->elastic_energy(), gpu->elastic_energy(), 1e-3 * cpu->elastic_energy());
}
