#include "exec_cpu.h"

#include <algorithm>
#include <cstring>

#include "sphfem/core/backend.h"

namespace sphfem {

std::uint32_t exclusive_scan(CpuExec&, const std::uint32_t* in, std::uint32_t* out, int n) {
  std::uint32_t sum = 0;
  for (int i = 0; i < n; ++i) {
    const std::uint32_t v = in[i];
    out[i] = sum;
    sum += v;
  }
  return sum;
}

void sort_pairs(CpuExec& ex, std::uint32_t* keys, std::uint32_t* vals, int n, int key_bits) {
  if (n <= 1) return;
  // Growth by a quarter, not the vector's doubling: the scratch lives as long as the run, and
  // the memory estimate (scene/limits.h) counts it so.
  for (std::vector<std::uint32_t>* s : {&ex.scratch_keys, &ex.scratch_vals}) {
    if (s->capacity() < std::size_t(n)) s->reserve(std::size_t(n) + std::size_t(n) / 4);
    s->resize(std::size_t(n));
  }
  std::uint32_t* k0 = keys;
  std::uint32_t* v0 = vals;
  std::uint32_t* k1 = ex.scratch_keys.data();
  std::uint32_t* v1 = ex.scratch_vals.data();
  int passes = 0;
  for (int shift = 0; shift < key_bits; shift += 8, ++passes) {
    std::uint32_t count[257] = {0};
    for (int i = 0; i < n; ++i) ++count[((k0[i] >> shift) & 0xffu) + 1];
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (int i = 0; i < n; ++i) {
      const std::uint32_t d = count[(k0[i] >> shift) & 0xffu]++;
      k1[d] = k0[i];
      v1[d] = v0[i];
    }
    std::swap(k0, k1);
    std::swap(v0, v1);
  }
  if (passes % 2 == 1) {
    std::memcpy(keys, k0, sizeof(std::uint32_t) * n);
    std::memcpy(vals, v0, sizeof(std::uint32_t) * n);
  }
}

bool sort_moved(CpuExec& ex, std::uint32_t* keys, std::uint32_t* vals, int n,
                const std::uint32_t* start, int cells) {
  if (n <= 1 || cells <= 0) return false;
  // Where index i stood in the earlier sort: the cell c with start[c] <= i < start[c + 1].
  // Walked alongside i; c only grows, so the keys kept are in order whatever start holds.
  const auto stayed = [&](std::uint32_t& c, int i) {
    if (std::uint32_t(i) >= start[cells]) return false;
    while (c + 1 < std::uint32_t(cells) && start[c + 1] <= std::uint32_t(i)) ++c;
    return keys[i] == c;
  };
  std::vector<std::uint64_t>& moved = ex.scratch_moved;
  const std::size_t most = std::size_t(n) / 4;
  if (moved.capacity() < most) moved.reserve(most);
  moved.clear();
  std::uint32_t c = 0;
  for (int i = 0; i < n; ++i) {
    if (stayed(c, i)) continue;
    if (moved.size() == most) return false;
    moved.push_back(std::uint64_t(keys[i]) << 32 | std::uint32_t(i));
  }
  if (moved.empty()) return true;
  // (key, index) orders both sequences, so their merge is the stable sort.
  std::sort(moved.begin(), moved.end());
  for (std::vector<std::uint32_t>* s : {&ex.scratch_keys, &ex.scratch_vals}) {
    if (s->capacity() < std::size_t(n)) s->reserve(std::size_t(n) + std::size_t(n) / 4);
    s->resize(std::size_t(n));
  }
  std::uint32_t* ko = ex.scratch_keys.data();
  std::uint32_t* vo = ex.scratch_vals.data();
  std::size_t m = 0;
  int o = 0;
  c = 0;
  const auto emit_moved = [&] {
    const std::uint32_t i = std::uint32_t(moved[m]);
    ko[o] = std::uint32_t(moved[m] >> 32);
    vo[o++] = vals[i];
    ++m;
  };
  for (int i = 0; i < n; ++i) {
    if (!stayed(c, i)) continue;
    const std::uint64_t here = std::uint64_t(keys[i]) << 32 | std::uint32_t(i);
    while (m < moved.size() && moved[m] < here) emit_moved();
    ko[o] = keys[i];
    vo[o++] = vals[i];
  }
  while (m < moved.size()) emit_moved();
  std::memcpy(keys, ko, sizeof(std::uint32_t) * std::size_t(n));
  std::memcpy(vals, vo, sizeof(std::uint32_t) * std::size_t(n));
  return true;
}

namespace {
int g_threads = 0;
}

namespace {
thread_local const char* g_stage_label = nullptr;
}  // namespace

void set_stage_label(const char* label) { g_stage_label = label; }
const char* stage_label() { return g_stage_label; }

void set_cpu_threads(int n) {
  g_threads = n;
  omp_set_num_threads(n > 0 ? n : omp_get_num_procs());
}
int cpu_threads() { return g_threads > 0 ? g_threads : omp_get_max_threads(); }

}  // namespace sphfem
