// The SPH stages, written once for every backend. Each stage is a function template over
// the execution backend (CpuExec, CudaExec) whose per-particle body is a host-and-device
// lambda; the arrays travel as raw pointers in small views copied by value.
//
// WCSPH: Becker & Teschner 2007 with the paper's state equation p = k (rho/rho0 - 1), p >= 0.
// DFSPH: Bender & Koschier 2015/2017 (divergence-free and constant-density solvers).
// Boundaries: static samples with mass psi (Akinci et al. 2012).
#pragma once

#include <cstdint>

#include "sphfem/sph/grid.h"
#include "sphfem/sph/model.h"

namespace sphfem::stages {

struct FluidView {
  int n = 0;
  Vec3* x = nullptr;
  Vec3* v = nullptr;
  Vec3* a = nullptr;
  Real* rho = nullptr;
  Real* p = nullptr;      // WCSPH pressure
  Real* alpha = nullptr;  // DFSPH factor 1 / (|sum V grad W|^2 + sum |V grad W|^2)
  Real* kappa = nullptr;  // DFSPH stiffness of the current solve
  int* nb = nullptr;      // fluid neighbour count
  std::uint32_t* id = nullptr;
};

struct BoundaryView {
  const Vec3* x = nullptr;
  const Real* psi = nullptr;
  GridView grid;
};

// Cell of every particle, and the identity permutation for the sort.
template <class Exec>
void cell_keys(Exec& ex, const GridView g, const Vec3* x, std::uint32_t* keys,
               std::uint32_t* perm, int n) {
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    keys[i] = g.cell(x[i]);
    perm[i] = std::uint32_t(i);
  });
}

// start[c] = first index with key >= c, for sorted keys; start[cells] = n.
template <class Exec>
void cell_starts(Exec& ex, const std::uint32_t* keys, std::uint32_t* start, int n, int cells) {
  if (n == 0) {
    parallel_for(ex, cells + 1, [=] SPHFEM_LAMBDA(int c) { start[c] = 0; });
    return;
  }
  parallel_for(ex, n + 1, [=] SPHFEM_LAMBDA(int i) {
    const std::uint32_t lo = i == 0 ? 0u : keys[i - 1] + 1u;
    const std::uint32_t hi = i == n ? std::uint32_t(cells) : keys[i];
    for (std::uint32_t c = lo; c <= hi; ++c) start[c] = std::uint32_t(i);
  });
}

template <class Exec, class T>
void gather(Exec& ex, const T* src, T* dst, const std::uint32_t* perm, int n) {
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) { dst[i] = src[perm[i]]; });
}

// Density (and the DFSPH factor): rho_i = m sum_j W_ij + sum_b psi_b W_ib. WCSPH also sets
// the pressure from the state equation; DFSPH leaves p to its pressure solve.
template <class Exec>
void density(Exec& ex, const SphParams P, FluidView f, const GridView g, const BoundaryView b,
             bool with_alpha) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i];
    Real sum = 0, grad2 = 0;
    Vec3 gsum, gwall;
    int count = 0;
    for_neighbors(g, f.x, xi, P.h2, [&](std::uint32_t, const Vec3& r, Real r2) {
      const Real rr = std::sqrt(r2);
      sum += P.kernel.W(rr);
      ++count;
      if (with_alpha) {
        const Vec3 gw = P.kernel.grad(r, rr) * P.volume;
        gsum += gw;
        grad2 += norm2(gw);
      }
    });
    Real rho = P.mass * sum;
    for_neighbors(b.grid, b.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      const Real rr = std::sqrt(r2);
      rho += b.psi[j] * P.kernel.W(rr);
      if (with_alpha) gwall += P.kernel.grad(r, rr) * (b.psi[j] / P.rho0);
    });
    f.rho[i] = rho;
    f.nb[i] = count;
    if (!with_alpha) {
      const Real p = P.stiffness * (rho / P.rho0 - Real(1));
      f.p[i] = p > Real(0) ? p : Real(0);
    } else {
      // The wall mirrors kappa_i (dfsph_apply), so it moves i by twice its gradient sum.
      const Real s = dot(gsum + gwall, gsum + gwall * Real(2)) + grad2;
      f.alpha[i] = s > Real(1e-6) ? Real(1) / s : Real(0);
    }
  });
}

// Accelerations: gravity, viscosity (Morris et al. 1997 Laplacian, Monaghan 1992 artificial
// viscosity, XSPH as a velocity-smoothing force) and, for WCSPH, the symmetric pressure force.
// The wall term is Akinci et al. 2012 eq. 10 (p_i / rho_i^2 only): mirroring the pressure as
// well doubled it and fed energy into hydrostatic tanks until they blew up.
template <class Exec>
void accelerations(Exec& ex, const SphParams P, FluidView f, const GridView g,
                   const BoundaryView b, bool with_pressure, Real dt) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i], vi = f.v[i];
    const Real rhoi = f.rho[i];
    const Real pi_rho2 = with_pressure ? f.p[i] / (rhoi * rhoi) : Real(0);
    const Real eps2 = Real(0.01) * P.spacing * P.spacing;
    const Real hs = Real(0.5) * P.h;  // smoothing length of the artificial viscosity
    const Real inv_dt = dt > Real(0) ? Real(1) / dt : Real(0);
    Vec3 acc = P.gravity;
    for_neighbors(g, f.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      if (r2 <= Real(0)) return;
      const Real rr = std::sqrt(r2);
      const Vec3 gw = P.kernel.grad(r, rr);
      const Real rhoj = f.rho[j];
      const Vec3 vij = vi - f.v[j];
      const Real vr = dot(vij, r);
      Real s = Real(0);
      if (with_pressure) s -= P.mass * (pi_rho2 + f.p[j] / (rhoj * rhoj));
      s += Real(10) * P.viscosity * (P.mass / rhoj) * vr / (r2 + eps2);
      if (P.alpha_av > Real(0) && vr < Real(0)) {
        const Real mu = hs * vr / (r2 + eps2);
        s += P.mass * P.alpha_av * P.sound_speed * mu / (Real(0.5) * (rhoi + rhoj));
      }
      acc += gw * s;
      if (P.xsph > Real(0)) acc -= vij * (P.xsph * inv_dt * (P.mass / rhoj) * P.kernel.W(rr));
    });
    if (with_pressure) {
        for_neighbors(b.grid, b.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
        const Real rr = std::sqrt(r2);
        acc -= P.kernel.grad(r, rr) * (b.psi[j] * pi_rho2);
      });
    }
    f.a[i] = acc;
  });
}

