// Triangle-level collision primitives (include/sphfem/collide/geometry.h) against known
// answers: hit points and barycentrics, exactly-once hits at shared edges and vertices,
// closest points against dense sampling, and the moving-face test against the closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "sphfem/collide/geometry.h"

using namespace sphfem;
using namespace sphfem::collide;

TEST(CollideTriangle, HitPointDistanceAndBarycentrics) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  Real t, u, v;
  // Straight down onto (0.25, 0.5): weights 0.25 of b and 0.5 of c.
  ASSERT_TRUE(intersect_ray_triangle(Vec3(0.25, 0.5, 2), Vec3(0, 0, -1), a, b, c, 10, t, u, v));
  EXPECT_FLOAT_EQ(t, 2);
  EXPECT_FLOAT_EQ(u, 0.25);
  EXPECT_FLOAT_EQ(v, 0.5);
  // From below (back side) too, with t in units of an unnormalised direction.
  ASSERT_TRUE(intersect_ray_triangle(Vec3(0.25, 0.5, -2), Vec3(0, 0, 4), a, b, c, 10, t, u, v));
  EXPECT_FLOAT_EQ(t, 0.5);
  // Outside the triangle, beyond tmax, behind the origin, parallel to the plane.
  EXPECT_FALSE(intersect_ray_triangle(Vec3(0.75, 0.5, 2), Vec3(0, 0, -1), a, b, c, 10, t, u, v));
  EXPECT_FALSE(intersect_ray_triangle(Vec3(0.25, 0.5, 2), Vec3(0, 0, -1), a, b, c, 1.9, t, u, v));
  EXPECT_FALSE(intersect_ray_triangle(Vec3(0.25, 0.5, 2), Vec3(0, 0, 1), a, b, c, 10, t, u, v));
  EXPECT_FALSE(intersect_ray_triangle(Vec3(-1, 0.25, 0), Vec3(1, 0, 0), a, b, c, 10, t, u, v));
  // An oblique ray: the reported point lies on the ray.
  const Vec3 o(-0.3, 0.2, 0.9), d(0.5, 0.1, -1.2);
  ASSERT_TRUE(intersect_ray_triangle(o, d, a, b, c, 10, t, u, v));
  const Vec3 hit = o + d * t, on = a * (1 - u - v) + b * u + c * v;
  EXPECT_LT(norm(hit - on), 1e-6);
  EXPECT_NEAR(hit.z, 0, 1e-6);
}

TEST(CollideTriangle, FanAroundVertexIsHitExactlyOnce) {
  // A flat fan of 7 triangles around a centre vertex, both windings consistent. Rays aimed
  // at the centre vertex and at points on the spokes from random origins on both sides must
  // hit exactly one triangle: never zero (leak), never two (a double count breaks parity).
  const int nf = 7;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  const Vec3 centre(0.3125f, -0.1875f, 0.5f);
  const Vec3 e1 = Vec3(0.8f, 0.6f, 0.0f), e2 = Vec3(-0.36f, 0.48f, 0.8f);  // orthonormal
  std::vector<Vec3> rim(nf);
  for (int k = 0; k < nf; ++k) {
    const double ang = 2 * M_PI * (k + 0.3 * U(rng) + 0.5) / nf;
    rim[k] = centre + e1 * Real(std::cos(ang)) + e2 * Real(std::sin(ang));
  }
  const Vec3 n = cross(e1, e2);
  auto hits = [&](const Vec3& o, const Vec3& d) {
    int count = 0;
    for (int k = 0; k < nf; ++k) {
      Real t, u, v;
      count += intersect_ray_triangle(o, d, centre, rim[k], rim[(k + 1) % nf], 100, t, u, v);
    }
    return count;
  };
  int tested = 0;
  for (int i = 0; i < 2000; ++i) {
    const Real side = i % 2 ? Real(1) : Real(-1);
    const Vec3 o =
        centre + n * (side * Real(1 + U(rng))) + e1 * Real(0.7 * U(rng)) + e2 * Real(0.7 * U(rng));
    EXPECT_EQ(hits(o, centre - o), 1) << "ray " << i << " at the centre vertex";
    // A point on spoke k, at a dyadic fraction of its length.
    const int k = i % nf;
    const Vec3 q = centre + (rim[k] - centre) * Real(0.25 * (1 + i % 3));
    EXPECT_EQ(hits(o, q - o), 1) << "ray " << i << " at spoke " << k;
    tested += 2;
  }
  EXPECT_EQ(tested, 4000);
}

