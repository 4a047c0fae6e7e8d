// A particle's listed pairs eight at a time in the host's vector lanes (AVX2): the gathers of
// x_j and of what a pair term reads at j, the kernel, the term and its sum all in lanes. The
// pair terms and the kernels are the scalar code's own generic expressions (stages.h, at();
// kernels.h, W_at), evaluated on a vector of Reals; g++'s vector extensions give that type the
// scalar's operators, ?: per lane included. Host code only; without AVX2, in double precision
// or under nvcc the pairs are summed one by one (SPHFEM_PAIR_LANES is then 0).
#pragma once

#include <cstddef>
#include <cstdint>

#include "sphfem/core/vec.h"

#if !defined(__CUDACC__) && defined(__GNUC__) && defined(__AVX2__) && !defined(SPHFEM_DOUBLE)
#define SPHFEM_PAIR_LANES 1
#include <immintrin.h>
#else
#define SPHFEM_PAIR_LANES 0
#endif

// Written after a pair term's parameters: the term inlined into the host's pair loops. Both
// loops (lanes::sum_pairs, sum_pairs_stored) call it, and g++ then left some terms as calls,
// their vectors passed through memory (WCSPH's accelerations 10 % slower).
#if SPHFEM_PAIR_LANES
#define SPHFEM_TERM __attribute__((always_inline))
#else
#define SPHFEM_TERM
#endif

