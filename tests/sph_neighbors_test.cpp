// Neighbour search by cell grid and counting sort equals an O(N^2) brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "core/exec_cpu.h"
#include "sph/stages.h"
#include "sphfem/core/backend.h"

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

// The cloud's positions as planes (FluidView::planes, stride n), with the seven Reals past the
// z plane that the host's groups of eight read.
std::vector<Real> cloud_planes(const SortedCloud& c) {
  CpuExec ex;
  std::vector<Real> planes(3 * std::size_t(c.n) + 7);
  stages::FluidView f;
  f.n = c.n;
  f.x = const_cast<Vec3*>(c.xs.data());
  f.planes = planes.data();
  f.planes_stride = std::size_t(c.n);
  stages::position_planes(ex, f);
  return planes;
}

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
  const std::vector<Real> planes = cloud_planes(c);
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

// The scan that sifts its candidates from the planes (the wall samples' scans of the fluid)
// makes for_neighbors' calls in its order with the same arguments to the bit: at the particles,
// at random points, and at points exactly at and just inside the support's edge of a particle.
TEST(SphNeighbors, SiftedScanCallsAsTheScan) {
  const SortedCloud c;
  const std::vector<Real> planes = cloud_planes(c);
  const Real h2 = c.h * c.h;
  std::vector<Vec3> at(c.xs);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.1f, 1.1f);
  for (int k = 0; k < 2000; ++k) at.push_back(Vec3(u(rng), u(rng), u(rng) * 0.5f));
  for (int k = 0; k < 500; ++k) {
    const Vec3 x = c.xs[std::size_t(k * 5)];
    at.push_back(x + Vec3(c.h, 0, 0));
    at.push_back(x - Vec3(0, c.h, 0));
    at.push_back(x + Vec3(0, 0, std::nextafter(c.h, Real(0))));
  }
  struct Call {
    std::uint32_t j;
    Vec3 r;
    Real r2;
  };
  auto same = [](const Call& a, const Call& b) {
    return a.j == b.j && a.r.x == b.r.x && a.r.y == b.r.y && a.r.z == b.r.z && a.r2 == b.r2;
  };
  long calls = 0;
  for (std::size_t q = 0; q < at.size(); ++q) {
    std::vector<Call> scan, sifted;
    for_neighbors(c.g, c.xs.data(), at[q], h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
      scan.push_back({j, r, r2});
    });
    for_neighbors(c.g, c.xs.data(), planes.data(), std::size_t(c.n), at[q], h2,
                  [&](std::uint32_t j, const Vec3& r, Real r2) {
                    sifted.push_back({j, r, r2});
                  });
    ASSERT_EQ(sifted.size(), scan.size()) << "query " << q;
    for (std::size_t k = 0; k < scan.size(); ++k)
      ASSERT_TRUE(same(sifted[k], scan[k])) << "query " << q << ", call " << k;
    calls += long(scan.size());
  }
  EXPECT_GT(calls, 20L * c.n);
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