TEST(CollideTriangle, AxisRaysOnSharedDiagonalHitOneTriangle) {
  // A unit square split along its diagonal; rays along -z (and +z) through exact points of
  // the diagonal, including its ends, hit exactly one of the two triangles.
  const Vec3 p00(0, 0, 0), p10(1, 0, 0), p11(1, 1, 0), p01(0, 1, 0);
  for (int k = 0; k <= 16; ++k) {
    const Real s = Real(k) / 16;
    for (Real dz : {Real(-1), Real(1)}) {
      const Vec3 o(s, s, -dz), d(0, 0, dz);
      Real t, u, v;
      const int n = int(intersect_ray_triangle(o, d, p00, p10, p11, 10, t, u, v)) +
                    int(intersect_ray_triangle(o, d, p00, p11, p01, 10, t, u, v));
      // The square's corners on the diagonal are on its boundary: at most one hit there.
      if (k == 0 || k == 16) {
        EXPECT_LE(n, 1) << s;
      } else {
        EXPECT_EQ(n, 1) << s;
      }
    }
  }
}

TEST(CollideTriangle, ClosestPointBeatsDenseSampling) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 a(U(rng), U(rng), U(rng)), b(U(rng), U(rng), U(rng)), c(U(rng), U(rng), U(rng));
    const Vec3 p(2 * U(rng), 2 * U(rng), 2 * U(rng));
    const ClosestOnTriangle r = closest_on_triangle(p, a, b, c);
    // The point is on the triangle, at the reported barycentrics.
    EXPECT_GE(r.u, -1e-6);
    EXPECT_GE(r.v, -1e-6);
    EXPECT_LE(r.u + r.v, 1 + 1e-6);
    EXPECT_LT(norm(r.point - (a * (1 - r.u - r.v) + b * r.u + c * r.v)), 1e-5);
    // No sample of the triangle is closer.
    const double d = norm(p - r.point);
    const int m = 60;
    double best = 1e30;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        const Real u = Real(i) / m, v = Real(j) / m;
        best = std::min(best, double(norm(p - (a * (1 - u - v) + b * u + c * v))));
      }
    EXPECT_LE(d, best + 1e-5) << trial;
    EXPECT_GT(d, best - 0.05) << trial;  // and sampling gets near it
    // Region: a vertex feature means the point is that vertex, an edge one that the third
    // barycentric weight is zero.
    if (r.feature == kVertex0) { EXPECT_EQ(norm(r.point - a), 0); }
    if (r.feature == kEdge12) { EXPECT_NEAR(1 - r.u - r.v, 0, 1e-6); }
  }
}

TEST(CollideTriangle, MovingFaceTranslatingOntoRestingParticle) {
  // A face at z = 0.1 translating by -0.3 over the step sweeps over a particle at rest at
  // the origin: the relative motion is +0.3 along z, the hit 0.1 away at the time 1/3.
  const Vec3 a(-1, -1, 0.1), b(1, -1, 0.1), c(0, 1, 0.1), d(0, 0, -0.3);
  MovingHit h;
  ASSERT_TRUE(moving_triangle(Vec3(0, 0, 0), Vec3(), 0, a, b, c, d, d, d, h));
  EXPECT_NEAR(h.t, 0.1, 1e-6);
  EXPECT_NEAR(h.len, 0.3, 1e-6);
  EXPECT_NEAR(h.rel.z, 0.3, 1e-6);
  // The same face moving away, or stopping short of the particle, is no hit; a skin that
  // reaches it is one.
  EXPECT_FALSE(moving_triangle(Vec3(0, 0, 0), Vec3(), 0, a, b, c, -d, -d, -d, h));
  const Vec3 s(0, 0, -0.05);
  EXPECT_FALSE(moving_triangle(Vec3(0, 0, 0), Vec3(), 0, a, b, c, s, s, s, h));
  ASSERT_TRUE(moving_triangle(Vec3(0, 0, 0), Vec3(), 0.06f, a, b, c, s, s, s, h));
  EXPECT_NEAR(h.t, 0.1, 1e-6);
  // A particle moving with the face never meets it.
  EXPECT_FALSE(moving_triangle(Vec3(0, 0, 0), d, 0.01f, a, b, c, d, d, d, h));
}

