// Collider over one execution backend: host vectors in, SurfaceBvh and the batch queries on
// the backend, host vectors out. Included once per backend after bvh_impl.h.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "collide/bvh_impl.h"
#include "sphfem/collide/collider.h"

namespace sphfem {

template <class Exec>
class ColliderT final : public Collider {
 public:
  ColliderT() {
    const MemSpace s = Exec::kSpace;
    tris_ = Buffer<Tri>(s);
    x_old_ = Buffer<Vec3>(s);
    x_ = Buffer<Vec3>(s);
  }

  void build(const std::vector<Vec3>& x, const std::vector<Tri>& tris, BvhBuild method) override {
    for (const Tri& t : tris)
      for (int k = 0; k < 3; ++k)
        if (t.v[k] < 0 || std::size_t(t.v[k]) >= x.size())
          throw std::invalid_argument("Collider::build: vertex index " + std::to_string(t.v[k]) +
                                      " outside the " + std::to_string(x.size()) + " positions");
    tris_.resize(tris.size());
    if (!tris.empty()) tris_.upload(tris.data(), tris.size());
    put(x_, x);
    put(x_old_, x);
    bvh_.build(ex_, x_.data(), tris_.data(), int(tris.size()), method);
    exec_sync(ex_);
  }

  void refit(const std::vector<Vec3>& x) override {
    check(x, "refit");
    put(x_, x);
    put(x_old_, x);
    bvh_.refit(ex_, x_.data());
    exec_sync(ex_);
  }

  void refit(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x_new) override {
    check(x_old, "refit");
    check(x_new, "refit");
    put(x_old_, x_old);
    put(x_, x_new);
    bvh_.refit(ex_, x_old_.data(), x_.data());
    exec_sync(ex_);
  }

  void rebuild(BvhBuild method) override {
    bvh_.rebuild(ex_, x_.data(), method);
    exec_sync(ex_);
  }

  double quality() override { return bvh_.quality(ex_); }
  int depth() const override { return bvh_.depth(); }

  std::vector<collide::RayHit> cast_rays(const std::vector<Vec3>& origin,
                                         const std::vector<Vec3>& dir,
                                         const std::vector<Real>& tmax) override {
    const int n = int(origin.size());
    if (dir.size() != origin.size() || (!tmax.empty() && tmax.size() != origin.size()))
      throw std::invalid_argument("Collider::cast_rays: origin, dir and tmax differ in length");
    Buffer<Vec3> o = to_exec(origin), d = to_exec(dir);
    Buffer<Real> tm = to_exec(tmax);
    Buffer<int> face(Exec::kSpace, n);
    Buffer<Real> t(Exec::kSpace, n), u(Exec::kSpace, n), v(Exec::kSpace, n);
    sphfem::cast_rays(ex_, bvh_, x_.data(), n, o.data(), d.data(),
                      tmax.empty() ? nullptr : tm.data(),
                      RayHits{face.data(), t.data(), u.data(), v.data()});
    exec_sync(ex_);
    std::vector<collide::RayHit> out(n);
    const std::vector<int> hf = to_host(face);
    const std::vector<Real> ht = to_host(t), hu = to_host(u), hv = to_host(v);
    for (int i = 0; i < n; ++i)
      out[i].face = hf[i], out[i].t = ht[i], out[i].u = hu[i], out[i].v = hv[i];
    return out;
  }

  std::vector<collide::SegmentHit> cast_moving(const std::vector<Vec3>& p,
                                               const std::vector<Vec3>& vel, Real dt,
                                               Real skin) override {
    const int n = int(p.size());
    if (vel.size() != p.size())
      throw std::invalid_argument("Collider::cast_moving: p and vel differ in length");
    Buffer<Vec3> bp = to_exec(p), bvel = to_exec(vel);
    Buffer<int> face(Exec::kSpace, n);
    Buffer<Real> t(Exec::kSpace, n), u(Exec::kSpace, n), v(Exec::kSpace, n), len(Exec::kSpace, n);
    Buffer<Vec3> rel(Exec::kSpace, n);
    sphfem::cast_moving(
        ex_, bvh_, x_old_.data(), x_.data(), n, bp.data(), bvel.data(), dt, skin,
        SegmentHits{face.data(), t.data(), u.data(), v.data(), len.data(), rel.data()});
    exec_sync(ex_);
    std::vector<collide::SegmentHit> out(n);
    const std::vector<int> hf = to_host(face);
    const std::vector<Real> ht = to_host(t), hu = to_host(u), hv = to_host(v), hl = to_host(len);
    const std::vector<Vec3> hr = to_host(rel);
    for (int i = 0; i < n; ++i) {
      out[i].face = hf[i], out[i].t = ht[i], out[i].u = hu[i], out[i].v = hv[i];
      out[i].len = hl[i], out[i].rel = hr[i];
    }
    return out;
  }

