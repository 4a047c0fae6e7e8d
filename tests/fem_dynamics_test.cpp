// Dynamics of the implicit co-rotated FEM: energy never grows and angular momentum is lost
// only at backward Euler's first-order rate; crushed and inverted bodies recover their rest
// shape; impulses change momentum by exactly their sum and bodies in one model do not
// interact; nodes sliding on the tank floor stop after the Coulomb distance v0^2 / (2 mu g).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fem/polar.h"
#include "sphfem/fem/solver.h"

using namespace sphfem;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Moments {
  double mass = 0;
  Vec3d com, momentum, angular;  // angular momentum about the centre of mass
};

Moments moments(const BodiesModel& m, const BodySnapshot& s, int first, int last) {
  Moments r;
  for (int i = first; i < last; ++i) {
    r.mass += m.mass[i];
    r.com += Vec3d(s.x[i]) * double(m.mass[i]);
    r.momentum += Vec3d(s.v[i]) * double(m.mass[i]);
  }
  r.com = r.com / r.mass;
  for (int i = first; i < last; ++i)
    r.angular += cross(Vec3d(s.x[i]) - r.com, Vec3d(s.v[i]) * double(m.mass[i]));
  return r;
}

struct SpinResult {
  double energy_rise = -1;  // largest step-to-step rise of kinetic + elastic energy / E0
  double kinetic_max = 0;   // max over time of K / K0
  double l_loss = 0;        // (|L0| - |L|) / |L0| at the end
  double l_turn = 0;        // angle between L and L0 at the end, rad
};

// Box 0.3 x 0.2 x 0.1 m spun about a skew (non-principal) axis at |omega| = pi rad/s for
// 2 s, undamped, no gravity: torque-free precession with constant L.
SpinResult spin(double dt) {
  const TetMesh mesh = make_box(Vec3d(-0.15, -0.1, -0.05), Vec3d(0.15, 0.1, 0.05), 6, 4, 2);
  Material mat;
  mat.young = 1e5, mat.poisson = 0.3;
  FemSettings set;
  set.gravity = Vec3d();
  set.cg_tolerance = 1e-5;
  const BodiesModel model = compile_bodies({compile_body(mesh, mat)}, set);
  auto solver = make_body_solver(model, Backend::Cpu);
  const Vec3d w = Vec3d(1, 2, 3) * (kPi / norm(Vec3d(1, 2, 3)));
  std::vector<Vec3> v(mesh.x.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = Vec3(cross(w, mesh.x[i]));
  solver->set_velocities(v);
  BodySnapshot s;
  solver->snapshot(s);
  const Vec3d L0 = moments(model, s, 0, s.n).angular;
  const double K0 = solver->kinetic_energy(), E0 = K0 + solver->elastic_energy();
  SpinResult r;
  double last = E0;
  for (int k = 0; k < int(std::lround(2.0 / dt)); ++k) {
    solver->step(dt);
    const double K = solver->kinetic_energy(), E = K + solver->elastic_energy();
    r.energy_rise = std::max(r.energy_rise, (E - last) / E0);
    r.kinetic_max = std::max(r.kinetic_max, K / K0);
    last = E;
  }
  solver->snapshot(s);
  const Moments m = moments(model, s, 0, s.n);
  EXPECT_LT(norm(m.momentum), 1e-6 * m.mass);
  r.l_loss = (norm(L0) - norm(m.angular)) / norm(L0);
  r.l_turn = std::acos(std::min(1.0, dot(L0, m.angular) / (norm(L0) * norm(m.angular))));
  return r;
}

// Largest node distance from the rest shape after the best rigid fit (Kabsch: the polar
// rotation of the covariance), and the volume and smallest element volume, relative to rest.
struct ShapeError {
  double deviation, volume, min_element;
};

ShapeError shape_error(const TetMesh& rest, const BodySnapshot& s) {
  Vec3d c, C;
  for (int i = 0; i < s.n; ++i) c += Vec3d(s.x[i]), C += rest.x[i];
  c = c / double(s.n), C = C / double(s.n);
  Mat3d A = Mat3d::zero();
  for (int i = 0; i < s.n; ++i) {
    const Vec3d p = Vec3d(s.x[i]) - c, q = rest.x[i] - C;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) A.m[a][b] += p[a] * q[b];
  }
  const Mat3d R = fem::extract_rotation_fresh(A, Q4<double>::identity(), 100).matrix();
  TetMesh cur = rest;
  ShapeError e{0, 0, 1e30};
  for (int i = 0; i < s.n; ++i) {
    cur.x[i] = Vec3d(s.x[i]);
    e.deviation = std::max(e.deviation, norm(cur.x[i] - c - R * (rest.x[i] - C)));
  }
  e.volume = mesh_volume(cur) / mesh_volume(rest);
  for (std::size_t t = 0; t < rest.tets.size(); ++t)
    e.min_element = std::min(e.min_element, tet_volume(cur, int(t)) / tet_volume(rest, int(t)));
  return e;
}

