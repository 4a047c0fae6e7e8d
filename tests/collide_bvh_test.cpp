// The BVH and its queries on the CPU against brute force over all triangles, for both
// builders (binned SAH, LBVH): nearest hits of static rays, after refits of moving meshes,
// crossing parity against the generalised winding number, the moving-segment query, and
// closest points with their inside/outside sign.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/exec_cpu.h"
#include "sphfem/collide/bvh.h"
#include "sphfem/fem/mesh.h"

using namespace sphfem;
using namespace sphfem::collide;

namespace {

struct Surface {
  std::vector<Vec3> x;
  std::vector<Tri> tris;
};

Surface surface_of(const TetMesh& m) {
  Surface s;
  s.tris = boundary_faces(m.tets);
  for (const Vec3d& p : m.x) s.x.push_back(Vec3(p));
  return s;
}

// A sphere, a cup (concave edges and corners) and a tube (a torus: genus one).
std::vector<Surface> test_surfaces() {
  return {surface_of(make_sphere(Vec3d(0.1, -0.2, 0.3), 0.5, 10)),
          surface_of(make_cup(Vec3d(0, 0, 0), 0.08, 0.1, 0.2, 0.02, 12)),
          surface_of(make_tube(Vec3d(0.3, 0.1, 0.3), 0.05, 0.08, 0.3, 16, 2, 8))};
}

void bounds(const std::vector<Vec3>& x, Vec3& lo, Vec3& hi) {
  lo = hi = x[0];
  for (const Vec3& p : x) lo = vmin(lo, p), hi = vmax(hi, p);
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const Vec3d v(g(rng), g(rng), g(rng));
    const double l = norm(v);
    if (l > 1e-3) return Vec3(v / l);
  }
}

Vec3 random_in(std::mt19937& rng, const Vec3& lo, const Vec3& hi, Real grow) {
  std::uniform_real_distribution<double> U(0, 1);
  const Vec3 e = hi - lo;
  return Vec3(lo.x - grow * e.x + (1 + 2 * grow) * e.x * Real(U(rng)),
              lo.y - grow * e.y + (1 + 2 * grow) * e.y * Real(U(rng)),
              lo.z - grow * e.z + (1 + 2 * grow) * e.z * Real(U(rng)));
}

// --- brute force references, with the same per-triangle functions and tie rule ---

RayHit brute_ray(const Surface& s, const Vec3& o, const Vec3& d, Real tmax) {
  RayHit h;
  h.t = tmax;
  for (int f = 0; f < int(s.tris.size()); ++f) {
    const Tri& t = s.tris[f];
    Real tt, u, v;
    if (intersect_ray_triangle(o, d, s.x[t.v[0]], s.x[t.v[1]], s.x[t.v[2]], h.t, tt, u, v) &&
        closer(tt, f, h.t, h.face))
      h.face = f, h.t = tt, h.u = u, h.v = v;
  }
  return h;
}

int brute_count(const Surface& s, const Vec3& o, const Vec3& d, Real tmax) {
  int n = 0;
  for (const Tri& t : s.tris) {
    Real tt, u, v;
    n += intersect_ray_triangle(o, d, s.x[t.v[0]], s.x[t.v[1]], s.x[t.v[2]], tmax, tt, u, v);
  }
  return n;
}

SegmentHit brute_moving(const Surface& s0, const Surface& s1, const Vec3& p, const Vec3& dp,
                        Real skin) {
  SegmentHit h;
  Real best = Real(FLT_MAX);
  for (int f = 0; f < int(s0.tris.size()); ++f) {
    const Tri& t = s0.tris[f];
    const Vec3 a = s0.x[t.v[0]], b = s0.x[t.v[1]], c = s0.x[t.v[2]];
    MovingHit m;
    if (moving_triangle(p, dp, skin, a, b, c, s1.x[t.v[0]] - a, s1.x[t.v[1]] - b, s1.x[t.v[2]] - c,
                        m) &&
        closer(m.t / m.len, f, best, h.face)) {
      best = m.t / m.len;
      h.face = f, h.t = m.t, h.u = m.u, h.v = m.v, h.len = m.len, h.rel = m.rel;
    }
  }
  return h;
}

ContactHit brute_contact(const Surface& s0, const Surface& s1, const Vec3& p, const Vec3& dp,
                         Real tol) {
  ContactHit h;
  Real best = 2;
  for (int f = 0; f < int(s0.tris.size()); ++f) {
    const Tri& t = s0.tris[f];
    const Vec3 a = s0.x[t.v[0]], b = s0.x[t.v[1]], c = s0.x[t.v[2]];
    Crossing k;
    if (point_face_contact(p, dp, a, b, c, s1.x[t.v[0]] - a, s1.x[t.v[1]] - b, s1.x[t.v[2]] - c,
                           tol, 2, k) &&
        closer(k.tau, f, best, h.face))
      best = k.tau, h.face = f, h.c = k;
  }
  return h;
}

