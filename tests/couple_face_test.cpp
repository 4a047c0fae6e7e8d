// One particle against one face: the exchange of couple/impulse.h through Coupler::apply
// against conservation laws and the paper's closed form. A free triangle of three nodes with
// unequal masses and velocities; a static face; a real body solver taking the impulses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "couple_harness.h"
#include "sphfem/couple/coupler.h"
#include "sphfem/fem/solver.h"

using namespace sphfem;
using testing_couple::Contact;

namespace {

const Vec3d kNodeX[3] = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0)};  // normal +z
const double kNodeM[3] = {0.5, 1.0, 2.0};
const Vec3d kNodeV[3] = {Vec3d(0.1, 0.2, 0.3), Vec3d(-0.2, 0.1, 0.4), Vec3d(0.05, -0.1, 0.2)};
constexpr double kParticleM = 0.3;
const Vec3d kParticleV(0.7, -0.4, -1.5);

// A particle `height` in front of the point (1 - u - v, u, v) of the free triangle.
Contact free_face(double u, double v, ContactCoeffs c, Vec3d vp = kParticleV,
                  double height = 0.02) {
  Contact k;
  for (int j = 0; j < 3; ++j) {
    k.xn.push_back(Vec3(kNodeX[j]));
    k.vn.push_back(Vec3(kNodeV[j]));
    k.mn.push_back(Real(kNodeM[j]));
  }
  k.tris.push_back(Tri{{0, 1, 2}});
  k.coeffs = {c};
  k.mass = Real(kParticleM);
  const Vec3d at = kNodeX[0] * (1 - u - v) + kNodeX[1] * u + kNodeX[2] * v;
  k.add_particle(Vec3(at + Vec3d(0, 0, height)), Vec3(vp), 0, Real(u), Real(v));
  return k;
}

Vec3d node_v_after(const Contact& k, int j) {
  return Vec3d(k.vn[j]) + Vec3d(k.impulse[j]) / double(k.mn[j]);
}

// Face velocity at the hit point minus the particle's, before or after the exchange.
Vec3d relative(const Contact& k, double u, double v, bool after, const Vec3d& vp_before) {
  const double w[3] = {1 - u - v, u, v};
  Vec3d vf;
  for (int j = 0; j < 3; ++j) vf += (after ? node_v_after(k, j) : Vec3d(k.vn[j])) * w[j];
  return vf - (after ? Vec3d(k.vp[0]) : vp_before);
}

Vec3d momentum(const Contact& k, bool after, const Vec3d& vp_before) {
  Vec3d p = (after ? Vec3d(k.vp[0]) : vp_before) * double(k.mass);
  for (int j = 0; j < 3; ++j) p += (after ? node_v_after(k, j) : Vec3d(k.vn[j])) * kNodeM[j];
  return p;
}

// sum |m v| over the particle and the nodes: the size of the momenta that round-off acts on.
double momentum_scale() {
  double s = kParticleM * norm(kParticleV);
  for (int j = 0; j < 3; ++j) s += kNodeM[j] * norm(kNodeV[j]);
  return s;
}

double kinetic(const Contact& k, bool after, const Vec3d& vp_before) {
  double e = 0.5 * double(k.mass) * norm2(after ? Vec3d(k.vp[0]) : vp_before);
  for (int j = 0; j < 3; ++j)
    e += 0.5 * kNodeM[j] * norm2(after ? node_v_after(k, j) : Vec3d(k.vn[j]));
  return e;
}

ContactCoeffs coeffs(double cr, double cs) {
  ContactCoeffs c;
  c.restitution = Real(cr);
  c.slip = Real(cs);
  return c;
}

// Float round-off bound for sums of a few products of O(1) numbers: 8 ulps of the scale.
constexpr double kRoundOff = 8 * 1.2e-7;

struct Hit {
  double u, v;
};
const Hit kHits[] = {{0, 0}, {1, 0}, {0, 1}, {1.0 / 3, 1.0 / 3}, {0.15, 0.6}, {0.5, 0.5}};

class CoupleFace : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    const std::string why = testing_couple::unusable(GetParam());
    if (!why.empty()) GTEST_SKIP() << why;
    coupler_ = make_coupler(GetParam());
  }
  std::unique_ptr<Coupler> coupler_;
};

