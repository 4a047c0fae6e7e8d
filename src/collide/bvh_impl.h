// SurfaceBvh and the batch queries over one execution backend. Included once per backend
// (bvh_cpu.cpp, bvh_cuda.cu) after that backend's exec header. Every loop body is a
// host-and-device lambda in a free function (nvcc does not allow extended lambdas in
// private members).
#pragma once

#include <algorithm>
#include <cfloat>
#include <stdexcept>
#include <string>
#include <vector>

#include "collide/host_build.h"
#include "collide/lbvh.h"
#include "sphfem/collide/bvh.h"

namespace sphfem {
namespace collide {

// Bounds of the triangle centroids (six reductions; the CUDA ones each read back a scalar).
template <class Exec>
void centroid_bounds(Exec& ex, const Vec3* x, const Tri* tris, int n, Vec3& lo, Vec3& hi) {
  Real m[6];
  for (int k = 0; k < 6; ++k) {
    const int axis = k % 3;
    const Real sign = k < 3 ? Real(1) : Real(-1);
    m[k] = reduce_max(ex, n, Real(-FLT_MAX), [=] SPHFEM_LAMBDA(int f) {
      const Tri t = tris[f];
      return sign * (x[t.v[0]][axis] + x[t.v[1]][axis] + x[t.v[2]][axis]) / Real(3);
    });
  }
  hi = Vec3(m[0], m[1], m[2]);
  lo = Vec3(-m[3], -m[4], -m[5]);
}

template <class Exec>
void morton_keys(Exec& ex, const Vec3* x, const Tri* tris, int n, Vec3 lo, Vec3 scale,
                 std::uint32_t* keys, std::uint32_t* vals) {
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int f) {
    const Tri t = tris[f];
    const Vec3 c = (x[t.v[0]] + x[t.v[1]] + x[t.v[2]]) / Real(3);
    const Vec3 q((c.x - lo.x) * scale.x, (c.y - lo.y) * scale.y, (c.z - lo.z) * scale.z);
    keys[f] = morton30(q);
    vals[f] = std::uint32_t(f);
  });
}

// Karras hierarchy: internal nodes 0 .. n-2, leaves n-1 .. 2n-2, one leaf per triangle.
template <class Exec>
void lbvh_topology(Exec& ex, const std::uint32_t* keys, const std::uint32_t* vals, int n,
                   BvhNode* nodes, int* parent, int* leaves, int* prims) {
  parallel_for(ex, n - 1, [=] SPHFEM_LAMBDA(int i) {
    int l, r;
    karras_children(keys, n, i, l, r);
    nodes[i].a = l;
    nodes[i].b = r;
    parent[l] = i;
    parent[r] = i;
    if (i == 0) parent[0] = -1;
  });
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int k) {
    const int node = n - 1 + k;
    nodes[node].a = k;
    nodes[node].b = -1;
    leaves[k] = node;
    prims[k] = int(vals[k]);
    if (n == 1) parent[0] = -1;
  });
}

// Longest root-to-leaf path (edges).
template <class Exec>
int tree_depth(Exec& ex, const int* parent, const int* leaves, int nleaves) {
  return reduce_max(ex, nleaves, 0, [=] SPHFEM_LAMBDA(int k) {
    int d = 0;
    for (int i = parent[leaves[k]]; i >= 0; i = parent[i]) ++d;
    return d;
  });
}

