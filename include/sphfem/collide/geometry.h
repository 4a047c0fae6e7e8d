// Triangle primitives for collision, written once for host and device (SPHFEM_HD):
//  - watertight ray-triangle intersection (Woop, Benthin & Wald 2013, JCGT 2(1)) with a
//    tie-breaking rule for rays through shared edges and vertices,
//  - closest point on a triangle (Ericson, Real-Time Collision Detection, 5.1.5),
//  - the moving-segment test of a particle against a moving face (relative motion),
//  - box helpers for the BVH.
//
// Why a tie-breaking rule: plain Woop reports a ray through a shared edge on both triangles
// (never on neither). Parity counts (inside tests) need exactly one. An edge whose edge
// function is exactly zero counts as inside only if the point, moved by an infinitesimal
// (eps, eps^2) in the sheared 2D frame, would be inside. Two triangles that meet at an edge
// with the ray crossing the surface there see the edge in opposite directions, so exactly
// one owns it; at a silhouette edge both or neither do, which keeps parity. The same
// perturbation argument covers vertices: the fan around a crossed vertex counts once.
#pragma once

#include <cfloat>
#include <cmath>

#include "sphfem/core/vec.h"

namespace sphfem::collide {

// --- boxes ---

struct Aabb {
  Vec3 lo, hi;
};

SPHFEM_HD Real rmin(Real a, Real b) { return a < b ? a : b; }
SPHFEM_HD Real rmax(Real a, Real b) { return a > b ? a : b; }
SPHFEM_HD Real rabs(Real a) { return a < 0 ? -a : a; }

SPHFEM_HD Real half_area(const Vec3& lo, const Vec3& hi) {
  const Vec3 e = hi - lo;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

// Squared distance from p to the box [lo, hi] (0 inside).
SPHFEM_HD Real box_distance2(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Real dx = rmax(rmax(lo.x - p.x, p.x - hi.x), Real(0));
  const Real dy = rmax(rmax(lo.y - p.y, p.y - hi.y), Real(0));
  const Real dz = rmax(rmax(lo.z - p.z, p.z - hi.z), Real(0));
  return dx * dx + dy * dy + dz * dz;
}

// A ray o + t d prepared for slab tests. Zero direction components are replaced by a tiny
// value of the same sign, so (lo - o) * inv is never 0 * inf (NaN) and a ray lying in a
// box face plane still overlaps the box.
struct SlabRay {
  Vec3 o, inv;
};

SPHFEM_HD Real safe_inverse(Real d) {
  const Real tiny = Real(1e-30);
  return Real(1) / (rabs(d) < tiny ? (d < 0 ? -tiny : tiny) : d);
}

SPHFEM_HD SlabRay slab_ray(const Vec3& o, const Vec3& d) {
  return SlabRay{o, Vec3(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z))};
}

// Relative slack on the exit distance that covers the rounding of the slab computation
// (Pharr, Jakob & Humphreys, PBRT 3rd ed. 3.9.2: t_far *= 1 + 2 gamma(3)).
SPHFEM_HD Real slab_slack() {
  return Real(1) + Real(8) * (sizeof(Real) == 4 ? FLT_EPSILON : DBL_EPSILON);
}

// Overlap of [tmin, tmax] with the ray's passage through the box [lo - pad, hi + pad];
// on overlap writes the entry distance.
SPHFEM_HD bool slab_test(const SlabRay& r, const Vec3& lo, const Vec3& hi, Real pad, Real tmin,
                         Real tmax, Real& t_enter) {
  Real t0 = (lo.x - pad - r.o.x) * r.inv.x, t1 = (hi.x + pad - r.o.x) * r.inv.x;
  Real tn = rmin(t0, t1), tf = rmax(t0, t1);
  t0 = (lo.y - pad - r.o.y) * r.inv.y, t1 = (hi.y + pad - r.o.y) * r.inv.y;
  tn = rmax(tn, rmin(t0, t1)), tf = rmin(tf, rmax(t0, t1));
  t0 = (lo.z - pad - r.o.z) * r.inv.z, t1 = (hi.z + pad - r.o.z) * r.inv.z;
  tn = rmax(tn, rmin(t0, t1)), tf = rmin(tf, rmax(t0, t1));
  tn = rmax(tn, tmin);
  tf = rmin(tf * slab_slack(), tmax);
  t_enter = tn;
  return tn <= tf;
}

// --- watertight ray-triangle intersection ---

// Watertightness needs the edge function of a shared edge to be the exact negation in its
// two triangles, and a vertex's sheared coordinates to be the same in every triangle. A
// fused multiply-add in one place and not in another breaks both, and compilers fuse
// freely (GCC in C++ by default, nvcc by default). In float builds the sheared coordinates
// are computed in double and rounded to float, and the edge functions are differences of
// products of floats, which double holds exactly: one rounding each, fused or not, so the
// results are the same everywhere. Double builds round each operation explicitly instead
// (_rn intrinsics on the device, a volatile store on the host).
#if defined(SPHFEM_DOUBLE)
SPHFEM_HD double mul_rn(double a, double b) {
#if defined(__CUDA_ARCH__)
  return __dmul_rn(a, b);
#else
  volatile double p = a * b;
  return p;
#endif
}
SPHFEM_HD double sheared(double p, double s, double pz) { return p - mul_rn(s, pz); }
SPHFEM_HD double edge_function(double a, double b, double c, double d) {
  return mul_rn(a, b) - mul_rn(c, d);
}
#else
SPHFEM_HD float sheared(float p, float s, float pz) {
  return float(double(p) - double(s) * double(pz));
}
SPHFEM_HD double edge_function(float a, float b, float c, float d) {
  return double(a) * double(b) - double(c) * double(d);
}
#endif

// Per-ray constants of the shear into the ray's frame (Woop et al. 2013, section 3).
struct RayShear {
  int kx, ky, kz;
  Real sx, sy, sz;
};

SPHFEM_HD RayShear ray_shear(const Vec3& d) {
  RayShear s;
  const Real ax = rabs(d.x), ay = rabs(d.y), az = rabs(d.z);
  s.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
  s.kx = s.kz == 2 ? 0 : s.kz + 1;
  s.ky = s.kx == 2 ? 0 : s.kx + 1;
  if (d[s.kz] < 0) {  // keep the winding: swap when the ray looks along -z
    const int k = s.kx;
    s.kx = s.ky;
    s.ky = k;
  }
  s.sx = d[s.kx] / d[s.kz];
  s.sy = d[s.ky] / d[s.kz];
  s.sz = Real(1) / d[s.kz];
  return s;
}

// Whether a zero edge function counts as inside: the point moved by (eps, eps^2) would be
// inside the triangle of orientation `positive` along the edge direction (ex, ey).
SPHFEM_HD bool owns_edge(bool positive, Real ex, Real ey) {
  const Real nx = positive ? ex : -ex, ny = positive ? ey : -ey;
  return ny > 0 || (ny == 0 && nx < 0);
}

// Edge function test with the tie-breaking rule: e is the edge function, (ex, ey) the edge,
// positive the orientation of the projected triangle.
SPHFEM_HD bool edge_inside(bool positive, double e, Real ex, Real ey) {
  return e == 0 ? owns_edge(positive, ex, ey) : (e > 0) == positive;
}

// Intersection of o + t d, t in [0, tmax], with triangle (a, b, c). On a hit writes t and the
// barycentric weights u of b and v of c (the hit point is (1-u-v) a + u b + v c). Either
// face side counts. The ray must have d != 0 (sh = ray_shear(d)).
SPHFEM_HD bool ray_triangle(const Vec3& o, const RayShear& sh, const Vec3& a, const Vec3& b,
                            const Vec3& c, Real tmax, Real& t, Real& u, Real& v) {
  const Vec3 A = a - o, B = b - o, C = c - o;
  const Real ax = sheared(A[sh.kx], sh.sx, A[sh.kz]), ay = sheared(A[sh.ky], sh.sy, A[sh.kz]);
  const Real bx = sheared(B[sh.kx], sh.sx, B[sh.kz]), by = sheared(B[sh.ky], sh.sy, B[sh.kz]);
  const Real cx = sheared(C[sh.kx], sh.sx, C[sh.kz]), cy = sheared(C[sh.ky], sh.sy, C[sh.kz]);
  // Scaled barycentrics: U weights a (edge b->c), V weights b (edge c->a), W weights c (a->b).
  const double U = edge_function(cx, by, cy, bx);
  const double V = edge_function(ax, cy, ay, cx);
  const double W = edge_function(bx, ay, by, ax);
  const double det = U + V + W;
  if (det == 0) return false;  // ray in the triangle's plane, or a degenerate triangle
  const bool positive = det > 0;
  if (!edge_inside(positive, U, cx - bx, cy - by) || !edge_inside(positive, V, ax - cx, ay - cy) ||
      !edge_inside(positive, W, bx - ax, by - ay))
    return false;
  const double az = double(sh.sz) * A[sh.kz], bz = double(sh.sz) * B[sh.kz],
               cz = double(sh.sz) * C[sh.kz];
  const double inv = 1.0 / det;
  const Real tt = Real((U * az + V * bz + W * cz) * inv);
  if (!(tt >= 0 && tt <= tmax)) return false;
  t = tt;
  u = Real(V * inv);
  v = Real(W * inv);
  return true;
}

// Convenience form for a single ray.
SPHFEM_HD bool intersect_ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b,
                                      const Vec3& c, Real tmax, Real& t, Real& u, Real& v) {
  if (d.x == 0 && d.y == 0 && d.z == 0) return false;
  return ray_triangle(o, ray_shear(d), a, b, c, tmax, t, u, v);
}

