// Cell starts and the per-step neighbour lists against brute force, in both list layouts
// (the host's contiguous lists and a device's interleaved ones, run here on the host).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "core/exec_cpu.h"
#include "sph/fluid_buffers.h"
#include "sph/sample_set.h"
#include "sph/stages.h"
#include "sph/wall_lists.h"

using namespace sphfem;

namespace {

// start[c] = number of keys below c, for every c in [0, cells].
void expect_starts(std::vector<std::uint32_t> keys, int cells, const char* what) {
  std::sort(keys.begin(), keys.end());
  CpuExec ex;
  const int n = int(keys.size());
  std::vector<std::uint32_t> start(std::size_t(cells) + 1, 0xdeadbeefu);
  stages::cell_starts(ex, keys.data(), start.data(), n, cells);
  std::size_t below = 0;
  for (int c = 0; c <= cells; ++c) {
    while (below < keys.size() && keys[below] < std::uint32_t(c)) ++below;
    ASSERT_EQ(start[std::size_t(c)], std::uint32_t(below)) << what << ": cell " << c;
  }
  EXPECT_EQ(start[std::size_t(cells)], std::uint32_t(n)) << what;
}

TEST(SphCells, CellStartsEqualBruteForce) {
  std::mt19937 rng(7);
  // Sizes around the host's block of cells, and far more cells than particles.
  for (int cells : {1, 2, 1023, 1024, 1025, 3000, 100000}) {
    expect_starts({}, cells, "no particles");
    for (std::uint32_t c : {0u, std::uint32_t(cells / 2), std::uint32_t(cells - 1)}) {
      expect_starts({c}, cells, "one particle");
      expect_starts(std::vector<std::uint32_t>(500, c), cells, "all in one cell");
    }
    for (int n : {10, 1000, 50000}) {
      std::vector<std::uint32_t> keys(static_cast<std::size_t>(n));
      // Clustered: most cells empty, long empty runs at both ends and between clusters.
      std::uniform_int_distribution<int> centre(0, cells - 1), off(-20, 20);
      const int c1 = centre(rng), c2 = centre(rng);
      for (int i = 0; i < n; ++i) {
        const int c = (i % 2 ? c1 : c2) + off(rng);
        keys[std::size_t(i)] = std::uint32_t(std::clamp(c, 0, cells - 1));
      }
      expect_starts(keys, cells, "clustered");
      for (auto& k : keys) k = std::uint32_t(centre(rng));
      expect_starts(keys, cells, "uniform");
    }
  }
}

// A jittered lattice block with a denser corner, inside a larger grid with empty cells.
struct ListScene {
  SphParams P;
  std::vector<Vec3> x;
  GridView g;
};

ListScene list_scene() {
  ListScene s;
  const Real h = Real(0.1), d = Real(0.05);
  SphParams& P = s.P;
  P.kernel = Kernel(0, h);
  P.h = h;
  P.h2 = h * h;
  P.spacing = d;
  P.rho0 = 1000;
  P.mass = P.rho0 * d * d * d;
  P.volume = P.mass / P.rho0;
  P.stiffness = 1000;
  P.full_neighbors = 33;
  std::vector<Vec3>& x = s.x;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jit(-0.2f, 0.2f), u(0.05f, 0.35f);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i)
        x.push_back(Vec3(Real(0.2) + d * (Real(i) + jit(rng)), Real(0.2) + d * (Real(j) + jit(rng)),
                         Real(0.2) + d * (Real(k) + jit(rng))));
  for (int i = 0; i < 60; ++i) x.push_back(Vec3(u(rng), u(rng), u(rng)));
  s.g.lo = Vec3(0, 0, 0);
  s.g.inv_cell = Real(1) / h;
  s.g.nx = 12;
  s.g.ny = 9;
  s.g.nz = 10;
  return s;
}

