// CPU backend of the execution layer: OpenMP loops with static schedules, so a run with a
// given thread count is deterministic. OpenMP over TBB: it ships with the compiler, needs no
// runtime package, and nvcc's host compiler understands it (docs/design.md).
#pragma once

#include <omp.h>

#include <cstdint>
#include <vector>

#include "sphfem/core/memory.h"

namespace sphfem {

struct CpuExec {
  static constexpr MemSpace kSpace = MemSpace::Host;
  std::vector<std::uint32_t> scratch_keys, scratch_vals;  // radix sort ping-pong
};

template <class F>
void parallel_for(CpuExec&, int n, F f) {
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) f(i);
}

// max over i of f(i); init for n = 0.
template <class T, class F>
T reduce_max(CpuExec&, int n, T init, F f) {
  T best = init;
#pragma omp parallel
  {
    T local = init;
#pragma omp for schedule(static) nowait
    for (int i = 0; i < n; ++i) {
      T v = f(i);
      local = v > local ? v : local;
    }
#pragma omp critical
    best = local > best ? local : best;
  }
  return best;
}

// Sum over i of f(i), accumulated in double in a fixed order per thread block.
template <class F>
double reduce_sum(CpuExec&, int n, F f) {
  const int nt = omp_get_max_threads();
  std::vector<double> part(nt, 0.0);
#pragma omp parallel
  {
    double s = 0.0;
    const int t = omp_get_thread_num();
#pragma omp for schedule(static) nowait
    for (int i = 0; i < n; ++i) s += double(f(i));
    part[t] = s;
  }
  double s = 0.0;
  for (double v : part) s += v;
  return s;
}

// out[i] = in[0] + ... + in[i-1]; returns the total. in and out may alias.
std::uint32_t exclusive_scan(CpuExec&, const std::uint32_t* in, std::uint32_t* out, int n);

// Stable sort of (keys, vals) by the low key_bits of keys (LSD radix sort, 8 bits a pass).
void sort_pairs(CpuExec&, std::uint32_t* keys, std::uint32_t* vals, int n, int key_bits);

}  // namespace sphfem

namespace sphfem {
inline void exec_sync(CpuExec&) {}
}  // namespace sphfem
