// Stages of the boundary-particle coupling (sph/moving_boundary.h), written once for every
// backend like stages.h: placing the samples on the moved surface, their psi, and the
// impulse the fluid gives them, returned to the surface's nodes.
//
// The impulses are gathered at the samples from the same pair terms the fluid particles
// summed (wall_viscous, wall_pressure_term, dfsph_wall_pair with the fluid's rij), so the
// fluid and the samples exchange equal and opposite momentum up to the order of the sums;
// the nodes then gather their samples' impulses by a fixed list, without atomics.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "sph/stages.h"
#include "sphfem/fem/mesh.h"

namespace sphfem::stages {

// DFSPH: a moving sample's walls-alone density is this share of what its own layer sums to
// (psi makes that rho0), so that its constraint rho_b <= rho0 holds with equality when the
// fluid rests in front of it, as the tank's multi-layer samples' does. The fluid rests where
// a lattice particle's density is rho0 with the layer standing in for the lattice below it:
// at y* with
//   A(y*) / A(0) = Phi(s / 2),
// A the plane integral of the kernel (the layer's density profile, psi-weighted) and Phi the
// half-space of lattice layers (sph/surface_density.h; the lattice below a particle lies
// beyond a plane s / 2 under it). The fluid then gives the sample rho0 Phi(y* - s / 2), and
// the sample's share is what is left: y* = 1.10 s and share 0.895 for the cubic spline,
// 1.08 s and 0.910 for Wendland C2, at h = 2 s. A share of 1/2 (the half-space behind the
// sample) left the samples at 0.6 rho0 under a resting column, never active: only the
// fluid's own term psi_b / rho0 kappa_i grad W pushed, half the pair's stiffness (as for a
// surface without samples, stages::surface_stiffness), and the column's pressure came out
// 8.5 % off (L2; bottom +15 %). A larger share (0.95, tried before wall_source weighted the
// samples by psi_b) made the samples' constraint fight the fluid's: the solve blew up.
//   lattice: half_space_table(kernel, n, s / h, m / (rho0 s^3));
//   continuum: half_space_table(kernel, n) (its slope row is A); layer = s / h.
inline Real moving_rest_share(const std::vector<Real>& lattice, const std::vector<Real>& continuum,
                              int n, double layer) {
  auto row = [n](const std::vector<Real>& t, int r, double q) {
    const double u = std::min(std::max(q, 0.0), 1.0) * n;
    const int k = std::min(int(u), n - 1);
    const double a = double(t[std::size_t(r) * (n + 1) + k]);
    const double b = double(t[std::size_t(r) * (n + 1) + k + 1]);
    return a + (u - k) * (b - a);
  };
  const double missing = row(lattice, kHalfPhi, 0.5 * layer);
  const double a0 = row(continuum, kHalfSlope, 0.0);
  double lo = 0, hi = 1;  // A decreases from A(0) to 0 at the support
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (row(continuum, kHalfSlope, mid) > missing * a0 ? lo : hi) = mid;
  }
  return Real(1.0 - row(lattice, kHalfPhi, 0.5 * (lo + hi) - 0.5 * layer));
}

// x = sum_c w_c x(node c) of each sample's triangle, v likewise (v null: not computed).
template <class Exec>
void place_samples(Exec& ex, int n, const int* tri_id, const Vec3* weight, const Tri* tris,
                   const Vec3* node_x, const Vec3* node_v, Vec3* x, Vec3* v) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int k) {
    const Tri t = tris[tri_id[k]];
    const Vec3 w = weight[k];
    x[k] = node_x[t.v[0]] * w.x + node_x[t.v[1]] * w.y + node_x[t.v[2]] * w.z;
    if (v) v[k] = node_v[t.v[0]] * w.x + node_v[t.v[1]] * w.y + node_v[t.v[2]] * w.z;
  });
}

// slot[perm[k]] = k: where the sort put each sample.
template <class Exec>
void invert(Exec& ex, const std::uint32_t* perm, std::uint32_t* slot, int n) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int k) { slot[perm[k]] = std::uint32_t(k); });
}

// Akinci et al. 2012, eq. 5: psi_b = rho0 / sum_k W_bk over the samples in reach, itself
// included, so that densely sampled parts of a surface do not push harder.
template <class Exec>
void sample_psi(Exec& ex, const SphParams P, const BoundaryView b, Real* psi) {
  parallel_for(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    Real sum = 0;
    for_neighbors(b.grid, b.x, b.x[k], P.h2,
                  [&](std::uint32_t, const Vec3&, Real r2) { sum += P.kernel.W(std::sqrt(r2)); });
    psi[k] = P.rho0 / sum;
  });
}

// Impulse of this step's viscous and (WCSPH) pressure accelerations on each sample: minus
// dt m times what each fluid neighbour took from it in accelerations. Call before the kick.
template <class Exec>
void sample_force_impulse(Exec& ex, const SphParams P, const FluidView f, const GridView g,
                          const BoundaryView b, bool with_pressure, Real dt, Vec3* impulse) {
  parallel_for(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    const Vec3 xb = b.x[k];
    const Real eps2 = Real(0.01) * P.spacing * P.spacing;
    Vec3 sum;
    for_neighbors(g, f.x, xb, P.h2, [&](std::uint32_t j, const Vec3&, Real) {
      const Vec3 r = f.x[j] - xb;  // as the fluid particle sees the sample
      const Real r2 = norm2(r);
      if (r2 <= Real(0)) return;
      const Vec3 gw = P.kernel.grad(r, std::sqrt(r2));
      sum += wall_viscous(P, b, k, f.v[j], r, r2, gw, eps2);
      if (with_pressure) {
        const Real rhoj = f.rho[j];
        sum -= wall_pressure_term(b, k, gw, f.p[j] / (rhoj * rhoj));
      }
    });
    impulse[k] -= sum * (P.mass * dt);
  });
}

// Impulse of a DFSPH solve on each sample: its fluid neighbours changed velocity by
// -dt sum over sweeps of psi_b / rho0 (kappa_j + kappa_b) grad W_jb, which is linear in the
// stiffness, so the solve's sums give the total. Call after the solve, before the next one.
template <class Exec>
void sample_pressure_impulse(Exec& ex, const SphParams P, const FluidView f, const GridView g,
                             const BoundaryView b, Real dt, Vec3* impulse) {
  parallel_for(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    const Vec3 xb = b.x[k];
    Vec3 sum;
    for_neighbors(g, f.x, xb, P.h2, [&](std::uint32_t j, const Vec3&, Real) {
      const Vec3 r = f.x[j] - xb;
      const Real c = dfsph_wall_pair(P, b, k, f.kappa_sum[j], b.kappa_sum[k]);
      if (c != Real(0)) sum += P.kernel.grad(r, std::sqrt(norm2(r))) * c;
    });
    impulse[k] += sum * (P.mass * dt);
  });
}

// Node n gathers weight[e] times the impulse of sample sample[e] (original numbering; slot
// maps it to the sorted one) for e in [start[n], start[n + 1]), and adds it to out[n].
template <class Exec>
void node_impulse(Exec& ex, int nodes, const int* start, const int* sample, const Real* weight,
                  const std::uint32_t* slot, const Vec3* impulse, Vec3* out) {
  parallel_for(ex, nodes, [=] SPHFEM_LAMBDA(int n) {
    Vec3 sum;
    for (int e = start[n]; e < start[n + 1]; ++e) sum += impulse[slot[sample[e]]] * weight[e];
    out[n] += sum;
  });
}

}  // namespace sphfem::stages
