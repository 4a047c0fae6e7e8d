// Penetration handling (paper eq. 6 with a skin) through the real fluid step: a StepHook casts
// one ray per particle against a wall of two triangles (brute force, double precision), the
// coupler's travel fractions limit the drift and its impulses act after it. No particle may
// cross the wall, and one whose ray hit ends at least the skin before the wall along its ray.
// Also: a hook that limits nothing leaves the step bit for bit as it was without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <vector>

#include "couple_harness.h"
#include "sphfem/couple/coupler.h"
#include "sphfem/scene/compile.h"
#include "sphfem/sph/solver.h"

using namespace sphfem;
using testing_couple::from_space;
using testing_couple::to_space;

namespace {

// Möller-Trumbore in double: distance along the unit direction d to triangle (a, b, c), with
// barycentrics; inclusive edges so a ray through the shared diagonal finds one of the two.
bool ray_triangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                  double& t, double& u, double& v) {
  const Vec3d e1 = b - a, e2 = c - a, p = cross(d, e2);
  const double det = dot(e1, p);
  if (std::fabs(det) < 1e-300) return false;
  const Vec3d s = o - a, q = cross(s, e1);
  u = dot(s, p) / det;
  v = dot(d, q) / det;
  t = dot(e2, q) / det;
  return u >= 0 && v >= 0 && u + v <= 1 && t >= 0;
}

// A wall x = const across the whole domain, facing -x, moving along x at a fixed speed: the
// stand-in for a body step, a BVH and its ray caster.
class WallHook : public StepHook {
 public:
  WallHook(Coupler& c, MemSpace s, double x0, double speed, Real skin_fraction)
      : coupler_(c), space_(s), x_(x0), speed_(speed), skin_fraction_(skin_fraction) {
    tris_ = {Tri{{0, 1, 2}}, Tri{{0, 2, 3}}};
    mass_.assign(4, Real(1e6));
    vel_.assign(4, Vec3(Real(speed), 0, 0));
    btri_ = to_space(s, tris_);
    bmass_ = to_space(s, mass_);
    bvel_ = to_space(s, vel_);
    bimp_ = to_space(s, std::vector<Vec3>(4));
    set_nodes(x0);
  }

  DriftLimits before_drift(const FluidArrays& f, double dt) override {
    skin_ = skin_fraction_ * f.radius;
    const double start = x_;
    x_ += speed_ * dt;  // the "body step" over the same dt
    const std::vector<Vec3d> corners = wall_corners(start);
    xs_.resize(f.n);
    vs_.resize(f.n);
    mem_copy(MemSpace::Host, xs_.data(), f.space, f.x, sizeof(Vec3) * f.n);
    mem_copy(MemSpace::Host, vs_.data(), f.space, f.v, sizeof(Vec3) * f.n);
    face_.assign(f.n, -1);
    t_.assign(f.n, 0), u_.assign(f.n, 0), v_.assign(f.n, 0);
    dir_.assign(f.n, Vec3d());
    // Rays from the particles along their velocity relative to the wall, against the wall at
    // the start of the step, as long as the relative displacement plus the skin.
    const Vec3d vw(speed_, 0, 0);
    for (int i = 0; i < f.n; ++i) {
      const Vec3d rel = Vec3d(vs_[i]) - vw;
      const double len = norm(rel) * dt;
      if (!(len > 0)) continue;
      const Vec3d d = rel / norm(rel);
      dir_[i] = d;
      double best = len + double(skin_);
      for (int k = 0; k < 2; ++k) {
        double t, u, v;
        const Tri tr = tris_[k];
        if (ray_triangle(Vec3d(xs_[i]), d, corners[tr.v[0]], corners[tr.v[1]], corners[tr.v[2]], t,
                         u, v) &&
            t <= best) {
          best = t;
          face_[i] = k, t_[i] = Real(t), u_[i] = Real(u), v_[i] = Real(v);
        }
      }
    }
    set_nodes(x_);  // the wall at the end of the step, as a body solver leaves it
    bface_ = to_space(space_, face_);
    bt_ = to_space(space_, t_);
    bu_ = to_space(space_, u_);
    bv_ = to_space(space_, v_);
    return coupler_.travel(hits(), f, {surface()}, skin_, dt);
  }

