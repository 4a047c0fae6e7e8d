// Small vector math shared by host and device code.
// Physics is written once as SPHFEM_HD inline functions; under nvcc they become
// __host__ __device__, elsewhere plain inline (DESIGN.md, "one source of physics").
#pragma once

#include <cmath>

#if defined(__CUDACC__)
#define SPHFEM_HD __host__ __device__ __forceinline__
#else
#define SPHFEM_HD inline
#endif

// A pair loop inlined into its caller on every compiler: the caller's sums then stay in
// registers (a sum behind a reference was stored and reloaded on every pair).
#if defined(__CUDACC__)
#define SPHFEM_HD_INLINE SPHFEM_HD
#elif defined(__GNUC__)
#define SPHFEM_HD_INLINE __attribute__((always_inline)) inline
#else
#define SPHFEM_HD_INLINE inline
#endif

// Annotation for lambdas passed to parallel_for: host+device under nvcc, nothing elsewhere.
#if defined(__CUDACC__)
#define SPHFEM_LAMBDA __host__ __device__
#else
#define SPHFEM_LAMBDA
#endif

namespace sphfem {

#if defined(SPHFEM_DOUBLE)
using Real = double;
#else
using Real = float;
#endif

template <class T>
struct V3 {
  T x, y, z;
  SPHFEM_HD V3() : x(0), y(0), z(0) {}
  SPHFEM_HD V3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <class U>
  SPHFEM_HD explicit V3(const V3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
  SPHFEM_HD T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  SPHFEM_HD T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  SPHFEM_HD V3& operator+=(const V3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  SPHFEM_HD V3& operator-=(const V3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  SPHFEM_HD V3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
};

template <class T> SPHFEM_HD V3<T> operator+(V3<T> a, const V3<T>& b) { return a += b; }
template <class T> SPHFEM_HD V3<T> operator-(V3<T> a, const V3<T>& b) { return a -= b; }
template <class T> SPHFEM_HD V3<T> operator-(const V3<T>& a) { return V3<T>(-a.x, -a.y, -a.z); }
template <class T> SPHFEM_HD V3<T> operator*(V3<T> a, T s) { return a *= s; }
template <class T> SPHFEM_HD V3<T> operator*(T s, V3<T> a) { return a *= s; }
template <class T> SPHFEM_HD V3<T> operator/(V3<T> a, T s) { return a *= (T(1) / s); }
template <class T> SPHFEM_HD T dot(const V3<T>& a, const V3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> SPHFEM_HD T norm2(const V3<T>& a) { return dot(a, a); }
template <class T> SPHFEM_HD T norm(const V3<T>& a) { return std::sqrt(dot(a, a)); }
template <class T> SPHFEM_HD V3<T> cross(const V3<T>& a, const V3<T>& b) {
  return V3<T>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
template <class T> SPHFEM_HD V3<T> vmin(const V3<T>& a, const V3<T>& b) {
  return V3<T>(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z);
}
template <class T> SPHFEM_HD V3<T> vmax(const V3<T>& a, const V3<T>& b) {
  return V3<T>(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z);
}

using Vec3 = V3<Real>;
using Vec3d = V3<double>;

}  // namespace sphfem