double brute_distance(const Surface& s, const Vec3& p, int* face = nullptr) {
  double best = 1e30;
  for (int f = 0; f < int(s.tris.size()); ++f) {
    const Tri& t = s.tris[f];
    const double d = norm(p - closest_on_triangle(p, s.x[t.v[0]], s.x[t.v[1]], s.x[t.v[2]]).point);
    if (d < best) {
      best = d;
      if (face) *face = f;
    }
  }
  return best;
}

// Generalised winding number (solid angles by Van Oosterom & Strackee 1983), in double:
// an independent inside test for closed, outward-oriented surfaces.
double winding_number(const Surface& s, const Vec3& p) {
  double w = 0;
  for (const Tri& t : s.tris) {
    const Vec3d a = Vec3d(s.x[t.v[0]]) - Vec3d(p), b = Vec3d(s.x[t.v[1]]) - Vec3d(p),
                c = Vec3d(s.x[t.v[2]]) - Vec3d(p);
    const double la = norm(a), lb = norm(b), lc = norm(c);
    const double num = dot(a, cross(b, c));
    const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    w += 2 * std::atan2(num, den);
  }
  return w / (4 * M_PI);
}

// Rigid rotation about `centre` by angle around axis, then a translation.
std::vector<Vec3> moved(const std::vector<Vec3>& x, const Vec3& centre, Vec3 axis, Real angle,
                        const Vec3& shift) {
  axis = axis / norm(axis);
  const Real c = std::cos(angle), s = std::sin(angle);
  std::vector<Vec3> y(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3 r = x[i] - centre;
    const Vec3 rot = r * c + cross(axis, r) * s + axis * (dot(axis, r) * (1 - c));
    y[i] = centre + rot + shift;
  }
  return y;
}

// A surface over one step: rotated about its centre, translated (shift in units of its size)
// and deformed by up to 1 % of its size per vertex.
struct Swept {
  Surface s1;
  Real size;
  const Surface& s0;
  Swept(const Surface& s, std::mt19937& rng, Vec3 axis, Real angle, Vec3 shift) : s0(s) {
    std::uniform_real_distribution<double> U(-1, 1);
    Vec3 lo, hi;
    bounds(s.x, lo, hi);
    size = norm(hi - lo);
    s1 = s;
    s1.x = moved(s.x, (lo + hi) * Real(0.5), axis, angle, shift * size);
    for (Vec3& x : s1.x) x += Vec3(U(rng), U(rng), U(rng)) * Real(0.01) * size;
  }
  // A BVH over s0, refit over the step.
  void build(CpuExec& ex, BvhBuild method, SurfaceBvh<CpuExec>& bvh) const {
    bvh.build(ex, s0.x.data(), s0.tris.data(), int(s0.tris.size()), method);
    bvh.refit(ex, s0.x.data(), s1.x.data());
  }
  // A particle near a random surface point (within 10 % of the size), moving randomly.
  void random_path(std::mt19937& rng, Vec3& p, Vec3& dp) const {
    std::uniform_real_distribution<double> U(-1, 1);
    const Tri& t = s0.tris[rng() % s0.tris.size()];
    p = (s0.x[t.v[0]] + s0.x[t.v[1]] + s0.x[t.v[2]]) / Real(3) +
        random_unit(rng) * Real(0.1 * size * (U(rng) + 1) / 2);
    dp = random_unit(rng) * Real(0.08 * size * (U(rng) + 1) / 2);
  }
};

// Results of the same per-triangle function at different call sites can differ in the last
// bits (compilers fuse multiply-adds differently where code is inlined): distances agree to
// a few units of round-off, and a different face is only accepted at a tie within that.
constexpr double kRoundoff = 1e-6;

::testing::AssertionResult same_hit(int fa, double ta, int fb, double tb,
                                    double roundoff = kRoundoff) {
  const bool near = std::fabs(ta - tb) <= roundoff * std::max(1.0, std::fabs(tb));
  if ((fa < 0) != (fb < 0) || (fa != fb && !near) || (fa >= 0 && !near))
    return ::testing::AssertionFailure()
           << "face " << fa << " at " << ta << " vs brute force face " << fb << " at " << tb;
  return ::testing::AssertionSuccess();
}

