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
  const std::size_t most = std::size_t(n) / 4;
  for (std::vector<std::uint32_t>* s : {&ex.scratch_keys, &ex.scratch_vals}) {
    if (s->capacity() < std::size_t(n)) s->reserve(std::size_t(n) + std::size_t(n) / 4);
    s->resize(std::size_t(n));
  }
  std::uint32_t* ko = ex.scratch_keys.data();
  std::uint32_t* vo = ex.scratch_vals.data();
  // A thread a part of the indices (the result does not depend on how many): it finds the
  // keys that moved, each part's in (key, index) order, then merges its kept keys with the
  // moved ones that fall between them into its own stretch of the output.
  constexpr int kMostParts = 64;
  const int parts = std::max(1, std::min({omp_get_max_threads(), n / 1024, kMostParts}));
  if (int(ex.scratch_parts.size()) < parts) ex.scratch_parts.resize(std::size_t(parts));
  std::vector<std::uint64_t>& moved = ex.scratch_moved;
  std::uint64_t first[kMostParts + 1];  // each part's first kept (key, index)
  std::size_t kept[kMostParts + 1] = {}, from[kMostParts + 1];
  // The cell c with start[c] <= i < start[c + 1] (start is monotone, as cell_starts writes it).
  const auto cell_of = [&](int i) {
    return std::uint32_t(std::upper_bound(start + 1, start + cells, std::uint32_t(i)) -
                         (start + 1));
  };
  constexpr std::uint64_t kNone = ~std::uint64_t(0);
  bool too_many = false, nothing = false;
#pragma omp parallel num_threads(parts)
  {
    const int p = omp_get_thread_num(), parts_run = omp_get_num_threads();
    const int lo = int(std::int64_t(n) * p / parts_run),
              hi = int(std::int64_t(n) * (p + 1) / parts_run);
    // Where index i stood in the earlier sort: cell_of(lo), then walked alongside i.
    std::uint32_t c = cell_of(lo);
    const auto stayed = [&](int i) {
      if (std::uint32_t(i) >= start[cells]) return false;
      while (c + 1 < std::uint32_t(cells) && start[c + 1] <= std::uint32_t(i)) ++c;
      return keys[i] == c;
    };
    std::vector<std::uint64_t>& mine = ex.scratch_parts[std::size_t(p)];
    mine.clear();
    std::size_t here = 0;
    std::uint64_t head = kNone;
    for (int i = lo; i < hi; ++i) {
      const std::uint64_t e = std::uint64_t(keys[i]) << 32 | std::uint32_t(i);
      if (stayed(i)) {
        head = here++ ? head : e;
        continue;
      }
      if (mine.size() > most) break;  // more than a quarter moved: the radix sort then
      mine.push_back(e);
    }
    first[std::size_t(p)] = head;
    kept[std::size_t(p)] = here;
    std::sort(mine.begin(), mine.end());
#pragma omp barrier
#pragma omp single
    {
      std::size_t total = 0;
      for (int q = 0; q < parts_run; ++q) total += ex.scratch_parts[std::size_t(q)].size();
      too_many = total > most;
      nothing = total == 0;
      if (!too_many && !nothing) {
        if (moved.capacity() < most) moved.reserve(most);
        moved.clear();
        for (int q = 0; q < parts_run; ++q) {
          const std::vector<std::uint64_t>& m = ex.scratch_parts[std::size_t(q)];
          const auto mid = moved.insert(moved.end(), m.begin(), m.end()) - moved.begin();
          std::inplace_merge(moved.begin(), moved.begin() + mid, moved.end());
        }
        // Part q takes the moved keys below the next part's first kept one: (key, index)
        // orders both sequences, so their merge is the stable sort.
        first[std::size_t(parts_run)] = kNone;
        for (int q = parts_run - 1; q > 0; --q)
          if (first[std::size_t(q)] == kNone) first[std::size_t(q)] = first[std::size_t(q) + 1];
        from[0] = 0;
        for (int q = 1; q < parts_run; ++q)
          from[std::size_t(q)] = std::size_t(
              std::lower_bound(moved.begin(), moved.end(), first[std::size_t(q)]) - moved.begin());
        from[std::size_t(parts_run)] = moved.size();
        std::size_t before = 0;
        for (int q = 0; q <= parts_run; ++q) {
          const std::size_t k = kept[std::size_t(q)];
          kept[std::size_t(q)] = before;  // the kept keys of the parts before q
          before += k;
        }
      }
    }
    if (!too_many && !nothing) {
      std::size_t m = from[std::size_t(p)];
      const std::size_t m_end = from[std::size_t(p) + 1];
      std::size_t o = kept[std::size_t(p)] + m;
      const std::size_t o0 = o;
      const auto emit_moved = [&] {
        const std::uint32_t i = std::uint32_t(moved[m]);
        ko[o] = std::uint32_t(moved[m] >> 32);
        vo[o++] = vals[i];
        ++m;
      };
      c = cell_of(lo);
      for (int i = lo; i < hi; ++i) {
        if (!stayed(i)) continue;
        const std::uint64_t e = std::uint64_t(keys[i]) << 32 | std::uint32_t(i);
        while (m < m_end && moved[m] < e) emit_moved();
        ko[o] = keys[i];
        vo[o++] = vals[i];
      }
      while (m < m_end) emit_moved();
#pragma omp barrier
      std::memcpy(keys + o0, ko + o0, sizeof(std::uint32_t) * (o - o0));
      std::memcpy(vals + o0, vo + o0, sizeof(std::uint32_t) * (o - o0));
    }
  }
  return !too_many;
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