  std::vector<collide::ContactHit> contacts(const std::vector<Vec3>& from,
                                            const std::vector<Vec3>& to, Real tol,
                                            bool front_only) override {
    const int n = int(from.size());
    if (to.size() != from.size())
      throw std::invalid_argument("Collider::contacts: from and to differ in length");
    Buffer<Vec3> a = to_exec(from), b = to_exec(to);
    Buffer<int> face(Exec::kSpace, n), side(Exec::kSpace, n);
    Buffer<Real> tau(Exec::kSpace, n), u(Exec::kSpace, n), v(Exec::kSpace, n);
    sphfem::cast_contacts(ex_, bvh_, x_old_.data(), x_.data(), n, a.data(), b.data(), tol,
                          ContactHits{face.data(), tau.data(), u.data(), v.data(), side.data()},
                          front_only);
    exec_sync(ex_);
    const std::vector<int> hf = to_host(face), hs = to_host(side);
    const std::vector<Real> ht = to_host(tau), hu = to_host(u), hv = to_host(v);
    std::vector<collide::ContactHit> out(n);
    for (int i = 0; i < n; ++i)
      out[i].face = hf[i], out[i].c = collide::Crossing{ht[i], hu[i], hv[i], hs[i]};
    return out;
  }

  std::vector<int> count_crossings(const std::vector<Vec3>& from,
                                   const std::vector<Vec3>& to) override {
    const int n = int(from.size());
    if (to.size() != from.size())
      throw std::invalid_argument("Collider::count_crossings: from and to differ in length");
    Buffer<Vec3> a = to_exec(from), b = to_exec(to);
    Buffer<int> c(Exec::kSpace, n);
    sphfem::count_crossings(ex_, bvh_, x_.data(), n, a.data(), b.data(), c.data());
    exec_sync(ex_);
    return to_host(c);
  }

  std::vector<std::uint8_t> inside(const std::vector<Vec3>& p) override {
    const int n = int(p.size());
    Buffer<Vec3> bp = to_exec(p);
    Buffer<std::uint8_t> in(Exec::kSpace, n);
    sphfem::inside_closed(ex_, bvh_, x_.data(), n, bp.data(), in.data());
    exec_sync(ex_);
    return to_host(in);
  }

  std::vector<collide::ClosestHit> closest(const std::vector<Vec3>& p, Real radius) override {
    const int n = int(p.size());
    Buffer<Vec3> bp = to_exec(p);
    Buffer<int> face(Exec::kSpace, n), side(Exec::kSpace, n);
    Buffer<Real> dist(Exec::kSpace, n), u(Exec::kSpace, n), v(Exec::kSpace, n);
    Buffer<Vec3> point(Exec::kSpace, n);
    sphfem::closest_points(
        ex_, bvh_, x_.data(), n, bp.data(), radius,
        ClosestHits{face.data(), dist.data(), point.data(), side.data(), u.data(), v.data()});
    exec_sync(ex_);
    std::vector<collide::ClosestHit> out(n);
    const std::vector<int> hf = to_host(face), hs = to_host(side);
    const std::vector<Real> hd = to_host(dist), hu = to_host(u), hv = to_host(v);
    const std::vector<Vec3> hp = to_host(point);
    for (int i = 0; i < n; ++i) {
      out[i].face = hf[i], out[i].dist = hd[i], out[i].point = hp[i], out[i].side = hs[i];
      out[i].u = hu[i], out[i].v = hv[i];
    }
    return out;
  }

 private:
  void check(const std::vector<Vec3>& x, const char* what) const {
    if (x.size() != x_.size())
      throw std::invalid_argument(std::string("Collider::") + what + ": " +
                                  std::to_string(x.size()) + " positions, built with " +
                                  std::to_string(x_.size()));
  }
  static void put(Buffer<Vec3>& b, const std::vector<Vec3>& v) {
    b.resize(v.size());
    if (!v.empty()) b.upload(v.data(), v.size());
  }
  template <class T>
  static Buffer<T> to_exec(const std::vector<T>& v) {
    Buffer<T> b(Exec::kSpace, v.size());
    if (!v.empty()) b.upload(v.data(), v.size());
    return b;
  }
  template <class T>
  static std::vector<T> to_host(const Buffer<T>& b) {
    std::vector<T> v(b.size());
    if (!v.empty()) b.download(v.data(), v.size());
    return v;
  }

  Exec ex_;
  SurfaceBvh<Exec> bvh_;
  Buffer<Tri> tris_;
  Buffer<Vec3> x_old_, x_;
};

}  // namespace sphfem
