// Many particles on many faces of a mesh whose nodes are shared, plus a static collider:
// grouping by face (radix sort, run starts) against a brute-force per-face grouping in double
// precision, and total linear momentum conserved to float round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "couple_harness.h"
#include "sphfem/couple/coupler.h"

using namespace sphfem;
using testing_couple::from_space;
using testing_couple::to_space;

namespace {

// One triangle set on the host; mass empty = static collider.
struct Mesh {
  std::vector<Vec3> x, v, impulse;
  std::vector<Real> m;
  std::vector<Tri> tri;
  std::vector<int> tri_offset;
  std::vector<ContactCoeffs> coeffs;
};

// g x g quads over [0, 1]^2 at height z = bump(x, y), two triangles each; every inner node is
// shared by six faces. Two bodies: the first and second half of the triangles.
Mesh grid_mesh(int g, std::mt19937& rng) {
  std::uniform_real_distribution<double> mass(0.5, 2.0), vel(-0.3, 0.3);
  Mesh k;
  for (int j = 0; j <= g; ++j)
    for (int i = 0; i <= g; ++i) {
      const double x = double(i) / g, y = double(j) / g;
      k.x.push_back(Vec3(Vec3d(x, y, 0.05 * std::sin(6 * x) * std::cos(5 * y))));
      k.v.push_back(Vec3(Vec3d(vel(rng), vel(rng), vel(rng))));
      k.m.push_back(Real(mass(rng)));
    }
  for (int j = 0; j < g; ++j)
    for (int i = 0; i < g; ++i) {
      const int a = j * (g + 1) + i, b = a + 1, c = a + g + 1, d = c + 1;
      k.tri.push_back(Tri{{a, b, d}});
      k.tri.push_back(Tri{{a, d, c}});
    }
  k.tri_offset = {0, int(k.tri.size()) / 2, int(k.tri.size())};
  ContactCoeffs c0, c1;
  c0.restitution = Real(0.3), c0.slip = Real(0.8);
  c1.restitution = Real(1.0), c1.slip = Real(0.0);
  k.coeffs = {c0, c1};
  k.impulse.assign(k.x.size(), Vec3());
  return k;
}

// A static wall: two triangles in the plane x = 1.2.
Mesh wall() {
  Mesh k;
  k.x = {Vec3(1.2f, 0, -1), Vec3(1.2f, 2, -1), Vec3(1.2f, 2, 1), Vec3(1.2f, 0, 1)};
  k.tri = {Tri{{0, 1, 2}}, Tri{{0, 2, 3}}};
  ContactCoeffs c;
  c.restitution = Real(0.5), c.slip = Real(0.5);
  k.coeffs = {c};
  return k;
}

struct Particles {
  std::vector<Vec3> x, v;
  std::vector<int> face;
  std::vector<Real> t, u, w;
  Real mass = Real(0.05);
};

Vec3d node(const Mesh& k, int f, int c) { return Vec3d(k.x[k.tri[f].v[c]]); }
Vec3d normal(const Mesh& k, int f) {
  const Vec3d n = cross(node(k, f, 1) - node(k, f, 0), node(k, f, 2) - node(k, f, 0));
  return n / norm(n);
}

// Particles in front of or behind random faces (a few faces take most), some without a hit.
Particles scatter(const Mesh& dyn, const Mesh& stat, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> uni(0.0, 1.0), vel(-1.0, 1.0);
  const int hot = 150;  // faces that take most hits: ~20 particles each
  std::vector<int> hot_faces;
  for (int i = 0; i < hot; ++i) hot_faces.push_back(int(uni(rng) * dyn.tri.size()));
  Particles p;
  for (int i = 0; i < count; ++i) {
    const double r = uni(rng);
    const Vec3d vr(vel(rng), vel(rng), vel(rng));
    if (r < 0.1) {  // no hit
      p.x.push_back(Vec3(Vec3d(uni(rng), uni(rng), 0.5)));
      p.v.push_back(Vec3(vr));
      p.face.push_back(-1);
      p.t.push_back(0), p.u.push_back(0), p.w.push_back(0);
      continue;
    }
    const bool on_wall = r < 0.15;
    const Mesh& k = on_wall ? stat : dyn;
    const int local = on_wall   ? int(uni(rng) * 2)
                      : r < 0.8 ? hot_faces[int(uni(rng) * hot)]
                                : int(uni(rng) * dyn.tri.size());
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Vec3d at =
        node(k, local, 0) * (1 - a - b) + node(k, local, 1) * a + node(k, local, 2) * b;
    const double side = uni(rng) < 0.7 ? 1.0 : -1.0;
    const Vec3d n = normal(k, local) * side;
    p.x.push_back(Vec3(at + n * (0.002 + 0.008 * uni(rng))));
    p.v.push_back(Vec3(vr - n * 0.6));  // mostly approaching; some groups separate
    p.face.push_back(on_wall ? int(dyn.tri.size()) + local : local);
    p.t.push_back(Real(0.01)), p.u.push_back(Real(a)), p.w.push_back(Real(b));
  }
  return p;
}

struct Reference {
  std::vector<Vec3d> v, impulse;
  std::vector<Vec3d> body_impulse;
  std::vector<double> body_magnitude;  // sum |J| per body
  int faces = 0, exchanges = 0;
};

// Brute force: for every face and side, scan all particles for those on it, and apply the
// exchange written out in double (the derivation in couple/impulse.h).
Reference brute_force(const Mesh& dyn, const Mesh& stat, const Particles& p) {
  Reference ref;
  for (const Vec3& v : p.v) ref.v.push_back(Vec3d(v));
  ref.impulse.assign(dyn.x.size(), Vec3d());
  ref.body_impulse.assign(3, Vec3d());
  ref.body_magnitude.assign(3, 0.0);
  const int nd = int(dyn.tri.size());
  const double M1 = double(p.mass);
  for (int f = 0; f < nd + int(stat.tri.size()); ++f) {
    const bool is_static = f >= nd;
    const Mesh& k = is_static ? stat : dyn;
    const int local = is_static ? f - nd : f;
    const int body = is_static ? 2 : (local < dyn.tri_offset[1] ? 0 : 1);
    const ContactCoeffs c = is_static ? stat.coeffs[0] : dyn.coeffs[body];
    bool touched = false;
    for (int side = 0; side < 2; ++side) {
      const Vec3d n = normal(k, local) * (side ? -1.0 : 1.0);
      std::vector<int> on;
      for (int i = 0; i < int(p.x.size()); ++i) {
        if (p.face[i] != f) continue;
        const double w0 = 1 - double(p.u[i]) - double(p.w[i]);
        const Vec3d at = node(k, local, 0) * w0 + node(k, local, 1) * double(p.u[i]) +
                         node(k, local, 2) * double(p.w[i]);
        if (dot(Vec3d(p.x[i]) - at, n) > 0) on.push_back(i);
      }
      if (on.empty()) continue;
      touched = true;
      const double K = double(on.size());
      Vec3d vp;
      double W[3] = {0, 0, 0};
      for (int i : on) {
        vp += Vec3d(p.v[i]) / K;
        W[0] += (1 - double(p.u[i]) - double(p.w[i])) / K;
        W[1] += double(p.u[i]) / K;
        W[2] += double(p.w[i]) / K;
      }
      double inv_mf = 0;
      Vec3d vf;
      if (!is_static)
        for (int c3 = 0; c3 < 3; ++c3) {
          const int j = k.tri[local].v[c3];
          inv_mf += W[c3] * W[c3] / double(k.m[j]);
          vf += Vec3d(k.v[j]) * W[c3];
        }
      const Vec3d dv = vf - vp;
      const double dn = dot(dv, n);
      if (dn <= 0) continue;
      ++ref.exchanges;
      const double inv_M = 1 / (K * M1);
      const Vec3d dvt = dv - n * dn;
      const Vec3d J =
          (n * (-(1 + double(c.restitution)) * dn) - dvt * (1 - double(c.slip))) / (inv_mf + inv_M);
      for (int i : on) ref.v[i] -= J * inv_M;
      if (!is_static)
        for (int c3 = 0; c3 < 3; ++c3) ref.impulse[k.tri[local].v[c3]] += J * W[c3];
      ref.body_impulse[body] += J;
      ref.body_magnitude[body] += norm(J);
    }
    ref.faces += touched;
  }
  return ref;
}

class CoupleGrouping : public ::testing::TestWithParam<Backend> {};

TEST_P(CoupleGrouping, MatchesBruteForceAndConservesMomentum) {
  const std::string why = testing_couple::unusable(GetParam());
  if (!why.empty()) GTEST_SKIP() << why;
  std::mt19937 rng(7);
  Mesh dyn = grid_mesh(24, rng);  // 1152 triangles, 625 nodes
  const Mesh stat = wall();
  const Particles p = scatter(dyn, stat, 4000, rng);
  const Reference ref = brute_force(dyn, stat, p);

  const MemSpace s = testing_couple::space_of(GetParam());
  auto bx = to_space(s, p.x), bv = to_space(s, p.v);
  auto bface = to_space(s, p.face);
  auto bt = to_space(s, p.t), bu = to_space(s, p.u), bw = to_space(s, p.w);
  auto dx = to_space(s, dyn.x), dv = to_space(s, dyn.v);
  auto dm = to_space(s, dyn.m);
  auto dimp = to_space(s, dyn.impulse);
  auto dtri = to_space(s, dyn.tri);
  auto sx = to_space(s, stat.x);
  auto stri = to_space(s, stat.tri);
  CoupleSurface a;
  a.space = s;
  a.nodes = int(dyn.x.size()), a.triangles = int(dyn.tri.size());
  a.tri = dtri.data(), a.x = dx.data(), a.v = dv.data(), a.mass = dm.data();
  a.impulse = dimp.data();
  a.tri_offset = dyn.tri_offset;
  a.coeffs = dyn.coeffs;
  const CoupleSurface b = static_surface(s, int(stat.x.size()), sx.data(), int(stat.tri.size()),
                                         stri.data(), stat.coeffs[0]);
  HitArrays h{s, bface.data(), bt.data(), bu.data(), bw.data()};
  FluidArrays f;
  f.space = s;
  f.n = int(p.x.size()), f.x = bx.data(), f.v = bv.data(), f.mass = p.mass;
  auto coupler = make_coupler(GetParam());
  const CoupleStats st = coupler->apply(h, f, {a, b});
  std::vector<Vec3> v_after(p.v.size());
  from_space(bv, v_after);
  from_space(dimp, dyn.impulse);

  // Grouping: the same groups, the same exchanges.
  int hits = 0;
  for (int fi : p.face) hits += fi >= 0;
  std::printf("%d hits on %d faces, %d exchanges\n", hits, ref.faces, ref.exchanges);
  EXPECT_EQ(st.contacts, hits);
  EXPECT_EQ(st.faces, ref.faces);
  EXPECT_EQ(st.exchanges, ref.exchanges);
  ASSERT_GT(ref.exchanges, 100);
  double vmax = 0, jmax = 0, dvmax = 0, djmax = 0;
  for (std::size_t i = 0; i < v_after.size(); ++i) {
    vmax = std::max(vmax, norm(ref.v[i]));
    dvmax = std::max(dvmax, norm(Vec3d(v_after[i]) - ref.v[i]));
  }
  for (std::size_t j = 0; j < dyn.impulse.size(); ++j) {
    jmax = std::max(jmax, norm(ref.impulse[j]));
    djmax = std::max(djmax, norm(Vec3d(dyn.impulse[j]) - ref.impulse[j]));
  }
  std::printf("max |dv| %.3g of %.3g, max |dJ| %.3g of %.3g\n", dvmax, vmax, djmax, jmax);
  EXPECT_LT(dvmax, 1e-5 * vmax);  // float against double: a few ulps of the largest value
  EXPECT_LT(djmax, 1e-5 * jmax);
  ASSERT_EQ(st.body_impulse.size(), 3u);
  for (int bi = 0; bi < 3; ++bi)
    EXPECT_LT(norm(st.body_impulse[bi] - ref.body_impulse[bi]), 1e-5 * ref.body_magnitude[bi])
        << "body " << bi;

  // Momentum: what the particles lost went into the nodes or the static wall. Each term is
  // rounded a few times with relative error 2^-24 of itself, so the float error is at most
  // about 4 * 6e-8 * sum |m v| of everything involved; 1e-6 of that scale leaves a factor 4.
  Vec3d dp;
  double scale = 0;
  for (std::size_t i = 0; i < p.v.size(); ++i) {
    dp += (Vec3d(v_after[i]) - Vec3d(p.v[i])) * double(p.mass);
    scale += double(p.mass) * (norm(Vec3d(p.v[i])) + norm(Vec3d(v_after[i])));
  }
  for (std::size_t j = 0; j < dyn.x.size(); ++j) {
    dp += Vec3d(dyn.impulse[j]);
    scale += double(dyn.m[j]) * norm(Vec3d(dyn.v[j])) + norm(Vec3d(dyn.impulse[j]));
  }
  dp += st.body_impulse[2];
  std::printf("momentum error %.3g of scale %.3g (%.2g)\n", norm(dp), scale, norm(dp) / scale);
  EXPECT_LT(norm(dp), 1e-6 * scale);
}

INSTANTIATE_TEST_SUITE_P(Backends, CoupleGrouping, ::testing::Values(Backend::Cpu, Backend::Cuda),
                         testing_couple::backend_name);

}  // namespace
