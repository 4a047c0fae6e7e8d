// The FEM stages, written once for every backend. Each stage is a function template over the
// execution backend (CpuExec, CudaExec) whose per-element or per-node body is a
// host-and-device lambda over raw arrays carried in small views copied by value.
//
// Implicit Euler (Baraff and Witkin 1998) with the co-rotated force linearised about the
// inertial prediction x~ = x + dt v, whose element rotations R~ are held fixed over the step,
// and Rayleigh damping D = alpha M + beta K (K = R~ K_e R~^T):
//   M dv = dt (f(x+) + f_ext - D v+),  v+ = v + dv,  x+ = x + dt v+ = x~ + dt dv,
// and f(x+) ~ f(x~) - dt K dv gives
//   (M + dt D + dt^2 K) dv = dt (f(x~) - beta K v - alpha M v + f_ext) + J.
// For fixed rotations f is affine in x, so f(x~) - beta K v is the elastic force at
// y = x + (dt + beta) v: the right-hand side costs one element pass. J are the impulses the
// coupling adds. Why x~ and not x: a rigid rotation is (nearly) in the null space of K, so
// rotations taken at x leave the forces in the start-of-step orientation; for a spinning,
// stressed body they then lag the rotation and push along the motion, and kinetic energy
// and angular momentum grow. At x~ the forces turn with the body and the step dissipates.
// The system is symmetric positive definite on the free nodes and is solved by CG with a
// block-Jacobi preconditioner (inverse 3x3 diagonal blocks per node). Optional Newton
// corrections repeat this about u = v + dv: rotations at x + dt u, elastic force at
// x + (dt + beta) u, damping on u, and the residual's inertia term - M dv.
//
// Element passes write per-element node vectors; node passes gather them through the
// node -> (element, local index) lists, so sums are deterministic and need no atomics.
#pragma once

#include <cstdint>

#include "fem/corotated.h"
#include "fem/polar.h"
#include "sphfem/fem/mesh.h"

