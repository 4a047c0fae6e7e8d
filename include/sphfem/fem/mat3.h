// 3x3 matrices and unit quaternions for the element math, usable on host and device.
// Hand-written on purpose: the project has no linear-algebra dependency, and the FEM only
// ever needs fixed 3x3 products, a determinant and an inverse.
#pragma once

#include "sphfem/core/vec.h"

namespace sphfem {

// Row-major 3x3 matrix. Trivially constructible so that device arrays of it need no init.
template <class T>
struct M3 {
  T m[3][3];

  SPHFEM_HD static M3 zero() {
    M3 a;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a.m[i][j] = T(0);
    return a;
  }
  SPHFEM_HD static M3 identity() {
    M3 a = zero();
    a.m[0][0] = a.m[1][1] = a.m[2][2] = T(1);
    return a;
  }
  // Matrix whose columns are a, b, c.
  SPHFEM_HD static M3 from_cols(const V3<T>& a, const V3<T>& b, const V3<T>& c) {
    M3 r;
    r.m[0][0] = a.x, r.m[0][1] = b.x, r.m[0][2] = c.x;
    r.m[1][0] = a.y, r.m[1][1] = b.y, r.m[1][2] = c.y;
    r.m[2][0] = a.z, r.m[2][1] = b.z, r.m[2][2] = c.z;
    return r;
  }
  SPHFEM_HD V3<T> row(int i) const { return V3<T>(m[i][0], m[i][1], m[i][2]); }
  SPHFEM_HD V3<T> col(int j) const { return V3<T>(m[0][j], m[1][j], m[2][j]); }
  SPHFEM_HD T trace() const { return m[0][0] + m[1][1] + m[2][2]; }
};

template <class T>
SPHFEM_HD V3<T> operator*(const M3<T>& a, const V3<T>& v) {
  return V3<T>(a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
               a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
               a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z);
}

template <class T>
SPHFEM_HD M3<T> operator*(const M3<T>& a, const M3<T>& b) {
  M3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return r;
}

template <class T>
SPHFEM_HD M3<T> transpose(const M3<T>& a) {
  M3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}

// a^T v
template <class T>
SPHFEM_HD V3<T> mul_transpose(const M3<T>& a, const V3<T>& v) {
  return a.col(0) * v.x + a.col(1) * v.y + a.col(2) * v.z;
}

template <class T>
SPHFEM_HD T det(const M3<T>& a) {
  return dot(a.row(0), cross(a.row(1), a.row(2)));
}

// Inverse by cofactors; the caller checks det != 0.
template <class T>
SPHFEM_HD M3<T> inverse(const M3<T>& a) {
  const V3<T> r0 = a.row(0), r1 = a.row(1), r2 = a.row(2);
  const V3<T> c0 = cross(r1, r2), c1 = cross(r2, r0), c2 = cross(r0, r1);
  const T inv = T(1) / dot(r0, c0);
  return M3<T>::from_cols(c0 * inv, c1 * inv, c2 * inv);
}

// Unit quaternion (w, x, y, z) for element rotations: 4 numbers of state per element.
template <class T>
struct Q4 {
  T w, x, y, z;

  SPHFEM_HD static Q4 identity() { return Q4{T(1), T(0), T(0), T(0)}; }
  // Rotation by |omega| radians about omega / |omega| (identity for a zero vector).
  SPHFEM_HD static Q4 from_rotation_vector(const V3<T>& omega) {
    const T a = norm(omega);
    if (!(a > T(0))) return identity();
    const T s = std::sin(T(0.5) * a) / a;
    return Q4{std::cos(T(0.5) * a), omega.x * s, omega.y * s, omega.z * s};
  }
  SPHFEM_HD M3<T> matrix() const {
    const T xx = x * x, yy = y * y, zz = z * z, xy = x * y, xz = x * z, yz = y * z;
    const T wx = w * x, wy = w * y, wz = w * z;
    M3<T> r;
    r.m[0][0] = T(1) - T(2) * (yy + zz), r.m[0][1] = T(2) * (xy - wz), r.m[0][2] = T(2) * (xz + wy);
    r.m[1][0] = T(2) * (xy + wz), r.m[1][1] = T(1) - T(2) * (xx + zz), r.m[1][2] = T(2) * (yz - wx);
    r.m[2][0] = T(2) * (xz - wy), r.m[2][1] = T(2) * (yz + wx), r.m[2][2] = T(1) - T(2) * (xx + yy);
    return r;
  }
};

template <class T>
SPHFEM_HD Q4<T> operator*(const Q4<T>& a, const Q4<T>& b) {
  return Q4<T>{
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

template <class T>
SPHFEM_HD Q4<T> normalized(const Q4<T>& q) {
  const T n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!(n2 > T(0))) return Q4<T>::identity();
  const T s = T(1) / std::sqrt(n2);
  return Q4<T>{q.w * s, q.x * s, q.y * s, q.z * s};
}

using Mat3 = M3<Real>;
using Mat3d = M3<double>;
using Quat = Q4<Real>;

}  // namespace sphfem