// --- closest point on a triangle ---

// Which feature of the triangle holds the closest point: its interior, a vertex, or an edge
// (edge k joins vertex k and vertex (k+1) % 3).
enum Feature : int {
  kFace = 0,
  kVertex0 = 1,
  kVertex1 = 2,
  kVertex2 = 3,
  kEdge01 = 4,
  kEdge12 = 5,
  kEdge20 = 6
};

template <class T>
struct ClosestOnTriangleT {
  V3<T> point;
  T u, v;  // barycentric weights of b and c
  int feature;
};
using ClosestOnTriangle = ClosestOnTriangleT<Real>;

// Ericson, Real-Time Collision Detection (2005), ClosestPtPointTriangle, with the Voronoi
// region reported so callers can pick the matching pseudonormal. In float or double.
template <class T>
SPHFEM_HD ClosestOnTriangleT<T> closest_on_triangle(const V3<T>& p, const V3<T>& a, const V3<T>& b,
                                                    const V3<T>& c) {
  using Real = T;
  using Vec3 = V3<T>;
  ClosestOnTriangleT<T> r;
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    r.point = a, r.u = 0, r.v = 0, r.feature = kVertex0;
    return r;
  }
  const Vec3 bp = p - b;
  const Real d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    r.point = b, r.u = 1, r.v = 0, r.feature = kVertex1;
    return r;
  }
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const Real w = d1 / (d1 - d3);
    r.point = a + w * ab, r.u = w, r.v = 0, r.feature = kEdge01;
    return r;
  }
  const Vec3 cp = p - c;
  const Real d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    r.point = c, r.u = 0, r.v = 1, r.feature = kVertex2;
    return r;
  }
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const Real w = d2 / (d2 - d6);
    r.point = a + w * ac, r.u = 0, r.v = w, r.feature = kEdge20;
    return r;
  }
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const Real w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    r.point = b + w * (c - b), r.u = 1 - w, r.v = w, r.feature = kEdge12;
    return r;
  }
  const Real den = Real(1) / (va + vb + vc);
  const Real v = vb * den, w = vc * den;
  r.point = a + ab * v + ac * w, r.u = v, r.v = w, r.feature = kFace;
  return r;
}