namespace sphfem::fem {

struct ElementView {
  int n = 0;
  const Tet* tet = nullptr;
  const Vec3* grad = nullptr;  // 3 per element: rows of Dm^-1
  const Real* mu_vol = nullptr;
  const Real* lambda_vol = nullptr;
  const Real* beta = nullptr;
};

struct NodeView {
  int n = 0;
  const Real* mass = nullptr;
  const Real* alpha = nullptr;
  const std::uint8_t* pinned = nullptr;
  const int* inc_start = nullptr;
  const int* inc = nullptr;  // element * 4 + local index
};

// Symmetric 3x3 matrix (xx, yy, zz, xy, xz, yz).
struct Sym3 {
  Real xx, yy, zz, xy, xz, yz;
};

SPHFEM_HD Vec3 operator*(const Sym3& s, const Vec3& v) {
  return Vec3(s.xx * v.x + s.xy * v.y + s.xz * v.z, s.xy * v.x + s.yy * v.y + s.yz * v.z,
              s.xz * v.x + s.yz * v.y + s.zz * v.z);
}

// Rotated gradient P_a = R g_a of local node a (P_0 = -(P_1 + P_2 + P_3)).
SPHFEM_HD Vec3 rotated_gradient(const Vec3* P, int t, int a) {
  if (a > 0) return P[3 * t + a - 1];
  return -(P[3 * t] + P[3 * t + 1] + P[3 * t + 2]);
}

// Element rotations at the positions x + c v (v may be null: at x) by Mueller et al. 2016,
// warm-started from q_in. `fresh`: no usable previous rotation (a pose set from outside), so probe
// many starting rotations and keep the best aligned (extract_rotation_fresh). Writes the rotations
// to q_out (may alias q_in) and the rotated gradients P = R g to P.
template <class Exec>
void rotations(Exec& ex, const ElementView e, const Vec3* x, const Vec3* v, Real c,
               const Quat* q_in, Quat* q_out, Vec3* P, int iterations, bool fresh) {
  parallel_for(ex, e.n, [=] SPHFEM_LAMBDA(int t) {
    const Tet tet = e.tet[t];
    Vec3 xs[4];
    for (int a = 0; a < 4; ++a) xs[a] = v ? x[tet.v[a]] + v[tet.v[a]] * c : x[tet.v[a]];
    const Vec3 g[3] = {e.grad[3 * t], e.grad[3 * t + 1], e.grad[3 * t + 2]};
    const Mat3 F = deformation_gradient(xs, g);
    const Quat q = fresh ? extract_rotation_fresh(F, q_in[t], iterations)
                         : extract_rotation(F, q_in[t], iterations);
    q_out[t] = q;
    const Mat3 R = q.matrix();
    for (int a = 0; a < 3; ++a) P[3 * t + a] = R * g[a];
  });
}

// Inverse diagonal blocks of A = (1 + dt alpha) M + dt (dt + beta) K_R; zero on pinned nodes,
// which masks them out of CG.
// Node i's diagonal block of A = (1 + dt alpha) M + dt (dt + beta) K_R (xx, yy, zz, xy, xz, yz).
SPHFEM_HD void diagonal_of_a(const ElementView& e, const NodeView& nv, const Vec3* P, Real dt,
                             int i, Real* b) {
  const Real m = nv.mass[i] * (Real(1) + dt * nv.alpha[i]);
  b[0] = b[1] = b[2] = m;
  b[3] = b[4] = b[5] = Real(0);
  for (int k = nv.inc_start[i]; k < nv.inc_start[i + 1]; ++k) {
    const int t = nv.inc[k] >> 2, a = nv.inc[k] & 3;
    const Real s = dt * (dt + e.beta[t]);
    Real d[6];
    diagonal_block(rotated_gradient(P, t, a), s * e.mu_vol[t], s * e.lambda_vol[t], d);
    for (int c = 0; c < 6; ++c) b[c] += d[c];
  }
}

// The inverse of a symmetric 3x3 block (xx, yy, zz, xy, xz, yz), by cofactors.
SPHFEM_HD Sym3 inverse_block(const Real* b) {
  const Real c00 = b[1] * b[2] - b[5] * b[5], c11 = b[0] * b[2] - b[4] * b[4];
  const Real c22 = b[0] * b[1] - b[3] * b[3], c01 = b[4] * b[5] - b[3] * b[2];
  const Real c02 = b[3] * b[5] - b[1] * b[4], c12 = b[3] * b[4] - b[0] * b[5];
  const Real inv = Real(1) / (b[0] * c00 + b[3] * c01 + b[4] * c02);
  return Sym3{c00 * inv, c11 * inv, c22 * inv, c01 * inv, c02 * inv, c12 * inv};
}

template <class Exec>
void preconditioner(Exec& ex, const ElementView e, const NodeView nv, const Vec3* P, Real dt,
                    Sym3* pinv) {
  parallel_for(ex, nv.n, [=] SPHFEM_LAMBDA(int i) {
    if (nv.pinned[i]) {
      pinv[i] = Sym3{0, 0, 0, 0, 0, 0};
      return;
    }
    Real b[6];
    diagonal_of_a(e, nv, P, dt, i, b);
    pinv[i] = inverse_block(b);
  });
}

// The diagonal blocks of A, 6 values per node (0 on pinned nodes).
template <class Exec>
void diagonal_blocks(Exec& ex, const ElementView e, const NodeView nv, const Vec3* P, Real dt,
                     Real* blocks) {
  parallel_for(ex, nv.n, [=] SPHFEM_LAMBDA(int i) {
    Real b[6] = {0, 0, 0, 0, 0, 0};
    if (!nv.pinned[i]) diagonal_of_a(e, nv, P, dt, i, b);
    for (int c = 0; c < 6; ++c) blocks[6 * i + c] = b[c];
  });
}

// Element elastic forces at y = x + (c + beta_t) v (v may be null: y = x), per element node.
template <class Exec>
void element_forces(Exec& ex, const ElementView e, const Vec3* x, const Vec3* v, Real c,
                    const Vec3* P, Vec3* fe) {
  parallel_for(ex, e.n, [=] SPHFEM_LAMBDA(int t) {
    const Tet tet = e.tet[t];
    Vec3 y[4];
    const Real s = v ? c + e.beta[t] : Real(0);
    for (int a = 0; a < 4; ++a) y[a] = v ? x[tet.v[a]] + v[tet.v[a]] * s : x[tet.v[a]];
    const Vec3 Pt[3] = {P[3 * t], P[3 * t + 1], P[3 * t + 2]};
    Vec3 out[4];
    stress_products(y, Pt, -e.mu_vol[t], -e.lambda_vol[t], Real(1), out);
    for (int a = 0; a < 4; ++a) fe[4 * t + a] = out[a];
  });
}

// Element products dt (dt + beta_t) K_R p, per element node.
template <class Exec>
void element_stiffness(Exec& ex, const ElementView e, const Vec3* p, const Vec3* P, Real dt,
                       Vec3* fe) {
  parallel_for(ex, e.n, [=] SPHFEM_LAMBDA(int t) {
    const Tet tet = e.tet[t];
    const Vec3 w[4] = {p[tet.v[0]], p[tet.v[1]], p[tet.v[2]], p[tet.v[3]]};
    const Vec3 Pt[3] = {P[3 * t], P[3 * t + 1], P[3 * t + 2]};
    const Real s = dt * (dt + e.beta[t]);
    Vec3 out[4];
    stress_products(w, Pt, s * e.mu_vol[t], s * e.lambda_vol[t], Real(0), out);
    for (int a = 0; a < 4; ++a) fe[4 * t + a] = out[a];
  });
}

// Sum of the element node vectors around node i.
SPHFEM_HD Vec3 gather(const NodeView& nv, const Vec3* fe, int i) {
  Vec3 s;
  for (int k = nv.inc_start[i]; k < nv.inc_start[i + 1]; ++k) s += fe[nv.inc[k]];
  return s;
}

// Right-hand side b = dt (f_el + f_ext + m g - alpha m u) + J - m dv on free nodes, 0 on
// pinned, with u = v + dv the velocity the step linearises about (dv: the velocity change so
// far, for Newton corrections). f_ext, J and dv may be null.
template <class Exec>
void assemble_rhs(Exec& ex, const NodeView nv, const Vec3* fe, const Vec3* u, const Vec3* fext,
                  const Vec3* J, const Vec3* dv, Vec3 gravity, Real dt, Vec3* b) {
  parallel_for(ex, nv.n, [=] SPHFEM_LAMBDA(int i) {
    if (nv.pinned[i]) {
      b[i] = Vec3();
      return;
    }
    const Real m = nv.mass[i];
    Vec3 f = gather(nv, fe, i) + gravity * m - u[i] * (nv.alpha[i] * m);
    if (fext) f += fext[i];
    Vec3 r = f * dt;
    if (J) r += J[i];
    if (dv) r -= dv[i] * m;
    b[i] = r;
  });
}

// q = A p on free nodes (0 on pinned) from the element products in fe; returns p . q.
template <class Exec>
double apply_nodes(Exec& ex, const NodeView nv, const Vec3* fe, const Vec3* p, Real dt, Vec3* q) {
  return reduce_sum(ex, nv.n, [=] SPHFEM_LAMBDA(int i) -> double {
    if (nv.pinned[i]) {
      q[i] = Vec3();
      return 0.0;
    }
    const Vec3 r = p[i] * (nv.mass[i] * (Real(1) + dt * nv.alpha[i])) + gather(nv, fe, i);
    q[i] = r;
    return double(dot(p[i], r));
  });
}

// The components a wall holds (mask bit c: axis c, see hold_walls) taken out of a.
SPHFEM_HD Vec3 free_part(Vec3 a, std::uint8_t m) {
  if (m & 1) a.x = Real(0);
  if (m & 2) a.y = Real(0);
  if (m & 4) a.z = Real(0);
  return a;
}

// CG start: r = b - q (q = A x0, or null for x0 = 0), z = Pinv r, p = z; returns r . z. With
// a mask, r and z lose the held components (Baraff & Witkin's filtered PCG).
template <class Exec>
double cg_start(Exec& ex, int n, const Vec3* b, const Vec3* q, const Sym3* pinv, Vec3* r, Vec3* z,
                Vec3* p, const std::uint8_t* mask = nullptr) {
  return reduce_sum(ex, n, [=] SPHFEM_LAMBDA(int i) -> double {
    Vec3 ri = q ? b[i] - q[i] : b[i];
    if (mask) ri = free_part(ri, mask[i]);
    Vec3 zi = pinv[i] * ri;
    if (mask) zi = free_part(zi, mask[i]);
    r[i] = ri;
    z[i] = zi;
    p[i] = zi;
    return double(dot(ri, zi));
  });
}

// x += a p, r -= a q, z = Pinv r; returns r . z. With a mask as cg_start.
template <class Exec>
double cg_update(Exec& ex, int n, Real a, const Vec3* p, const Vec3* q, const Sym3* pinv, Vec3* x,
                 Vec3* r, Vec3* z, const std::uint8_t* mask = nullptr) {
  return reduce_sum(ex, n, [=] SPHFEM_LAMBDA(int i) -> double {
    x[i] += p[i] * a;
    Vec3 ri = r[i] - q[i] * a;
    if (mask) ri = free_part(ri, mask[i]);
    Vec3 zi = pinv[i] * ri;
    if (mask) zi = free_part(zi, mask[i]);
    r[i] = ri;
    z[i] = zi;
    return double(dot(ri, zi));
  });
}

// p = z + beta p.
template <class Exec>
void cg_direction(Exec& ex, int n, Real beta, const Vec3* z, Vec3* p) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) { p[i] = z[i] + p[i] * beta; });
}