// Bottom-up box update: one thread per leaf; at each parent the first child to arrive
// stops, the second (which then sees both boxes) computes the parent and goes on. Flags
// start at zero and are reset by the thread that goes on, ready for the next refit. With
// x_new, leaf boxes hold the faces at both positions, grown by their sweep deviation.
template <class Exec>
void refit_boxes(Exec& ex, BvhNode* nodes, const int* parent, const int* leaves, int nleaves,
                 const int* prims, const Tri* tris, int* flags, const Vec3* x_old,
                 const Vec3* x_new) {
  parallel_for(ex, nleaves, [=] SPHFEM_LAMBDA(int k) {
    const int leaf = leaves[k];
    const BvhNode nd = nodes[leaf];
    Vec3 lo(FLT_MAX, FLT_MAX, FLT_MAX), hi(-FLT_MAX, -FLT_MAX, -FLT_MAX);
    Real dev = 0;
    for (int j = nd.a; j < nd.a - nd.b; ++j) {
      const Tri t = tris[prims[j]];
      const Vec3 a = x_old[t.v[0]], b = x_old[t.v[1]], c = x_old[t.v[2]];
      lo = vmin(lo, vmin(a, vmin(b, c)));
      hi = vmax(hi, vmax(a, vmax(b, c)));
      if (x_new) {
        const Vec3 a1 = x_new[t.v[0]], b1 = x_new[t.v[1]], c1 = x_new[t.v[2]];
        lo = vmin(lo, vmin(a1, vmin(b1, c1)));
        hi = vmax(hi, vmax(a1, vmax(b1, c1)));
        dev = rmax(dev, sweep_deviation(a1 - a, b1 - b, c1 - c));
      }
    }
    // A few units of round-off of the coordinates' magnitude: a ray that starts on a face
    // of the box, or grazes it, still enters it.
    const Real mag = rmax(rmax(rmax(rabs(lo.x), rabs(hi.x)), rmax(rabs(lo.y), rabs(hi.y))),
                          rmax(rabs(lo.z), rabs(hi.z)));
    const Real pad = dev + mag * Real(4) * (sizeof(Real) == 4 ? FLT_EPSILON : DBL_EPSILON);
    nodes[leaf].lo = lo - Vec3(pad, pad, pad);
    nodes[leaf].hi = hi + Vec3(pad, pad, pad);
    for (int p = parent[leaf]; p >= 0; p = parent[p]) {
      if (arrive(&flags[p]) == 0) return;
      flags[p] = 0;
      const int l = nodes[p].a, r = nodes[p].b;
      Vec3 llo, lhi, rlo, rhi;
      load_box(nodes, l, llo, lhi);
      load_box(nodes, r, rlo, rhi);
      nodes[p].lo = vmin(llo, rlo);
      nodes[p].hi = vmax(lhi, rhi);
    }
  });
}

template <class Exec>
double internal_area(Exec& ex, const BvhNode* nodes, int nnodes) {
  return reduce_sum(ex, nnodes, [=] SPHFEM_LAMBDA(int i) {
    const BvhNode n = nodes[i];
    return is_leaf(n) ? Real(0) : half_area(n.lo, n.hi);
  });
}

}  // namespace collide

// --- SurfaceBvh ---

template <class Exec>
SurfaceBvh<Exec>::SurfaceBvh() {
  const MemSpace s = Exec::kSpace;
  nodes_ = Buffer<collide::BvhNode>(s);
  for (Buffer<int>* b : {&parent_, &leaves_, &prims_, &flags_, &nbr_, &vstart_, &vfaces_})
    *b = Buffer<int>(s);
  keys_ = Buffer<std::uint32_t>(s);
  vals_ = Buffer<std::uint32_t>(s);
}

namespace collide {
template <class T>
void upload_vector(Buffer<T>& b, const std::vector<T>& v) {
  b.resize(v.size());
  if (!v.empty()) b.upload(v.data(), v.size());
}

// Host copy of n elements of a caller array in `space`.
template <class T>
std::vector<T> host_copy(MemSpace space, const T* p, std::size_t n) {
  std::vector<T> h(n);
  if (n) mem_copy(MemSpace::Host, h.data(), space, p, n * sizeof(T));
  return h;
}
}  // namespace collide

template <class Exec>
void SurfaceBvh<Exec>::derive_topology(Exec& ex, const Tri* tris, int ntris) {
  exec_sync(ex);
  const std::vector<Tri> t = collide::host_copy(Exec::kSpace, tris, std::size_t(ntris));
  const collide::SurfaceTopology s = collide::surface_topology(t.data(), ntris);
  collide::upload_vector(nbr_, s.nbr);
  collide::upload_vector(vstart_, s.vstart);
  collide::upload_vector(vfaces_, s.vfaces);
  nverts_ = s.nverts;
}

template <class Exec>
void SurfaceBvh<Exec>::build(Exec& ex, const Vec3* x, const Tri* tris, int ntris, BvhBuild method) {
  if (ntris < 0) throw std::invalid_argument("SurfaceBvh::build: negative triangle count");
  derive_topology(ex, tris, ntris);
  tris_ = tris;
  ntris_ = ntris;
  rebuild(ex, x, method);
}

