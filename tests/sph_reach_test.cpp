// The scans the wall passes skip: a wall sample outside the fluid's reach box and a particle
// inside the tank's quiet box must have nothing within the support, by brute force in the
// scan's own float arithmetic (|x - x_j|^2 < h^2), most of all at the boxes' faces.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/exec_cpu.h"
#include "sph/stages.h"
#include "sphfem/scene/compile.h"

using namespace sphfem;

namespace {

// Whether any of x[0..n) lies within h of p, as the grid scans test it.
bool any_in_reach(const std::vector<Vec3>& x, const Vec3& p, Real h2) {
  for (const Vec3& q : x)
    if (norm2(p - q) < h2) return true;
  return false;
}

// Points on and around the faces of [lo, hi]: each coordinate within a hundredth of h of a
// face or anywhere between, so many points sit right at the reach.
std::vector<Vec3> near_faces(const Vec3& lo, const Vec3& hi, Real h, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), off(-0.01f, 0.01f);
  std::vector<Vec3> pts;
  for (int k = 0; k < count; ++k) {
    Vec3 p;
    for (int a = 0; a < 3; ++a) {
      const float pick = u(rng);
      const Real span = hi[a] - lo[a] + Real(4) * h;
      const Real c = pick < 0.3f   ? lo[a] + off(rng) * h
                     : pick < 0.6f ? hi[a] + off(rng) * h
                                   : lo[a] - Real(2) * h + u(rng) * span;
      (a == 0 ? p.x : a == 1 ? p.y : p.z) = c;
    }
    pts.push_back(p);
  }
  return pts;
}

TEST(SphReach, NoParticleWithinReachOfAPointOutsideTheFluidsBox) {
  CpuExec ex;
  SphParams P;
  P.h = Real(0.05);
  P.h2 = P.h * P.h;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3> x;
  for (int i = 0; i < 3000; ++i)
    x.push_back(Vec3(Real(0.3) + Real(0.4) * u(rng), Real(0.1) * u(rng), Real(0.2) * u(rng)));
  stages::FluidView f;
  f.n = int(x.size());
  f.x = x.data();
  stages::fluid_reach(ex, P, f);
  ASSERT_EQ(f.reached, 1);
  int skipped = 0, close = 0;
  for (const Vec3& p : near_faces(f.reach_lo, f.reach_hi, P.h, 20000, 9)) {
    if (!stages::out_of_reach(f, p)) continue;
    ++skipped;
    ASSERT_FALSE(any_in_reach(x, p, P.h2))
        << "a point the wall passes skip has a particle in reach: " << p.x << " " << p.y << " "
        << p.z;
  }
  // Not vacuous, and not loose: a point a support and a hundredth beyond the particles'
  // bounds is skipped.
  EXPECT_GT(skipped, 2000);
  for (const Vec3& p : near_faces(f.reach_lo, f.reach_hi, P.h, 2000, 10))
    close += stages::out_of_reach(f, p) && !any_in_reach(x, p, Real(1.03) * Real(1.03) * P.h2);
  EXPECT_GT(close, 0);
  // Without positions nothing is skipped.
  stages::FluidView empty;
  stages::fluid_reach(ex, P, empty);
  EXPECT_FALSE(stages::out_of_reach(empty, Vec3(100, 100, 100)));
}

TEST(SphReach, NoTankSampleWithinReachOfAPointInsideTheQuietBox) {
  SceneSpec s;
  s.fluid.particle_radius = 0.01;
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.4, 0.3, 0.2);
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.1, 0.1, 0.1), Vec3d()});
  for (bool open_top : {false, true}) {
    s.domain.open_top = open_top;
    const FluidModel m = compile_fluid(s);
    const SphParams& P = m.params;
    const std::vector<Vec3>& b = m.boundary_x;
    stages::BoundaryView tank;
    stages::quiet_box(b.data(), int(b.size()), P.clamp_lo, P.clamp_hi, P.h, tank);
    int quiet = 0;
    for (const Vec3& p : near_faces(tank.quiet_lo, tank.quiet_hi, P.h, 20000, 3)) {
      if (!stages::in_quiet(tank, p)) continue;
      ++quiet;
      ASSERT_FALSE(any_in_reach(b, p, P.h2))
          << "a particle that skips the tank's scan has a sample in reach: " << p.x << " " << p.y
          << " " << p.z;
    }
    EXPECT_GT(quiet, 2000);
    // A sample inside the domain (a pillar, say) empties the box: nothing is skipped.
    std::vector<Vec3> inside = b;
    inside.push_back(Vec3(Real(0.2), Real(0.15), Real(0.1)));
    stages::quiet_box(inside.data(), int(inside.size()), P.clamp_lo, P.clamp_hi, P.h, tank);
    EXPECT_FALSE(stages::in_quiet(tank, Vec3(Real(0.2), Real(0.15), Real(0.1))));
  }
}

}  // namespace