// The scene's particles in fb at velocities v (none: at rest), sorted into g (its starts
// fb's); nbr_cap > 0 overrides the lists' room. Lists as DFSPH keeps them where dfsph.
void load_sorted(FluidBuffers& fb, const ListScene& s, const SphParams& P,
                 const std::vector<Vec3>& v, bool dfsph, GridView& g, int nbr_cap = 0) {
  CpuExec ex;
  const int n = int(s.x.size());
  fb.allocate(MemSpace::Host, n, P.full_neighbors, s.g.cells(), /*factors=*/dfsph);
  if (nbr_cap > 0) fb.nbr_cap = nbr_cap;
  fb.x.upload(s.x.data(), std::size_t(n));
  if (v.empty())
    fb.v.zero();
  else
    fb.v.upload(v.data(), std::size_t(n));
  fb.id.upload(std::vector<std::uint32_t>(std::size_t(n), 0u).data(), std::size_t(n));
  fb.p.zero();
  fb.warm_div.zero();
  fb.warm_dens.zero();
  g = s.g;
  fb.sort(ex, g, n, 11, dfsph);
  g.start = fb.start.data();
}

// Wall samples in set: three layers under the scene's block and one far above it (1,764, two
// blocks of kSumBlock), with psi = m and their rest density; returns their number.
int sample_layers(SampleSet<CpuExec>& set, const ListScene& scene, const SphParams& P) {
  CpuExec ex;
  std::vector<Vec3> xs;
  for (const Real y : {Real(0.05), Real(0.1), Real(0.15), Real(0.85)})
    for (int a = 0; a < 21; ++a)
      for (int c = 0; c < 21; ++c)
        xs.push_back(Vec3(Real(0.05) * Real(a + 1), y, Real(0.05) * Real(c + 1)));
  const int nb = int(xs.size());
  GridView geometry = scene.g;
  geometry.start = nullptr;
  set.resize(nb, geometry);
  Buffer<Vec3> x(MemSpace::Host, std::size_t(nb));
  Buffer<std::uint32_t> keys(MemSpace::Host, std::size_t(nb)),
      perm(MemSpace::Host, std::size_t(nb));
  x.upload(xs.data(), std::size_t(nb));
  stages::cell_keys(ex, set.grid(), x.data(), keys.data(), perm.data(), nb);
  sort_pairs(ex, keys.data(), perm.data(), nb, 11);
  stages::gather(ex, x.data(), set.x.data(), perm.data(), nb);
  stages::cell_starts(ex, keys.data(), set.start.data(), nb, set.grid().cells());
  std::vector<Real> psi(std::size_t(nb), P.mass);
  set.psi.upload(psi.data(), std::size_t(nb));
  stages::wall_rest(ex, P, set.rest.data(), set.nb_rest.data(), set.view(nb));
  return nb;
}

// n velocities of random directions and sizes, from seed.
std::vector<Vec3> random_velocities(std::size_t n, unsigned seed) {
  std::vector<Vec3> v(n);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  for (Vec3& vi : v) vi = Vec3(u(rng), u(rng), u(rng));
  return v;
}

// The scene in fb at velocities v as DFSPH's density pass leaves it with walls w: sorted into g,
// its lists and kernel factors stored, the warm-start filter's sums in kappa and ksum. Returns
// the view after the pass.
stages::FluidView dfsph_density(FluidBuffers& fb, const ListScene& s, const SphParams& P,
                                const std::vector<Vec3>& v, const stages::Walls& w, GridView& g) {
  CpuExec ex;
  load_sorted(fb, s, P, v, /*dfsph=*/true, g);
  const int n = int(s.x.size());
  stages::FluidView f = fb.view(n);
  stages::WarmSums warm;
  warm.dens_w = fb.kappa.data();
  warm.dens_kw = fb.ksum.data();
  fb.list_and_density(ex, P, f, g, w, /*with_alpha=*/true, warm);
  return fb.view(n);
}

