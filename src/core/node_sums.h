// Deterministic scatter-add into nodes, on every backend. Float atomics sum in whatever order
// the threads arrive, so a run's bits would change with the thread count and from run to run.
// Instead the contributions are listed (node, value), sorted stably by node, and each node's
// run is summed in list order by one thread: the same bits on 1 thread, 2 threads or a GPU
// launch, given the same list.
#pragma once

#include <cstdint>

#include "sphfem/core/memory.h"
#include "sphfem/core/vec.h"

namespace sphfem {

template <class Exec>
class NodeSums {
 public:
  NodeSums()
      : keys_(Exec::kSpace), vals_(Exec::kSpace), values_(Exec::kSpace) {}

  // out[node] += sum of the values of the contributions k < m naming node, in the order of k.
  // contribution(k, node, value) sets node (< 0: none) and value; out has `nodes` entries.
  template <class Contribution>
  void add(Exec& ex, int m, int nodes, Contribution contribution, Vec3* out) {
    if (m <= 0 || nodes <= 0) return;
    grow(keys_, m);
    grow(vals_, m);
    grow(values_, m);
    std::uint32_t* keys = keys_.data();
    std::uint32_t* vals = vals_.data();
    Vec3* values = values_.data();
    const std::uint32_t none = std::uint32_t(nodes);  // sorts after every node
    parallel_for(ex, m, [=] SPHFEM_LAMBDA(int k) {
      int node = -1;
      Vec3 value;
      contribution(k, node, value);
      keys[k] = node >= 0 && node < nodes ? std::uint32_t(node) : none;
      vals[k] = std::uint32_t(k);
      values[k] = value;
    });
    int bits = 1;
    while ((1ll << bits) <= (long long)nodes) ++bits;
    sort_pairs(ex, keys, vals, m, bits);
    // The first entry of each node's run sums the run; the stable sort kept it in k order.
    parallel_for(ex, m, [=] SPHFEM_LAMBDA(int k) {
      const std::uint32_t key = keys[k];
      if (key == none || (k > 0 && keys[k - 1] == key)) return;
      Vec3 s;
      for (int j = k; j < m && keys[j] == key; ++j) s += values[vals[j]];
      out[key] += s;
    });
    exec_sync(ex);
  }

 private:
  template <class T>
  static void grow(Buffer<T>& b, int n) {
    if (b.size() < std::size_t(n)) b.resize(std::size_t(n) + std::size_t(n) / 4);
  }

  Buffer<std::uint32_t> keys_, vals_;
  Buffer<Vec3> values_;
};

}  // namespace sphfem