// A contact time is a root of a cubic: where the particle meets the face at a shallow angle
// the root moves by the coefficients' last-bit differences over a small slope.
constexpr double kContactRoundoff = 1e-5;

class CollideBvh : public ::testing::TestWithParam<BvhBuild> {
 protected:
  CpuExec ex;
};

}  // namespace

TEST_P(CollideBvh, NearestHitMatchesBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  for (const Surface& s : test_surfaces()) {
    SurfaceBvh<CpuExec> bvh;
    bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
    EXPECT_GT(bvh.depth(), 0);
    EXPECT_LT(bvh.depth(), kStackSize);
    Vec3 lo, hi;
    bounds(s.x, lo, hi);
    const BvhView bv = bvh.view();
    int hits = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3 o = random_in(rng, lo, hi, Real(0.3));
      // Mostly aimed at the body, some random, some bounded.
      const Vec3 target = random_in(rng, lo, hi, 0);
      const Vec3 d = i % 4 == 0 ? random_unit(rng) : target - o;
      const Real tmax = i % 3 == 0 ? Real(U(rng)) : Real(INFINITY);
      const RayHit a = ray_nearest(bv, s.x.data(), o, d, tmax);
      const RayHit b = brute_ray(s, o, d, tmax);
      ASSERT_TRUE(same_hit(a.face, a.t, b.face, b.t)) << "ray " << i;
      if (a.face >= 0 && a.face == b.face) {
        EXPECT_NEAR(a.u, b.u, kRoundoff);
        EXPECT_NEAR(a.v, b.v, kRoundoff);
      }
      hits += a.face >= 0;
      EXPECT_EQ(ray_count(bv, s.x.data(), o, d, tmax, false), brute_count(s, o, d, tmax));
    }
    EXPECT_GT(hits, 1000);  // the comparison saw many hits, not only misses
  }
}

TEST_P(CollideBvh, RefitTracksMovingMeshes) {
  // Deform, rotate and translate over many steps, refitting only: every few steps the
  // nearest hits equal brute force, and at the end equal those of a fresh build.
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(-1, 1);
  Surface s = test_surfaces()[1];
  const Surface rest = s;
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  bvh.refit(ex, s.x.data());
  EXPECT_DOUBLE_EQ(bvh.quality(ex), 1.0);  // refit at the build positions changes nothing
  Vec3 lo, hi;
  bounds(s.x, lo, hi);
  const Vec3 centre = (lo + hi) * Real(0.5);
  const int steps = 60;
  for (int k = 1; k <= steps; ++k) {
    const Real a = Real(0.05) * k;
    s.x = moved(rest.x, centre, Vec3(1, 2, 3), a, Vec3(0.01f * k, -0.005f * k, 0.002f * k));
    for (std::size_t i = 0; i < s.x.size(); ++i)  // a smooth wobble plus noise
      s.x[i] +=
          Vec3(0.02f * std::sin(30 * rest.x[i].y + a), 0.01f * std::cos(20 * rest.x[i].x), 0) +
          Vec3(U(rng), U(rng), U(rng)) * Real(0.002);
    bvh.refit(ex, s.x.data());
    if (k % 10 != 0) continue;
    bounds(s.x, lo, hi);
    const BvhView bv = bvh.view();
    for (int i = 0; i < 500; ++i) {
      const Vec3 o = random_in(rng, lo, hi, Real(0.3));
      const Vec3 d = random_in(rng, lo, hi, 0) - o;
      const RayHit h = ray_nearest(bv, s.x.data(), o, d, Real(INFINITY));
      const RayHit b = brute_ray(s, o, d, Real(INFINITY));
      ASSERT_TRUE(same_hit(h.face, h.t, b.face, b.t)) << "step " << k << " ray " << i;
    }
  }
  EXPECT_GT(bvh.quality(ex), 1.0);  // the refit tree is looser than the one built
  SurfaceBvh<CpuExec> fresh;
  fresh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  for (int i = 0; i < 1000; ++i) {
    const Vec3 o = random_in(rng, lo, hi, Real(0.3));
    const Vec3 d = random_in(rng, lo, hi, 0) - o;
    const RayHit a = ray_nearest(bvh.view(), s.x.data(), o, d, Real(INFINITY));
    const RayHit b = ray_nearest(fresh.view(), s.x.data(), o, d, Real(INFINITY));
    ASSERT_TRUE(same_hit(a.face, a.t, b.face, b.t)) << "ray " << i;
  }
}