template <class Exec>
void SurfaceBvh<Exec>::rebuild(Exec& ex, const Vec3* x, BvhBuild method) {
  if (method == BvhBuild::Auto)
    method = Exec::kSpace == MemSpace::Host ? BvhBuild::Sah : BvhBuild::Lbvh;
  method_ = method;
  nnodes_ = nleaves_ = depth_ = 0;
  area0_ = 0;
  if (ntris_ == 0) return;
  if (method == BvhBuild::Sah)
    build_sah(ex, x);
  else
    build_lbvh(ex, x);
  finish_build(ex, x);
}

template <class Exec>
void SurfaceBvh<Exec>::build_sah(Exec& ex, const Vec3* x) {
  std::vector<Tri> th;
  std::vector<Vec3> xh;
  const Tri* t = tris_;
  const Vec3* xp = x;
  if (Exec::kSpace != MemSpace::Host) {
    exec_sync(ex);
    th = collide::host_copy(Exec::kSpace, tris_, std::size_t(ntris_));
    xh = collide::host_copy(Exec::kSpace, x, std::size_t(nverts_));
    t = th.data();
    xp = xh.data();
  }
  const collide::HostTree tree = collide::build_sah_tree(xp, t, ntris_);
  collide::upload_vector(nodes_, tree.nodes);
  collide::upload_vector(parent_, tree.parent);
  collide::upload_vector(leaves_, tree.leaves);
  collide::upload_vector(prims_, tree.prims);
  nnodes_ = int(tree.nodes.size());
  nleaves_ = int(tree.leaves.size());
  depth_ = tree.depth;
}

template <class Exec>
void SurfaceBvh<Exec>::build_lbvh(Exec& ex, const Vec3* x) {
  const int n = ntris_;
  nnodes_ = 2 * n - 1;
  nleaves_ = n;
  nodes_.resize(nnodes_);
  parent_.resize(nnodes_);
  prims_.resize(n);
  leaves_.resize(n);
  keys_.resize(n);
  vals_.resize(n);
  Vec3 lo, hi;
  collide::centroid_bounds(ex, x, tris_, n, lo, hi);
  const Vec3 e = hi - lo;
  const auto inv = [](Real w) { return w > 0 ? Real(1) / w : Real(0); };
  const Vec3 scale(inv(e.x), inv(e.y), inv(e.z));
  collide::morton_keys(ex, x, tris_, n, lo, scale, keys_.data(), vals_.data());
  sort_pairs(ex, keys_.data(), vals_.data(), n, 30);
  collide::lbvh_topology(ex, keys_.data(), vals_.data(), n, nodes_.data(), parent_.data(),
                         leaves_.data(), prims_.data());
  depth_ = collide::tree_depth(ex, parent_.data(), leaves_.data(), nleaves_);
}

template <class Exec>
void SurfaceBvh<Exec>::finish_build(Exec& ex, const Vec3* x) {
  // A depth-first traversal keeps at most depth + 1 entries on its stack.
  if (depth_ >= collide::kStackSize)
    throw std::runtime_error("SurfaceBvh::build: tree depth " + std::to_string(depth_) +
                             " exceeds the traversal stack (" +
                             std::to_string(collide::kStackSize) + ")");
  flags_.resize(nnodes_);
  flags_.zero();
  refit(ex, x);
  area0_ = collide::internal_area(ex, nodes_.data(), nnodes_);
}

template <class Exec>
void SurfaceBvh<Exec>::refit(Exec& ex, const Vec3* x) {
  if (ntris_ == 0) return;
  collide::refit_boxes(ex, nodes_.data(), parent_.data(), leaves_.data(), nleaves_, prims_.data(),
                       tris_, flags_.data(), x, static_cast<const Vec3*>(nullptr));
}

template <class Exec>
void SurfaceBvh<Exec>::refit(Exec& ex, const Vec3* x_old, const Vec3* x_new) {
  if (ntris_ == 0) return;
  collide::refit_boxes(ex, nodes_.data(), parent_.data(), leaves_.data(), nleaves_, prims_.data(),
                       tris_, flags_.data(), x_old, x_new);
}

template <class Exec>
double SurfaceBvh<Exec>::quality(Exec& ex) {
  if (ntris_ == 0 || !(area0_ > 0)) return 1.0;
  return collide::internal_area(ex, nodes_.data(), nnodes_) / area0_;
}

template <class Exec>
collide::BvhView SurfaceBvh<Exec>::view() const {
  collide::BvhView v;
  v.nodes = nodes_.data();
  v.prims = prims_.data();
  v.tris = tris_;
  v.ntris = ntris_;
  v.nbr = nbr_.data();
  v.vstart = vstart_.data();
  v.vfaces = vfaces_.data();
  v.nverts = nverts_;
  return v;
}

