// Boundary-particle coupling (sph/moving_boundary.h, Akinci et al. 2012): samples on the
// triangles of a body surface, placed every step from its nodes, act on the fluid like the
// tank's wall samples, and the fluid's impulse on them returns to the nodes.
//   - the sampler covers a surface at the asked spacing, once per point;
//   - a column held only by an open box of samples rests there: nothing passes, pressure
//     follows rho g (H - y), and the nodes carry the column's weight;
//   - without gravity, fluid and nodes exchange momentum exactly (to float round-off);
//   - a moving plate pushes the fluid ahead of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <vector>

#include "sph_profile.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/scene/compile.h"
#include "sphfem/sph/moving_boundary.h"
#include "sphfem/sph/solver.h"

using namespace sphfem;

namespace {

constexpr double kRadius = 0.01, kSpacing = 2 * kRadius;

Vec3d at(const std::vector<Vec3d>& x, const Tri& t, const SurfaceSample& s) {
  return x[t.v[0]] * double(s.w[0]) + x[t.v[1]] * double(s.w[1]) + x[t.v[2]] * double(s.w[2]);
}

// Samples on a box's surface: inside their triangles, every surface point within the spacing
// of one, and about one per spacing^2 of area (up to three where cut triangles are
// right-angled). Cubic cells cut every triangle alike, so shared corners and edge points are
// kept once and no two samples come closer than the cut; cells of two sizes leave closer
// pairs along the edges where the cuts differ, but still none on one spot.
TEST(SphMovingBoundary, SamplerCoversTheSurfaceOnce) {
  for (const int nz : {6, 3}) {
    const TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(0.2, 0.1, 0.3), 4, 2, nz);
    const std::vector<Tri> tris = boundary_faces(box.tets);
    const std::vector<SurfaceSample> s = sample_surface(box.x, tris, kSpacing);
    double area = 0;
    for (const Tri& t : tris)
      area += 0.5 * norm(cross(box.x[t.v[1]] - box.x[t.v[0]], box.x[t.v[2]] - box.x[t.v[0]]));
    std::vector<Vec3d> p;
    for (const SurfaceSample& k : s) {
      ASSERT_GE(k.tri, 0);
      ASSERT_LT(k.tri, int(tris.size()));
      for (Real w : k.w) EXPECT_GE(w, 0);
      EXPECT_NEAR(k.w[0] + k.w[1] + k.w[2], 1, 1e-6);
      p.push_back(at(box.x, tris[k.tri], k));
    }
    double closest_pair = 1e30;
    for (std::size_t a = 0; a < p.size(); ++a)
      for (std::size_t b = a + 1; b < p.size(); ++b)
        closest_pair = std::min(closest_pair, norm(p[a] - p[b]));
    // Cells of 0.05 m cut 4 times (their diagonal is 0.071 m): samples 0.0125 m apart.
    if (nz == 6)
      EXPECT_GT(closest_pair, 0.0125 * 0.999);
    else
      EXPECT_GT(closest_pair, 0.1 * kSpacing);
    const double per_area = double(p.size()) * kSpacing * kSpacing / area;
    std::printf("%zu samples, %.2f per spacing^2, closest pair %.4f m\n", p.size(), per_area,
                closest_pair);
    EXPECT_GT(per_area, 1.0);
    EXPECT_LT(per_area, 3.0);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    double farthest = 0;
    for (int k = 0; k < 2000; ++k) {
      const Tri& t = tris[std::size_t(u(rng) * tris.size()) % tris.size()];
      double a = u(rng), b = u(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const Vec3d q = box.x[t.v[0]] * (1 - a - b) + box.x[t.v[1]] * a + box.x[t.v[2]] * b;
      double best = 1e30;
      for (const Vec3d& x : p) best = std::min(best, norm(q - x));
      farthest = std::max(farthest, best);
    }
    EXPECT_LT(farthest, 0.75 * kSpacing);
  }
  const TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(1, 1, 1), 1, 1, 1);
  EXPECT_THROW(sample_surface(box.x, boundary_faces(box.tets), 0.0), std::invalid_argument);
  EXPECT_THROW(sample_surface(box.x, {Tri{{0, 1, int(box.x.size())}}}, kSpacing),
               std::invalid_argument);
}

