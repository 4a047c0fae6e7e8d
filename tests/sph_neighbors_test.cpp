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

// A clustered cloud (some cells crowded, some empty) plus points outside the grid box, which
// must land in the border cells and still be found, sorted into a grid of cell size h = 0.1.
struct SortedCloud {
  static constexpr int n = 3000;
  const Real h = Real(0.1);
  GridView g;
  std::vector<std::uint32_t> keys, perm, start;
  std::vector<Vec3> xs;

  SortedCloud() : keys(n), perm(n), xs(n) {
    CpuExec ex;
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> u(-0.05f, 1.05f);
    std::normal_distribution<float> gclust(0.3f, 0.05f);
    std::vector<Vec3> x(n);
    for (int i = 0; i < n; ++i)
      x[i] = i % 3 == 0 ? Vec3(gclust(rng), gclust(rng), gclust(rng))
                        : Vec3(u(rng), u(rng), u(rng) * 0.5f);
    g.lo = Vec3(0, 0, 0);
    g.inv_cell = Real(1) / h;
    g.nx = 10;
    g.ny = 10;
    g.nz = 5;
    start.resize(std::size_t(g.cells()) + 1);
    stages::cell_keys(ex, g, x.data(), keys.data(), perm.data(), n);
    sort_pairs(ex, keys.data(), perm.data(), n, 9);
    stages::gather(ex, x.data(), xs.data(), perm.data(), n);
    stages::cell_starts(ex, keys.data(), start.data(), n, g.cells());
    g.start = start.data();
  }
};

TEST(SphNeighbors, GridSearchEqualsBruteForce) {
  const SortedCloud c;
  const int n = c.n;
  const Real h = c.h;
  const GridView& g = c.g;
  const auto& xs = c.xs;
  const auto& perm = c.perm;
  const auto& start = c.start;
  ASSERT_TRUE(std::is_sorted(c.keys.begin(), c.keys.end()));
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

// The list builder finds for_neighbors' neighbours in its order, reading the positions as Vec3s
// or as planes (FluidView::planes), on the host's packed path and on the capped one.
TEST(SphNeighbors, ListsFromPlanesAndFromVectorsEqualTheScan) {
  const SortedCloud c;
  CpuExec ex;
  // Seven Reals past the z plane: the host's groups of eight read there (FluidView::planes).
  std::vector<Real> planes(3 * std::size_t(c.n) + 7);
  stages::FluidView f;
  f.n = c.n;
  f.x = const_cast<Vec3*>(c.xs.data());
  f.planes = planes.data();
  f.planes_stride = std::size_t(c.n);
  stages::position_planes(ex, f);
  const Real h2 = c.h * c.h;
  for (int last : {255, 20}) {  // room for all; the overflow into the last slot
    for (int i = 0; i < c.n; ++i) {
      std::vector<std::uint32_t> scan;
      for_neighbors(c.g, c.xs.data(), c.xs[i], h2,
                    [&](std::uint32_t j, const Vec3&, Real) { scan.push_back(j); });
      std::vector<std::uint32_t> from_vectors(256), from_planes(256);
      const int a =
          collect_neighbors(c.g, c.xs.data(), c.xs[i], h2, from_vectors.data(), 1, last, 0);
      const int b = collect_neighbors(c.g, c.xs.data(), c.xs[i], h2, from_planes.data(), 1, last, 0,
                                      planes.data(), std::size_t(c.n));
      ASSERT_EQ(a, int(scan.size())) << "particle " << i;
      ASSERT_EQ(b, a) << "particle " << i;
      const int kept = std::min(a, last);
      for (int k = 0; k < kept; ++k) {
        ASSERT_EQ(from_vectors[k], scan[k]) << "particle " << i << ", entry " << k;
        ASSERT_EQ(from_planes[k], scan[k]) << "particle " << i << ", entry " << k;
      }
    }
  }
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