TEST_P(CoupleFace, MomentumIsConservedExactly) {
  for (const Hit& h : kHits)
    for (double cr : {0.0, 0.4, 1.0})
      for (double cs : {0.0, 0.7, 1.0}) {
        Contact k = free_face(h.u, h.v, coeffs(cr, cs));
        const CoupleStats st = k.apply(*coupler_, GetParam());
        ASSERT_EQ(st.exchanges, 1);
        const Vec3d p0 = momentum(k, false, kParticleV), p1 = momentum(k, true, kParticleV);
        const double scale = momentum_scale();
        EXPECT_LT(norm(p1 - p0), kRoundOff * scale) << "u " << h.u << " v " << h.v;
        // The statistics report the impulse the body received: what the particle lost.
        const Vec3d lost = (kParticleV - Vec3d(k.vp[0])) * kParticleM;
        EXPECT_LT(norm(st.body_impulse.at(0) - lost), kRoundOff * scale);
      }
}

TEST_P(CoupleFace, RestitutionSetsTheNormalRelativeVelocity) {
  const Vec3d n(0, 0, 1);
  for (const Hit& h : kHits)
    for (double cr : {0.0, 0.5, 1.0}) {
      Contact k = free_face(h.u, h.v, coeffs(cr, 0.6));
      k.apply(*coupler_, GetParam());
      const double before = dot(relative(k, h.u, h.v, false, kParticleV), n);
      const double after = dot(relative(k, h.u, h.v, true, kParticleV), n);
      ASSERT_GT(before, 0.5);  // approaching
      EXPECT_NEAR(after, -cr * before, 1e-5 * before) << "C_r " << cr;
    }
}

TEST_P(CoupleFace, SlipSetsTheTangentialRelativeVelocity) {
  const Vec3d n(0, 0, 1);
  for (const Hit& h : kHits)
    for (double cs : {0.0, 0.5, 1.0}) {
      Contact k = free_face(h.u, h.v, coeffs(0.3, cs));
      k.apply(*coupler_, GetParam());
      const Vec3d b = relative(k, h.u, h.v, false, kParticleV);
      const Vec3d a = relative(k, h.u, h.v, true, kParticleV);
      const Vec3d bt = b - n * dot(b, n), at = a - n * dot(a, n);
      ASSERT_GT(norm(bt), 0.5);
      EXPECT_LT(norm(at - bt * cs), 1e-5 * norm(bt)) << "C_s " << cs;
    }
}

// With 1/m_f = sum w_j^2 / m_j the exchange is an elastic collision of the particle with the
// lumped nodes wherever it hits; the paper's m_face = mean(m_j) would fail at the centre.
TEST_P(CoupleFace, ElasticContactKeepsKineticEnergy) {
  for (const Hit& h : kHits) {
    Contact k = free_face(h.u, h.v, coeffs(1, 1));
    k.apply(*coupler_, GetParam());
    const double e0 = kinetic(k, false, kParticleV), e1 = kinetic(k, true, kParticleV);
    EXPECT_NEAR(e1, e0, 1e-5 * e0) << "u " << h.u << " v " << h.v;
    EXPECT_GT(norm(Vec3d(k.vp[0]) - kParticleV), 0.5);  // it did bounce
  }
}

// Paper eq. 14, v+ = (m_i v_i + E_face - C (m_face v_i - E_face)) / (m_i + m_face), per
// direction: C = C_r along the normal; along the face C = -C_s (DESIGN.md correction 1, the
// slip keeps the relative tangential velocity). Face mass and velocity at the hit point.
TEST_P(CoupleFace, SingleParticleFollowsPaperEq14) {
  const Vec3d n(0, 0, 1);
  for (const Hit& h : kHits) {
    const double cr = 0.6, cs = 0.3;
    Contact k = free_face(h.u, h.v, coeffs(cr, cs));
    k.apply(*coupler_, GetParam());
    const double w[3] = {1 - h.u - h.v, h.u, h.v};
    double inv_mf = 0;
    Vec3d vf;
    for (int j = 0; j < 3; ++j) {
      inv_mf += w[j] * w[j] / kNodeM[j];
      vf += kNodeV[j] * w[j];
    }
    const double mf = 1 / inv_mf, mi = kParticleM;
    auto eq14 = [&](double vi, double vface, double C) {
      return (mi * vi + mf * vface - C * (mf * vi - mf * vface)) / (mi + mf);
    };
    const Vec3d vi = kParticleV;
    const Vec3d vin = n * dot(vi, n), vfn = n * dot(vf, n);
    const Vec3d vit = vi - vin, vft = vf - vfn;
    Vec3d expect = n * eq14(dot(vi, n), dot(vf, n), cr);
    for (int c = 0; c < 3; ++c) expect[c] += eq14(vit[c], vft[c], -cs);
    EXPECT_LT(norm(Vec3d(k.vp[0]) - expect), 1e-5 * norm(vi)) << "u " << h.u << " v " << h.v;
  }
}