// A body surface the test moves by hand: nodes on the host, an impulse array the solver adds
// to, and a scripted velocity (zero: at rest). The impulse is read and cleared every step.
class SurfaceHook : public StepHook {
 public:
  SurfaceHook(std::vector<Vec3> x, std::vector<Tri> tris, Vec3 velocity)
      : x(std::move(x)), tris(std::move(tris)), vel_(velocity) {
    impulse_.assign(this->x.size(), Vec3());
    v_.assign(this->x.size(), velocity);
  }

  MovingSurface moving_boundary(const FluidArrays&) override {
    MovingSurface m;
    m.space = MemSpace::Host;
    m.nodes = int(x.size());
    m.tri = tris.data();
    m.x = x.data();
    m.v = norm2(vel_) > 0 ? v_.data() : nullptr;
    m.impulse = impulse_.data();
    return m;
  }

  DriftLimits before_drift(const FluidArrays&, double dt) override {
    Vec3d j;
    for (Vec3& i : impulse_) j += Vec3d(i), i = Vec3();
    step_impulse = j;
    total_impulse += j;
    for (Vec3& p : x) p += vel_ * Real(dt);  // the "body step" over the same dt
    return DriftLimits();
  }

  void after_drift(const FluidArrays&, double) override {}

  std::vector<Vec3> x;
  std::vector<Tri> tris;
  Vec3d step_impulse, total_impulse;

 private:
  Vec3 vel_;
  std::vector<Vec3> v_, impulse_;
};

Vec3d momentum(FluidSolver& sim) {
  FluidSnapshot s;
  sim.snapshot(s);
  Vec3d p;
  for (const Vec3& v : s.v) p += Vec3d(v);
  return p * double(sim.model().params.mass);
}

// --- a column in an open box made of samples ---

constexpr double kWidth = 0.2, kDepth = 0.3;
// Akinci's psi makes one layer of samples count like a full neighbourhood at contact, so the
// fluid rests about 1.1 spacings from it (docs/design.md); the column starts a spacing off
// the walls, as it would start squeezed by half its density at the lattice's half spacing.
constexpr double kGap = kSpacing;

// The box [0, kWidth] x [0, 0.45] x [0, kWidth] without its lid, far from the tank's walls.
SurfaceHook cup() {
  const TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(kWidth, 0.45, kWidth), 4, 9, 4);
  std::vector<Tri> open;
  for (const Tri& t : boundary_faces(box.tets)) {
    bool lid = true;
    for (int c = 0; c < 3; ++c) lid = lid && box.x[t.v[c]].y > 0.45 - 1e-9;
    if (!lid) open.push_back(t);
  }
  std::vector<Vec3> x;
  for (const Vec3d& p : box.x) x.push_back(Vec3(p));
  return SurfaceHook(x, open, Vec3());
}

struct CupResult {
  double weight_error;  // vertical force on the nodes over the column's weight, minus 1
  double sideways;      // horizontal force over the weight
  double l2_pressure_error, bottom_pressure_error, max_compression;
  int outside;  // particles found outside the box (snapshots)
};