// --- batch queries ---

template <class Exec>
void cast_rays(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* origin,
               const Vec3* dir, const Real* tmax, RayHits out) {
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    const Real tm = tmax ? tmax[i] : Real(INFINITY);
    const collide::RayHit h = collide::ray_nearest(bv, x, origin[i], dir[i], tm);
    out.face[i] = h.face;
    out.t[i] = h.t;
    out.u[i] = h.u;
    out.v[i] = h.v;
  });
}

template <class Exec>
void cast_moving(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x_old, const Vec3* x_new, int n,
                 const Vec3* p, const Vec3* vel, Real dt, Real skin, SegmentHits out,
                 int face_offset, bool merge, bool front_only) {
  if (merge && !out.len)
    throw std::invalid_argument("cast_moving: merging hits needs the len array");
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    const collide::SegmentHit h =
        collide::moving_nearest(bv, x_old, x_new, p[i], vel[i] * dt, skin, front_only);
    if (merge) {
      if (h.face < 0) return;
      const int f = out.face[i];
      if (f >= 0 && !collide::closer(h.t / h.len, h.face + face_offset, out.t[i] / out.len[i], f))
        return;
    }
    out.face[i] = h.face < 0 ? -1 : h.face + face_offset;
    out.t[i] = h.t;
    out.u[i] = h.u;
    out.v[i] = h.v;
    if (out.len) out.len[i] = h.len;
    if (out.rel) out.rel[i] = h.rel;
  });
}

template <class Exec>
void cast_contacts(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x_old, const Vec3* x_new,
                   int n, const Vec3* from, const Vec3* to, Real tol, ContactHits out,
                   bool front_only) {
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    const collide::ContactHit h =
        collide::moving_contact(bv, x_old, x_new, from[i], to[i] - from[i], tol, front_only);
    out.face[i] = h.face;
    if (out.tau) out.tau[i] = h.c.tau;
    if (out.u) out.u[i] = h.c.u;
    if (out.v) out.v[i] = h.c.v;
    if (out.side) out.side[i] = h.c.side;
  });
}

template <class Exec>
void count_crossings(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* from,
                     const Vec3* to, int* count) {
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    count[i] = collide::ray_count(bv, x, from[i], to[i] - from[i], Real(1), false);
  });
}

template <class Exec>
void inside_closed(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* p,
                   std::uint8_t* inside) {
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    // Any direction gives the right parity (watertight test with tie-breaking); an oblique
    // one keeps rays off the axis-aligned planes meshes tend to have.
    const Vec3 d(Real(0.5391), Real(0.7212), Real(0.4350));
    inside[i] = std::uint8_t(collide::ray_count(bv, x, p[i], d, Real(INFINITY), false) & 1);
  });
}

template <class Exec>
void closest_points(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* p,
                    Real radius, ClosestHits out) {
  const collide::BvhView bv = bvh.view();
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    const collide::ClosestHit h = collide::closest_point(bv, x, p[i], radius);
    out.face[i] = h.face;
    out.dist[i] = h.dist;
    if (out.point) out.point[i] = h.point;
    if (out.side) out.side[i] = h.side;
    if (out.u) out.u[i] = h.u;
    if (out.v) out.v[i] = h.v;
  });
}

// Explicit instantiation of everything for one backend.
#define SPHFEM_INSTANTIATE_COLLIDE(EXEC)                                                           \
  template class SurfaceBvh<EXEC>;                                                                 \
  template void cast_rays<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, int, const Vec3*,     \
                                const Vec3*, const Real*, RayHits);                                \
  template void cast_moving<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, const Vec3*, int,   \
                                  const Vec3*, const Vec3*, Real, Real, SegmentHits, int, bool,    \
                                  bool);                                                           \
  template void cast_contacts<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, const Vec3*, int, \
                                    const Vec3*, const Vec3*, Real, ContactHits, bool);            \
  template void count_crossings<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, int,            \
                                      const Vec3*, const Vec3*, int*);                             \
  template void inside_closed<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, int, const Vec3*, \
                                    std::uint8_t*);                                                \
  template void closest_points<EXEC>(EXEC&, const SurfaceBvh<EXEC>&, const Vec3*, int,             \
                                     const Vec3*, Real, ClosestHits);

}  // namespace sphfem