// density() stores each particle's fluid neighbours; for_fluid_neighbors and for_fluid_pairs
// (with the kernel's values) must give them back in the grid's order, in every layout (the
// host's, packed or not, and a device's), and they must be the brute-force neighbour set.
void check_lists(int nbr_cap_override, bool packed) {
  CpuExec ex;
  const ListScene scene = list_scene();
  const SphParams& P = scene.P;
  const Real h = P.h;
  const std::vector<Vec3>& x = scene.x;
  GridView g = scene.g;
  const int n = int(x.size());
  const int cap = n + 37;  // the interleaved stride is the capacity, not n
  FluidBuffers fb;
  fb.allocate(MemSpace::Host, cap, P.full_neighbors, g.cells(), /*factors=*/packed);
  if (nbr_cap_override > 0) fb.nbr_cap = nbr_cap_override;
  fb.x.upload(x.data(), std::size_t(n));
  fb.v.zero();
  fb.id.upload(std::vector<std::uint32_t>(std::size_t(cap), 0u).data(), std::size_t(cap));
  fb.p.zero();
  fb.sort(ex, g, n, 11, /*dfsph=*/false);
  g.start = fb.start.data();

  // A value per particle for the pair terms to read at j.
  std::vector<Real> q(static_cast<std::size_t>(cap));
  for (int j = 0; j < cap; ++j) q[std::size_t(j)] = Real(1) + Real(0.01) * Real(j % 97);

  stages::FluidView host = fb.view(n);
  ASSERT_EQ(host.nbr_at != nullptr, packed);
  ASSERT_EQ(host.nbr_sk, std::size_t(1));
  stages::Walls walls;
  // Packed, the pool starts too small for the lists: the pass runs again.
  fb.list_and_density(ex, P, host, g, walls, /*with_alpha=*/false);
  // Kept aside: the second run below writes the counts in the other layout.
  std::vector<std::uint32_t> host_list(fb.nbr.data(), fb.nbr.data() + fb.nbr.size());
  std::vector<std::uint32_t> host_at(packed ? fb.nbr_at.data() : nullptr,
                                     packed ? fb.nbr_at.data() + n : nullptr);
  std::vector<int> host_n(fb.nbr_n.data(), fb.nbr_n.data() + n);
  const std::vector<Real> host_rho(fb.rho.data(), fb.rho.data() + n);
  if (packed) {
    // One list after another, none overlapping, the pool (once grown) no larger than an
    // eighth beyond what they take, scaled from the particles to the capacity.
    std::size_t entries = 0;
    for (int i = 0; i < n; ++i) entries += std::size_t(stages::list_entries(host, i));
    EXPECT_LE(double(fb.nbr.size()), std::max(1.125 * double(entries) * cap / n + 1.0,
                                              double(cap) * FluidBuffers::kFirstListRoom));
    std::vector<int> owner(fb.nbr.size(), -1);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < stages::list_entries(host, i); ++k) {
        ASSERT_LT(host_at[std::size_t(i)] + std::size_t(k), owner.size());
        ASSERT_EQ(owner[host_at[std::size_t(i)] + std::size_t(k)], -1) << "particle " << i;
        owner[host_at[std::size_t(i)] + std::size_t(k)] = i;
      }
  }

  // A device's layout: entry k of particle i at k * cap + i, room for nbr_cap each.
  std::vector<std::uint32_t> dev_list(std::size_t(cap) * std::size_t(fb.nbr_cap), 0xffffffffu);
  stages::FluidView dev = host;
  dev.nbr = dev_list.data();
  dev.nbr_at = nullptr;
  dev.nbr_gs = nullptr;
  dev.nbr_si = 1;
  dev.nbr_sk = std::size_t(cap);
  stages::density(ex, P, dev, g, walls, /*with_alpha=*/false);

  host.nbr = host_list.data();
  host.nbr_at = packed ? host_at.data() : nullptr;
  host.nbr_n = host_n.data();
  const Vec3* xs = fb.x.data();
  int overflowed = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(fb.nbr_n.data()[i], host_n[std::size_t(i)]);
    // The same neighbours, summed in the host's vector lanes or one by one: the same density
    // up to the order of the float additions.
    ASSERT_NEAR(fb.rho.data()[i], host_rho[std::size_t(i)], 1e-5 * host_rho[std::size_t(i)]);
    std::vector<std::uint32_t> grid_order, host_order, dev_order;
    for_neighbors(g, xs, xs[i], P.h2,
                  [&](std::uint32_t j, const Vec3&, Real) { grid_order.push_back(j); });
    stages::for_fluid_neighbors(host, g, i, xs[i], P.h2, [&](std::uint32_t j, const Vec3&, Real) {
      host_order.push_back(j);
    });
    stages::for_fluid_neighbors(dev, g, i, xs[i], P.h2, [&](std::uint32_t j, const Vec3&, Real) {
      dev_order.push_back(j);
    });
    ASSERT_EQ(host_order, grid_order) << "particle " << i;
    ASSERT_EQ(dev_order, grid_order) << "particle " << i;
    // The pair sums (in vector lanes on the host's list, pair by pair in the device layout)
    // against the same sums in double precision over the grid's neighbours: every pair once,
    // none past the list's end (i itself would add W(0)), each read at its own j.
    for (const int kind : {0, 1}) {
      const Kernel K(kind, h);
      double bw = 0, bq = 0, br2w = 0, mag = 0, gmag = 0;
      Vec3d bg;
      for (const std::uint32_t j : grid_order) {
        const Vec3 rij = xs[i] - xs[j];
        const Real rr = std::sqrt(norm2(rij));
        const double w = K.W(rr);
        const Vec3 gw = K.grad(rij, rr);
        bw += w;
        bq += w * double(q[j]);
        br2w += double(norm2(rij)) * w;
        bg += Vec3d(gw);
        mag += w * double(q[j]);
        gmag += double(norm(gw));
      }
      for (const stages::FluidView* view : {&host, &dev}) {
        const auto s = stages::sum_fluid_pairs<true, stages::Both<Real, stages::Both<Vec3, Real>>>(
            *view, g, K, i, xs[i], P.h2,
            [&](const auto& j, const auto&, const auto& r2, const auto& w, const auto& gw) {
              using stages::at;
              return stages::both(w * at(q.data(), j), stages::both(gw, r2 * w));
            });
        const double tol = 1e-5 * mag + 1e-6;
        EXPECT_NEAR(s.a, bq, tol) << "particle " << i;
        EXPECT_NEAR(s.b.b, br2w, 1e-5 * P.h2 * bw + 1e-9) << "particle " << i;
        EXPECT_NEAR(s.b.a.x, bg.x, 1e-5 * gmag + 1e-6) << "particle " << i;
        EXPECT_NEAR(s.b.a.y, bg.y, 1e-5 * gmag + 1e-6) << "particle " << i;
        EXPECT_NEAR(s.b.a.z, bg.z, 1e-5 * gmag + 1e-6) << "particle " << i;
      }
    }
    const int m = fb.nbr_n.data()[i];
    if (m < 0) {
      ++overflowed;
    } else {
      ASSERT_EQ(m, int(grid_order.size()));
      for (int k = 0; k < m; ++k) {
        ASSERT_EQ(host_list[stages::list_start(host, i) + std::size_t(k)],
                  grid_order[std::size_t(k)]);
        ASSERT_EQ(dev_list[std::size_t(k) * std::size_t(cap) + std::size_t(i)],
                  grid_order[std::size_t(k)]);
      }
    }
    std::set<std::uint32_t> brute, found(grid_order.begin(), grid_order.end());
    for (int j = 0; j < n; ++j)
      if (norm2(xs[i] - xs[j]) < P.h2) brute.insert(std::uint32_t(j));
    ASSERT_EQ(found, brute) << "particle " << i;
  }
  if (nbr_cap_override > 0)
    EXPECT_GT(overflowed, 0);  // the grid-scan fallback ran
  else
    EXPECT_LT(overflowed, n / 10);
}

