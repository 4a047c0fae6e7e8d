// The BVH's node layout and its traversals, written once for host and device (SPHFEM_HD):
// the same functions run in a CPU parallel_for and in a CUDA kernel, on a small fixed stack.
//
// Layout: one array of 32-byte nodes (float build), root at index 0. An internal node holds
// its box and its two children; a leaf holds its box and a range of the primitive index
// array (triangles first .. first + count - 1 in prims). Both builders (binned SAH on the
// host, LBVH on Morton codes on any backend) write this layout, so traversal is shared.
#pragma once

#include <climits>
#include <cstdint>

#include "sphfem/collide/geometry.h"
#include "sphfem/fem/mesh.h"

namespace sphfem::collide {

// Stack depth of every traversal; builders refuse trees deeper than this.
constexpr int kStackSize = 64;

struct BvhNode {
  Vec3 lo;
  int a;  // internal: left child; leaf: first index into prims
  Vec3 hi;
  int b;  // internal: right child (> 0); leaf: -count
};

SPHFEM_HD bool is_leaf(const BvhNode& n) { return n.b < 0; }

// What kernels need to traverse: raw arrays in the backend's memory space.
struct BvhView {
  const BvhNode* nodes = nullptr;
  const int* prims = nullptr;  // leaf ranges index this; values are triangle ids
  const Tri* tris = nullptr;
  int ntris = 0;
  // Surface topology for pseudonormals: the face across edge k of face f (edge k joins
  // corners k and k+1) is nbr[3 f + k], -1 on a boundary or non-manifold edge; the faces
  // around vertex i are vfaces[vstart[i] .. vstart[i + 1] - 1].
  const int* nbr = nullptr;
  const int* vstart = nullptr;
  const int* vfaces = nullptr;
  int nverts = 0;
};

struct RayHit {
  int face = -1;  // -1: no hit
  Real t = 0, u = 0, v = 0;
};

struct SegmentHit {
  int face = -1;  // -1: no hit
  Real t = 0;     // distance from p along rel / len to the face's old position
  Real u = 0, v = 0;
  Real len = 0;  // |rel|: the relative motion over the step, without the skin
  Vec3 rel;      // particle displacement minus the face's, over the step
};

struct ClosestHit {
  int face = -1;  // -1: nothing within the radius
  Real dist = 0;
  Real u = 0, v = 0;
  Vec3 point;
  int side = 0;  // +1 outside (front of the surface), -1 inside, 0 on it
};

// Ties between equal distances go to the lower face id, so every build (and brute force)
// returns the same face.
SPHFEM_HD bool closer(Real t, int f, Real best_t, int best_f) {
  return t < best_t || (t == best_t && unsigned(f) < unsigned(best_f));
}

// Nearest hit of o + t d, t in [0, tmax], over the triangles at positions x. d need not be
// unit length: t is in units of d. tmax may be infinite.
SPHFEM_HD RayHit ray_nearest(const BvhView& bv, const Vec3* x, const Vec3& o, const Vec3& d,
                             Real tmax) {
  RayHit h;
  h.t = tmax;
  if (bv.ntris == 0 || (d.x == 0 && d.y == 0 && d.z == 0)) return h;
  const RayShear sh = ray_shear(d);
  const SlabRay sr = slab_ray(o, d);
  int stack[kStackSize];
  Real enter[kStackSize];
  int sp = 0;
  Real te;
  int node = 0;
  if (!slab_test(sr, bv.nodes[0].lo, bv.nodes[0].hi, 0, 0, h.t, te)) return h;
  for (;;) {
    const BvhNode n = bv.nodes[node];
    if (is_leaf(n)) {
      for (int k = n.a; k < n.a - n.b; ++k) {
        const int f = bv.prims[k];
        const Tri tr = bv.tris[f];
        Real t, u, v;
        if (ray_triangle(o, sh, x[tr.v[0]], x[tr.v[1]], x[tr.v[2]], h.t, t, u, v) &&
            closer(t, f, h.t, h.face))
          h.face = f, h.t = t, h.u = u, h.v = v;
      }
    } else {
      const BvhNode& l = bv.nodes[n.a];
      const BvhNode& r = bv.nodes[n.b];
      Real tl, tr;
      const bool hl = slab_test(sr, l.lo, l.hi, 0, 0, h.t, tl);
      const bool hr = slab_test(sr, r.lo, r.hi, 0, 0, h.t, tr);
      if (hl && hr) {
        const bool left_first = tl <= tr;
        stack[sp] = left_first ? n.b : n.a;
        enter[sp++] = left_first ? tr : tl;
        node = left_first ? n.a : n.b;
        continue;
      }
      if (hl || hr) {
        node = hl ? n.a : n.b;
        continue;
      }
    }
    // Pop the next subtree that may still hold a nearer hit.
    do {
      if (sp == 0) return h;
      --sp;
    } while (enter[sp] > h.t);
    node = stack[sp];
  }
}

// Number of triangles o + t d crosses for t in [0, tmax] (each crossing of a closed surface
// counts once, also through edges and vertices); with `any`, stops at the first.
SPHFEM_HD int ray_count(const BvhView& bv, const Vec3* x, const Vec3& o, const Vec3& d, Real tmax,
                        bool any) {
  if (bv.ntris == 0 || (d.x == 0 && d.y == 0 && d.z == 0)) return 0;
  const RayShear sh = ray_shear(d);
  const SlabRay sr = slab_ray(o, d);
  int stack[kStackSize];
  int sp = 0, count = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const BvhNode n = bv.nodes[stack[--sp]];
    Real te;
    if (!slab_test(sr, n.lo, n.hi, 0, 0, tmax, te)) continue;
    if (is_leaf(n)) {
      for (int k = n.a; k < n.a - n.b; ++k) {
        const Tri tr = bv.tris[bv.prims[k]];
        Real t, u, v;
        if (ray_triangle(o, sh, x[tr.v[0]], x[tr.v[1]], x[tr.v[2]], tmax, t, u, v)) {
          ++count;
          if (any) return count;
        }
      }
    } else {
      stack[sp++] = n.b;
      stack[sp++] = n.a;
    }
  }
  return count;
}

