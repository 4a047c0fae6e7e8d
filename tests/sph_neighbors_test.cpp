// Neighbour search by cell grid and counting sort equals an O(N^2) brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "core/exec_cpu.h"
#include "sph/stages.h"

using namespace sphfem;

namespace {

TEST(SphNeighbors, GridSearchEqualsBruteForce) {
  CpuExec ex;
  const Real h = Real(0.1);
  const int n = 3000;
  std::mt19937 rng(42);
  // A clustered cloud (some cells crowded, some empty) plus points outside the grid box,
  // which must land in the border cells and still be found.
  std::uniform_real_distribution<float> u(-0.05f, 1.05f);
  std::normal_distribution<float> gclust(0.3f, 0.05f);
  std::vector<Vec3> x(n);
  for (int i = 0; i < n; ++i)
    x[i] = i % 3 == 0 ? Vec3(gclust(rng), gclust(rng), gclust(rng)) : Vec3(u(rng), u(rng), u(rng) * 0.5f);

  GridView g;
  g.lo = Vec3(0, 0, 0);
  g.inv_cell = Real(1) / h;
  g.nx = 10;
  g.ny = 10;
  g.nz = 5;
  std::vector<std::uint32_t> keys(n), perm(n), start(g.cells() + 1);
  std::vector<Vec3> xs(n);
  stages::cell_keys(ex, g, x.data(), keys.data(), perm.data(), n);
  sort_pairs(ex, keys.data(), perm.data(), n, 9);
  ASSERT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  stages::gather(ex, x.data(), xs.data(), perm.data(), n);
  stages::cell_starts(ex, keys.data(), start.data(), n, g.cells());
  g.start = start.data();
  EXPECT_EQ(start[0], 0u);
  EXPECT_EQ(start[g.cells()], std::uint32_t(n));

  long pairs = 0;
  for (int i = 0; i < n; ++i) {
    std::set<std::uint32_t> grid_set, brute;
    for_neighbors(g, xs.data(), xs[i], h * h, [&](std::uint32_t j, const Vec3&, Real) {
      EXPECT_TRUE(grid_set.insert(perm[j]).second) << "a neighbour was visited twice";
    });
    for (int j = 0; j < n; ++j)
      if (norm2(xs[i] - xs[j]) < h * h) brute.insert(perm[j]);
    ASSERT_EQ(grid_set, brute) << "particle " << perm[i];
    pairs += long(brute.size());
  }
  EXPECT_GT(pairs, 20L * n);  // the test exercises real neighbourhoods
}

TEST(SphNeighbors, RadixSortIsStableAndMatchesStdSort) {
  CpuExec ex;
  std::mt19937 rng(3);
  const int n = 10000;
  std::vector<std::uint32_t> k(n), v(n);
  for (int i = 0; i < n; ++i) {
    k[i] = rng() % 5000u;
    v[i] = std::uint32_t(i);
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ref(n);
  for (int i = 0; i < n; ++i) ref[i] = {k[i], v[i]};
  std::stable_sort(ref.begin(), ref.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  sort_pairs(ex, k.data(), v.data(), n, 13);
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(k[i], ref[i].first);
    ASSERT_EQ(v[i], ref[i].second);
  }
}

}  // namespace