TEST(SphCells, NeighbourListsInEveryLayoutEqualBruteForce) {
  check_lists(0, /*packed=*/false);
  check_lists(0, /*packed=*/true);
}

// DFSPH's passes read each pair's kernel factor where the density pass stored it: their sums
// must be those of the kernel evaluated again, to the bit, for both kernels.
TEST(SphCells, StoredKernelFactorsGiveTheKernelsBits) {
  CpuExec ex;
  ListScene scene = list_scene();
  const int n = int(scene.x.size());
  const std::vector<Vec3> v = random_velocities(scene.x.size(), 5);
  for (const int kind : {0, 1}) {
    SphParams P = scene.P;
    P.kernel = Kernel(kind, P.h);
    FluidBuffers fb;
    GridView g;
    const stages::FluidView f = dfsph_density(fb, scene, P, v, stages::Walls(), g);
    ASSERT_NE(f.nbr_gs, nullptr);
    stages::FluidView fresh = f;
    fresh.nbr_gs = nullptr;
    int listed = 0;
    for (int i = 0; i < n; ++i) {
      listed += fb.nbr_n.data()[i] > 0;
      const Vec3 xi = f.x[i], vi = f.v[i];
      auto term = [&](const auto& j, const auto&, const auto& r2, const auto&, const auto& gw) {
        using stages::at;
        return stages::both(dot(vi - at(f.v, j), gw), stages::both(gw, r2));
      };
      const auto a = stages::sum_fluid_pairs<false, stages::Both<Real, stages::Both<Vec3, Real>>>(
          f, g, P.kernel, i, xi, P.h2, term);
      const auto b = stages::sum_fluid_pairs<false, stages::Both<Real, stages::Both<Vec3, Real>>>(
          fresh, g, P.kernel, i, xi, P.h2, term);
      ASSERT_EQ(a.a, b.a) << "kernel " << kind << ", particle " << i;
      ASSERT_EQ(a.b.a.x, b.b.a.x) << "kernel " << kind << ", particle " << i;
      ASSERT_EQ(a.b.a.y, b.b.a.y) << "kernel " << kind << ", particle " << i;
      ASSERT_EQ(a.b.a.z, b.b.a.z) << "kernel " << kind << ", particle " << i;
      ASSERT_EQ(a.b.b, b.b.b) << "kernel " << kind << ", particle " << i;
    }
    EXPECT_GT(listed, n / 2);
  }
}
// The DFSPH density pass also sums the fluid pairs of the divergence solve's warm-start sweep
// (WarmSums::div_dv); the sweep applies that sum instead of its own pass over the pairs. The
// velocities must be those of the pass, to the bit, for both kernels, with lists and with
// lists that overflow (then summed over the grid).
TEST(SphCells, DivergenceWarmStartSummedByTheDensityPassGivesTheSweepsBits) {
  CpuExec ex;
  ListScene scene = list_scene();
  const int n = int(scene.x.size());
  std::vector<Vec3> v(scene.x.size());
  std::vector<Real> warm(scene.x.size());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  for (Vec3& vi : v) vi = Vec3(u(rng), u(rng), u(rng));
  for (Real& k : warm) k = Real(50) * (Real(1) + u(rng));
  for (const int kind : {0, 1})
    for (const int cap : {0, 8}) {
      SphParams P = scene.P;
      P.kernel = Kernel(kind, P.h);
      FluidBuffers fb;
      GridView g;
      load_sorted(fb, scene, P, v, /*dfsph=*/true, g, cap);
      fb.warm_div.upload(warm.data(), warm.size());
      stages::FluidView f = fb.view(n);
      stages::WarmSums sums;
      sums.dens_w = fb.kappa.data();
      sums.dens_kw = fb.ksum.data();
      sums.div_dv = fb.warm_dv.data();
      fb.list_and_density(ex, P, f, g, stages::Walls(), /*with_alpha=*/true, sums);
      f = fb.view(n);
      const std::vector<Vec3> v0(f.v, f.v + n);
      std::vector<Vec3> after[2];
      for (const bool fused : {true, false}) {
        fb.v.upload(v0.data(), v0.size());
        stages::dfsph_warm_start(ex, f, /*divergence=*/true);
        stages::dfsph_apply(ex, P, f, g, stages::Walls(), Real(1e-3),
                            fused ? fb.warm_dv.data() : nullptr);
        after[fused] = std::vector<Vec3>(f.v, f.v + n);
      }
      int listed = 0, moved = 0;
      for (int i = 0; i < n; ++i) {
        listed += fb.nbr_n.data()[i] > 0;
        const Vec3 a = after[1][std::size_t(i)], b = after[0][std::size_t(i)];
        moved += !(a.x == v0[std::size_t(i)].x);
        ASSERT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z)
            << "kernel " << kind << ", cap " << cap << ", particle " << i;
      }
      EXPECT_GT(moved, n / 2);
      if (cap)
        EXPECT_LT(listed, n / 2);
      else
        EXPECT_GT(listed, n / 2);
    }
}