// Nearest-first descent of the boxes that the path p -> p + dp (parameterised over [0, 1])
// passes through, the boxes grown by pad, skipping what lies beyond visit.best (a time in
// steps). visit(f) tests face f and may lower visit.best. The BVH must have been refit over
// the step (SurfaceBvh::refit(ex, x_old, x_new)): its leaf boxes then hold the swept faces.
template <class Visit>
SPHFEM_HD void descend_path(const BvhView& bv, const Vec3& p, const Vec3& dp, Real pad,
                            Visit& visit) {
  if (bv.ntris == 0) return;
  const SlabRay sr = slab_ray(p, dp);
  int stack[kStackSize];
  Real enter[kStackSize];
  int sp = 0;
  Real te;
  int node = 0;
  if (!slab_test(sr, bv.nodes[0].lo, bv.nodes[0].hi, pad, 0, 1, te)) return;
  for (;;) {
    const BvhNode n = bv.nodes[node];
    if (is_leaf(n)) {
      for (int k = n.a; k < n.a - n.b; ++k) visit(bv.prims[k]);
    } else {
      const BvhNode& l = bv.nodes[n.a];
      const BvhNode& r = bv.nodes[n.b];
      Real tl, tr;
      const Real lim = rmin(visit.best, Real(1));
      const bool hl = slab_test(sr, l.lo, l.hi, pad, 0, lim, tl);
      const bool hr = slab_test(sr, r.lo, r.hi, pad, 0, lim, tr);
      if (hl && hr) {
        const bool left_first = tl <= tr;
        stack[sp] = left_first ? n.b : n.a;
        enter[sp++] = left_first ? tr : tl;
        node = left_first ? n.a : n.b;
        continue;
      }
      if (hl || hr) {
        node = hl ? n.a : n.b;
        continue;
      }
    }
    do {
      if (sp == 0) return;
      --sp;
    } while (enter[sp] > visit.best);
    node = stack[sp];
  }
}