  // As the coupling's contact_fix and exchange stages do (couple/ray_coupling.h): a particle
  // that hit ends at least a skin in front of the plane, then the momentum exchange.
  void after_drift(const FluidArrays& f, double) override {
    coupler_.push_out(hits(), f, {surface()}, skin_);
    const CoupleStats st = coupler_.apply(hits(), f, {surface()});
    contacts_ += st.contacts;
    mem_copy(MemSpace::Host, xs_.data(), f.space, f.x, sizeof(Vec3) * f.n);
    for (int i = 0; i < f.n; ++i) {
      const double gap = x_ - double(xs_[i].x);  // in front of the wall: gap > 0
      min_gap_ = std::min(min_gap_, gap);
      if (face_[i] < 0) continue;
      // Along its ray, a particle that hit stops the skin short of the wall (eq. 6); one that
      // started inside the skin layer stays where it was. Measured across the wall: along a
      // grazing ray the float round-off of a position would be magnified by 1 / cosine.
      const double cosine = std::fabs(dir_[i].x);
      const double keep = std::min(double(t_[i]), double(skin_)) * cosine;
      max_deficit_ = std::max(max_deficit_, keep - gap);
      min_clearance_ = std::min(min_clearance_, gap / cosine);
    }
  }

  double min_gap_ = 1e30, min_clearance_ = 1e30, max_deficit_ = -1e30;
  long contacts_ = 0;
  Real skin_ = 0;

 private:
  std::vector<Vec3d> wall_corners(double x) const {
    return {Vec3d(x, -0.1, -0.1), Vec3d(x, -0.1, 0.2), Vec3d(x, 0.4, 0.2), Vec3d(x, 0.4, -0.1)};
  }
  void set_nodes(double x) {
    std::vector<Vec3> c;
    for (const Vec3d& p : wall_corners(x)) c.push_back(Vec3(p));
    bx_ = to_space(space_, c);
  }
  HitArrays hits() { return HitArrays{space_, bface_.data(), bt_.data(), bu_.data(), bv_.data()}; }
  CoupleSurface surface() {
    CoupleSurface s;
    s.space = space_;
    s.nodes = 4, s.triangles = 2;
    s.tri = btri_.data(), s.x = bx_.data(), s.v = bvel_.data(), s.mass = bmass_.data();
    s.impulse = bimp_.data();
    s.coeffs = {ContactCoeffs()};  // inelastic, free slip
    return s;
  }

  Coupler& coupler_;
  MemSpace space_;
  double x_, speed_;
  Real skin_fraction_;
  std::vector<Tri> tris_;
  std::vector<Real> mass_;
  std::vector<Vec3> vel_;
  Buffer<Tri> btri_;
  Buffer<Real> bmass_;
  Buffer<Vec3> bvel_, bimp_, bx_;
  std::vector<Vec3> xs_, vs_;
  std::vector<Vec3d> dir_;
  std::vector<int> face_;
  std::vector<Real> t_, u_, v_;
  Buffer<int> bface_;
  Buffer<Real> bt_, bu_, bv_;
};

// A block thrown at +x toward the wall.
SceneSpec thrown_block(SolverKind solver) {
  SceneSpec s;
  s.simulation.solver = solver;
  s.fluid.particle_radius = 0.005;
  s.fluid.viscosity = 1e-6;
  s.fluid.max_speed = 2.5;
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.3, 0.2, 0.05);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.08, 0.06, 0.05), Vec3d(1.5, 0, 0)});
  return s;
}

using Case = std::tuple<Backend, SolverKind, double>;  // backend, solver, wall speed

class CouplePenetration : public ::testing::TestWithParam<Case> {};