TEST_P(CollideBvh, QualityFlagsADegradedTree) {
  // Shuffling which vertex sits where scatters every face over the body: the refit boxes
  // grow far beyond those of the build, and a rebuild restores the ratio to 1.
  Surface s = test_surfaces()[0];
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  EXPECT_DOUBLE_EQ(bvh.quality(ex), 1.0);
  std::mt19937 rng(13);
  std::shuffle(s.x.begin(), s.x.end(), rng);
  bvh.refit(ex, s.x.data());
  EXPECT_GT(bvh.quality(ex), 2.0);
  bvh.rebuild(ex, s.x.data(), GetParam());
  EXPECT_DOUBLE_EQ(bvh.quality(ex), 1.0);
}

TEST_P(CollideBvh, AxisRaysThroughGridVerticesAndEdgesNeverLeak) {
  // A box [-1, 1]^3 of 8^3 cells: vertex coordinates are multiples of 1/4 and the shared
  // edges (grid lines and quad diagonals) pass through multiples of 1/8, all exact in
  // binary. Axis-aligned rays through every such point of a face enter and leave the box
  // exactly once each; rays along a face plane cross an even number of times.
  const Surface s = surface_of(make_box(Vec3d(-1, -1, -1), Vec3d(1, 1, 1), 8, 8, 8));
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  const BvhView bv = bvh.view();
  int rays = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (Real sign : {Real(1), Real(-1)})
      for (int i = -8; i <= 8; ++i)
        for (int j = -8; j <= 8; ++j) {
          Vec3 o, d;
          o[axis] = -2 * sign;
          d[axis] = sign;
          o[(axis + 1) % 3] = Real(i) / 8;
          o[(axis + 2) % 3] = Real(j) / 8;
          const int n = ray_count(bv, s.x.data(), o, d, Real(INFINITY), false);
          ++rays;
          if (std::abs(i) < 8 && std::abs(j) < 8) {  // inside the face square
            ASSERT_EQ(n, 2) << "axis " << axis << " through (" << i << ", " << j << ")/8";
            const RayHit h = ray_nearest(bv, s.x.data(), o, d, Real(INFINITY));
            ASSERT_GE(h.face, 0);
            EXPECT_EQ(h.t, 1);  // the entry face, one unit away
          } else {
            EXPECT_EQ(n % 2, 0) << "axis " << axis << " along the face plane";
          }
        }
  EXPECT_EQ(rays, 6 * 17 * 17);
}

TEST_P(CollideBvh, RaysFromInsideThroughVerticesAndEdgesCrossOnce) {
  // Star-shaped closed surfaces seen from their centre: a ray through any mesh vertex or
  // edge midpoint leaves exactly once (the watertight test with tie-breaking).
  const Vec3d c(0.1, -0.2, 0.3);
  const std::vector<std::pair<Surface, Vec3>> cases = {
      {surface_of(make_sphere(c, 0.5, 10)), Vec3(c)},
      {surface_of(make_box(Vec3d(-1, -1, -1), Vec3d(1, 1, 1), 8, 8, 8)), Vec3(0, 0, 0)}};
  for (const auto& [s, centre] : cases) {
    SurfaceBvh<CpuExec> bvh;
    bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
    const BvhView bv = bvh.view();
    int rays = 0;
    for (const Tri& t : s.tris)
      for (int k = 0; k < 3; ++k) {
        const Vec3 v = s.x[t.v[k]], w = s.x[t.v[(k + 1) % 3]];
        ASSERT_EQ(ray_count(bv, s.x.data(), centre, v - centre, Real(INFINITY), false), 1);
        ASSERT_EQ(
            ray_count(bv, s.x.data(), centre, (v + w) * Real(0.5) - centre, Real(INFINITY), false),
            1);
        rays += 2;
      }
    EXPECT_EQ(rays, 6 * int(s.tris.size()));
  }
}

TEST_P(CollideBvh, ParityClassifiesInsideAndOutside) {
  // Thousands of random points around a sphere, a cup and a tube: odd crossings of a ray to
  // infinity exactly where the winding number says inside. Points within 1e-5 of the
  // surface are skipped (there float rounding of the point itself decides).
  std::mt19937 rng(14);
  for (const Surface& s : test_surfaces()) {
    SurfaceBvh<CpuExec> bvh;
    bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
    Vec3 lo, hi;
    bounds(s.x, lo, hi);
    std::vector<Vec3> p;
    for (int i = 0; i < 3000; ++i) {
      const Vec3 q = random_in(rng, lo, hi, Real(0.1));
      if (brute_distance(s, q) > 1e-5) p.push_back(q);
    }
    std::vector<std::uint8_t> in(p.size());
    inside_closed(ex, bvh, s.x.data(), int(p.size()), p.data(), in.data());
    int inside = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double w = winding_number(s, p[i]);
      ASSERT_LT(std::min(std::fabs(w), std::fabs(w - 1)), 1e-3) << "not a closed surface";
      ASSERT_EQ(int(in[i]), int(w > 0.5)) << "point " << i;
      inside += in[i];
    }
    EXPECT_GT(inside, 100);
    EXPECT_GT(int(p.size()) - inside, 100);
  }
}

