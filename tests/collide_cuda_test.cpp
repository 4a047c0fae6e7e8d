// The CUDA backend runs the same BVH code as the CPU: LBVH build, swept refit and every
// query (the exact contact test included) on a moving cup agree with the CPU's SAH tree (nearest
// faces equal except at ties within round-off; distances to single-precision round-off, as the GPU
// fuses multiply-adds). Skips without a usable GPU.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "sphfem/collide/collider.h"
#include "sphfem/fem/mesh.h"

using namespace sphfem;

namespace {

bool same(int fa, double ta, int fb, double tb) {
  const bool near = std::fabs(ta - tb) <= 1e-5 * std::max(1.0, std::fabs(tb));
  if ((fa < 0) != (fb < 0)) return false;
  return fa < 0 || near;
}

}  // namespace

TEST(CollideCuda, MatchesCpu) {
  std::string why;
  if (!cuda_available(&why)) GTEST_SKIP() << why;
  const TetMesh cup = make_cup(Vec3d(0, 0, 0), 0.08, 0.1, 0.2, 0.02, 16);
  const std::vector<Tri> tris = boundary_faces(cup.tets);
  std::vector<Vec3> x0, x1;
  for (const Vec3d& p : cup.x) {
    x0.push_back(Vec3(p));
    x1.push_back(Vec3(p) + Vec3(0.01f, 0.004f * std::sin(30 * float(p.y)), -0.005f));
  }
  auto cpu = make_collider(Backend::Cpu);
  auto gpu = make_collider(Backend::Cuda);
  cpu->build(x0, tris, BvhBuild::Sah);
  gpu->build(x0, tris, BvhBuild::Lbvh);
  EXPECT_NEAR(gpu->quality(), 1.0, 1e-6);
  cpu->refit(x0, x1);
  gpu->refit(x0, x1);

  std::mt19937 rng(21);
  std::uniform_real_distribution<float> U(-0.15f, 0.25f), V(-0.5f, 0.5f);
  const int n = 20000;
  std::vector<Vec3> p(n), d(n), vel(n);
  for (int i = 0; i < n; ++i) {
    p[i] = Vec3(U(rng) - 0.05f, U(rng), U(rng) - 0.05f);
    d[i] = Vec3(V(rng), V(rng), V(rng));
    vel[i] = d[i] * Real(2);
  }
  const auto rc = cpu->cast_rays(p, d, {});
  const auto rg = gpu->cast_rays(p, d, {});
  const auto mc = cpu->cast_moving(p, vel, 0.01f, 0.002f);
  const auto mg = gpu->cast_moving(p, vel, 0.01f, 0.002f);
  std::vector<Vec3> to(n);
  for (int i = 0; i < n; ++i) to[i] = p[i] + vel[i] * Real(0.01);
  const auto kc = cpu->contacts(p, to, 1e-6f, true);
  const auto kg = gpu->contacts(p, to, 1e-6f, true);
  const auto ic = cpu->inside(p);
  const auto ig = gpu->inside(p);
  const auto cc = cpu->closest(p, 0.05f);
  const auto cg = gpu->closest(p, 0.05f);
  int ray_hits = 0, moving_hits = 0, contact_hits = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(same(rg[i].face, rg[i].t, rc[i].face, rc[i].t)) << "ray " << i;
    ASSERT_TRUE(same(mg[i].face, mg[i].t / (mg[i].face >= 0 ? mg[i].len : 1), mc[i].face,
                     mc[i].t / (mc[i].face >= 0 ? mc[i].len : 1)))
        << "moving " << i;
    ASSERT_TRUE(same(cg[i].face, cg[i].dist, cc[i].face, cc[i].dist)) << "closest " << i;
    if (cc[i].face >= 0 && cc[i].dist > 1e-4) { EXPECT_EQ(cg[i].side, cc[i].side) << i; }
    EXPECT_EQ(ig[i], ic[i]) << "inside " << i;
    ASSERT_TRUE(same(kg[i].face, kg[i].c.tau, kc[i].face, kc[i].c.tau)) << "contact " << i;
    contact_hits += kc[i].face >= 0;
    ray_hits += rc[i].face >= 0;
    moving_hits += mc[i].face >= 0;
  }
  EXPECT_GT(ray_hits, n / 10);
  EXPECT_GT(moving_hits, n / 100);
  EXPECT_GT(contact_hits, n / 200);
}
