// The host's lists of the wall samples' fluid neighbours under DFSPH (BoundaryView::listed).
// wall_density scans the fluid's grid from every sample once a step; the sweeps' wall_source
// (three a solve, two solves a step) scanned it again each time, about 200 candidates for some
// 15 neighbours, and visited all the samples, of which about 5 % have fluid in reach in the dam
// break. The lists keep what the first scan found, in its order, so the sums and bits are the
// same.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/exec_cpu.h"
#include "sph/stages.h"

namespace sphfem {

class WallLists {
 public:
  // stages::wall_density over b, its fluid neighbours listed; returns the samples with fluid
  // in reach. A thread takes kSumBlock samples at a time, lists their neighbours in a block of
  // its own and moves them to the pool's next free entries; where they land depends on which
  // thread came first, what a list holds does not. Where the pool was too small it grows and
  // the pass runs again (the first step; the values written are the same).
  int density(CpuExec& ex, const SphParams& P, const stages::FluidView& f, const GridView& g,
              const stages::BoundaryView& b) {
    const int blocks = (b.n + kSumBlock - 1) / kSumBlock;
    if (int(blocks_.size()) < blocks) blocks_.resize(std::size_t(blocks));
    for (;;) {
      std::atomic<std::size_t> used{0};
      parallel_blocks(
          ex, b.n, kSumBlock,
          [&](int b0, int b1) {
            thread_local std::vector<std::uint32_t> hits;
            hits.clear();
            Block& B = blocks_[std::size_t(b0 / kSumBlock)];
            B.samples.clear();
            B.ends.clear();
            for (int k = b0; k < b1; ++k) {
              const int count = stages::wall_density_at(
                  P, f, g, b, k, [&](std::uint32_t j) { hits.push_back(j); });
              if (count > 0) {
                B.samples.push_back(std::uint32_t(k));
                B.ends.push_back(std::uint32_t(hits.size()));
              }
            }
            B.at = used.fetch_add(hits.size());
            if (B.at + hits.size() <= pool_.size())
              std::copy(hits.begin(), hits.end(), pool_.begin() + std::ptrdiff_t(B.at));
          },
          [] {});
      if (used.load() <= pool_.size()) break;
      pool_.resize(used.load() + used.load() / 4);
    }
    // The listed samples in ascending order: a prefix over the blocks.
    block_first_.resize(std::size_t(blocks) + 1);
    std::uint32_t listed = 0;
    for (int k = 0; k < blocks; ++k) {
      block_first_[std::size_t(k)] = listed;
      listed += std::uint32_t(blocks_[std::size_t(k)].samples.size());
    }
    block_first_[std::size_t(blocks)] = listed;
    listed_.resize(listed);
    begin_.resize(listed);
    end_.resize(listed);
    for (int k = 0; k < blocks; ++k) {
      const Block& B = blocks_[std::size_t(k)];
      std::uint32_t from = std::uint32_t(B.at);
      for (std::size_t s = 0; s < B.samples.size(); ++s) {
        const std::size_t p = block_first_[std::size_t(k)] + s;
        listed_[p] = B.samples[s];
        begin_[p] = from;
        end_[p] = std::uint32_t(B.at) + B.ends[s];
        from = end_[p];
      }
    }
    n_listed_ = int(listed);
    valid_ = true;
    return n_listed_;
  }

  // The fluid has moved: the lists no longer hold.
  void invalidate() { valid_ = false; }

  // b with the lists, where they hold.
  void attach(stages::BoundaryView& b) const {
    if (!valid_) return;
    b.listed = listed_.data();
    b.listed_at = begin_.data();
    b.listed_end = end_.data();
    b.fluid_list = pool_.data();
    b.block_first = block_first_.data();
    b.n_listed = n_listed_;
  }

 private:
  struct Block {
    std::vector<std::uint32_t> samples, ends;  // the block's listed samples, their lists' ends
    std::size_t at = 0;                        // where its lists begin in the pool
  };
  std::vector<Block> blocks_;
  std::vector<std::uint32_t> pool_, listed_, begin_, end_, block_first_;
  int n_listed_ = 0;
  bool valid_ = false;
};

}  // namespace sphfem
