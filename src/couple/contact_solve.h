// The momentum exchange of one step with every particle-face contact solved together
// (docs/design.md, "The joint contact solve"), written once for every backend.
//
// Each particle whose ray hit a face is one contact c: the face's normal n toward the
// particle, the hit's barycentric weights w, and its relative velocity u = v_face(w) - v_p.
// An impulse J_c on the face (the particle gets -J_c, node j gets w_j J_c) moves every
// contact sharing a node with c. The law each active contact meets after the exchange:
//   u = u*,  u*.n = -C_r u0.n,  u*_t = C_s u0_t        (an approaching contact), or
//   u.n = 0 with J along n                              (one that other contacts pushed in);
// and no contact pulls (J.n <= 0). For a given set of active contacts, with P_c the identity
// or n n^T, the particle side follows from the nodes' velocity change dV:
//   J_c = m_p P_c (u*_c - u0_c - sum_j w_cj dV_j),
// so the nodes satisfy the symmetric positive definite system
//   (M + m_p W P W^T) dV = m_p W P (u* - u0),
// which conjugate gradients solve matrix-free over the nodes the contacts touch (Jacobi
// preconditioned). With the bodies' step operator (NodeOperator) in place of M, A = (1 + dt
// alpha) M + dt (dt + beta) K, the unknowns are every node of the bodies and the solve sees
// the velocity change the next implicit step will make of the impulses: a light node held by
// its elements is not taken for a free one (docs/design.md). An outer loop drops contacts that
// would pull and adds those pushed into approach, until the set no longer changes; in its later
// rounds it only drops (join = false), so it cannot cycle. Node sums run
// over a list sorted by node in a fixed order, and every particle gets exactly -J_c: momentum is
// exact, bits are the same on any thread count.
#pragma once

#include <cstdint>

#include "couple/stages.h"