TEST_P(CollideBvh, MovingSegmentsMatchBruteForce) {
  // A mesh rotating, translating and deforming over a step, particles near its surface with
  // velocities of the same size as the faces': the BVH over swept boxes finds exactly the
  // brute-force earliest hit, for several skins.
  std::mt19937 rng(15);
  for (const Surface& s0 : test_surfaces()) {
    const Swept w(s0, rng, Vec3(0.3f, 1, -0.5f), Real(0.15), Vec3(0.03f, -0.02f, 0.05f));
    const Surface& s1 = w.s1;
    const Real size = w.size;
    SurfaceBvh<CpuExec> bvh;
    w.build(ex, GetParam(), bvh);
    const BvhView bv = bvh.view();
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
      Vec3 p, dp;
      w.random_path(rng, p, dp);
      const Real skin = i % 2 ? Real(0) : Real(0.01) * size;
      const SegmentHit a = moving_nearest(bv, s0.x.data(), s1.x.data(), p, dp, skin);
      const SegmentHit b = brute_moving(s0, s1, p, dp, skin);
      // Compared by the time of the hit within the step, the quantity the query minimises.
      ASSERT_TRUE(
          same_hit(a.face, a.face >= 0 ? a.t / a.len : 0, b.face, b.face >= 0 ? b.t / b.len : 0))
          << "particle " << i;
      if (a.face >= 0 && a.face == b.face) {
        EXPECT_NEAR(a.t, b.t, kRoundoff * std::max(1.0, double(b.t)));
        EXPECT_NEAR(a.len, b.len, kRoundoff * std::max(1.0, double(b.len)));
      }
      hits += a.face >= 0;
    }
    EXPECT_GT(hits, 200);
  }
}

TEST_P(CollideBvh, ExactContactsMatchBruteForce) {
  // The same moving meshes: the earliest exact contact of each path through the BVH over
  // swept boxes is the brute-force one over all faces; cast_contacts gives the same, and a
  // particle put a skin in front of the face's new position there meets nothing more.
  std::mt19937 rng(16);
  for (const Surface& s0 : test_surfaces()) {
    const Swept w(s0, rng, Vec3(-0.4f, 1, 0.2f), Real(0.2), Vec3(-0.02f, 0.03f, 0.04f));
    const Surface& s1 = w.s1;
    const Real size = w.size;
    SurfaceBvh<CpuExec> bvh;
    w.build(ex, GetParam(), bvh);
    const BvhView bv = bvh.view();
    const Real tol = Real(1e-5) * size;
    std::vector<Vec3> from, to;
    std::vector<ContactHit> want;
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
      Vec3 p, dp;
      w.random_path(rng, p, dp);
      const ContactHit a = moving_contact(bv, s0.x.data(), s1.x.data(), p, dp, tol);
      const ContactHit b = brute_contact(s0, s1, p, dp, tol);
      ASSERT_TRUE(same_hit(a.face, a.c.tau, b.face, b.c.tau, kContactRoundoff)) << "particle " << i;
      if (a.face >= 0 && a.face == b.face) {
        EXPECT_EQ(a.c.side, b.c.side);
        EXPECT_NEAR(a.c.u, b.c.u, kRoundoff);
      }
      hits += a.face >= 0;
      from.push_back(p), to.push_back(p + dp), want.push_back(b);
    }
    EXPECT_GT(hits, 200);
    const int n = int(from.size());
    std::vector<int> face(n), side(n);
    std::vector<Real> tau(n), u(n), v(n);
    cast_contacts(ex, bvh, s0.x.data(), s1.x.data(), n, from.data(), to.data(), tol,
                  ContactHits{face.data(), tau.data(), u.data(), v.data(), side.data()});
    int fixed = 0;
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(same_hit(face[i], tau[i], want[i].face, want[i].c.tau, kContactRoundoff))
          << "particle " << i;
      if (face[i] < 0) continue;
      const Tri& t = s0.tris[face[i]];
      const Vec3 a = s1.x[t.v[0]], b = s1.x[t.v[1]], c = s1.x[t.v[2]];
      const Vec3 q = a * (1 - u[i] - v[i]) + b * u[i] + c * v[i];
      const Vec3 end = q + unit_normal(a, b, c) * (Real(side[i]) * Real(0.002) * size);
      fixed += moving_contact(bv, s0.x.data(), s1.x.data(), from[i], end - from[i], tol).face < 0;
    }
    // The fix clears almost every contact at once; what remains is left for another pass.
    EXPECT_GT(fixed, hits * 9 / 10);
  }
}

