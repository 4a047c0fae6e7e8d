// CPU backend of the execution layer: OpenMP loops whose results do not depend on the thread
// count or the schedule (independent items, sums in fixed blocks). OpenMP over TBB: it ships with
// the compiler, needs no runtime package, and nvcc's host compiler understands it (docs/design.md).
#pragma once

#include <omp.h>

#include <cstdint>
#include <vector>

#include "sphfem/core/memory.h"

namespace sphfem {

struct CpuExec {
  static constexpr MemSpace kSpace = MemSpace::Host;
  std::vector<std::uint32_t> scratch_keys, scratch_vals;  // radix sort ping-pong
  std::vector<std::uint64_t> scratch_moved;               // sort_moved's keys that moved
  std::vector<std::vector<std::uint64_t>> scratch_parts;  // the same, a thread's part
};

// Items a thread takes at a time: about a sixteenth of a thread's share, from kLeastChunk to
// kMostChunk. The loops' items are independent (each writes its own outputs), so the
// schedule cannot make a bit depend on the threads; a dynamic one keeps both busy where the
// work is uneven along the array: the particles are sorted by cell, so the walls' and the
// surface's particles, and the wall samples with fluid in reach, crowd into one thread's
// static half (DFSPH 12 % faster on two threads, docs/design.md). Chunks of 1024 particles
// instead of 256, with the light loops below: WCSPH and DFSPH steps 0.90 and 0.94 of the time
// on two threads; a thread's chunk is one stream through the lists and arrays for longer (a
// chunk itself takes about 40 ns to hand out). A small body's few hundred tetrahedra still
// make enough chunks to share.
constexpr int kLeastChunk = 64, kMostChunk = 1024;

inline int for_chunk(int n) {
  const int share = n / (16 * omp_get_max_threads());
  return share < kLeastChunk ? kLeastChunk : (share > kMostChunk ? kMostChunk : share);
}

// parallel_for of a loop whose items all cost the same few nanoseconds (copies, gathers, cell
// keys, vector updates): each thread a fixed half, one stream the hardware's prefetchers
// follow. The sort's gathers and cell starts took 0.55 ms a step at two threads in dynamic
// chunks of 256, 0.25 statically.
template <class F>
void parallel_for_light(CpuExec&, int n, F f) {
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) f(i);
}

template <class F>
void parallel_for(CpuExec&, int n, F f) {
  const int chunk = for_chunk(n);
#pragma omp parallel for schedule(dynamic, chunk)
  for (int i = 0; i < n; ++i) f(i);
}

// f(begin, end) for consecutive blocks of `block` items, kBlocksTaken consecutive blocks to a
// thread, taken as the threads come free (longer streams; the DFSPH density pass lists 64
// particles a block); then done() once on each thread, after its last block.
constexpr int kBlocksTaken = 4;

template <class F, class G>
void parallel_blocks(CpuExec&, int n, int block, F f, G done) {
  const int blocks = n > 0 ? (n + block - 1) / block : 0;
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, kBlocksTaken) nowait
    for (int b = 0; b < blocks; ++b) f(b * block, b == blocks - 1 ? n : (b + 1) * block);
    done();
  }
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

// lo[a] and hi[a]: the least and the greatest x[i][a] over i < n (3e38 and -3e38 for n = 0).
template <class V, class T>
void reduce_bounds(CpuExec&, int n, const V* x, T lo[3], T hi[3]) {
  const T big = T(3e38);
  for (int a = 0; a < 3; ++a) {
    lo[a] = big;
    hi[a] = -big;
  }
#pragma omp parallel
  {
    T l[3] = {big, big, big}, h[3] = {-big, -big, -big};
#pragma omp for schedule(static) nowait
    for (int i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        const T v = x[i][a];
        l[a] = v < l[a] ? v : l[a];
        h[a] = v > h[a] ? v : h[a];
      }
#pragma omp critical
    for (int a = 0; a < 3; ++a) {
      lo[a] = l[a] < lo[a] ? l[a] : lo[a];
      hi[a] = h[a] > hi[a] ? h[a] : hi[a];
    }
  }
}

// Sum over i of f(i) in double: fixed blocks of kSumBlock terms, each summed in order, then
// the blocks in order. The blocks do not depend on the thread count, so neither do the bits:
// a run with 1 thread and one with 2 give the same sums (CG, DFSPH residuals, gauges).
constexpr int kSumBlock = 1024;

template <class F>
double reduce_sum(CpuExec&, int n, F f) {
  const int blocks = n > 0 ? (n + kSumBlock - 1) / kSumBlock : 0;
  if (blocks <= 1) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += double(f(i));
    return s;
  }
  std::vector<double> part(std::size_t(blocks), 0.0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < blocks; ++b) {
    const int end = b == blocks - 1 ? n : (b + 1) * kSumBlock;
    double s = 0.0;
    for (int i = b * kSumBlock; i < end; ++i) s += double(f(i));
    part[std::size_t(b)] = s;
  }
  double s = 0.0;
  for (double v : part) s += v;
  return s;
}

// reduce_sum of an f that is 0 but at some listed indices, ascending: first[b] is the first of
// them in block b of kSumBlock indices (blocks + 1 entries), g(p) is f at the p-th. The blocks
// and their order are reduce_sum's, and a 0 added leaves a sum as it was: the same bits.
template <class G>
double reduce_sum_listed(CpuExec&, int n, const std::uint32_t* first, G g) {
  const int blocks = n > 0 ? (n + kSumBlock - 1) / kSumBlock : 0;
  if (blocks <= 1) {
    double s = 0.0;
    for (std::uint32_t p = first[0]; p < first[blocks]; ++p) s += double(g(int(p)));
    return s;
  }
  std::vector<double> part(std::size_t(blocks), 0.0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < blocks; ++b) {
    double s = 0.0;
    for (std::uint32_t p = first[b]; p < first[b + 1]; ++p) s += double(g(int(p)));
    part[std::size_t(b)] = s;
  }
  double s = 0.0;
  for (double v : part) s += v;
  return s;
}

// out[i] = in[0] + ... + in[i-1]; returns the total. in and out may alias.
std::uint32_t exclusive_scan(CpuExec&, const std::uint32_t* in, std::uint32_t* out, int n);

// Stable sort of (keys, vals) by the low key_bits of keys (LSD radix sort, 8 bits a pass).
void sort_pairs(CpuExec&, std::uint32_t* keys, std::uint32_t* vals, int n, int key_bits);

// The same stable sort where most keys are those an earlier sort left in place: start (cells +
// 1 entries, as cell_starts writes them) the ranges it left, index i in [start[c], start[c +
// 1]) then holding key c. The keys that still do stay in order; the others (moved, or past
// start[cells]) are sorted on their own and merged in. Any start gives the stable order, a
// stale one only more work; returns false, having changed nothing, where more than a quarter
// moved (sort_pairs is then the faster).
bool sort_moved(CpuExec&, std::uint32_t* keys, std::uint32_t* vals, int n,
                const std::uint32_t* start, int cells);

}  // namespace sphfem

namespace sphfem {
inline void exec_sync(CpuExec&) {}
}  // namespace sphfem