// What the visits of moving faces share: the faces over the step, the particle's path, and
// face f's old corners and their displacements.
struct PathQuery {
  const BvhView& bv;
  const Vec3 *x_old, *x_new;
  Vec3 p, dp;
  bool front_only;
  SPHFEM_HD void face(int f, Vec3 x[3], Vec3 d[3]) const {
    const Tri tr = bv.tris[f];
    for (int k = 0; k < 3; ++k) x[k] = x_old[tr.v[k]], d[k] = x_new[tr.v[k]] - x[k];
  }
};

// moving_triangle against each face a path reaches; keeps the earliest hit in the step.
struct MovingVisit {
  PathQuery q;
  Real skin;
  Real best = Real(FLT_MAX);  // time of the hit, in steps
  SegmentHit h;
  SPHFEM_HD void operator()(int f) {
    Vec3 x[3], d[3];
    q.face(f, x, d);
    if (q.front_only && dot(q.p - x[0], cross(x[1] - x[0], x[2] - x[0])) < Real(0)) return;
    MovingHit m;
    if (!moving_triangle(q.p, q.dp, skin, x[0], x[1], x[2], d[0], d[1], d[2], m)) return;
    const Real tau = m.t / m.len;
    if (closer(tau, f, best, h.face)) {
      best = tau;
      h.face = f, h.t = m.t, h.u = m.u, h.v = m.v, h.len = m.len, h.rel = m.rel;
    }
  }
};

// The moving-segment query (see moving_triangle): a particle at p moving by dp over a step
// against faces moving from x_old to x_new. The particle's own path p -> p + dp passes
// through every box that can hold a hit, once the boxes grow by skin (a hit in the skin
// beyond the step lies in a box the path's end point touches). Returns the earliest hit in
// the step's time, t / len (ties to the lower face id). With front_only, faces the particle
// starts behind are skipped: behind a face of a closed, outward-oriented surface is inside the
// body, and a particle there (an inverted element, a fluid block placed over a body) must be
// let out, not held in. From outside, the earliest hit is a front face anyway.
SPHFEM_HD SegmentHit moving_nearest(const BvhView& bv, const Vec3* x_old, const Vec3* x_new,
                                    const Vec3& p, const Vec3& dp, Real skin,
                                    bool front_only = false) {
  MovingVisit visit{PathQuery{bv, x_old, x_new, p, dp, front_only}, skin, Real(FLT_MAX),
                    SegmentHit()};
  descend_path(bv, p, dp, skin, visit);
  return visit.h;
}

// The earliest exact contact (point_face_contact) of a particle's path p -> p + dp with the
// faces moving linearly from x_old to x_new over the step; face -1 when none.
struct ContactHit {
  int face = -1;
  Crossing c;
};

struct ContactVisit {
  PathQuery q;
  Real tol;
  Real best = Real(2);  // beyond the step: nothing found yet
  ContactHit h;
  SPHFEM_HD void operator()(int f) {
    Vec3 x[3], d[3];
    q.face(f, x, d);
    Crossing k;
    // A little beyond best, so that ties go to the lower face id (closer) in any visit order.
    if (!point_face_contact(q.p, q.dp, x[0], x[1], x[2], d[0], d[1], d[2], tol, best * slab_slack(),
                            k, q.front_only))
      return;
    if (closer(k.tau, f, best, h.face)) {
      best = k.tau;
      h.face = f, h.c = k;
    }
  }
};

// With front_only, only contacts from in front of a face count (entries into a closed,
// outward-oriented body; see moving_nearest).
SPHFEM_HD ContactHit moving_contact(const BvhView& bv, const Vec3* x_old, const Vec3* x_new,
                                    const Vec3& p, const Vec3& dp, Real tol,
                                    bool front_only = false) {
  ContactVisit visit{PathQuery{bv, x_old, x_new, p, dp, front_only}, tol, Real(2), ContactHit()};
  descend_path(bv, p, dp, tol, visit);
  return visit.h;
}

// Unit normal of triangle (a, b, c), or 0 for a degenerate one.
SPHFEM_HD Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const Real l = norm(n);
  return l > 0 ? n / l : Vec3();
}