TEST_P(CollideBvh, FaceSweepingOverRestingParticlesIsFound) {
  // A sphere moving 0.05 along +x over a step towards particles at rest just beyond its
  // surface: the particles' own (zero) motion finds nothing, the relative motion finds the
  // face that reaches them, on the old surface, at the distance the sphere covers.
  const Surface s0 = surface_of(make_sphere(Vec3d(0, 0, 0), 0.5, 10));
  Surface s1 = s0;
  const Vec3 shift(0.05f, 0, 0);
  for (Vec3& x : s1.x) x += shift;
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s0.x.data(), s0.tris.data(), int(s0.tris.size()), GetParam());
  bvh.refit(ex, s0.x.data(), s1.x.data());
  std::vector<Vec3> p, zero;
  for (int j = -3; j <= 3; ++j)
    for (int k = -3; k <= 3; ++k) {
      const Real y = Real(0.05) * j, z = Real(0.05) * k;
      const Real xs = std::sqrt(Real(0.25) - y * y - z * z);  // on the sphere (not the mesh)
      p.push_back(Vec3(xs + 0.02f, y, z));                    // reached by the face within the step
      p.push_back(Vec3(xs + 0.09f, y, z));                    // out of reach
    }
  zero.assign(p.size(), Vec3());
  const int n = int(p.size());
  std::vector<int> face(n);
  std::vector<Real> t(n), u(n), v(n), len(n);
  std::vector<Vec3> rel(n);
  cast_moving(ex, bvh, s0.x.data(), s1.x.data(), n, p.data(), zero.data(), Real(0.01), Real(0),
              SegmentHits{face.data(), t.data(), u.data(), v.data(), len.data(), rel.data()});
  // The particles' absolute paths (a point each) meet nothing.
  std::vector<int> f2(n);
  std::vector<Real> t2(n), u2(n), v2(n), tmax(n, Real(1));
  cast_rays(ex, bvh, s1.x.data(), n, p.data(), zero.data(), tmax.data(),
            RayHits{f2.data(), t2.data(), u2.data(), v2.data()});
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(f2[i], -1);
    const bool reached = i % 2 == 0;
    ASSERT_EQ(face[i] >= 0, reached) << "particle " << i;
    if (!reached) continue;
    EXPECT_NEAR(len[i], 0.05, 1e-6);
    EXPECT_NEAR(rel[i].x, -0.05, 1e-6);  // the particle moves towards -x relative to the face
    // The hit lies on the old face, in front of the particle along -x.
    const Tri& tr = s0.tris[face[i]];
    const Vec3 q = s0.x[tr.v[0]] * (1 - u[i] - v[i]) + s0.x[tr.v[1]] * u[i] + s0.x[tr.v[2]] * v[i];
    EXPECT_LT(norm(q - (p[i] - Vec3(t[i], 0, 0))), 1e-5);
    EXPECT_GT(t[i], 0.02 - 1e-5);  // at least the gap to the true sphere
    EXPECT_LT(t[i], 0.05);
  }
}

