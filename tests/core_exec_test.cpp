// The CPU execution layer's loops: every item once, whatever the schedule and the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <vector>

#include "core/exec_cpu.h"

namespace sphfem {
namespace {

// Sizes around the chunks' bounds and a thread's share, and one past a power of two.
const int kSizes[] = {0, 1, 7, 63, 64, 65, 1023, 1024, 1025, 5000, 65537};

// Runs body on 1, 2 and 3 threads, the default restored after.
template <class F>
void on_threads(F body) {
  const int before = omp_get_max_threads();
  for (int t : {1, 2, 3}) {
    omp_set_num_threads(t);
    body(t);
  }
  omp_set_num_threads(before);
}

// loop(n, f) calls f(i) for every i < n exactly once, on 1, 2 and 3 threads.
template <class Loop>
void expect_every_item_once(Loop loop) {
  on_threads([&](int t) {
    for (int n : kSizes) {
      std::vector<std::atomic<int>> seen(static_cast<std::size_t>(n));
      loop(n, [&](int i) { seen[std::size_t(i)].fetch_add(1); });
      for (int i = 0; i < n; ++i) ASSERT_EQ(seen[std::size_t(i)].load(), 1) << n << " " << t;
    }
  });
}

TEST(CoreExec, ParallelForVisitsEveryItemOnce) {
  CpuExec ex;
  expect_every_item_once([&](int n, auto f) { parallel_for(ex, n, f); });
}

TEST(CoreExec, ParallelForLightVisitsEveryItemOnce) {
  CpuExec ex;
  expect_every_item_once([&](int n, auto f) { parallel_for_light(ex, n, f); });
}

// The chunks: within their bounds, and enough of them for every thread where the loop is
// long enough (a small body's few hundred tetrahedra shared out).
TEST(CoreExec, ChunksAreASixteenthOfAThreadsShareWithinBounds) {
  on_threads([&](int t) {
    for (int n : kSizes) {
      const int c = for_chunk(n);
      EXPECT_GE(c, kLeastChunk);
      EXPECT_LE(c, kMostChunk);
      if (n >= 16 * t * kLeastChunk && n <= 16 * t * kMostChunk) {
        EXPECT_EQ(c, n / (16 * t)) << n << " " << t;
      }
    }
    EXPECT_EQ(for_chunk(2058), t == 1 ? 128 : 64);  // a sphere of Table 1: 2,058 tetrahedra
    EXPECT_EQ(for_chunk(64000), 1024);              // the dam break's particles
  });
}

// parallel_blocks: the blocks tile [0, n) in order of their begin, each once, and done()
// runs once on each thread that ran.
TEST(CoreExec, ParallelBlocksTileTheRangeAndEndEachThreadOnce) {
  CpuExec ex;
  on_threads([&](int t) {
    for (int n : kSizes) {
      for (int block : {1, 64, 1000}) {
        const int blocks = (n + block - 1) / block;
        std::vector<std::atomic<int>> seen(static_cast<std::size_t>(n));
        std::vector<std::atomic<int>> started(static_cast<std::size_t>(blocks));
        std::atomic<int> done{0};
        std::atomic<bool> bad{false};
        parallel_blocks(
            ex, n, block,
            [&](int b0, int b1) {
              if (b0 % block != 0 || b1 <= b0 || b1 - b0 > block || b1 > n) bad = true;
              if (b1 - b0 < block && b1 != n) bad = true;  // only the last block is short
              started[std::size_t(b0 / block)].fetch_add(1);
              for (int i = b0; i < b1; ++i) seen[std::size_t(i)].fetch_add(1);
            },
            [&] { done.fetch_add(1); });
        ASSERT_FALSE(bad.load()) << n << " " << block << " " << t;
        for (int b = 0; b < blocks; ++b) ASSERT_EQ(started[std::size_t(b)].load(), 1);
        for (int i = 0; i < n; ++i) ASSERT_EQ(seen[std::size_t(i)].load(), 1);
        EXPECT_EQ(done.load(), t) << n << " " << block;
      }
    }
  });
}

}  // namespace
}  // namespace sphfem