template <class Exec>
void accumulate(Exec& ex, int n, const Vec3* src, Vec3* dst) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) { dst[i] += src[i]; });
}

template <class Exec>
void add(Exec& ex, int n, const Vec3* a, const Vec3* b, Vec3* out) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) { out[i] = a[i] + b[i]; });
}

// v += dv (pinned nodes stay at rest), x += dt v.
template <class Exec>
void integrate(Exec& ex, const NodeView nv, const Vec3* dv, Real dt, Vec3* x, Vec3* v) {
  parallel_for_light(ex, nv.n, [=] SPHFEM_LAMBDA(int i) {
    if (nv.pinned[i]) {
      v[i] = Vec3();
      return;
    }
    const Vec3 vi = v[i] + dv[i];
    v[i] = vi;
    x[i] += vi * dt;
  });
}

// Nodes outside the box [lo, hi] go back onto it; the outward normal velocity is removed and
// the tangential velocity loses mu times the removed normal speed (Coulomb friction, sticking
// when that exceeds it). Returns the number of nodes pushed back.
template <class Exec>
int collide_box(Exec& ex, int n, Vec3 lo, Vec3 hi, Real mu, Vec3* x, Vec3* v) {
  const double hits = reduce_sum(ex, n, [=] SPHFEM_LAMBDA(int i) -> double {
    Vec3 xi = x[i], vi = v[i];
    Real removed = 0;
    bool hit = false, normal[3] = {false, false, false};
    for (int c = 0; c < 3; ++c) {
      if (xi[c] < lo[c]) {
        xi[c] = lo[c];
        if (vi[c] < Real(0)) removed -= vi[c], vi[c] = Real(0), normal[c] = true;
        hit = true;
      } else if (xi[c] > hi[c]) {
        xi[c] = hi[c];
        if (vi[c] > Real(0)) removed += vi[c], vi[c] = Real(0), normal[c] = true;
        hit = true;
      }
    }
    if (!hit) return 0.0;
    if (removed > Real(0)) {
      Vec3 vt = vi;
      for (int c = 0; c < 3; ++c)
        if (normal[c]) vt[c] = Real(0);
      const Real st = norm(vt);
      const Real keep = st > mu * removed ? Real(1) - mu * removed / st : Real(0);
      for (int c = 0; c < 3; ++c)
        if (!normal[c]) vi[c] *= keep;
    }
    x[i] = xi;
    v[i] = vi;
    return 1.0;
  });
  return int(hits + 0.5);
}

template <class Exec>
double kinetic_energy(Exec& ex, const NodeView nv, const Vec3* v) {
  return reduce_sum(ex, nv.n, [=] SPHFEM_LAMBDA(int i) -> double {
    return 0.5 * double(nv.mass[i]) * double(norm2(v[i]));
  });
}

// Co-rotated elastic energy with rotations refined from q by `iterations` (not stored).
template <class Exec>
double elastic_energy(Exec& ex, const ElementView e, const Vec3* x, const Quat* q, int iterations) {
  return reduce_sum(ex, e.n, [=] SPHFEM_LAMBDA(int t) -> double {
    const Tet tet = e.tet[t];
    const Vec3 xs[4] = {x[tet.v[0]], x[tet.v[1]], x[tet.v[2]], x[tet.v[3]]};
    const Vec3 g[3] = {e.grad[3 * t], e.grad[3 * t + 1], e.grad[3 * t + 2]};
    const Mat3 R = extract_rotation(deformation_gradient(xs, g), q[t], iterations).matrix();
    const Vec3 P[3] = {R * g[0], R * g[1], R * g[2]};
    return double(corotated_energy(xs, P, e.mu_vol[t], e.lambda_vol[t]));
  });
}

}  // namespace sphfem::fem