TEST_P(CoupleFace, SeparatingContactExchangesNothing) {
  // In front, moving away faster than the face follows; behind, moving away from the back.
  for (double side : {1.0, -1.0}) {
    Contact k = free_face(0.2, 0.3, coeffs(1, 0), Vec3d(0.4, 0.3, 2.0 * side), 0.02 * side);
    const Vec3 v0 = k.vp[0];
    const CoupleStats st = k.apply(*coupler_, GetParam());
    EXPECT_EQ(st.contacts, 1);
    EXPECT_EQ(st.exchanges, 0);
    EXPECT_EQ(k.vp[0].x, v0.x);
    EXPECT_EQ(k.vp[0].y, v0.y);
    EXPECT_EQ(k.vp[0].z, v0.z);
    for (const Vec3& J : k.impulse) EXPECT_EQ(norm(J), 0.0f);
  }
}

// Behind the face and moving into its back: the normal toward the particle is -z.
TEST_P(CoupleFace, ContactFromBehindPushesTheFaceForward) {
  Contact k = free_face(0.2, 0.3, coeffs(1, 1), Vec3d(0, 0, 3.0), -0.02);
  const CoupleStats st = k.apply(*coupler_, GetParam());
  EXPECT_EQ(st.exchanges, 1);
  EXPECT_LT(k.vp[0].z, 0.0f);
  EXPECT_GT(st.body_impulse.at(0).z, 0.0);
  const double e0 = kinetic(k, false, Vec3d(0, 0, 3.0)), e1 = kinetic(k, true, Vec3d(0, 0, 3.0));
  EXPECT_NEAR(e1, e0, 1e-5 * e0);
}

// Infinite mass: the particle reflects with the restitution and keeps C_s of its tangential
// velocity; a static collider and a triangle of pinned nodes give the same answer.
TEST_P(CoupleFace, StaticFaceReflectsTheParticle) {
  const Vec3d vp(1.0, 0.5, -2.0);
  const Vec3d expect(0.8, 0.4, 1.0);  // C_r = 0.5, C_s = 0.8
  for (bool pinned : {false, true}) {
    Contact k = free_face(0.25, 0.25, coeffs(0.5, 0.8), vp);
    if (pinned)
      k.pinned.assign(3, 1), k.vn.assign(3, Vec3());  // the body solver holds pinned nodes
    else
      k.mn.clear(), k.vn.clear();  // static collider: no mass, velocity or impulses
    const std::vector<Vec3> x0 = k.xn;
    const CoupleStats st = k.apply(*coupler_, GetParam());
    EXPECT_LT(norm(Vec3d(k.vp[0]) - expect), 1e-6) << (pinned ? "pinned" : "static");
    // What the wall took: the particle's momentum change, for wall-force gauges.
    EXPECT_LT(norm(st.body_impulse.at(0) - (vp - expect) * kParticleM), 1e-6);
    for (int j = 0; j < 3; ++j) EXPECT_EQ(norm(Vec3d(k.xn[j]) - Vec3d(x0[j])), 0.0);
  }
}

