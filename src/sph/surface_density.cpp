// Tables of kernel integrals beyond a plane (sph/surface_density.h).
#include "sphfem/sph/surface_density.h"

#include <cmath>

namespace sphfem {

std::vector<Real> half_space_table(const Kernel& kernel, int n, double layer, double mass) {
  const Kernel unit(kernel.kind, Real(1));
  const double two_pi = 2.0 * 3.14159265358979323846;
  auto w = [&](double q) { return q < 1.0 ? double(unit.W(Real(q))) : 0.0; };
  // A(z) by trapezoid sums from z = 1 down on a grid 64 times finer than the table: the
  // kernels are C2, so the error is far below float round-off.
  const int sub = 64, m = n * sub;
  const double dq = 1.0 / m;
  std::vector<double> plane(m + 1, 0.0), normal(m + 1, 0.0), phi(m + 1, 0.0), moment(m + 1, 0.0);
  for (int k = m - 1; k >= 0; --k) {
    const double q0 = k * dq, q1 = (k + 1) * dq;
    plane[k] = plane[k + 1] + two_pi * 0.5 * dq * (q0 * w(q0) + q1 * w(q1));
    normal[k] = normal[k + 1] + two_pi * 0.5 * dq * (q0 * q0 * w(q0) + q1 * q1 * w(q1));
    phi[k] = phi[k + 1] + 0.5 * dq * (plane[k] + plane[k + 1]);
    moment[k] = moment[k + 1] + 0.5 * dq * (q0 * plane[k] + q1 * plane[k + 1]);
  }
  // A(z) between grid points, for the layers.
  auto plane_at = [&](double z) {
    if (z >= 1.0) return 0.0;
    const double u = z / dq;
    const int k = int(u);
    return plane[k] + (u - k) * (plane[k + 1] - plane[k]);
  };
  std::vector<Real> t(std::size_t(kHalfRows) * (n + 1));
  for (int k = 0; k <= n; ++k) {
    const double q = double(k) / n;
    double p = phi[k * sub], a = plane[k * sub], tn = normal[k * sub], mo = moment[k * sub];
    if (layer > 0) {
      p = a = tn = mo = 0;
      for (double z = q + 0.5 * layer; z < 1.0; z += layer) {
        p += plane_at(z);
        a += two_pi * z * w(z);
        tn += two_pi * z * z * w(z);
        mo += z * plane_at(z);
      }
      p *= mass * layer;
      a *= mass * layer;
      tn *= mass * layer;
      mo *= mass * layer;
    }
    t[std::size_t(kHalfPhi) * (n + 1) + k] = Real(p);
    t[std::size_t(kHalfSlope) * (n + 1) + k] = Real(a);
    t[std::size_t(kHalfNormal) * (n + 1) + k] = Real(tn);
    t[std::size_t(kHalfMoment) * (n + 1) + k] = Real(mo);
  }
  return t;
}

}  // namespace sphfem