// Sphere R = 0.1 m (1296 tets), E = 1e5 Pa, nu = 0.3, mass damping alpha = 2/s, no gravity,
// released from a pose made by `pose` and stepped for 1 s at dt = 5 ms.
template <class Pose>
ShapeError recover(Pose pose) {
  const TetMesh mesh = make_sphere(Vec3d(0, 0.5, 0), 0.1, 6);
  Material mat;
  mat.young = 1e5, mat.poisson = 0.3, mat.alpha = 2.0;
  FemSettings set;
  set.gravity = Vec3d();
  auto solver = make_body_solver(compile_bodies({compile_body(mesh, mat)}, set), Backend::Cpu);
  std::vector<Vec3> x(mesh.x.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3(pose(mesh.x[i]));
  solver->set_positions(x);
  BodySnapshot s;
  solver->snapshot(s);
  EXPECT_LT(shape_error(mesh, s).min_element, 1e-6);  // really crushed or inverted
  for (int k = 0; k < 200; ++k) solver->step(0.005);
  solver->snapshot(s);
  return shape_error(mesh, s);
}

}  // namespace

TEST(FemDynamics, SpinningBodyLosesEnergyAndMomentumOnlyAtBackwardEulerRate) {
  // Backward Euler with torque-free forces f+ at the new positions changes L by
  // -dt^2 sum v+ x f+ per step; for rotation at omega that is about (omega dt)^2 L, so over
  // a time T it removes at most about T omega^2 dt of L (3.9 % for dt = 2 ms), and half as
  // much for half the step. It must never add energy.
  const SpinResult a = spin(0.002), b = spin(0.001);
  std::printf(
      "[ measured ] spin: L loss %.2f %% (dt 2 ms), %.2f %% (dt 1 ms); L turned %.2g rad;"
      " largest energy rise per step %.2g E0; max K/K0 %.6f\n",
      100 * a.l_loss, 100 * b.l_loss, a.l_turn, a.energy_rise, a.kinetic_max);
  for (const SpinResult& r : {a, b}) {
    EXPECT_LE(r.energy_rise, 1e-6);
    EXPECT_LE(r.kinetic_max, 1.0 + 1e-6);
    EXPECT_GT(r.l_loss, 0.0);
    EXPECT_LT(r.l_turn, 0.01);
  }
  EXPECT_LT(a.l_loss, 2.0 * kPi * kPi * 0.002);
  EXPECT_LT(b.l_loss, 2.0 * kPi * kPi * 0.001);
  EXPECT_NEAR(b.l_loss / a.l_loss, 0.5, 0.1);  // first order in dt: vanishes with the step
}