// --- particle against a moving face ---

// Result of a particle's motion against one face, in the face's frame: the particle starts
// at p and moves by rel (its displacement minus the face's over the step); the hit is at
// distance t along rel / len from p, on the face's old position, at barycentrics (u, v).
struct MovingHit {
  Real t, u, v, len;
  Vec3 rel;
};

// A particle moving by dp (= v_particle dt) against a face moving from (a, b, c) by
// (da, db, dc) over the same step; skin extends the cast beyond the step's relative motion.
// Over one step the face is treated as translating with the displacement of one of its
// points: the cast goes from p along rel = dp - d_face against the old face. The point is
// first the face point closest to p (where a contact within the step can happen when the
// particle is near), then, once, the point of that cast's hit. The refined hit is kept when
// it exists, else the first (misses cost leaks, a slightly early contact costs little).
// Exact for a translating face, first order in the step for a rotating or stretching one;
// unlike the face's mean velocity it sees a face that spins in place or swings on a hinge.
// A face that does not move relative to the particle is no hit.
SPHFEM_HD bool moving_triangle(const Vec3& p, const Vec3& dp, Real skin, const Vec3& a,
                               const Vec3& b, const Vec3& c, const Vec3& da, const Vec3& db,
                               const Vec3& dc, MovingHit& hit) {
  const ClosestOnTriangle foot = closest_on_triangle(p, a, b, c);
  const Vec3 rel = dp - (da * (1 - foot.u - foot.v) + db * foot.u + dc * foot.v);
  const Real len = norm(rel);
  if (!(len > 0)) return false;
  Real t, u, v;
  if (!intersect_ray_triangle(p, rel / len, a, b, c, len + skin, t, u, v)) return false;
  hit = MovingHit{t, u, v, len, rel};
  const Vec3 rel1 = dp - (da * (1 - u - v) + db * u + dc * v);
  const Real len1 = norm(rel1);
  if (len1 > 0 && intersect_ray_triangle(p, rel1 / len1, a, b, c, len1 + skin, t, u, v))
    hit = MovingHit{t, u, v, len1, rel1};
  return true;
}

