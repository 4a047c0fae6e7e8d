// Near-surface density: the kernel mass a particle misses beyond a surface that has no
// boundary samples (the ray-traced coupling's bodies). The surface is taken as the plane
// through the particle's closest surface point, and the space beyond it as filled like the
// tank's walls: layers of frozen fluid lattice (spacing s, particle mass m), the first s / 2
// behind the plane, averaged along the plane. The missing density is then rho0 * Phi(d), a
// function of q = d / h alone, tabulated once per kernel.
//
// With W(r) = w(r / h) / h^3 and the particle at height d over the plane (normal n toward
// it), a plane at depth z holds A(z) = 2 pi int_z^h r W(r) dr of the kernel (rings of radius
// rho, r^2 = z^2 + rho^2), and a layer of the lattice, averaged along it, m / s^2 times
// that. Over the layers z_k = d + (k + 1/2) s, with c = m / (rho0 s^3):
//   Phi(d) = c s sum_k A(z_k)                 density share; the continuum is int_d^h A dz
//   A(d)   = -dPhi/dd = c s sum_k 2 pi z_k W(z_k)
//   T      = sum_beyond psi/rho0 (y - x) (x) grad_x W = a(d) n n^T + Phi(d) (I - n n^T),
//   a(d)   = c s sum_k 2 pi z_k^2 W(z_k)     (continuum: a(0) = Phi(0) = 1/2)
//   M(d)   = c s sum_k z_k A(z_k)            = sum_beyond psi/rho0 W (x - y) . n, the first
//            moment: the head of a quantity continued beyond the surface (the warm start's
//            filter, stages.h)
// T carries the hydrostatic head of the pressure continued beyond the surface (stages.h).
// Why layers and not the continuum integral: a lattice layer at d = s / 2, the fluid at
// rest, must have rest density. The continuum gives it +3.8 % (cubic spline) or +4.8 %
// (Wendland C2) at h = 2 s, which a WCSPH column answered with a jolt at its start.
#pragma once

#include <vector>

#include "sphfem/sph/kernels.h"

namespace sphfem {

// Rows of the table, each sampled at q = k / n, k = 0..n.
enum HalfSpaceRow { kHalfPhi = 0, kHalfSlope = 1, kHalfNormal = 2, kHalfMoment = 3, kHalfRows = 4 };

// Phi(q), h A(q), a(q) and M(q) / h for h = 1 (all dimensionless), row after row. layer:
// the lattice spacing over h (0: the continuum integrals); mass: m / (rho0 s^3).
std::vector<Real> half_space_table(const Kernel& kernel, int n, double layer = 0, double mass = 1);

// The table in the solver's memory space, linearly interpolated.
struct HalfSpaceView {
  const Real* table = nullptr;
  int n = 0;
  Real inv_h = 0;

  // For a particle at distance d >= 0: phi = Phi, slope = A = -dPhi/dd (1/m), normal = a.
  // Zero at and beyond the support.
  SPHFEM_HD void lookup(Real d, Real& phi, Real& slope, Real& normal) const {
    phi = slope = normal = Real(0);
    Real u = d * inv_h * Real(n);
    if (!(u < Real(n))) return;
    if (u < Real(0)) u = Real(0);
    const int k = int(u);
    const Real t = u - Real(k);
    const Real* r0 = table + k;
    const Real* r1 = table + (n + 1) * kHalfSlope + k;
    const Real* r2 = table + (n + 1) * kHalfNormal + k;
    phi = r0[0] + t * (r0[1] - r0[0]);
    slope = (r1[0] + t * (r1[1] - r1[0])) * inv_h;
    normal = r2[0] + t * (r2[1] - r2[0]);
  }
  // M(d) (m) for a particle at distance d >= 0; zero at and beyond the support.
  SPHFEM_HD Real moment(Real d) const {
    Real u = d * inv_h * Real(n);
    if (!(u < Real(n))) return Real(0);
    if (u < Real(0)) u = Real(0);
    const int k = int(u);
    const Real t = u - Real(k);
    const Real* r = table + (n + 1) * kHalfMoment + k;
    return (r[0] + t * (r[1] - r[0])) / inv_h;
  }
};

// Share of a full support sphere beyond a plane at distance d = q h (a spherical cap):
// how many lattice neighbours the surface stands in for.
SPHFEM_HD Real half_space_volume(Real q) {
  if (q >= Real(1)) return Real(0);
  if (q < Real(0)) q = Real(0);
  return (Real(1) - q) * (Real(1) - q) * (Real(2) + q) * Real(0.25);
}

}  // namespace sphfem