CupResult settle_in_cup(SolverKind solver) {
  SceneSpec s;
  s.simulation.solver = solver;
  s.simulation.dt_max = 2e-3;
  s.fluid.particle_radius = kRadius;
  s.fluid.viscosity = 1e-3;
  s.domain.lo = Vec3d(-0.2, -0.2, -0.2);
  s.domain.hi = Vec3d(kWidth + 0.2, 0.7, kWidth + 0.2);
  s.fluid.blocks.push_back(
      {Vec3d(kGap, kGap, kGap), Vec3d(kWidth - kGap, kGap + kDepth, kWidth - kGap), Vec3d()});
  auto sim = make_fluid_solver(compile_fluid(s), Backend::Cpu);
  SurfaceHook hook = cup();
  std::vector<Vec3d> xd;
  for (const Vec3& p : hook.x) xd.push_back(Vec3d(p));
  sim->set_moving_samples(sample_surface(xd, hook.tris, kSpacing), hook.tris, int(xd.size()));
  sim->set_hook(&hook);
  CupResult r{};
  const double settle = 1.5;
  // SPHFEM_VERBOSE: the fluid's momentum and the force on the nodes every 0.05 s (a column
  // still moving shows here, and in the weight error, as a momentum that does not settle).
  for (double next = 0.05; sim->time() < settle;) {
    const double dt = sim->step(settle - sim->time()).dt;
    if (std::getenv("SPHFEM_VERBOSE") && sim->time() >= next) {
      next += 0.05;
      std::printf("t %.3f fluid momentum %+.5f N s, force on the nodes %+.3f N\n", sim->time(),
                  momentum(*sim).y, hook.step_impulse.y / dt);
    }
  }
  test::PressureProfile profile(15, kGap + kDepth, kWidth / 2, kWidth / 2, kSpacing);
  Vec3d impulse;
  FluidSnapshot snap;
  const double t0 = sim->time();
  if (std::getenv("SPHFEM_VERBOSE")) {
    sim->snapshot(snap);
    Vec3d p0;
    for (int i = 0; i < snap.n; ++i) p0 += Vec3d(snap.v[i]) * double(sim->model().params.mass);
    std::printf("fluid momentum at the window's start %.5f N s\n", p0.y);
  }
  for (double t_end = t0 + 0.1; sim->time() < t_end - 1e-9;) {
    sim->step(t_end - sim->time());
    impulse += hook.step_impulse;
    if (sim->steps() % 10) continue;
    sim->snapshot(snap);
    profile.add(snap);
    for (int i = 0; i < snap.n; ++i) {
      const Vec3 x = snap.x[i];
      r.max_compression = std::max(r.max_compression, double(snap.rho[i]) / 1000.0 - 1.0);
      if (x.x < 0 || x.x > kWidth || x.y < 0 || x.z < 0 || x.z > kWidth) ++r.outside;
    }
  }
  const Vec3d force = impulse / (sim->time() - t0);
  if (std::getenv("SPHFEM_VERBOSE")) {
    // The fluid's own momentum change over the window, over the weight: the part of the
    // weight the nodes did not carry because the column was not yet at rest.
    const double m = double(sim->model().params.mass);
    sim->snapshot(snap);
    Vec3d p1;
    double ke = 0;
    for (int i = 0; i < snap.n; ++i)
      p1 += Vec3d(snap.v[i]) * m, ke += 0.5 * m * norm2(Vec3d(snap.v[i]));
    std::printf(
        "window %.3f s: fluid momentum at its end %.5f N s (weight x window %.5f), kinetic "
        "energy %.3e J\n",
        sim->time() - t0, p1.y, double(sim->count()) * m * 9.81 * (sim->time() - t0), ke);
  }
  const double weight = double(sim->count()) * double(sim->model().params.mass) * 9.81;
  r.weight_error = -force.y / weight - 1;
  r.sideways = std::sqrt(force.x * force.x + force.z * force.z) / weight;
  const test::PressureProfile::Error e = profile.against(profile.surface(kRadius));
  r.l2_pressure_error = e.l2;
  r.bottom_pressure_error = e.bottom;
  return r;
}

class SphMovingBoundary : public ::testing::TestWithParam<SolverKind> {};

TEST_P(SphMovingBoundary, ColumnRestsOnSampledSurface) {
  const CupResult r = settle_in_cup(GetParam());
  std::printf(
      "force on the nodes / weight - 1 %+.4f, sideways %.4f, bottom pressure %+.4f, pressure L2 "
      "error %.4f, max compression %.4f, outside %d\n",
      r.weight_error, r.sideways, r.bottom_pressure_error, r.l2_pressure_error, r.max_compression,
      r.outside);
  EXPECT_EQ(r.outside, 0);
  EXPECT_LT(std::fabs(r.weight_error), 0.03);
  EXPECT_LT(r.sideways, 0.01);
  EXPECT_LT(std::fabs(r.bottom_pressure_error), 0.05);
  EXPECT_LT(r.l2_pressure_error, 0.05);
  EXPECT_LT(r.max_compression, 0.02);
}

// --- momentum exchange without gravity ---

// A square plate x = at, spanning y and z over [lo, hi], as two triangles facing -x.
SurfaceHook plate(double at, double lo, double hi, Vec3 velocity) {
  std::vector<Vec3> x = {Vec3(Real(at), Real(lo), Real(lo)), Vec3(Real(at), Real(lo), Real(hi)),
                         Vec3(Real(at), Real(hi), Real(hi)), Vec3(Real(at), Real(hi), Real(lo))};
  return SurfaceHook(x, {Tri{{0, 1, 2}}, Tri{{0, 2, 3}}}, velocity);
}