// --- exact continuous collision of a point and a linearly moving face ---

// Where a particle moving linearly from p by dp over a step meets a face whose vertices move
// linearly from (a, b, c) by (da, db, dc) over the same step: tau in (0, 1] is the time in the
// step, (u, v) the barycentrics of the contact at that time, side the sign of the particle's
// side of the face before it (+1: the side the face normal (b - a) x (c - a) points to).
struct Crossing {
  Real tau = 0, u = 0, v = 0;
  int side = 0;
};

// f(tau) = (p - a) . ((b - a) x (c - a)) at time tau, a cubic in tau; k[i] multiplies tau^i.
// In double: the inputs are floats, and the products of their differences lose nothing that
// matters to the sign changes below.
SPHFEM_HD void coplanarity_cubic(const Vec3d& P, const Vec3d& dP, const Vec3d& B, const Vec3d& dB,
                                 const Vec3d& C, const Vec3d& dC, double k[4]) {
  const Vec3d n0 = cross(B, C), n1 = cross(dB, C) + cross(B, dC), n2 = cross(dB, dC);
  k[0] = dot(P, n0);
  k[1] = dot(dP, n0) + dot(P, n1);
  k[2] = dot(dP, n1) + dot(P, n2);
  k[3] = dot(dP, n2);
}

SPHFEM_HD double cubic_at(const double k[4], double t) {
  return ((k[3] * t + k[2]) * t + k[1]) * t + k[0];
}