// The sort of keys that mostly stayed where an earlier sort put them: the stable order for
// any ranges of that sort (right, stale, empty), with particles appended, and nothing changed
// where more than a quarter moved.
TEST(SphNeighbors, SortOfMovedKeysIsTheStableSort) {
  CpuExec ex;
  std::mt19937 rng(7);
  const int cells = 700, n = 8000;
  // An earlier sort's keys and ranges.
  std::vector<std::uint32_t> before(n);
  for (std::uint32_t& key : before) key = rng() % std::uint32_t(cells);
  std::sort(before.begin(), before.end());
  std::vector<std::uint32_t> start(cells + 1, 0);
  for (int c = 0, i = 0; c <= cells; ++c) {
    while (i < n && before[std::size_t(i)] < std::uint32_t(c)) ++i;
    start[std::size_t(c)] = std::uint32_t(i);
  }
  std::vector<std::uint32_t> stale(start);  // other ranges, still monotone
  for (std::uint32_t& s : stale) s = rng() % std::uint32_t(n + 1);
  std::sort(stale.begin(), stale.end());
  const std::vector<std::uint32_t> none(cells + 1, 0);
  struct Case {
    const char* what;
    double moved;
    int appended;
    const std::vector<std::uint32_t>* start;
    bool sorts;
  };
  const Case cases[] = {{"3 % moved", 0.03, 0, &start, true},
                        {"3 % moved, 50 appended", 0.03, 50, &start, true},
                        {"none moved", 0.0, 0, &start, true},
                        {"stale ranges", 0.03, 0, &stale, false},
                        {"no earlier sort", 0.03, 0, &none, false},
                        {"40 % moved", 0.4, 0, &start, false}};
  const int threads = cpu_threads();
  for (const int parts : {1, 2, 3})
    for (const Case& t : cases) {
      set_cpu_threads(parts);  // sort_moved splits the indices a part a thread
      std::vector<std::uint32_t> k(before);
      std::uniform_real_distribution<double> u(0, 1);
      for (std::uint32_t& key : k)
        if (u(rng) < t.moved) {
          const int step = int(rng() % 3) == 0 ? 40 : 1;  // a neighbouring cell or a layer away
          key = std::uint32_t(std::clamp(int(key) + (rng() % 2 ? step : -step), 0, cells - 1));
        }
      for (int a = 0; a < t.appended; ++a) k.push_back(rng() % std::uint32_t(cells));
      const int m = int(k.size());
      std::vector<std::uint32_t> v(static_cast<std::size_t>(m));
      for (int i = 0; i < m; ++i) v[std::size_t(i)] = std::uint32_t(1000000 + i);
      std::vector<std::uint32_t> rk(k), rv(v);
      sort_pairs(ex, rk.data(), rv.data(), m, 10);
      const std::vector<std::uint32_t> k0(k), v0(v);
      const bool sorted = sort_moved(ex, k.data(), v.data(), m, t.start->data(), cells);
      set_cpu_threads(threads);
      if (t.sorts) { EXPECT_TRUE(sorted) << t.what << ", " << parts << " threads"; }
      if (sorted) {
        EXPECT_EQ(k, rk) << t.what << ", " << parts << " threads";
        EXPECT_EQ(v, rv) << t.what << ", " << parts << " threads";
      } else {
        EXPECT_EQ(k, k0) << t.what << ", " << parts << " threads";
        EXPECT_EQ(v, v0) << t.what << ", " << parts << " threads";
      }
    }
}

}  // namespace

namespace {

// The reach box of the fluid (stages::fluid_reach, the host's bounds in one pass): the
// particles' least and greatest coordinates widened by the support, at 1, 2 and 3 threads.
TEST(SphNeighbors, ReachBoxIsTheBoundsWidenedBySupport) {
  CpuExec ex;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-2, 3);
  SphParams P;
  P.h = Real(0.1);
  const int threads = cpu_threads();
  for (const int n : {0, 1, 5000})
    for (const int parts : {1, 2, 3}) {
      std::vector<Vec3> x(static_cast<std::size_t>(n) + 1);
      for (Vec3& p : x) p = Vec3(u(rng), u(rng), u(rng));
      stages::FluidView f;
      f.n = n;
      f.x = x.data();
      set_cpu_threads(parts);
      stages::fluid_reach(ex, P, f);
      set_cpu_threads(threads);
      ASSERT_EQ(f.reached, n > 0 ? 1 : 0);
      if (!n) continue;
      for (int a = 0; a < 3; ++a) {
        Real lo = x[0][a], hi = x[0][a];
        for (int i = 0; i < n; ++i) {
          lo = std::min(lo, x[std::size_t(i)][a]);
          hi = std::max(hi, x[std::size_t(i)][a]);
        }
        const Real reach = P.h * Real(1.001);
        EXPECT_EQ(f.reach_lo[a], lo - reach) << "n " << n << ", axis " << a;
        EXPECT_EQ(f.reach_hi[a], hi + reach) << "n " << n << ", axis " << a;
      }
    }
}

}  // namespace