TEST_P(CouplePenetration, NoParticleCrossesAMovingOrStaticWall) {
  const auto [backend, solver, speed] = GetParam();
  const std::string why = testing_couple::unusable(backend);
  if (!why.empty()) GTEST_SKIP() << why;
  const FluidModel m = compile_fluid(thrown_block(solver));
  auto sim = make_fluid_solver(m, backend);
  auto coupler = make_coupler(backend);
  // A static wall at x = 0.15, or one starting at 0.25 and moving toward the fluid.
  WallHook hook(*coupler, testing_couple::space_of(backend), speed == 0 ? 0.15 : 0.25, speed,
                Real(0.25));
  sim->set_hook(&hook);
  while (sim->time() < 0.15) sim->step(0.15 - sim->time());
  const double skin = double(hook.skin_);
  std::printf(
      "%ld steps, %ld contacts, min gap %.3g m, min clearance along the ray %.4g m "
      "(skin %.4g m), largest shortfall across the wall %.3g m\n",
      sim->steps(), hook.contacts_, hook.min_gap_, hook.min_clearance_, skin, hook.max_deficit_);
  // The block did pile up against the wall. (Each contact now ends exactly at rest against
  // the wall, so a resting particle is not hit again and again: 600-1,000 contacts.)
  EXPECT_GT(hook.contacts_, 500);
  EXPECT_GT(hook.min_gap_, 0.0);
  // Float positions near 0.2 m carry ~1e-8 m of round-off per operation; 1e-6 m is 1/1000 of
  // the skin.
  EXPECT_LE(hook.max_deficit_, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(All, CouplePenetration,
                         ::testing::Combine(::testing::Values(Backend::Cpu, Backend::Cuda),
                                            ::testing::Values(SolverKind::WCSPH, SolverKind::DFSPH),
                                            ::testing::Values(0.0, -0.5)),
                         [](const ::testing::TestParamInfo<Case>& i) {
                           return std::string(std::get<0>(i.param) == Backend::Cuda ? "Cuda"
                                                                                    : "Cpu") +
                                  (std::get<1>(i.param) == SolverKind::WCSPH ? "Wcsph" : "Dfsph") +
                                  (std::get<2>(i.param) == 0 ? "Static" : "Moving");
                         });

// Eq. 6 in numbers, head on: the particle ends exactly the skin before the wall, which has
// moved on by its own displacement.
TEST(CoupleTravel, HeadOnStopsTheSkinShort) {
  for (double speed : {0.0, -1.0}) {
    auto coupler = make_coupler(Backend::Cpu);
    const Real skin = Real(0.0025);
    const double dt = 0.03, wall = 0.2, xp = 0.15;
    std::vector<Vec3> x = {Vec3(Real(xp), 0.1f, 0.05f)}, v = {Vec3(2.0f, 0, 0)};
    std::vector<Vec3> nodes = {Vec3(Real(wall), -1, -1), Vec3(Real(wall), -1, 1),
                               Vec3(Real(wall), 1, 1)};
    std::vector<Vec3> nv(3, Vec3(Real(speed), 0, 0)), imp(3);
    std::vector<Real> nm(3, Real(1));
    std::vector<Tri> tri = {Tri{{0, 1, 2}}};
    std::vector<int> face = {0};
    const double rel = 2.0 - speed;
    std::vector<Real> t = {Real(wall - xp)}, u = {Real(0.25)}, w = {Real(0.5)};
    CoupleSurface s;
    s.nodes = 3, s.triangles = 1, s.tri = tri.data(), s.x = nodes.data(), s.v = nv.data();
    s.mass = nm.data(), s.impulse = imp.data(), s.coeffs = {ContactCoeffs()};
    HitArrays h{MemSpace::Host, face.data(), t.data(), u.data(), w.data()};
    FluidArrays f;
    f.n = 1, f.x = x.data(), f.v = v.data(), f.mass = Real(0.1), f.radius = Real(0.01);
    const DriftLimits d = coupler->travel(h, f, {s}, skin, dt);
    const double travel = (wall - xp - double(skin)) / (rel * dt);
    EXPECT_NEAR(double(d.travel[0]), travel, 1e-6);
    EXPECT_NEAR(double(d.surface_v[0].x), speed, 1e-7);
    // The drift's rule, x += dt (s + travel (v - s)), against the wall's own displacement.
    const double end = xp + dt * (speed + double(d.travel[0]) * (2.0 - speed));
    EXPECT_NEAR(wall + speed * dt - end, double(skin), 1e-6);
  }
}

// Limits that change nothing, and no limits at all, give the same bits as no hook.
class NeutralHook : public StepHook {
 public:
  explicit NeutralHook(bool arrays) : arrays_(arrays) {}
  DriftLimits before_drift(const FluidArrays& f, double) override {
    if (!arrays_) return DriftLimits();
    travel_.assign(f.n, Real(1));
    surface_v_.assign(f.n, Vec3());
    return DriftLimits{travel_.data(), surface_v_.data()};
  }
  void after_drift(const FluidArrays&, double) override { ++calls_; }
  int calls_ = 0;

 private:
  bool arrays_;
  std::vector<Real> travel_;
  std::vector<Vec3> surface_v_;
};

TEST(CoupleHook, NeutralHookLeavesTheStepUnchanged) {
  for (SolverKind solver : {SolverKind::WCSPH, SolverKind::DFSPH})
    for (bool arrays : {false, true}) {
      const FluidModel m = compile_fluid(thrown_block(solver));
      auto a = make_fluid_solver(m, Backend::Cpu);
      auto b = make_fluid_solver(m, Backend::Cpu);
      NeutralHook hook(arrays);
      b->set_hook(&hook);
      for (int k = 0; k < 40; ++k) {
        a->step(1.0);
        b->step(1.0);
      }
      EXPECT_EQ(hook.calls_, 40);
      FluidSnapshot sa, sb;
      a->snapshot(sa);
      b->snapshot(sb);
      ASSERT_EQ(sa.n, sb.n);
      EXPECT_EQ(a->time(), b->time());
      int differ = 0;
      for (int i = 0; i < sa.n; ++i)
        differ += sa.x[i].x != sb.x[i].x || sa.x[i].y != sb.x[i].y || sa.x[i].z != sb.x[i].z ||
                  sa.v[i].x != sb.v[i].x || sa.v[i].y != sb.v[i].y || sa.v[i].z != sb.v[i].z ||
                  sa.id[i] != sb.id[i];
      EXPECT_EQ(differ, 0);
    }
}

}  // namespace