TEST_P(CollideBvh, MergedTriangleSetsEqualOneSoup) {
  // The cup's faces split into two sets with their own BVHs, cast one after the other with
  // merging and an id offset, give the earliest hits of one BVH over all faces.
  const Surface s0 = test_surfaces()[1];
  Surface s1 = s0;
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> U(-1, 1);
  for (Vec3& x : s1.x)
    x += Vec3(0.004f, -0.002f, 0.001f) + Vec3(U(rng), U(rng), U(rng)) * Real(0.001);
  const int nt = int(s0.tris.size()), half = nt / 3;
  SurfaceBvh<CpuExec> all, a, b;
  all.build(ex, s0.x.data(), s0.tris.data(), nt, GetParam());
  a.build(ex, s0.x.data(), s0.tris.data(), half, GetParam());
  b.build(ex, s0.x.data(), s0.tris.data() + half, nt - half, GetParam());
  for (SurfaceBvh<CpuExec>* t : {&all, &a, &b}) t->refit(ex, s0.x.data(), s1.x.data());
  const int n = 4000;
  std::vector<Vec3> p(n), vel(n);
  for (int i = 0; i < n; ++i) {
    const Tri& t = s0.tris[rng() % s0.tris.size()];
    p[i] = (s0.x[t.v[0]] + s0.x[t.v[1]] + s0.x[t.v[2]]) / Real(3) + random_unit(rng) * Real(0.01);
    vel[i] = random_unit(rng) * Real(2 * (U(rng) + 1));
  }
  std::vector<int> f1(n), f2(n);
  std::vector<Real> t1(n), t2(n), u1(n), u2(n), v1(n), v2(n), l1(n), l2(n);
  const Real dt = 0.005f, skin = 0.001f;
  cast_moving(ex, all, s0.x.data(), s1.x.data(), n, p.data(), vel.data(), dt, skin,
              SegmentHits{f1.data(), t1.data(), u1.data(), v1.data(), l1.data()});
  cast_moving(ex, a, s0.x.data(), s1.x.data(), n, p.data(), vel.data(), dt, skin,
              SegmentHits{f2.data(), t2.data(), u2.data(), v2.data(), l2.data()});
  cast_moving(ex, b, s0.x.data(), s1.x.data(), n, p.data(), vel.data(), dt, skin,
              SegmentHits{f2.data(), t2.data(), u2.data(), v2.data(), l2.data()}, half, true);
  int hits = 0, from_b = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(
        same_hit(f2[i], f2[i] >= 0 ? t2[i] / l2[i] : 0, f1[i], f1[i] >= 0 ? t1[i] / l1[i] : 0))
        << "particle " << i;
    hits += f1[i] >= 0;
    from_b += f2[i] >= half;
  }
  EXPECT_GT(hits, 200);
  EXPECT_GT(from_b, 100);
  EXPECT_GT(hits - from_b, 50);
}

TEST_P(CollideBvh, SkinReachesFacesJustBeyondTheStep) {
  // Particles moving straight at a resting sphere and stopping short of it: within the skin
  // they hit (at the face's true distance), beyond it they do not. Their paths end outside
  // the tight leaf boxes of a resting mesh, so this needs the traversal to grow boxes by
  // the skin.
  const Surface s = surface_of(make_sphere(Vec3d(0, 0, 0), 0.5, 10));
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  bvh.refit(ex, s.x.data(), s.x.data());
  const BvhView bv = bvh.view();
  const Real skin = Real(0.01);
  std::mt19937 rng(17);
  for (int i = 0; i < 500; ++i) {
    const Vec3 dir = random_unit(rng);
    const Vec3 p = dir * Real(0.7);
    const RayHit wall = brute_ray(s, p, -dir, Real(INFINITY));
    ASSERT_GE(wall.face, 0);
    const Real gap = i % 2 ? Real(0.5) * skin : Real(1.5) * skin;  // left after the step
    const SegmentHit h = moving_nearest(bv, s.x.data(), s.x.data(), p, -dir * (wall.t - gap), skin);
    if (i % 2) {
      ASSERT_TRUE(same_hit(h.face, h.t, wall.face, wall.t)) << "particle " << i;
    } else {
      EXPECT_EQ(h.face, -1) << "particle " << i;
    }
  }
}

TEST_P(CollideBvh, FrontOnlyLetsParticlesOutOfABodyButNotIn) {
  // A sphere of radius 0.5 at rest; particles just inside and just outside its surface, moving
  // radially by 0.05 over the step. With front_only, the ray and the exact test let the inner
  // ones out (no hit) and still stop the outer ones moving in; without, both are hit.
  const Surface s = surface_of(make_sphere(Vec3d(0, 0, 0), 0.5, 10));
  SurfaceBvh<CpuExec> bvh;
  bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
  bvh.refit(ex, s.x.data(), s.x.data());
  const BvhView bv = bvh.view();
  std::mt19937 rng(23);
  for (int i = 0; i < 500; ++i) {
    const Vec3 d = random_unit(rng);
    const Vec3 in = d * Real(0.45), out = d * Real(0.55);
    const Vec3 leave = d * Real(0.1), enter = d * Real(-0.1);
    const Real tol = 1e-6f;
    EXPECT_GE(moving_nearest(bv, s.x.data(), s.x.data(), in, leave, 0).face, 0);
    EXPECT_EQ(moving_nearest(bv, s.x.data(), s.x.data(), in, leave, 0, true).face, -1) << i;
    EXPECT_GE(moving_nearest(bv, s.x.data(), s.x.data(), out, enter, 0, true).face, 0) << i;
    const ContactHit exit_all = moving_contact(bv, s.x.data(), s.x.data(), in, leave, tol);
    ASSERT_GE(exit_all.face, 0);
    EXPECT_EQ(exit_all.c.side, -1);
    EXPECT_EQ(moving_contact(bv, s.x.data(), s.x.data(), in, leave, tol, true).face, -1) << i;
    const ContactHit entry = moving_contact(bv, s.x.data(), s.x.data(), out, enter, tol, true);
    ASSERT_GE(entry.face, 0) << i;
    EXPECT_EQ(entry.c.side, 1);
  }
}