TEST(CollideTriangle, MovingFaceUsesVelocityAtTheHitPoint) {
  // A face hinged at its edge x = -1 and swinging down: its points move in proportion to
  // x + 1. The refined cast uses the displacement at the hit's barycentrics, so the hit
  // distance is that of a face translating with the local velocity.
  const Vec3 a(-1, -1, 0.1), b(1, -1, 0.1), c(-1, 1, 0.1);
  const Vec3 da(0, 0, 0), db(0, 0, -0.4), dc(0, 0, 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < 200; ++i) {
    const Real px = Real(-1 + 1.5 * U(rng)), py = Real(-1 + 0.9 * (1 - px) * U(rng));
    const Vec3 p(px, py, 0);
    MovingHit h;
    const Real local = Real(0.2) * (px + 1);  // the face's downward displacement at (px, py)
    const bool hit = moving_triangle(p, Vec3(), 0, a, b, c, da, db, dc, h);
    if (local > Real(0.1) + 1e-4) {
      ASSERT_TRUE(hit) << px << " " << py;
      EXPECT_NEAR(h.t, 0.1, 1e-5);
      EXPECT_NEAR(h.len, local, 1e-5) << px;
    } else if (local < Real(0.1) - 1e-4) {
      EXPECT_FALSE(hit) << px << " " << py;
    }
  }
}

TEST(CollideTriangle, ExactContactOfATranslatingFace) {
  // The face of the test above, translating by -0.3 along z onto a particle at rest at the
  // origin: contact at a third of the step, at the particle's barycentrics, from behind the
  // face (its normal points to +z).
  const Vec3 a(-1, -1, 0.1), b(1, -1, 0.1), c(0, 1, 0.1), d(0, 0, -0.3);
  Crossing k;
  ASSERT_TRUE(point_face_contact(Vec3(), Vec3(), a, b, c, d, d, d, 1e-6f, 2, k));
  EXPECT_NEAR(k.tau, 1.0 / 3, 1e-6);
  const Vec3 q = a * (1 - k.u - k.v) + b * k.u + c * k.v;
  EXPECT_NEAR(q.x, 0, 1e-6);
  EXPECT_NEAR(q.y, 0, 1e-6);
  EXPECT_EQ(k.side, -1);
  // Moving away, stopping short, or moving with the particle: no contact.
  EXPECT_FALSE(point_face_contact(Vec3(), Vec3(), a, b, c, -d, -d, -d, 1e-6f, 2, k));
  const Vec3 s(0, 0, -0.05);
  EXPECT_FALSE(point_face_contact(Vec3(), Vec3(), a, b, c, s, s, s, 1e-6f, 2, k));
  EXPECT_FALSE(point_face_contact(Vec3(), d, a, b, c, d, d, d, 1e-6f, 2, k));
  // A particle ending exactly on the face touches it at the step's end; one passing the
  // face's plane beside the triangle does not.
  ASSERT_TRUE(
      point_face_contact(Vec3(), Vec3(0, 0, 0.1f), a, b, c, Vec3(), Vec3(), Vec3(), 1e-6f, 2, k));
  EXPECT_NEAR(k.tau, 1, 1e-6);
  EXPECT_FALSE(point_face_contact(Vec3(3, 0, 0), Vec3(), a, b, c, d, d, d, 1e-6f, 2, k));
  // A contact later than tau_max is not reported.
  EXPECT_FALSE(point_face_contact(Vec3(), Vec3(), a, b, c, d, d, d, 1e-6f, 0.3f, k));
}

