// Test helper for the coupling: particles, hits and one triangle set kept on the host, copied
// to the coupler's memory space for a call and back, so every test runs on every backend.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sphfem/core/memory.h"
#include "sphfem/couple/coupler.h"

namespace sphfem::testing_couple {

inline MemSpace space_of(Backend b) {
  return b == Backend::Cuda ? MemSpace::Device : MemSpace::Host;
}

inline std::string backend_name(const ::testing::TestParamInfo<Backend>& i) {
  return i.param == Backend::Cuda ? "Cuda" : "Cpu";
}

// Why the backend cannot run here, or "" when it can.
inline std::string unusable(Backend b) {
  std::string why;
  if (b == Backend::Cuda && !cuda_available(&why)) return why.empty() ? "no CUDA" : why;
  return "";
}

template <class T>
Buffer<T> to_space(MemSpace s, const std::vector<T>& v) {
  Buffer<T> b(s, v.empty() ? 1 : v.size());
  if (!v.empty()) b.upload(v.data(), v.size());
  return b;
}

template <class T>
void from_space(const Buffer<T>& b, std::vector<T>& v) {
  if (!v.empty()) b.download(v.data(), v.size());
}

// One call's worth of data on the host.
struct Contact {
  // particles and their hits
  std::vector<Vec3> xp, vp;
  Real mass = 1;
  std::vector<int> face;
  std::vector<Real> t, u, v;
  std::vector<Real> bias;  // HitArrays::bias; empty: none
  // one triangle set; mass empty = static collider (infinite mass, at rest, no impulses)
  std::vector<Vec3> xn, vn, impulse;
  std::vector<Real> mn;
  std::vector<std::uint8_t> pinned;
  std::vector<Tri> tris;
  std::vector<int> tri_offset;
  std::vector<ContactCoeffs> coeffs{ContactCoeffs()};

  void add_particle(const Vec3& x, const Vec3& vel, int f, Real uu, Real vv, Real tt = 0) {
    xp.push_back(x);
    vp.push_back(vel);
    face.push_back(f);
    u.push_back(uu);
    v.push_back(vv);
    t.push_back(tt);
  }

  // Runs Coupler::apply on the backend; particle velocities and node impulses come back here.
  CoupleStats apply(Coupler& c, Backend b) {
    const MemSpace s = space_of(b);
    auto bxp = to_space(s, xp), bvp = to_space(s, vp);
    auto bface = to_space(s, face);
    auto bt = to_space(s, t), bu = to_space(s, u), bv = to_space(s, v), bb = to_space(s, bias);
    const bool dynamic = !mn.empty();
    if (dynamic && impulse.size() != xn.size()) impulse.assign(xn.size(), Vec3());
    auto bxn = to_space(s, xn), bvn = to_space(s, vn), bimp = to_space(s, impulse);
    auto bmn = to_space(s, mn);
    auto bpin = to_space(s, pinned);
    auto btri = to_space(s, tris);
    HitArrays h;
    h.space = s;
    h.face = bface.data();
    h.t = bt.data();
    h.u = bu.data();
    h.v = bv.data();
    if (!bias.empty()) h.bias = bb.data();
    FluidArrays f;
    f.space = s;
    f.n = int(xp.size());
    f.x = bxp.data();
    f.v = bvp.data();
    f.mass = mass;
    f.radius = Real(0.01);
    CoupleSurface cs;
    cs.space = s;
    cs.nodes = int(xn.size());
    cs.triangles = int(tris.size());
    cs.tri = btri.data();
    cs.x = bxn.data();
    if (dynamic) {
      cs.v = bvn.data();
      cs.mass = bmn.data();
      cs.impulse = bimp.data();
      if (!pinned.empty()) cs.pinned = bpin.data();
    }
    cs.tri_offset = tri_offset;
    cs.coeffs = coeffs;
    const CoupleStats st = c.apply(h, f, {cs});
    from_space(bvp, vp);
    if (dynamic) from_space(bimp, impulse);
    return st;
  }
};

}  // namespace sphfem::testing_couple
