// Rotational part of a deformation gradient, after Mueller, Bender, Chentanez and Macklin
// 2016, "A robust method to extract the rotational part of deformations" (MIG '16).
// Replaces the paper's Gram-Schmidt (docs/design.md, correction 3): Gram-Schmidt depends on
// column order and breaks down for flat and inverted elements; this iteration always returns
// a proper rotation, is smooth in A, and converges in a few steps from last step's rotation.
#pragma once

#include "sphfem/fem/mat3.h"

namespace sphfem::fem {

// Iterates R <- exp(omega) R, omega = sum_i r_i x a_i / (|sum_i r_i . a_i| + eps), where r_i
// and a_i are the columns of R and A: each update turns R towards the rotation maximising
// tr(R^T A), i.e. the rotation of the polar decomposition A = R S when det A > 0.
template <class T>
SPHFEM_HD Q4<T> extract_rotation(const M3<T>& A, Q4<T> q, int iterations) {
  for (int it = 0; it < iterations; ++it) {
    const M3<T> R = q.matrix();
    V3<T> num;
    T den = T(0);
    for (int c = 0; c < 3; ++c) {
      num += cross(R.col(c), A.col(c));
      den += dot(R.col(c), A.col(c));
    }
    const V3<T> omega = num * (T(1) / (std::fabs(den) + T(1e-9)));
    if (norm2(omega) < T(1e-18)) break;
    q = normalized(Q4<T>::from_rotation_vector(omega) * q);
  }
  return q;
}

// tr(R^T A): the objective the polar rotation maximises; used to pick the best of several
// starting rotations when there is no previous rotation to start from.
template <class T>
SPHFEM_HD T rotation_alignment(const M3<T>& R, const M3<T>& A) {
  return dot(R.col(0), A.col(0)) + dot(R.col(1), A.col(1)) + dot(R.col(2), A.col(2));
}

// The 24 rotations of the cube (binary octahedral group modulo sign), s = 0..23: every
// rotation lies within about 63 degrees of one of them, close enough for the iteration above
// to converge from. Used to start elements that have no previous rotation.
template <class T>
SPHFEM_HD Q4<T> cube_rotation(int s) {
  T c[4] = {T(0), T(0), T(0), T(0)};
  if (s < 4) {
    c[s] = T(1);  // identity and the half-turns about x, y, z
  } else if (s < 12) {
    c[0] = T(0.5);  // thirds of a turn about the cube diagonals
    for (int b = 0; b < 3; ++b) c[b + 1] = ((s - 4) >> b) & 1 ? T(-0.5) : T(0.5);
  } else {
    const int k = (s - 12) >> 1;  // quarter turns and edge half-turns: pairs of components
    const int a = k < 3 ? 0 : (k < 5 ? 1 : 2), b = k < 3 ? k + 1 : (k < 5 ? k - 1 : 3);
    c[a] = T(0.70710678118654752);
    c[b] = (s & 1) ? T(-0.70710678118654752) : T(0.70710678118654752);
  }
  return Q4<T>{c[0], c[1], c[2], c[3]};
}

// Rotation of A with no usable previous rotation: probe the cube rotations (and `hint`) with
// a few iterations each, keep the best aligned, then iterate it to convergence.
template <class T>
SPHFEM_HD Q4<T> extract_rotation_fresh(const M3<T>& A, Q4<T> hint, int iterations) {
  constexpr int kProbe = 4;
  Q4<T> best = extract_rotation(A, hint, kProbe);
  T score = rotation_alignment(best.matrix(), A);
  for (int s = 0; s < 24; ++s) {
    const Q4<T> q = extract_rotation(A, cube_rotation<T>(s), kProbe);
    const T a = rotation_alignment(q.matrix(), A);
    if (a > score + T(1e-6) * (std::fabs(score) + T(1))) score = a, best = q;
  }
  return extract_rotation(A, best, iterations);
}

}  // namespace sphfem::fem