TEST(FemDynamics, CrushedBodyRecoversRestShape) {
  // Every node flattened onto the plane y = 0.5: all 1296 elements have zero volume.
  const ShapeError e = recover([](Vec3d x) { return Vec3d(x.x, 0.5, x.z); });
  std::printf(
      "[ measured ] crushed sphere after 1 s: volume %.5f of rest, smallest element"
      " %.4f, largest deviation from rigid fit %.3g m\n",
      e.volume, e.min_element, e.deviation);
  EXPECT_NEAR(e.volume, 1.0, 0.01);
  EXPECT_GT(e.min_element, 0.9);
  EXPECT_LT(e.deviation, 0.01 * 0.1);
}

TEST(FemDynamics, InvertedBodyRecoversRestShape) {
  // Mirrored through the plane y = 0.5: every element inside out (volume -V).
  const ShapeError e = recover([](Vec3d x) { return Vec3d(x.x, 1.0 - x.y, x.z); });
  std::printf(
      "[ measured ] inverted sphere after 1 s: volume %.5f of rest, smallest element"
      " %.4f, largest deviation from rigid fit %.3g m\n",
      e.volume, e.min_element, e.deviation);
  EXPECT_NEAR(e.volume, 1.0, 0.01);
  EXPECT_GT(e.min_element, 0.9);
  EXPECT_LT(e.deviation, 0.01 * 0.1);
}

TEST(FemDynamics, NewtonCorrectionsSolveTheNonlinearBackwardEulerStep) {
  // One large step (dt = 20 ms, stiff regime) of a stretched, twisted box released at rest,
  // no gravity or damping. Backward Euler asks M (v+ - v) = dt f(x + dt v+); the linearly
  // implicit step leaves a residual from linearising the rotations, Newton corrections
  // shrink it.
  const TetMesh mesh = make_box(Vec3d(-0.1, -0.05, -0.05), Vec3d(0.1, 0.05, 0.05), 6, 3, 3);
  Material mat;
  mat.young = 1e5, mat.poisson = 0.3;
  std::vector<Vec3> x0(mesh.x.size());
  for (std::size_t i = 0; i < x0.size(); ++i) {
    const Vec3d X = mesh.x[i];
    const double t = 4.0 * X.x;  // twist up to 0.4 rad about x
    x0[i] = Vec3(Vec3d(1.3 * X.x, std::cos(t) * X.y - std::sin(t) * X.z,
                       std::sin(t) * X.y + std::cos(t) * X.z));
  }
  const double dt = 0.02;
  auto residual = [&](int newton) {
    FemSettings set;
    set.gravity = Vec3d();
    set.cg_tolerance = 1e-5;
    set.cg_max_iterations = 1000;
    set.newton_iterations = newton;
    const BodiesModel model = compile_bodies({compile_body(mesh, mat)}, set);
    auto solver = make_body_solver(model, Backend::Cpu);
    solver->set_positions(x0);
    solver->step(dt);
    BodySnapshot s;
    solver->snapshot(s);
    std::vector<Vec3> f;
    solver->elastic_forces(f);
    double r = 0, scale = 0;
    for (int i = 0; i < s.n; ++i) {
      r += norm2(Vec3d(s.v[i]) * double(model.mass[i]) - Vec3d(f[i]) * dt);
      scale += norm2(Vec3d(s.v[i]) * double(model.mass[i]));
    }
    return std::sqrt(r / scale);
  };
  const double r1 = residual(1), r4 = residual(4);
  std::printf("[ measured ] backward Euler residual after one step: %.3g (1 solve), %.3g (4)\n", r1,
              r4);
  EXPECT_LT(r4, 0.3 * r1);
}

