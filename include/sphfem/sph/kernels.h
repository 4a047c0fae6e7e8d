// SPH smoothing kernels in 3D with support radius h (W = 0 for r >= h).
// Cubic spline as in Monaghan (1992) rescaled to support h; Wendland C2 (Wendland 1995;
// Dehnen & Aly 2012). Both normalised: the integral of W over R^3 is 1.
#pragma once

#include "sphfem/core/vec.h"

namespace sphfem {

// A kernel's calls on one Real, from its templates W_at and gscale_at.
template <class K>
struct ScalarCalls {
  SPHFEM_HD Real W(Real r) const { return static_cast<const K&>(*this).W_at(r); }
  SPHFEM_HD Real gscale(Real r) const { return static_cast<const K&>(*this).gscale_at(r); }
  // Gradient with respect to x_i of W(|x_i - x_j|), given rij = x_i - x_j and r = |rij|.
  SPHFEM_HD Vec3 grad(const Vec3& rij, Real r) const { return rij * gscale(r); }
};

struct CubicSpline : ScalarCalls<CubicSpline> {
  Real h, inv_h, k, l;
  CubicSpline() = default;
  explicit CubicSpline(Real h_) : h(h_), inv_h(Real(1) / h_) {
    const Real pi = Real(3.14159265358979323846);
    k = Real(8) / (pi * h * h * h);
    l = Real(48) / (pi * h * h * h);
  }
  // W and the gradient's scale select between their pieces instead of branching, and take R =
  // Real or a host vector of Reals (sph/pair_lanes.h: ?: selects per lane there), so the host
  // computes a particle's pairs in vector lanes with these same expressions. Always inlined:
  // where g++ left them as calls, the lanes' passes ran them out of line (their last step is
  // a select, so a caller's arithmetic cannot fuse with them either way: the same bits).
  template <class R>
  SPHFEM_HD_INLINE R W_at(R r) const {
    const R q = r * inv_h;
    const R f = Real(1) - q;
    const R inner = k * (Real(6) * q * q * q - Real(6) * q * q + Real(1));
    const R outer = k * Real(2) * f * f * f;
    const R w = q <= Real(0.5) ? inner : outer;
    return q >= Real(1) ? R{} : w;
  }
  // grad W = rij * gscale(r), 0 outside the support and at r = 0.
  template <class R>
  SPHFEM_HD_INLINE R gscale_at(R r) const {
    const R q = r * inv_h;
    const R f = Real(1) - q;
    const R inner = l * q * (Real(3) * q - Real(2));
    const R outer = -l * f * f;
    const R dq = q <= Real(0.5) ? inner : outer;
    const R s = dq * inv_h / r;
    return (q >= Real(1)) | (r <= Real(1e-9) * h) ? R{} : s;
  }
};

struct WendlandC2 : ScalarCalls<WendlandC2> {
  Real h, inv_h, k;
  WendlandC2() = default;
  explicit WendlandC2(Real h_) : h(h_), inv_h(Real(1) / h_) {
    const Real pi = Real(3.14159265358979323846);
    k = Real(21) / (Real(2) * pi * h * h * h);
  }
  template <class R>
  SPHFEM_HD_INLINE R W_at(R r) const {
    const R q = r * inv_h;
    const R f = Real(1) - q;
    const R w = k * f * f * f * f * (Real(1) + Real(4) * q);
    return q >= Real(1) ? R{} : w;
  }
  // dW/dr = -20 k q (1-q)^3 / h; divided by r this is -20 k (1-q)^3 / h^2 (no 1/r singularity).
  template <class R>
  SPHFEM_HD_INLINE R gscale_at(R r) const {
    const R q = r * inv_h;
    const R f = Real(1) - q;
    const R s = Real(-20) * k * f * f * f * inv_h * inv_h;
    return q >= Real(1) ? R{} : s;
  }
};

// Either kernel behind one value type, so the solver is not templated on it.
struct Kernel {
  int kind = 0;  // 0 cubic spline, 1 Wendland C2
  CubicSpline cubic;
  WendlandC2 wendland;
  Kernel() = default;
  Kernel(int kind_, Real h) : kind(kind_), cubic(h), wendland(h) {}
  SPHFEM_HD Real W(Real r) const { return kind == 0 ? cubic.W(r) : wendland.W(r); }
  SPHFEM_HD Vec3 grad(const Vec3& rij, Real r) const {
    return kind == 0 ? cubic.grad(rij, r) : wendland.grad(rij, r);
  }
  SPHFEM_HD Real gscale(Real r) const { return kind == 0 ? cubic.gscale(r) : wendland.gscale(r); }
};

}  // namespace sphfem