namespace sphfem::couple {

struct Contact {
  int particle = 0, face = 0, body = 0;
  int node[3] = {-1, -1, -1};  // global node (SurfaceView::node_base + local); -1: immovable
  Real w[3] = {0, 0, 0};
  Real inv_m[3] = {0, 0, 0};
  Vec3 n;       // unit face normal toward the particle's side
  Vec3 u0;      // v_face - v_particle before the exchange
  Vec3 target;  // u* of an approaching contact
  int approaching = 0;
  int mode = 0;  // 0 inactive, 1 the full law (P = I), 2 the normal only (P = n n^T)
  Vec3 s;        // m_p P (u* - u0)
  Vec3 t;        // m_p P (W^T x) for the vector x the solve applies its matrix to
  Vec3 J;        // impulse on the face
};

// Contact offset[i] for each particle i with a hit (offset: exclusive scan of the hit flags).
template <class Exec>
void contact_setup(Exec& ex, const SurfacesView S, const HitView h, const ParticleView p,
                   const std::uint32_t* offset, Contact* contacts) {
  parallel_for(ex, p.n, [=] SPHFEM_LAMBDA(int i) {
    const int f = h.face[i];
    if (f < 0 || f >= S.faces) return;
    const FaceNodes fn = face_nodes(S, f);
    Contact c;
    c.particle = i;
    c.face = f;
    c.body = body_of(S, f);
    weights(h, i, c.w);
    const int base = S.set[fn.set].node_base;
    for (int k = 0; k < 3; ++k) {
      c.inv_m[k] = fn.inv_m[k];
      c.node[k] = fn.inv_m[k] > Real(0) && c.w[k] != Real(0) ? base + fn.node[k] : -1;
    }
    // The particle's side of the face: where it is, or on the plane the side it comes from.
    Vec3 n = face_normal(fn.x[0], fn.x[1], fn.x[2]);
    const Vec3 vf = at(fn.v, c.w);
    Real side = dot(p.x[i] - at(fn.x, c.w), n);
    if (side == Real(0)) side = -dot(p.v[i] - vf, n);
    if (side < Real(0)) n = -n;
    c.n = n;
    c.u0 = vf - p.v[i];
    const Real un = dot(c.u0, n);
    const ContactCoeffs cc = S.coeffs[c.body];
    c.approaching = un > Real(0) ? 1 : 0;
    c.target = c.approaching ? n * (-cc.restitution * un) + (c.u0 - n * un) * cc.slip : Vec3();
    c.mode = c.approaching;
    const Real b = h.bias ? h.bias[i] : Real(0);
    if (b == b && h.bias) {
      // Held at separation speed b: u.n = -b is u'.n = 0 for u' = u + n b, the normal-only
      // law (mode 2) on the shifted velocity.
      c.u0 += n * b;
      c.approaching = 0;
      c.target = Vec3();
      c.mode = dot(c.u0, n) > Real(0) ? 2 : 0;
    }
    contacts[offset[i]] = c;
  });
}

// Entry e = 3 c + corner of the node list: key = its node (nodes: none), value e.
template <class Exec>
void node_entries(Exec& ex, const Contact* contacts, int m, int nodes, std::uint32_t* keys,
                  std::uint32_t* vals) {
  parallel_for(ex, 3 * m, [=] SPHFEM_LAMBDA(int e) {
    const int node = contacts[e / 3].node[e % 3];
    keys[e] = node >= 0 ? std::uint32_t(node) : std::uint32_t(nodes);
    vals[e] = std::uint32_t(e);
  });
}

// head[e] = 1 where a run of equal keys starts.
template <class Exec>
void run_heads(Exec& ex, const std::uint32_t* keys, int m, std::uint32_t* head) {
  parallel_for(ex, m,
               [=] SPHFEM_LAMBDA(int e) { head[e] = e == 0 || keys[e] != keys[e - 1] ? 1u : 0u; });
}

// first[r] = the first entry of run r (index: exclusive scan of the heads), first[runs] = m;
// slot[value] = the run of each entry, so a contact finds its nodes' runs.
template <class Exec>
void run_starts(Exec& ex, const std::uint32_t* keys, const std::uint32_t* vals,
                const std::uint32_t* index, int m, int runs, std::uint32_t* first,
                std::uint32_t* slot) {
  parallel_for(ex, m, [=] SPHFEM_LAMBDA(int e) {
    const bool head = e == 0 || keys[e] != keys[e - 1];
    const std::uint32_t r = head ? index[e] : index[e] - 1u;
    if (head) first[r] = std::uint32_t(e);
    if (e == m - 1) first[runs] = std::uint32_t(m);
    slot[vals[e]] = r;
  });
}

// Per node run: its mass and the diagonal of the solve's matrix, m_j + m_p sum_c w_cj^2.
template <class Exec>
void node_diagonal(Exec& ex, const Contact* contacts, const std::uint32_t* vals,
                   const std::uint32_t* first, int runs, Real mp, Real* mass, Real* diag) {
  parallel_for(ex, runs, [=] SPHFEM_LAMBDA(int r) {
    const std::uint32_t v0 = vals[first[r]];
    const Real m = Real(1) / contacts[v0 / 3].inv_m[v0 % 3];
    Real d = m;
    for (std::uint32_t e = first[r]; e < first[r + 1]; ++e) {
      const std::uint32_t v = vals[e];
      const Real w = contacts[v / 3].w[v % 3];
      if (contacts[v / 3].mode) d += mp * w * w;
    }
    mass[r] = m;
    diag[r] = d;
  });
}

// Where contact c's corner j reads a node vector: its run (slot), or with slot null the
// node itself (vectors over every node, as the solve with the bodies' operator keeps them).
SPHFEM_HD int node_slot(const Contact& ct, int c, int j, const std::uint32_t* slot) {
  return slot ? int(slot[3 * c + j]) : ct.node[j];
}

SPHFEM_HD Vec3 project(const Contact& c, const Vec3& a) {
  return c.mode == 1 ? a : c.mode == 2 ? c.n * dot(c.n, a) : Vec3();
}

// s_c = m_p P_c (u*_c - u0_c) for the active contacts; 0 for the others.
template <class Exec>
void contact_rhs(Exec& ex, Contact* contacts, int m, Real mp) {
  parallel_for(ex, m, [=] SPHFEM_LAMBDA(int c) {
    Contact& ct = contacts[c];
    const Vec3 target = ct.mode == 1 ? ct.target : Vec3();  // mode 2: u.n = 0
    ct.s = project(ct, target - ct.u0) * mp;
  });
}

// t_c = m_p P_c sum_j w_cj x_j, for the node vector x (by run, or by node with slot null;
// immovable nodes have none).
template <class Exec>
void contact_apply(Exec& ex, Contact* contacts, int m, const std::uint32_t* slot, const Vec3* x,
                   Real mp) {
  parallel_for(ex, m, [=] SPHFEM_LAMBDA(int c) {
    Contact& ct = contacts[c];
    Vec3 a;
    for (int j = 0; j < 3; ++j)
      if (ct.node[j] >= 0) a += x[node_slot(ct, c, j, slot)] * ct.w[j];
    ct.t = project(ct, a) * mp;
  });
}

// Per node run, in its fixed order, a sum over its contacts c of w_cj times:
//   kMatrix: t_c, plus mass x (the matrix applied to x);  kRhs: s_c;  kImpulse: J_c;
//   kContact: t_c alone (the contacts' part of the matrix).
enum NodeSum { kMatrix, kRhs, kImpulse, kContact };
template <class Exec>
void node_gather(Exec& ex, const Contact* contacts, const std::uint32_t* vals,
                 const std::uint32_t* first, int runs, NodeSum what, const Real* mass,
                 const Vec3* x, Vec3* out) {
  parallel_for(ex, runs, [=] SPHFEM_LAMBDA(int r) {
    Vec3 s;
    for (std::uint32_t e = first[r]; e < first[r + 1]; ++e) {
      const std::uint32_t v = vals[e];
      const Contact& ct = contacts[v / 3];
      s += (what == kMatrix || what == kContact ? ct.t : what == kRhs ? ct.s : ct.J) * ct.w[v % 3];
    }
    out[r] = what == kMatrix ? x[r] * mass[r] + s : s;
  });
}

// J_c = s_c - t_c (t_c from the solved node velocities), and the active set's next change:
// an active contact that would pull leaves it, an inactive one the others pushed into
// approach joins it (normal only). Returns the number of changes.
template <class Exec>
int contact_update(Exec& ex, Contact* contacts, int m, const std::uint32_t* slot, const Vec3* dV,
                   Real tol, bool join = true) {
  const double changes = reduce_sum(ex, m, [=] SPHFEM_LAMBDA(int c) -> double {
    Contact& ct = contacts[c];
    ct.J = ct.mode ? ct.s - ct.t : Vec3();
    if (ct.mode) {
      if (dot(ct.J, ct.n) > Real(0)) {
        ct.mode = 0;
        return 1.0;
      }
      return 0.0;
    }
    if (!join) return 0.0;
    Vec3 u = ct.u0;
    for (int j = 0; j < 3; ++j)
      if (ct.node[j] >= 0) u += dV[node_slot(ct, c, j, slot)] * ct.w[j];
    if (dot(u, ct.n) > tol) {
      ct.mode = ct.approaching ? 1 : 2;
      return 1.0;
    }
    return 0.0;
  });
  return int(changes + 0.5);
}

// The largest distance of a contact from its law after the solve (m/s): the active ones from
// their target, the inactive ones from non-approach.
template <class Exec>
Real contact_residual(Exec& ex, const Contact* contacts, int m, const std::uint32_t* slot,
                      const Vec3* dV, Real inv_mp) {
  return reduce_max(ex, m, Real(0), [=] SPHFEM_LAMBDA(int c) -> Real {
    const Contact& ct = contacts[c];
    Vec3 u = ct.u0 + ct.J * inv_mp;
    for (int j = 0; j < 3; ++j)
      if (ct.node[j] >= 0) u += dV[node_slot(ct, c, j, slot)] * ct.w[j];
    if (ct.mode == 1) return norm(u - ct.target);
    const Real un = dot(u, ct.n);
    if (ct.mode == 2) return un < Real(0) ? -un : un;
    return un > Real(0) ? un : Real(0);
  });
}

// The particles' share: v_p -= J / m_p (one contact per particle, so plain writes).
template <class Exec>
void apply_to_particles(Exec& ex, const Contact* contacts, int m, Vec3* v, Real inv_mp) {
  parallel_for(ex, m,
               [=] SPHFEM_LAMBDA(int c) { v[contacts[c].particle] -= contacts[c].J * inv_mp; });
}

// The nodes' share sum_c w_cj J_c (by run), into each set's impulse array; nodes below
// `from` are left out (they took theirs as a velocity change).
template <class Exec>
void apply_to_nodes(Exec& ex, const SurfacesView S, const std::uint32_t* keys,
                    const std::uint32_t* first, int runs, const Vec3* impulse_of_run, int from) {
  parallel_for(ex, runs, [=] SPHFEM_LAMBDA(int r) {
    const int node = int(keys[first[r]]);
    if (node < from) return;
    int s = 0;
    while (s + 1 < S.count && node >= S.set[s + 1].node_base) ++s;
    Vec3* impulse = S.set[s].impulse;
    if (impulse) impulse[node - S.set[s].node_base] += impulse_of_run[r];
  });
}

}  // namespace sphfem::couple
