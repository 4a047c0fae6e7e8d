// Deterministic scatter-add into nodes, on every backend. Float atomics sum in whatever order
// the threads arrive, so a run's bits would change with the thread count and from run to run.
// Instead the contributions are listed (node, value), those naming a node compacted by a scan,
// sorted stably by node, and each node's run is summed in list order by one thread: the same bits
// on 1 thread, 2 threads or a GPU launch, given the same list.
#pragma once

#include <cstdint>

#include "sphfem/core/memory.h"
#include "sphfem/core/vec.h"

namespace sphfem {

template <class Exec>
class NodeSums {
 public:
  NodeSums()
      : node_(Exec::kSpace),
        flag_(Exec::kSpace),
        keys_(Exec::kSpace),
        vals_(Exec::kSpace),
        values_(Exec::kSpace) {}

  // out[node] += sum of the values of the contributions k < m naming node, in the order of k.
  // contribution(k, node, value) sets node (< 0: none) and value; out has `nodes` entries.
  template <class Contribution>
  void add(Exec& ex, int m, int nodes, Contribution contribution, Vec3* out) {
    if (m <= 0 || nodes <= 0) return;
    for (Buffer<std::uint32_t>* b : {&node_, &flag_, &keys_, &vals_}) grow(*b, m);
    grow(values_, m);
    std::uint32_t* node_of = node_.data();
    std::uint32_t* flag = flag_.data();
    Vec3* values = values_.data();
    parallel_for(ex, m, [=] SPHFEM_LAMBDA(int k) {
      int node = -1;
      Vec3 value;
      contribution(k, node, value);
      const bool some = node >= 0 && node < nodes;
      node_of[k] = some ? std::uint32_t(node) : 0u;
      flag[k] = some ? 1u : 0u;
      values[k] = value;
    });
    // Only the contributions that name a node are sorted (most particles touch no surface).
    const int count = int(exclusive_scan(ex, flag, flag, m));
    if (count == 0) return;
    std::uint32_t* keys = keys_.data();
    std::uint32_t* vals = vals_.data();
    parallel_for(ex, m, [=] SPHFEM_LAMBDA(int k) {
      const bool some = k + 1 < m ? flag[k + 1] != flag[k] : std::uint32_t(count) != flag[k];
      if (!some) return;
      keys[flag[k]] = node_of[k];
      vals[flag[k]] = std::uint32_t(k);
    });
    int bits = 1;
    while ((1ll << bits) < (long long)nodes) ++bits;
    sort_pairs(ex, keys, vals, count, bits);
    // The first entry of each node's run sums the run; the stable sort kept it in k order.
    parallel_for(ex, count, [=] SPHFEM_LAMBDA(int k) {
      const std::uint32_t key = keys[k];
      if (k > 0 && keys[k - 1] == key) return;
      Vec3 s;
      for (int j = k; j < count && keys[j] == key; ++j) s += values[vals[j]];
      out[key] += s;
    });
    exec_sync(ex);
  }

 private:
  template <class T>
  static void grow(Buffer<T>& b, int n) {
    if (b.size() < std::size_t(n)) b.resize(std::size_t(n) + std::size_t(n) / 4);
  }

  Buffer<std::uint32_t> node_, flag_, keys_, vals_;
  Buffer<Vec3> values_;
};

}  // namespace sphfem
