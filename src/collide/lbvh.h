// LBVH pieces as host-and-device functions: Morton codes of triangle centroids and the
// parallel radix-tree construction of Karras (2012), "Maximizing Parallelism in the
// Construction of BVHs, Octrees, and k-d Trees", HPG 2012, section 4 and figure 4.
#pragma once

#include <cstdint>

#include "sphfem/collide/traverse.h"

namespace sphfem::collide {

SPHFEM_HD int clz32(std::uint32_t x) {
#if defined(__CUDA_ARCH__)
  return __clz(int(x));
#else
  return x == 0 ? 32 : __builtin_clz(x);
#endif
}

// Spreads the low 10 bits of v so that two zero bits follow each bit.
SPHFEM_HD std::uint32_t spread_bits(std::uint32_t v) {
  v = (v * 0x00010001u) & 0xFF0000FFu;
  v = (v * 0x00000101u) & 0x0F00F00Fu;
  v = (v * 0x00000011u) & 0xC30C30C3u;
  v = (v * 0x00000005u) & 0x49249249u;
  return v;
}

// 30-bit Morton code of a point given in [0, 1]^3 (clamped).
SPHFEM_HD std::uint32_t morton30(const Vec3& q) {
  const Real s = Real(1024);
  const Real x = rmin(rmax(q.x * s, Real(0)), Real(1023));
  const Real y = rmin(rmax(q.y * s, Real(0)), Real(1023));
  const Real z = rmin(rmax(q.z * s, Real(0)), Real(1023));
  return (spread_bits(std::uint32_t(x)) << 2) | (spread_bits(std::uint32_t(y)) << 1) |
         spread_bits(std::uint32_t(z));
}

// Length of the common prefix of sorted keys i and j, -1 outside [0, n); equal keys are told
// apart by their indices (Karras, section 4: augment the key with its index).
SPHFEM_HD int common_prefix(const std::uint32_t* keys, int n, int i, int j) {
  if (j < 0 || j >= n) return -1;
  const std::uint32_t a = keys[i], b = keys[j];
  if (a == b) return 32 + clz32(std::uint32_t(i) ^ std::uint32_t(j));
  return clz32(a ^ b);
}

// Children of internal node i of the radix tree over n sorted keys. Internal nodes are
// 0 .. n-2 (root 0), leaf k is node n-1+k.
SPHFEM_HD void karras_children(const std::uint32_t* keys, int n, int i, int& left, int& right) {
  // Direction of the node's range: towards the neighbour with the longer common prefix.
  const int d = common_prefix(keys, n, i, i + 1) - common_prefix(keys, n, i, i - 1) >= 0 ? 1 : -1;
  // Upper bound on the range length, then its exact other end by binary search.
  const int dmin = common_prefix(keys, n, i, i - d);
  int lmax = 2;
  while (common_prefix(keys, n, i, i + lmax * d) > dmin) lmax <<= 1;
  int l = 0;
  for (int t = lmax >> 1; t >= 1; t >>= 1)
    if (common_prefix(keys, n, i, i + (l + t) * d) > dmin) l += t;
  const int j = i + l * d;
  // Split: the last key that shares more than the range's common prefix with key i.
  const int dnode = common_prefix(keys, n, i, j);
  int s = 0, t = l;
  do {
    t = (t + 1) >> 1;
    if (common_prefix(keys, n, i, i + (s + t) * d) > dnode) s += t;
  } while (t > 1);
  const int gamma = i + s * d + (d < 0 ? d : 0);
  const int lo = i < j ? i : j, hi = i < j ? j : i;
  left = lo == gamma ? n - 1 + gamma : gamma;
  right = hi == gamma + 1 ? n - 1 + gamma + 1 : gamma + 1;
}

// Arrival at a parent during bottom-up refit: returns how many children arrived before.
// Release/acquire so the first child's box is visible to the second, which goes on.
SPHFEM_HD int arrive(int* flag) {
#if defined(__CUDA_ARCH__)
  __threadfence();
  const int k = atomicAdd(flag, 1);
  __threadfence();
  return k;
#else
  return __atomic_fetch_add(flag, 1, __ATOMIC_ACQ_REL);
#endif
}

// Reads a node box another thread wrote in the same kernel (bypassing the GPU's L1).
SPHFEM_HD void load_box(const BvhNode* nodes, int i, Vec3& lo, Vec3& hi) {
#if defined(__CUDA_ARCH__)
  const BvhNode* n = nodes + i;
  lo = Vec3(__ldcg(&n->lo.x), __ldcg(&n->lo.y), __ldcg(&n->lo.z));
  hi = Vec3(__ldcg(&n->hi.x), __ldcg(&n->hi.y), __ldcg(&n->hi.z));
#else
  lo = nodes[i].lo;
  hi = nodes[i].hi;
#endif
}

}  // namespace sphfem::collide