// The earliest time in the step at which the point crosses the moving triangle's plane inside
// it, found by sampling the step finely (double, linear interpolation within a sample);
// -1 when none, -2 when a crossing lies too close to the triangle's boundary to tell.
double sampled_contact(const Vec3d& p, const Vec3d& dp, const Vec3d x0[3], const Vec3d dx[3]) {
  const int N = 20000;
  auto state = [&](double t, double& f, Vec3d& q) {
    const Vec3d a = x0[0] + dx[0] * t, b = x0[1] + dx[1] * t, c = x0[2] + dx[2] * t;
    const Vec3d pt = p + dp * t;
    const Vec3d n = cross(b - a, c - a);
    f = dot(pt - a, n) / norm(n);
    q = pt - n * (dot(pt - a, n) / dot(n, n));  // projection on the plane
    // Barycentrics of the projection.
    const Vec3d e1 = b - a, e2 = c - a, r = q - a;
    const double d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    const double r1 = dot(r, e1), r2 = dot(r, e2), det = d11 * d22 - d12 * d12;
    const double u = (d22 * r1 - d12 * r2) / det, v = (d11 * r2 - d12 * r1) / det;
    q = Vec3d(1 - u - v, u, v);
  };
  double f0;
  Vec3d q0;
  state(0, f0, q0);
  for (int k = 1; k <= N; ++k) {
    const double t = double(k) / N;
    double f1;
    Vec3d q1;
    state(t, f1, q1);
    if ((f0 < 0) != (f1 < 0)) {
      const double s = f0 / (f0 - f1);
      const Vec3d q = q0 + (q1 - q0) * s;
      const double m = std::min(q.x, std::min(q.y, q.z));
      if (std::fabs(m) < 1e-3) return -2;
      if (m > 0) return (k - 1 + s) / N;
    }
    f0 = f1, q0 = q1;
  }
  return -1;
}

TEST(CollideTriangle, ExactContactMatchesFineSamplingOfTurningFaces) {
  // Faces that turn, stretch and translate over the step, against particles moving by about
  // as much: the exact contact agrees with a fine sampling of the step, and the one-point
  // translation of moving_triangle misses some of the contacts it finds.
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> U(-1, 1);
  int contacts = 0, compared = 0, missed_by_translation = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Vec3d x0[3], dx[3];
    for (int k = 0; k < 3; ++k) {
      x0[k] = Vec3d(U(rng), U(rng), 0.2 * U(rng));
      dx[k] = Vec3d(0.6 * U(rng), 0.6 * U(rng), 1.2 * U(rng));
    }
    const Vec3d p(0.3 * U(rng), 0.3 * U(rng), 0.6 * U(rng)),
        dp(0.3 * U(rng), 0.3 * U(rng), 0.3 * U(rng));
    // Inputs in float, as the simulation has them; the reference sees the same values.
    Vec3 xf[3], df[3];
    for (int k = 0; k < 3; ++k)
      xf[k] = Vec3(x0[k]), df[k] = Vec3(dx[k]), x0[k] = Vec3d(xf[k]), dx[k] = Vec3d(df[k]);
    const Vec3 pf(p), dpf(dp);
    const double ref = sampled_contact(Vec3d(pf), Vec3d(dpf), x0, dx);
    if (ref == -2) continue;
    Crossing k;
    const bool hit =
        point_face_contact(pf, dpf, xf[0], xf[1], xf[2], df[0], df[1], df[2], 1e-6f, 2, k);
    ++compared;
    ASSERT_EQ(hit, ref >= 0) << "trial " << trial << " reference " << ref << " tau " << k.tau;
    if (!hit) continue;
    ++contacts;
    EXPECT_NEAR(k.tau, ref, 2e-4) << "trial " << trial;
    MovingHit m;
    if (!moving_triangle(pf, dpf, 0, xf[0], xf[1], xf[2], df[0], df[1], df[2], m))
      ++missed_by_translation;
  }
  EXPECT_GT(compared, 3500);
  EXPECT_GT(contacts, 300);
  EXPECT_GT(missed_by_translation, 0);
  std::printf("%d contacts of %d cases; the translating cast misses %d\n", contacts, compared,
              missed_by_translation);
}