// Angle-weighted pseudonormal (Baerentzen & Aanaes 2005) of the feature of face f that holds
// a closest point: the face normal inside, the sum of the two face normals on an edge, the
// sum of face normals weighted by their angles at a vertex. Its sign against p - closest
// classifies p as inside or outside a closed, outward-oriented surface, also next to edges
// and corners where a single face normal can give the wrong answer.
SPHFEM_HD Vec3 pseudonormal(const BvhView& bv, const Vec3* x, int f, int feature) {
  const Tri t = bv.tris[f];
  const Vec3 nf = unit_normal(x[t.v[0]], x[t.v[1]], x[t.v[2]]);
  if (feature == kFace || bv.nbr == nullptr) return nf;
  if (feature >= kEdge01) {
    const int g = bv.nbr[3 * f + (feature - kEdge01)];
    if (g < 0) return nf;
    const Tri s = bv.tris[g];
    return nf + unit_normal(x[s.v[0]], x[s.v[1]], x[s.v[2]]);
  }
  const int vi = t.v[feature - kVertex0];
  Vec3 n;
  for (int k = bv.vstart[vi]; k < bv.vstart[vi + 1]; ++k) {
    const Tri s = bv.tris[bv.vfaces[k]];
    const int c = s.v[0] == vi ? 0 : (s.v[1] == vi ? 1 : 2);
    const Vec3 p0 = x[s.v[c]];
    const Vec3 e1 = x[s.v[c == 2 ? 0 : c + 1]] - p0, e2 = x[s.v[c == 0 ? 2 : c - 1]] - p0;
    const Real l1 = norm(e1), l2 = norm(e2);
    if (!(l1 > 0 && l2 > 0)) continue;
    Real cosang = dot(e1, e2) / (l1 * l2);
    cosang = rmax(Real(-1), rmin(Real(1), cosang));
    n += std::acos(cosang) * unit_normal(x[s.v[0]], x[s.v[1]], x[s.v[2]]);
  }
  return n;
}

// Closest point of the surface to p within radius (inclusive); face -1 when none. The side
// comes from the pseudonormal of the closest feature.
SPHFEM_HD ClosestHit closest_point(const BvhView& bv, const Vec3* x, const Vec3& p, Real radius) {
  ClosestHit h;
  if (bv.ntris == 0) return h;
  Real best = radius * radius;
  int feature = kFace;
  int stack[kStackSize];
  Real enter[kStackSize];
  int sp = 0;
  int node = 0;
  if (box_distance2(p, bv.nodes[0].lo, bv.nodes[0].hi) > best) return h;
  for (;;) {
    const BvhNode n = bv.nodes[node];
    if (is_leaf(n)) {
      for (int k = n.a; k < n.a - n.b; ++k) {
        const int f = bv.prims[k];
        const Tri tr = bv.tris[f];
        const ClosestOnTriangle c = closest_on_triangle(p, x[tr.v[0]], x[tr.v[1]], x[tr.v[2]]);
        const Real d2 = norm2(p - c.point);
        if (d2 <= best && closer(d2, f, best, h.face)) {
          best = d2;
          h.face = f, h.u = c.u, h.v = c.v, h.point = c.point;
          feature = c.feature;
        }
      }
    } else {
      const BvhNode& l = bv.nodes[n.a];
      const BvhNode& r = bv.nodes[n.b];
      const Real dl = box_distance2(p, l.lo, l.hi), dr = box_distance2(p, r.lo, r.hi);
      const bool hl = dl <= best, hr = dr <= best;
      if (hl && hr) {
        const bool left_first = dl <= dr;
        stack[sp] = left_first ? n.b : n.a;
        enter[sp++] = left_first ? dr : dl;
        node = left_first ? n.a : n.b;
        continue;
      }
      if (hl || hr) {
        node = hl ? n.a : n.b;
        continue;
      }
    }
    do {
      if (sp == 0) {
        if (h.face >= 0) {
          h.dist = std::sqrt(best);
          const Real s = dot(p - h.point, pseudonormal(bv, x, h.face, feature));
          h.side = s > 0 ? 1 : (s < 0 ? -1 : 0);
        }
        return h;
      }
      --sp;
    } while (enter[sp] > best);
    node = stack[sp];
  }
}

}  // namespace sphfem::collide