#if SPHFEM_PAIR_LANES
namespace sphfem::lanes {

// Every step of a pair inlined into its pass: g++ left the gathers as calls.
#define SPHFEM_LANE __attribute__((always_inline)) inline

constexpr int kWidth = 8;
typedef float R8 __attribute__((vector_size(32)));
typedef std::int32_t I8 __attribute__((vector_size(32)));

// Eight neighbour indices, read by at() from where they lie.
struct J8 {
  const std::uint32_t* k;
};

// Eight 3-vectors, one per lane.
struct V8 {
  R8 x{}, y{}, z{};
};

SPHFEM_LANE V8 operator+(const V8& a, const V8& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
SPHFEM_LANE V8 operator-(const V8& a, const V8& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
SPHFEM_LANE V8 operator-(const Vec3& a, const V8& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
SPHFEM_LANE V8 operator-(const V8& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
SPHFEM_LANE V8 operator-(const V8& a) { return {-a.x, -a.y, -a.z}; }
SPHFEM_LANE V8 operator*(const V8& a, R8 s) { return {a.x * s, a.y * s, a.z * s}; }
SPHFEM_LANE V8 operator*(R8 s, const V8& a) { return a * s; }
SPHFEM_LANE V8 operator*(const V8& a, Real s) { return {a.x * s, a.y * s, a.z * s}; }
SPHFEM_LANE R8 dot(const V8& a, const V8& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SPHFEM_LANE R8 dot(const Vec3& a, const V8& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SPHFEM_LANE R8 dot(const V8& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SPHFEM_LANE R8 norm2(const V8& a) { return dot(a, a); }
SPHFEM_LANE R8 sqrt(R8 a) { return R8(_mm256_sqrt_ps(__m256(a))); }

// The per-lane choice of ?: for 3-vectors (mask lanes are -1 or 0).
SPHFEM_LANE V8 select(I8 m, const V8& a, const V8& b) {
  return {m ? a.x : b.x, m ? a.y : b.y, m ? a.z : b.z};
}
SPHFEM_LANE R8 select(I8 m, R8 a, R8 b) { return m ? a : b; }

// a[j] in every lane, by eight loads: on the machines measured they took less time than the
// AVX2 gather instruction, which made DFSPH's sweeps 1.6x slower than scalar code.
SPHFEM_LANE R8 at(const Real* a, const J8& j) {
  const std::uint32_t* k = j.k;
  return R8{a[k[0]], a[k[1]], a[k[2]], a[k[3]], a[k[4]], a[k[5]], a[k[6]], a[k[7]]};
}
// Four Reals from a + stride * k on for each of the eight k of j, transposed: lane l of c0
// holds the first Real of the l-th, and so on.
SPHFEM_LANE void gather4(const Real* a, std::size_t stride, const J8& j, R8& c0, R8& c1, R8& c2,
                         R8& c3) {
  const std::uint32_t* k = j.k;
  // Inlined by force: with gather4 in more passes, g++ left this as a call in every one.
  auto two = [&](int l) __attribute__((always_inline)) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(a + stride * k[l])),
                                _mm_loadu_ps(a + stride * k[l + 4]), 1);
  };
  const __m256 a0 = two(0), a1 = two(1), a2 = two(2), a3 = two(3);
  const __m256 t0 = _mm256_unpacklo_ps(a0, a1);  // x0 x1 y0 y1 | x4 x5 y4 y5
  const __m256 t1 = _mm256_unpackhi_ps(a0, a1);  // z0 z1 w0 w1 | z4 z5 w4 w5
  const __m256 t2 = _mm256_unpacklo_ps(a2, a3);
  const __m256 t3 = _mm256_unpackhi_ps(a2, a3);
  c0 = R8(_mm256_shuffle_ps(t0, t2, 0x44));
  c1 = R8(_mm256_shuffle_ps(t0, t2, 0xEE));
  c2 = R8(_mm256_shuffle_ps(t1, t3, 0x44));
  c3 = R8(_mm256_shuffle_ps(t1, t3, 0xEE));
}
// a[j] as four Reals from x_j on, the fourth the next vector's x, then transposed: a buffer
// read here holds one Vec3 more than its particles (FluidBuffers::allocate).
SPHFEM_LANE V8 at(const Vec3* a, const J8& j) {
  static_assert(sizeof(Vec3) == 3 * sizeof(Real), "Vec3 read as three Reals");
  V8 v;
  R8 next_x;
  gather4(&a[0].x, 3, j, v.x, v.y, v.z, next_x);
  return v;
}

// The first three cache lines of a list (48 entries: a full support's fluid neighbours and a
// few tank samples), asked for a few particles before a pass reads (or density() writes) it:
// DFSPH's sweeps waited on the lists at two threads, which the hardware's prefetchers do not
// fetch ahead (bench/results/README.md, "Lists fetched ahead").
template <bool Write = false, class E>
SPHFEM_LANE void prefetch_list(const E* list) {
  static_assert(sizeof(E) == 4, "a list's entries are four bytes");
  for (int l = 0; l < 3; ++l) __builtin_prefetch(list + 16 * l, Write ? 1 : 0);
}

// The lanes' sum in one fixed order, whatever the machine: the bits depend on the list alone.
// Lane l meets lane l + 2 first. Three DFSPH checks sit within the spread of the rounding
// (the hydrostatic tank's pressure error, the resting column's decay, the sampled cup's
// pressure error): of the orders tried, this one passes all three (docs/validation.md).
SPHFEM_LANE Real total(R8 a) {
  // ((a0 + a2) + (a1 + a3)) + ((a4 + a6) + (a5 + a7)) by in-lane swaps, as g++ does not
  // find them (a float sum's two operands commute exactly).
  const __m256 v = __m256(a);
  const __m256 t = _mm256_add_ps(v, _mm256_permute_ps(v, 0x4E));  // a0 + a2, a1 + a3 | ...
  const __m256 u = _mm256_add_ps(t, _mm256_permute_ps(t, 0xB1));  // (a0 + a2) + (a1 + a3) | ...
  return _mm_cvtss_f32(_mm_add_ss(_mm256_castps256_ps128(u), _mm256_extractf128_ps(u, 1)));
}
SPHFEM_LANE Vec3 total(const V8& a) { return Vec3(total(a.x), total(a.y), total(a.z)); }

// The lane type of a pair term of type T.
template <class T>
struct Of;
template <>
struct Of<Real> {
  using type = R8;
};
template <>
struct Of<Vec3> {
  using type = V8;
};

// What a group of eight pairs hands its term besides j, rij and r2: W (0 where the pass takes
// none) and the gradient's factor, grad W = rij * gs.
struct WG {
  R8 w, gs;
};

// What a pass reads of eight neighbours j: gather(j, x, of) sets their positions x and what
// its term takes of them, of (each member set on its own: g++ took a returned aggregate of
// vectors apart through general registers, and the forces' pairs ran 1.3x slower).
// ByIndex: the indices themselves, the term reading its arrays through at().
struct ByIndex {
  using Of = J8;
  const Vec3* x;
  SPHFEM_LANE void operator()(const J8& j, V8& xj, J8& of) const {
    xj = at(x, j);
    of = j;
  }
};

// The sum over list[0..n) of term(of_j, rij, r2, W, grad W) with rij = xi - x_j, kWidth pairs
// at a time; gather(j) gives x_j and of_j (ByIndex: j itself), kernel(k0, r2) the group's WG.
// The list is padded to whole groups with i itself (stages::listed_end), whose lanes' terms
// are dropped.
template <class T, class Gather, class Term, class Kernel>
SPHFEM_LANE T sum_groups(const std::uint32_t* list, int n, const Gather& gather, const Vec3& xi,
                         Term& term, const Kernel& kernel) {
  const I8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  typename Of<T>::type acc{};
  for (int k0 = 0; k0 < n; k0 += kWidth) {
    const int m = n - k0;
    const I8 valid = lane < m;
    V8 xj;
    typename Gather::Of of;
    gather(J8{list + k0}, xj, of);
    const V8 r = xi - xj;
    const R8 r2 = norm2(r);
    const WG p = kernel(k0, r2);
    const auto t = term(of, r, r2, p.w, r * p.gs);
    acc = acc + (m >= kWidth ? t : select(valid, t, decltype(t){}));
  }
  return total(acc);
}

// sum_groups with the kernel's W (only when WithW, else 0) and gradient. Store: factors is
// where to store each pair's gradient factor (the padding's too), or nullptr. g++ computes
// the factor only where a term or the store takes it (the WCSPH density's terms do not).
template <bool WithW, class T, bool Store, class Kern, class Gather, class Term>
SPHFEM_LANE T sum_pairs(const Kern& kernel, const std::uint32_t* list, int n, const Gather& gather,
                        const Vec3& xi, Term& term, Real* factors) {
  const Kern K = kernel;  // a local copy: no store in the loop can change it
  return sum_groups<T>(list, n, gather, xi, term, [&](int k0, R8 r2) SPHFEM_TERM {
    const R8 rr = sqrt(r2);
    const R8 gs = K.gscale_at(rr);
    if (Store && factors) __builtin_memcpy(factors + k0, &gs, sizeof gs);
    return WG{WithW ? K.W_at(rr) : R8{}, gs};
  });
}

// The same without W, each pair's gradient factor read from where sum_pairs stored it for the
// same positions: the bits of grad W are those the kernel gives, and the pass no longer waits
// on a square root, a division and the kernel's polynomial for every group of eight.
template <class T, class Term>
SPHFEM_LANE T sum_pairs_stored(const std::uint32_t* list, const Real* factors, int n, const Vec3* x,
                               const Vec3& xi, Term& term) {
  return sum_groups<T>(list, n, ByIndex{x}, xi, term, [&](int k0, R8) SPHFEM_TERM {
    R8 gs;
    __builtin_memcpy(&gs, factors + k0, sizeof gs);
    return WG{R8{}, gs};
  });
}

// sum_pairs of the term W alone, from the pairs' squared distances where the list's build
// staged them in the list's order (collect_neighbors' dist2): the same W of the same r2 in the
// same lanes, without reading x_j again.
template <class Kern>
SPHFEM_LANE Real sum_w_staged(const Kern& kernel, const Real* dist2, int n) {
  const Kern K = kernel;
  const I8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  R8 acc{};
  for (int k0 = 0; k0 < n; k0 += kWidth) {
    const int m = n - k0;
    const I8 valid = lane < m;
    R8 r2;
    __builtin_memcpy(&r2, dist2 + k0, sizeof r2);
    const R8 w = K.W_at(sqrt(r2));
    acc = acc + (m >= kWidth ? w : select(valid, w, R8{}));
  }
  return total(acc);
}

}  // namespace sphfem::lanes
#endif