// WCSPH's density pass sums W of the squared distances its list build staged (from the
// positions' planes); without the planes it gathers x_j again. Both give each density to the
// bit, for both kernels and with lists that overflow (then summed over the grid).
TEST(SphCells, StagedDistancesGiveTheDensitysBits) {
  CpuExec ex;
  ListScene scene = list_scene();
  const int n = int(scene.x.size());
  for (const int kind : {0, 1})
    for (const int cap : {0, 8}) {
      SphParams P = scene.P;
      P.kernel = Kernel(kind, P.h);
      FluidBuffers fb;
      GridView g;
      load_sorted(fb, scene, P, {}, /*dfsph=*/false, g, cap);
      stages::FluidView f = fb.view(n);
      f.planes = &fb.a.data()[0].x;
      f.planes_stride = std::size_t(fb.cap) + 1;
      stages::position_planes(ex, f);
      fb.list_and_density(ex, P, f, g, stages::Walls(), /*with_alpha=*/false);
      const std::vector<Real> staged(fb.rho.data(), fb.rho.data() + n);
      const std::vector<int> counts(fb.nbr_n.data(), fb.nbr_n.data() + n);
      stages::FluidView gathered = fb.view(n);
      fb.list_and_density(ex, P, gathered, g, stages::Walls(), /*with_alpha=*/false);
      int listed = 0;
      for (int i = 0; i < n; ++i) {
        ASSERT_EQ(counts[std::size_t(i)], fb.nbr_n.data()[i]) << "particle " << i;
        listed += counts[std::size_t(i)] > 0;
        ASSERT_EQ(staged[std::size_t(i)], fb.rho.data()[i])
            << "kernel " << kind << ", cap " << cap << ", particle " << i;
        ASSERT_GT(staged[std::size_t(i)], Real(0));
      }
      if (cap)
        EXPECT_LT(listed, n / 2);
      else
        EXPECT_GT(listed, n / 2);
    }
}