// The times in (0, 1] to test, ascending: every root of the cubic there (bisection on the
// monotone pieces between the roots of its derivative), every interior extremum (a touch
// without a sign change) and the step's end. Returns how many (at most 6).
SPHFEM_HD int contact_candidates(const double k[4], double out[6]) {
  // Split points: 0, the derivative's roots in (0, 1), 1.
  double s[4];
  int ns = 0;
  s[ns++] = 0;
  const double a = 3 * k[3], b = 2 * k[2], c = k[1];  // f' = a t^2 + b t + c
  double r0 = 2, r1 = 2;
  const double scale = std::fabs(a) + std::fabs(b) + std::fabs(c);
  if (scale > 0) {
    if (std::fabs(a) <= 1e-12 * scale) {
      if (b != 0) r0 = -c / b;
    } else {
      const double disc = b * b - 4 * a * c;
      if (disc >= 0) {
        const double q = -0.5 * (b + (b < 0 ? -1 : 1) * std::sqrt(disc));
        r0 = q / a;
        r1 = q != 0 ? c / q : 2;
        if (r1 < r0) {
          const double t = r0;
          r0 = r1, r1 = t;
        }
      }
    }
  }
  if (r0 > 0 && r0 < 1) s[ns++] = r0;
  if (r1 > 0 && r1 < 1 && r1 != r0) s[ns++] = r1;
  s[ns++] = 1;
  int m = 0;
  for (int j = 0; j + 1 < ns; ++j) {
    double lo = s[j], hi = s[j + 1];
    double flo = cubic_at(k, lo), fhi = cubic_at(k, hi);
    if (flo != 0 && fhi != 0 && (flo < 0) != (fhi < 0)) {
      for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi), fm = cubic_at(k, mid);
        if (fm == 0) {
          lo = hi = mid;
          break;
        }
        if ((fm < 0) == (flo < 0))
          lo = mid, flo = fm;
        else
          hi = mid;
      }
      out[m++] = hi;  // the later end: the particle has reached the plane
    }
    out[m++] = s[j + 1];  // an extremum, or the step's end
  }
  return m;
}

// Exact continuous collision of the particle's path with the moving face, up to tol: the
// earliest time in (0, tau_max) at which the particle is within tol of the face (a root of
// the coplanarity cubic, an extremum of it, or the step's end). Unlike moving_triangle it
// follows every vertex's own motion, so a face that turns or stretches within the step is
// caught exactly. Rounding is covered by tol, which also makes shared edges count on both
// faces. A particle that starts on the face's plane and touches nothing else is no crossing.
// With front_only, contacts from behind the face (side -1) are passed over.
SPHFEM_HD bool point_face_contact(const Vec3& p, const Vec3& dp, const Vec3& a, const Vec3& b,
                                  const Vec3& c, const Vec3& da, const Vec3& db, const Vec3& dc,
                                  Real tol, Real tau_max, Crossing& out, bool front_only = false) {
  const Vec3d A(a), dA(da);
  const Vec3d P = Vec3d(p) - A, dP = Vec3d(dp) - dA;
  const Vec3d B = Vec3d(b) - A, dB = Vec3d(db) - dA;
  const Vec3d C = Vec3d(c) - A, dC = Vec3d(dc) - dA;
  double k[4];
  coplanarity_cubic(P, dP, B, dB, C, dC, k);
  if (k[0] == 0 && k[1] == 0 && k[2] == 0 && k[3] == 0) return false;
  double cand[6];
  const int m = contact_candidates(k, cand);
  double prev = 0;
  for (int j = 0; j < m; ++j) {
    const double t = cand[j];
    if (!(t < double(tau_max))) break;
    const Vec3d pt = P + dP * t;
    const ClosestOnTriangleT<double> q = closest_on_triangle(pt, Vec3d(), B + dB * t, C + dC * t);
    const double fmid = cubic_at(k, 0.5 * (prev + t));
    if (norm(pt - q.point) <= double(tol) && (front_only ? fmid > 0 : fmid != 0)) {
      out = Crossing{Real(t), Real(q.u), Real(q.v), fmid > 0 ? 1 : -1};
      return true;
    }
    prev = t;
  }
  return false;
}

// Bound on how far moving_triangle's casts, which move the whole face with the displacement
// of one of its points, can reach outside the box swept by the face's true motion: the
// displacements of two face points differ by at most twice the largest deviation of a
// vertex displacement from the mean. Refit grows leaf boxes by it.
SPHFEM_HD Real sweep_deviation(const Vec3& da, const Vec3& db, const Vec3& dc) {
  const Vec3 m = (da + db + dc) * (Real(1) / Real(3));
  return Real(2) * rmax(norm(da - m), rmax(norm(db - m), norm(dc - m)));
}

}  // namespace sphfem::collide