// Largest squared speed; +inf when any velocity or position is not finite.
template <class Exec>
Real max_speed2(Exec& ex, const FluidView f) {
  return reduce_max(ex, f.n, Real(0), [=] SPHFEM_LAMBDA(int i) -> Real {
    const Vec3 v = f.v[i], x = f.x[i];
    const Real s = norm2(v) + Real(0) * (x.x + x.y + x.z);
    return s == s && s < Real(3e38) ? s : Real(3.0e38);
  });
}

template <class Exec>
void kick(Exec& ex, FluidView f, Real dt) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) { f.v[i] += f.a[i] * dt; });
}

// x += dt v, then the last-resort box; returns how many particles it had to stop.
template <class Exec>
int drift(Exec& ex, const SphParams P, FluidView f, Real dt) {
  const double clamped = reduce_sum(ex, f.n, [=] SPHFEM_LAMBDA(int i) -> double {
    Vec3 x = f.x[i] + f.v[i] * dt;
    Vec3 v = f.v[i];
    int hit = 0;
    for (int c = 0; c < 3; ++c) {
      if (x[c] < P.clamp_lo[c]) {
        x[c] = P.clamp_lo[c];
        if (v[c] < Real(0)) v[c] = Real(0);
        hit = 1;
      } else if (x[c] > P.clamp_hi[c]) {
        x[c] = P.clamp_hi[c];
        if (v[c] > Real(0)) v[c] = Real(0);
        hit = 1;
      }
    }
    f.x[i] = x;
    f.v[i] = v;
    return double(hit);
  });
  return int(clamped + 0.5);
}

// DFSPH source: predicted relative density (density solve) or its rate (divergence solve),
// then kappa = source * alpha / dt^2 (or / dt). Returns the sum of the errors.
template <class Exec>
double dfsph_source(Exec& ex, const SphParams P, FluidView f, const GridView g,
                    const BoundaryView b, Real dt, bool divergence) {
  const int min_nb = (P.full_neighbors * 2) / 3;
  return reduce_sum(ex, f.n, [=] SPHFEM_LAMBDA(int i) -> double {
    const Vec3 xi = f.x[i], vi = f.v[i];
    Real d = 0;
    for_neighbors(g, f.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      d += P.volume * dot(vi - f.v[j], P.kernel.grad(r, std::sqrt(r2)));
    });
    for_neighbors(b.grid, b.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      d += (b.psi[j] / P.rho0) * dot(vi, P.kernel.grad(r, std::sqrt(r2)));
    });
    Real err, kappa;
    if (divergence) {
      // Only compression counts, and only where the neighbourhood is nearly full.
      err = (d > Real(0) && f.nb[i] >= min_nb) ? d * dt : Real(0);
      kappa = err * f.alpha[i] / (dt * dt);
    } else {
      Real rho_adv = f.rho[i] / P.rho0 + dt * d;
      err = rho_adv > Real(1) ? rho_adv - Real(1) : Real(0);
      kappa = err * f.alpha[i] / (dt * dt);
    }
    f.kappa[i] = kappa;
    return double(err);
  });
}

// v_i -= dt (sum_j V_j (kappa_i + kappa_j) grad W_ij + sum_b psi_b/rho0 kappa_i grad W_ib).
// Both solves also sum the pressure p_i = rho_i^2 / rho0 * kappa_i (gauges, output).
template <class Exec>
void dfsph_apply(Exec& ex, const SphParams P, FluidView f, const GridView g, const BoundaryView b,
                 Real dt, bool sum_pressure) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i];
    const Real ki = f.kappa[i];
    Vec3 dv;
    for_neighbors(g, f.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      const Real k = ki + f.kappa[j];
      if (k != Real(0)) dv += P.kernel.grad(r, std::sqrt(r2)) * (P.volume * k);
    });
    if (ki != Real(0))
      for_neighbors(b.grid, b.x, xi, P.h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
        dv += P.kernel.grad(r, std::sqrt(r2)) * ((b.psi[j] / P.rho0) * Real(2) * ki);
      });
    f.v[i] -= dv * dt;
    if (sum_pressure) f.p[i] += ki * f.rho[i] * f.rho[i] / P.rho0;
  });
}

// Appends one emitter layer at slots [first, first + count).
template <class Exec>
void emit_layer(Exec& ex, FluidView f, const Vec3* disc, int count, int first, Vec3 origin,
                Vec3 velocity, std::uint32_t first_id) {
  parallel_for(ex, count, [=] SPHFEM_LAMBDA(int k) {
    const int i = first + k;
    f.x[i] = origin + disc[k];
    f.v[i] = velocity;
    f.id[i] = first_id + std::uint32_t(k);
  });
}

}  // namespace sphfem::stages