// The wall samples' fluid neighbours listed by the density pass (WallLists) give the DFSPH
// sweeps' wall terms to the bit: the density pass's values, each solve's residual, the samples'
// stiffness and its sum, over two blocks of samples with and without fluid in reach.
TEST(SphCells, ListedWallSamplesGiveTheScansBits) {
  CpuExec ex;
  ListScene scene = list_scene();
  const SphParams& P = scene.P;
  const int n = int(scene.x.size());
  SampleSet<CpuExec> set;
  const int nb = sample_layers(set, scene, P);
  FluidBuffers fb;
  GridView g;
  stages::Walls w;
  w.fixed = set.view(nb);
  stages::FluidView f = dfsph_density(fb, scene, P, random_velocities(std::size_t(n), 3), w, g);
  stages::fluid_reach(ex, P, f);

  auto copy = [](const Real* a, int m) { return std::vector<Real>(a, a + m); };
  const int scanned = stages::wall_density(ex, P, f, g, set.view(nb));
  const std::vector<Real> rho = copy(set.rho.data(), nb), alpha = copy(set.alpha.data(), nb),
                          wdiv = copy(set.warm_div.data(), nb),
                          wdens = copy(set.warm_dens.data(), nb);
  set.rho.zero();
  set.alpha.zero();
  WallLists lists;
  const int listed = lists.density(ex, P, f, g, set.view(nb));
  EXPECT_EQ(listed, scanned);
  EXPECT_GT(listed, 200);
  EXPECT_LT(listed, nb - 441);  // the far layer has no fluid in reach
  for (int k = 0; k < nb; ++k) {
    ASSERT_EQ(rho[std::size_t(k)], set.rho.data()[k]) << "sample " << k;
    ASSERT_EQ(alpha[std::size_t(k)], set.alpha.data()[k]) << "sample " << k;
    ASSERT_EQ(wdiv[std::size_t(k)], set.warm_div.data()[k]) << "sample " << k;
    ASSERT_EQ(wdens[std::size_t(k)], set.warm_dens.data()[k]) << "sample " << k;
  }
  stages::BoundaryView with = set.view(nb);
  lists.attach(with);
  ASSERT_NE(with.listed, nullptr);
  ASSERT_EQ(with.n_listed, listed);
  EXPECT_GT(with.block_first[1], 0u);  // both blocks hold listed samples
  EXPECT_GT(with.block_first[2], with.block_first[1]);
  for (const bool divergence : {true, false}) {
    std::vector<Real> kappa[2], ksum[2];
    double sum[2][2];
    for (int run = 0; run < 2; ++run) {
      const stages::BoundaryView b = run ? with : set.view(nb);
      stages::wall_warm_start(ex, b, divergence);
      for (int sweep = 0; sweep < 2; ++sweep) {
        sum[run][sweep] = stages::wall_source(ex, P, f, g, b, Real(1e-3), Real(0.5), divergence);
        stages::wall_accumulate(ex, b);
      }
      kappa[run] = copy(set.kappa.data(), nb);
      ksum[run] = copy(set.kappa_sum.data(), nb);
    }
    EXPECT_NE(sum[0][0], 0.0);
    for (int sweep = 0; sweep < 2; ++sweep) EXPECT_EQ(sum[0][sweep], sum[1][sweep]);
    for (int k = 0; k < nb; ++k) {
      ASSERT_EQ(kappa[0][std::size_t(k)], kappa[1][std::size_t(k)]) << "sample " << k;
      ASSERT_EQ(ksum[0][std::size_t(k)], ksum[1][std::size_t(k)]) << "sample " << k;
    }
  }
  lists.invalidate();
  stages::BoundaryView without = set.view(nb);
  lists.attach(without);
  EXPECT_EQ(without.listed, nullptr);
}