// A contact held at a separation speed b (HitArrays::bias, the near-surface pressure's push
// handed to the exchange): against an immovable face the particle leaves at exactly b; against
// the free triangle it leaves at b relative to the face's new velocity, momentum exact, with a
// push that never pulls: a particle already leaving faster than b keeps its velocity.
TEST_P(CoupleFace, HeldSeparationSpeedIsMetAndNeverPulls) {
  const double u = 0.2, v = 0.3, b = 0.4;
  const Vec3d vp(0.3, -0.2, -0.9);
  Contact fixed = free_face(u, v, coeffs(1, 0.5), vp);
  fixed.mn.clear(), fixed.vn.clear();
  fixed.bias = {Real(b)};
  fixed.apply(*coupler_, GetParam());
  // The normal only: the tangential velocity and the restitution law play no part.
  EXPECT_LT(norm(Vec3d(fixed.vp[0]) - Vec3d(vp.x, vp.y, b)), 1e-6);

  Contact k = free_face(u, v, coeffs(1, 0.5), vp);
  k.bias = {Real(b)};
  const CoupleStats st = k.apply(*coupler_, GetParam());
  EXPECT_EQ(st.exchanges, 1);
  EXPECT_NEAR(-relative(k, u, v, true, vp).z, b, 1e-5);
  EXPECT_NEAR(k.vp[0].x, vp.x, 1e-6);
  EXPECT_LT(norm(momentum(k, true, vp) - momentum(k, false, vp)), 1e-6);
  EXPECT_LT(st.body_impulse.at(0).z, 0.0);  // pushed away from the particle

  Contact away = free_face(u, v, coeffs(1, 0.5), Vec3d(0, 0, 2.0));
  away.bias = {Real(b)};
  EXPECT_EQ(away.apply(*coupler_, GetParam()).exchanges, 0);
  EXPECT_EQ(away.vp[0].z, 2.0f);

  // NaN: the law, as with no bias at all.
  Contact law = free_face(u, v, coeffs(1, 0.5), vp), plain = free_face(u, v, coeffs(1, 0.5), vp);
  law.bias = {Real(NAN)};
  law.apply(*coupler_, GetParam());
  plain.apply(*coupler_, GetParam());
  EXPECT_EQ(norm(Vec3d(law.vp[0]) - Vec3d(plain.vp[0])), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Backends, CoupleFace, ::testing::Values(Backend::Cpu, Backend::Cuda),
                         testing_couple::backend_name);

// The body solver takes the node impulses into its next step: a free body's momentum grows by
// exactly what the particle lost (no gravity or damping; the elastic forces sum to zero), and
// a fully pinned body does not move.
TEST(CoupleBody, SolverTakesTheImpulses) {
  for (bool pinned : {false, true}) {
    FemSettings set;
    set.gravity = Vec3d(0, 0, 0);
    // The step adds the impulses to its right-hand side; the momentum it gives the nodes is
    // that sum minus the sum of the CG residual, so the residual must be small here.
    set.cg_tolerance = 1e-6;
    set.cg_max_iterations = 1000;
    Material mat;
    mat.young = 1e4;
    const TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(0.1, 0.1, 0.1), 2, 2, 2);
    std::vector<std::uint8_t> pins;
    if (pinned) pins.assign(box.x.size(), 1);
    const BodiesModel model = compile_bodies({compile_body(box, mat, pins)}, set);
    auto body = make_body_solver(model, Backend::Cpu);
    auto coupler = make_coupler(Backend::Cpu);
    BodyArrays arrays = body->arrays();
    std::vector<CoupleSurface> surfaces = {body_surface(arrays, model, {coeffs(0.5, 1)})};
    // The top face (y = 0.1) nearest the middle, hit from above by a falling particle.
    int top = -1;
    for (int f = 0; f < int(model.surface.size()); ++f) {
      const Tri t = model.surface[f];
      bool up = true;
      for (int c = 0; c < 3; ++c) up = up && model.x0[t.v[c]].y > Real(0.0999);
      if (up) top = f;
    }
    ASSERT_GE(top, 0);
    const Tri t = model.surface[top];
    const Vec3 hit = (model.x0[t.v[0]] + model.x0[t.v[1]] + model.x0[t.v[2]]) / Real(3);
    std::vector<Vec3> xp = {hit + Vec3(0, Real(0.002), 0)}, vp = {Vec3(0.2f, -3.0f, 0)};
    std::vector<int> face = {top};
    std::vector<Real> tt = {0}, u = {Real(1) / 3}, v = {Real(1) / 3};
    HitArrays h{MemSpace::Host, face.data(), tt.data(), u.data(), v.data()};
    FluidArrays f;
    f.n = 1, f.x = xp.data(), f.v = vp.data(), f.mass = Real(0.01), f.radius = Real(0.002);
    BodySnapshot s0, s1;
    body->snapshot(s0);
    const Vec3d p_particle0 = Vec3d(vp[0]) * double(f.mass);
    const CoupleStats st = coupler->apply(h, f, surfaces);
    ASSERT_EQ(st.exchanges, 1);
    const Vec3d lost = p_particle0 - Vec3d(vp[0]) * double(f.mass);
    EXPECT_LT(lost.y, 0.0);  // the particle bounced up: the body took momentum along -y
    body->step(1e-3);
    body->snapshot(s1);
    Vec3d dp;
    double moved = 0;
    for (int i = 0; i < s0.n; ++i) {
      dp += (Vec3d(s1.v[i]) - Vec3d(s0.v[i])) * double(model.mass[i]);
      moved = std::max(moved, double(norm(s1.x[i] - s0.x[i])));
    }
    if (pinned) {
      EXPECT_EQ(moved, 0.0);
    } else {
      std::printf("body momentum change %.6g %.6g %.6g, particle lost %.6g %.6g %.6g\n", dp.x, dp.y,
                  dp.z, lost.x, lost.y, lost.z);
      EXPECT_LT(norm(dp - lost), 1e-5 * norm(lost));
      EXPECT_NEAR(st.body_impulse.at(0).y, lost.y, 1e-6 * norm(lost));
    }
  }
}

}  // namespace