TEST_P(CollideBvh, ClosestPointsMatchBruteForceWithSign) {
  // Closest points within a radius equal brute force; the pseudonormal sign agrees with the
  // winding number, also near the cup's rims and concave edges and the box's corners.
  std::mt19937 rng(16);
  std::vector<Surface> surfaces = test_surfaces();
  surfaces.push_back(surface_of(make_box(Vec3d(-1, -1, -1), Vec3d(1, 1, 1), 4, 4, 4)));
  for (const Surface& s : surfaces) {
    SurfaceBvh<CpuExec> bvh;
    bvh.build(ex, s.x.data(), s.tris.data(), int(s.tris.size()), GetParam());
    Vec3 lo, hi;
    bounds(s.x, lo, hi);
    const Real radius = Real(0.15) * norm(hi - lo);
    std::vector<Vec3> p;
    for (int i = 0; i < 2000; ++i) p.push_back(random_in(rng, lo, hi, Real(0.2)));
    for (const Vec3& c : s.x) p.push_back(c + random_unit(rng) * Real(0.02) * radius);
    const int n = int(p.size());
    std::vector<int> face(n), side(n);
    std::vector<Real> dist(n), u(n), v(n);
    std::vector<Vec3> point(n);
    closest_points(
        ex, bvh, s.x.data(), n, p.data(), radius,
        ClosestHits{face.data(), dist.data(), point.data(), side.data(), u.data(), v.data()});
    int found = 0, signs = 0;
    for (int i = 0; i < n; ++i) {
      int bf = -1;
      const double d = brute_distance(s, p[i], &bf);
      if (d > radius) {
        EXPECT_EQ(face[i], -1) << i;
        continue;
      }
      ASSERT_GE(face[i], 0) << i;
      EXPECT_NEAR(dist[i], d, 1e-7) << i;
      // The reported face attains the distance, and the point is on it.
      const Tri& t = s.tris[face[i]];
      const Vec3 a = s.x[t.v[0]], b = s.x[t.v[1]], c = s.x[t.v[2]];
      EXPECT_NEAR(norm(p[i] - closest_on_triangle(p[i], a, b, c).point), d, 1e-7);
      EXPECT_LT(norm(point[i] - (a * (1 - u[i] - v[i]) + b * u[i] + c * v[i])), 1e-5);
      ++found;
      if (d < 1e-5) continue;  // on the surface, within rounding
      const bool in = winding_number(s, p[i]) > 0.5;
      ASSERT_EQ(side[i], in ? -1 : 1) << "point " << i << " at distance " << d;
      ++signs;
    }
    EXPECT_GT(found, 500);
    EXPECT_GT(signs, 500);
  }
}

INSTANTIATE_TEST_SUITE_P(Builds, CollideBvh, ::testing::Values(BvhBuild::Sah, BvhBuild::Lbvh),
                         [](const ::testing::TestParamInfo<BvhBuild>& i) {
                           return std::string(i.param == BvhBuild::Sah ? "Sah" : "Lbvh");
                         });

TEST(CollideBvhEdgeCases, EmptyAndSingleTriangle) {
  CpuExec ex;
  SurfaceBvh<CpuExec> bvh;
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::vector<Tri> tris = {Tri{{0, 1, 2}}};
  bvh.build(ex, x.data(), tris.data(), 0);
  EXPECT_EQ(ray_nearest(bvh.view(), x.data(), Vec3(0.2f, 0.2f, 1), Vec3(0, 0, -1), 10).face, -1);
  for (BvhBuild m : {BvhBuild::Sah, BvhBuild::Lbvh}) {
    bvh.build(ex, x.data(), tris.data(), 1, m);
    EXPECT_EQ(bvh.node_count(), 1);
    const RayHit h = ray_nearest(bvh.view(), x.data(), Vec3(0.2f, 0.2f, 1), Vec3(0, 0, -1), 10);
    EXPECT_EQ(h.face, 0);
    EXPECT_FLOAT_EQ(h.t, 1);
    EXPECT_EQ(closest_point(bvh.view(), x.data(), Vec3(0.2f, 0.2f, 1), 2).side, 1);
    EXPECT_EQ(closest_point(bvh.view(), x.data(), Vec3(0.2f, 0.2f, -1), 2).side, -1);
  }
}
