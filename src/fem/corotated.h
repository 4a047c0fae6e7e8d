// Co-rotated linear elasticity of one linear tetrahedron (paper eq. 5, f_e = R_e K_e
// (R_e^T x - p); Mueller and Gross 2004), written in the world frame so that a matrix-free
// product costs two 3x3x3 contractions per element.
//
// With g_a the gradients of the shape functions N1..N3 (rows of Dm^-1) and P_a = R g_a, an
// element displacement w gives the rotated displacement gradient H = sum_a (w_a - w_0) P_a^T
// (= R^T-frame gradient rotated back), stress sigma = mu (H + H^T) + lambda tr(H) I, and
// nodal forces -V sigma P_a (a = 1..3), node 0 taking minus their sum. For w = x this is the
// elastic force once the rest shape is subtracted: H = F R^T - I. For any w it is the product
// with K_R = R K_e R^T, the stiffness the implicit step linearises with (R held fixed).
#pragma once

#include "sphfem/fem/mat3.h"

namespace sphfem::fem {

// F = Ds Dm^-1 = sum_a (x_a - x_0) g_a^T.
SPHFEM_HD Mat3 deformation_gradient(const Vec3 x[4], const Vec3 g[3]) {
  Mat3 F = Mat3::zero();
  for (int a = 0; a < 3; ++a) {
    const Vec3 d = x[a + 1] - x[0];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F.m[i][j] += d[i] * g[a][j];
  }
  return F;
}

// out_a = sigma P_a with H = sum_a (w_a - w_0) P_a^T - shift I, sigma = cm (H + H^T) +
// cl tr(H) I. cm = V mu and cl = V lambda (times any scale); out[0] = -(out1 + out2 + out3).
// shift = 1 with w = x gives minus the elastic force; shift = 0 gives K_R w.
SPHFEM_HD void stress_products(const Vec3 w[4], const Vec3 P[3], Real cm, Real cl, Real shift,
                               Vec3 out[4]) {
  Real H[3][3] = {};
  for (int a = 0; a < 3; ++a) {
    const Vec3 d = w[a + 1] - w[0];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) H[i][j] += d[i] * P[a][j];
  }
  const Real tr = H[0][0] + H[1][1] + H[2][2] - Real(3) * shift;
  const Real s00 = cm * Real(2) * (H[0][0] - shift) + cl * tr;
  const Real s11 = cm * Real(2) * (H[1][1] - shift) + cl * tr;
  const Real s22 = cm * Real(2) * (H[2][2] - shift) + cl * tr;
  const Real s01 = cm * (H[0][1] + H[1][0]);
  const Real s02 = cm * (H[0][2] + H[2][0]);
  const Real s12 = cm * (H[1][2] + H[2][1]);
  out[0] = Vec3();
  for (int a = 0; a < 3; ++a) {
    const Vec3 p = P[a];
    const Vec3 f(s00 * p.x + s01 * p.y + s02 * p.z, s01 * p.x + s11 * p.y + s12 * p.z,
                 s02 * p.x + s12 * p.y + s22 * p.z);
    out[a + 1] = f;
    out[0] -= f;
  }
}

// Elastic energy V (mu |eps|^2 + lambda/2 tr(eps)^2), eps = sym(R^T F) - I, from
// H = F R^T = sum_a (x_a - x_0) P_a^T (the Frobenius norm and trace are rotation invariant).
SPHFEM_HD Real corotated_energy(const Vec3 x[4], const Vec3 P[3], Real mu_vol, Real lambda_vol) {
  Real H[3][3] = {};
  for (int a = 0; a < 3; ++a) {
    const Vec3 d = x[a + 1] - x[0];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) H[i][j] += d[i] * P[a][j];
  }
  Real e2 = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Real e = Real(0.5) * (H[i][j] + H[j][i]) - (i == j ? Real(1) : Real(0));
      e2 += e * e;
    }
  const Real tr = H[0][0] + H[1][1] + H[2][2] - Real(3);
  return mu_vol * e2 + Real(0.5) * lambda_vol * tr * tr;
}

// Diagonal 3x3 block of K_R for local node a, with P_a its rotated gradient (P_0 = -sum):
// V (mu |P_a|^2 I + (mu + lambda) P_a P_a^T), stored as (xx, yy, zz, xy, xz, yz).
SPHFEM_HD void diagonal_block(const Vec3& p, Real cm, Real cl, Real out[6]) {
  const Real d = cm * norm2(p), c = cm + cl;
  out[0] = d + c * p.x * p.x;
  out[1] = d + c * p.y * p.y;
  out[2] = d + c * p.z * p.z;
  out[3] = c * p.x * p.y;
  out[4] = c * p.x * p.z;
  out[5] = c * p.y * p.z;
}

}  // namespace sphfem::fem
