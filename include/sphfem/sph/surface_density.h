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
    int k;
    Real t;
    if (!place(d, k, t)) return;
    phi = row_at(kHalfPhi, k, t);
    slope = row_at(kHalfSlope, k, t) * inv_h;
    normal = row_at(kHalfNormal, k, t);
  }
  // M(d) (m) for a particle at distance d >= 0; zero at and beyond the support.
  SPHFEM_HD Real moment(Real d) const {
    int k;
    Real t;
    return place(d, k, t) ? row_at(kHalfMoment, k, t) / inv_h : Real(0);
  }

 private:
  // The table's interval k and the fraction t of it at distance d; false beyond the support.
  SPHFEM_HD bool place(Real d, int& k, Real& t) const {
    Real u = d * inv_h * Real(n);
    if (!(u < Real(n))) return false;
    if (u < Real(0)) u = Real(0);
    k = int(u);
    t = u - Real(k);
    return true;
  }
  SPHFEM_HD Real row_at(int row, int k, Real t) const {
    const Real* r = table + (n + 1) * row + k;
    return r[0] + t * (r[1] - r[0]);
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