// DFSPH's residual sweep reads the kernel factors of the tank's samples a particle listed
// where the density pass stored them beside the fluid's (stages::for_wall_grads): each
// residual and stiffness must be what the kernel evaluated again gives, to the bit, for both
// kernels and both solves.
TEST(SphCells, StoredTankFactorsGiveTheKernelsBits) {
  CpuExec ex;
  ListScene scene = list_scene();
  const int n = int(scene.x.size());
  const std::vector<Vec3> v = random_velocities(scene.x.size(), 9);
  for (const int kind : {0, 1}) {
    SphParams P = scene.P;
    P.kernel = Kernel(kind, P.h);
    SampleSet<CpuExec> set;
    const int nb = sample_layers(set, scene, P);
    FluidBuffers fb;
    GridView g;
    stages::Walls w;
    w.fixed = set.view(nb);
    const stages::FluidView f = dfsph_density(fb, scene, P, v, w, g);
    fb.ksum.zero();
    int listed = 0;
    for (int i = 0; i < n; ++i) listed += (fb.flags.data()[i] >> stages::kTankListed) > 1;
    EXPECT_GT(listed, 50);
    stages::FluidView fresh = f;
    fresh.nbr_gs = nullptr;
    for (const bool divergence : {true, false}) {
      const double a = stages::dfsph_source(ex, P, f, g, w, Real(1e-3), Real(0.5), divergence);
      const std::vector<Real> ka(fb.kappa.data(), fb.kappa.data() + n);
      const double b = stages::dfsph_source(ex, P, fresh, g, w, Real(1e-3), Real(0.5), divergence);
      EXPECT_NE(a, 0.0);
      EXPECT_EQ(a, b) << "kernel " << kind << (divergence ? ", divergence" : ", density");
      for (int i = 0; i < n; ++i)
        ASSERT_EQ(ka[std::size_t(i)], fb.kappa.data()[i])
            << "kernel " << kind << ", particle " << i;
    }
  }
}