SceneSpec weightless(SolverKind solver, const Vec3d& block_velocity) {
  SceneSpec s;
  s.simulation.solver = solver;
  s.simulation.gravity = Vec3d(0, 0, 0);
  s.fluid.particle_radius = kRadius;
  s.fluid.viscosity = 0;  // the fluid's own viscosity is not pairwise symmetric
  s.fluid.max_speed = 2;
  s.domain.lo = Vec3d(-0.3, -0.3, -0.3);
  s.domain.hi = Vec3d(0.5, 0.4, 0.4);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.1, 0.1, 0.1), block_velocity});
  return s;
}

void attach(FluidSolver& sim, SurfaceHook& hook) {
  std::vector<Vec3d> xd;
  for (const Vec3& p : hook.x) xd.push_back(Vec3d(p));
  sim.set_moving_samples(sample_surface(xd, hook.tris, kSpacing), hook.tris, int(xd.size()));
  sim.set_hook(&hook);
}

TEST_P(SphMovingBoundary, FluidAndNodesExchangeMomentumExactly) {
  auto sim = make_fluid_solver(compile_fluid(weightless(GetParam(), Vec3d(1, 0, 0))), Backend::Cpu);
  SurfaceHook hook = plate(0.13, -0.1, 0.2, Vec3());
  attach(*sim, hook);
  const Vec3d p0 = momentum(*sim);
  while (sim->time() < 0.12) sim->step(1.0);
  const Vec3d p1 = momentum(*sim);
  const Vec3d error = p1 - p0 + hook.total_impulse;
  std::printf(
      "momentum: start %.6f, fluid now %.6f %.6f %.6f, nodes %.6f %.6f %.6f N s; "
      "sum of changes %.2e %.2e %.2e\n",
      p0.x, p1.x, p1.y, p1.z, hook.total_impulse.x, hook.total_impulse.y, hook.total_impulse.z,
      error.x, error.y, error.z);
  // A real collision: the plate took most of the block's momentum.
  EXPECT_GT(hook.total_impulse.x, 0.5 * p0.x);
  EXPECT_LT(norm(error), 1e-5 * norm(p0));
}

// --- a plate pushing fluid ---

TEST_P(SphMovingBoundary, MovingPlatePushesFluid) {
  const double speed = 0.5;
  auto sim = make_fluid_solver(compile_fluid(weightless(GetParam(), Vec3d())), Backend::Cpu);
  SurfaceHook hook = plate(-0.015, -0.1, 0.2, Vec3(Real(speed), 0, 0));
  attach(*sim, hook);
  int behind = 0;
  while (sim->time() < 0.2) {
    sim->step(1.0);
    FluidSnapshot s;
    sim->snapshot(s);
    for (const Vec3& x : s.x) behind += double(x.x) < double(hook.x[0].x);
  }
  FluidSnapshot s;
  sim->snapshot(s);
  const double wall = double(hook.x[0].x);
  double near = 0;
  int n_near = 0;
  for (int i = 0; i < s.n; ++i)
    if (double(s.x[i].x) < wall + 2 * kSpacing && std::fabs(s.x[i].y - 0.05) < 0.03 &&
        std::fabs(s.x[i].z - 0.05) < 0.03)
      near += s.v[i].x, ++n_near;
  near /= std::max(n_near, 1);
  const Vec3d p = momentum(*sim);
  std::printf(
      "plate at %.4f m: %d particles within two spacings move at %.3f m/s (plate %.3f); "
      "fluid momentum %.5f, impulse on the plate %.5f N s\n",
      wall, n_near, near, speed, p.x, hook.total_impulse.x);
  EXPECT_EQ(behind, 0);
  EXPECT_GT(n_near, 0);
  EXPECT_NEAR(near, speed, 0.25 * speed);
  EXPECT_GT(p.x, 0);
  EXPECT_NEAR(p.x, -hook.total_impulse.x, 1e-5 * p.x + 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Solvers, SphMovingBoundary,
                         ::testing::Values(SolverKind::WCSPH, SolverKind::DFSPH),
                         [](const auto& i) {
                           return i.param == SolverKind::WCSPH ? "WCSPH" : "DFSPH";
                         });

}  // namespace