TEST(FemDynamics, ImpulsesChangeMomentumByTheirSumAndBodiesStayApart) {
  // Two bodies in one model, no gravity. Impulses on the ball's nodes: its momentum changes
  // by their sum (internal forces cancel up to the CG residual), and the box, which shares
  // the arrays and kernels but no element, keeps still: its nodes move only by the residual
  // stress of the rest shape rounded to single precision (strains ~1e-7).
  Material mat;
  mat.young = 1e5, mat.poisson = 0.3;
  FemSettings set;
  set.gravity = Vec3d();
  set.cg_tolerance = 1e-6;
  const BodiesModel model = compile_bodies(
      {compile_body(make_sphere(Vec3d(0, 0, 0), 0.1, 4), mat, {}, "ball"),
       compile_body(make_box(Vec3d(0.3, 0, 0), Vec3d(0.5, 0.1, 0.1), 4, 2, 2), mat, {}, "box")},
      set);
  auto solver = make_body_solver(model, Backend::Cpu);
  const int ball_end = model.node_offset[1];
  std::vector<Vec3> J(model.nodes);
  Vec3d total;
  for (int i = 0; i < ball_end; ++i) {
    J[i] = Vec3(Real(0.01 * std::sin(i)), Real(0.02 * std::cos(3 * i)), Real(0.005));
    total += Vec3d(J[i]);
  }
  solver->add_node_impulses(J);
  BodySnapshot s;
  for (int k = 0; k < 50; ++k) {
    solver->step(0.005);
    solver->snapshot(s);
    const Moments ball = moments(model, s, 0, ball_end);
    EXPECT_LT(norm(ball.momentum - total), 1e-4 * norm(total)) << k;
  }
  double ball_speed = 0, box_speed = 0, box_shift = 0;
  for (int i = 0; i < ball_end; ++i) ball_speed = std::max(ball_speed, double(norm(s.v[i])));
  for (int i = ball_end; i < model.nodes; ++i) {
    box_speed = std::max(box_speed, double(norm(s.v[i])));
    box_shift = std::max(box_shift, double(norm(s.x[i] - model.x0[i])));
  }
  EXPECT_GT(ball_speed, 0.05);
  EXPECT_LT(box_speed, 1e-4 * ball_speed);
  EXPECT_LT(box_shift, 1e-6);
}

TEST(FemDynamics, BlockSlidingOnTankFloorStopsAtCoulombDistance) {
  // A 0.1 m cube (E = 1e6 Pa) resting on the tank floor, launched at v0 = 1 m/s with
  // mu = 0.3: the floor removes the normal velocity gravity adds each step, and friction
  // mu times that from the tangential velocity, so the block stops after v0^2 / (2 mu g).
  const double mu = 0.3, v0 = 1.0, g = 9.81;
  const TetMesh mesh = make_box(Vec3d(-0.05, 0, -0.05), Vec3d(0.05, 0.1, 0.05), 4, 4, 4);
  Material mat;
  mat.young = 1e6, mat.poisson = 0.3;
  FemSettings set;
  set.gravity = Vec3d(0, -g, 0);
  set.box = true, set.box_lo = Vec3d(-1, 0, -1), set.box_hi = Vec3d(1, 1, 1);
  set.friction = mu;
  BodyModel body = compile_body(mesh, mat);
  body.velocity = Vec3d(v0, 0, 0);
  const BodiesModel model = compile_bodies({body}, set);
  auto solver = make_body_solver(model, Backend::Cpu);
  BodySnapshot s;
  for (int k = 0; k < 400; ++k) solver->step(0.002);
  solver->snapshot(s);
  const Moments m = moments(model, s, 0, s.n);
  const double exact = v0 * v0 / (2 * mu * g);
  double ymin = 1;
  for (const Vec3& x : s.x) ymin = std::min(ymin, double(x.y));
  std::printf("[ measured ] sliding block: distance %.4f m, v0^2/(2 mu g) %.4f m\n", m.com.x,
              exact);
  EXPECT_NEAR(m.com.x, exact, 0.02 * exact);
  EXPECT_LT(norm(m.momentum) / m.mass, 1e-3);  // at rest
  EXPECT_GE(ymin, 0.0);
  EXPECT_NEAR(m.com.y, 0.05, 0.001);  // resting on the floor, squeezed only by its weight
}