struct ForcesExec : CpuExec {};

// WCSPH's forces read what they take of a neighbour from its records (FluidView::rec_x,
// rec_v) where the host keeps them: the accelerations must be those the arrays give, to the
// bit, for both kernels, with and without XSPH and artificial viscosity, and where lists
// overflowed (those particles scan the grid and read the arrays).
TEST(SphCells, RecordsGiveTheForcesBits) {
  CpuExec ex;
  // The stages instantiated for a type of this file's own: accelerations instantiated for
  // CpuExec here, the linker took this file's copy for the library's too, and this file's
  // inlining gave the DFSPH scenes' accelerations other bits (Paper/SimState200).
  ForcesExec fex;
  const ListScene scene = list_scene();
  const int n = int(scene.x.size());
  const std::vector<Vec3> v = random_velocities(std::size_t(n), 5);
  for (const int kind : {0, 1})
    for (const int cap : {0, 8})
      for (const Real smoothing : {Real(0), Real(0.1)})
        for (const Real av : {Real(0), Real(0.05)}) {
          SphParams P = scene.P;
          P.kernel = Kernel(kind, P.h);
          P.viscosity = Real(1e-3);
          P.xsph = smoothing;
          P.alpha_av = av;
          P.sound_speed = Real(20);
          P.gravity = Vec3(0, Real(-9.81), 0);
          FluidBuffers fb;
          GridView g;
          load_sorted(fb, scene, P, v, /*dfsph=*/false, g, cap);
          stages::FluidView f = fb.view(n);
          fb.list_and_density(ex, P, f, g, stages::Walls(), /*with_alpha=*/false);
          const Real dt = Real(1e-3);
          stages::accelerations(fex, P, f, g, stages::Walls(), true, dt, nullptr, nullptr);
          const std::vector<Vec3> from_arrays(fb.a.data(), fb.a.data() + n);
          ASSERT_TRUE(fb.see_records(f));
          stages::pair_records(fex, P, f);
          fb.a.zero();
          stages::accelerations(fex, P, f, g, stages::Walls(), true, dt, nullptr, nullptr);
          int pushed = 0;
          for (int i = 0; i < n; ++i) {
            const Vec3 a = fb.a.data()[i], b = from_arrays[std::size_t(i)];
            ASSERT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z)
                << "kernel " << kind << ", cap " << cap << ", xsph " << smoothing << ", av " << av
                << ", particle " << i;
            pushed += norm(b - P.gravity) > Real(1);
          }
          EXPECT_GT(pushed, n / 2);  // the pairs' terms are there to compare
        }
}

TEST(SphCells, OverflowingListsFallBackToTheGridInEveryLayout) {
  check_lists(8, /*packed=*/false);
  check_lists(8, /*packed=*/true);
}

}  // namespace
