// The SPH stages, written once for every backend. Each stage is a function template over
// the execution backend (CpuExec, CudaExec) whose per-particle body is a host-and-device
// lambda; the arrays travel as raw pointers in small views copied by value.
//
// WCSPH: Becker & Teschner 2007 with the paper's state equation p = k (rho/rho0 - 1), p >= 0.
// DFSPH: Bender & Koschier 2015/2017 (divergence-free and constant-density solvers).
// Boundaries: static samples with mass psi (Akinci et al. 2012). WCSPH gives them a pressure
// each step (Adami, Hu & Adams 2012); DFSPH solves for their stiffness with the fluid's.
// Samples on moving body surfaces (boundary-particle coupling) take the same code with a
// velocity; a body surface without samples (ray-traced coupling) adds the kernel mass
// missing beyond it (near-surface density, sph/surface_density.h).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "sph/pair_lanes.h"
#include "sphfem/core/memory.h"
#include "sphfem/sph/grid.h"
#include "sphfem/sph/model.h"
#include "sphfem/sph/surface_density.h"

namespace sphfem::stages {

struct FluidView {
  int n = 0;
  Vec3* x = nullptr;
  Vec3* v = nullptr;
  Vec3* a = nullptr;
  Real* rho = nullptr;
  Real* p = nullptr;          // pressure: WCSPH state equation, DFSPH rho^2 / rho0 sum kappa
  Real* alpha = nullptr;      // DFSPH factor 1 / (|sum V grad W|^2 + sum |V grad W|^2)
  Real* kappa = nullptr;      // DFSPH stiffness of the current Jacobi sweep
  Real* kappa_sum = nullptr;  // DFSPH stiffness summed over the current solve
  Real* warm_div = nullptr;   // DFSPH warm start of the divergence solve (dfsph_remember)
  Real* warm_dens = nullptr;  // the same for the density solve
  int* nb = nullptr;          // fluid neighbour count
  int* flags = nullptr;       // kFullSupport, kNearTank of density()
  Vec3* gwall = nullptr;      // DFSPH: sum_b V grad W_ib (density), read by wall_density
  std::uint32_t* id = nullptr;
  // Fluid neighbours of each particle as density() found them, kept for the step's later
  // passes: the k-th of particle i at nbr[i * nbr_si + k * nbr_sk], k < nbr_n[i]; nbr_n[i] =
  // -1 where nbr_cap or more were found (those particles scan the grid); on the host the
  // list is padded with i up to listed_end, where the tank's listed samples begin. nbr =
  // nullptr: no list. The host lays a particle's list out contiguously (nbr_sk = 1, cache lines), a
  // device interleaves the lists (nbr_si = 1, coalesced reads of neighbouring threads); see
  // FluidBuffers::view.
  std::uint32_t* nbr = nullptr;
  int* nbr_n = nullptr;
  int nbr_cap = 0;
  std::size_t nbr_si = 0, nbr_sk = 0;
  // The host packs the lists one after another (FluidBuffers: a pool sized by their lengths,
  // not nbr_cap a particle): particle i's begins at nbr[nbr_at[i]]; nullptr: at i * nbr_si.
  std::uint32_t* nbr_at = nullptr;
  // DFSPH on the host: beside each listed fluid neighbour, the kernel's gradient factor of the
  // pair (Kernel::gscale, grad W_ij = rij * factor), stored by density() from the positions
  // the step's later passes see too, which then read it instead of evaluating the kernel
  // again; nullptr: not stored.
  Real* nbr_gs = nullptr;
  // The positions again as three planes of planes_stride Reals (x, y, z), for the list build's
  // scan (collect_neighbors), with seven readable Reals after the z plane's n; nullptr: not
  // there.
  Real* planes = nullptr;
  std::size_t planes_stride = 0;
  // WCSPH on the host: what the forces read of a neighbour j, four Reals a particle in two
  // records, (x_j, p_j / rho_j^2) and (v_j, m / rho_j) (pair_records), so that a group of
  // eight neighbours is two gathers of 16 bytes each a neighbour; nullptr: read from x, v, p
  // and rho (FluidNeighbour).
  Real* rec_x = nullptr;
  Real* rec_v = nullptr;
  // Where the fluid's supports end this step (fluid_reach): no particle is within reach of a
  // point outside [reach_lo, reach_hi]. reached = 0: not known, every point may be.
  int reached = 0;
  Vec3 reach_lo, reach_hi;
};

// Where particle i's list begins in f.nbr (FluidView::nbr_at).
SPHFEM_HD std::size_t list_start(const FluidView& f, int i) {
  return f.nbr_at ? std::size_t(f.nbr_at[i]) : std::size_t(i) * f.nbr_si;
}

// f(j, rij, r2) for each fluid neighbour j of particle i (at xi = f.x[i]), from the list
// density() stored or from the grid. The list holds the grid's neighbours in the grid's order
// and rij, r2 are computed alike, so the sums are those of a grid scan (up to the compiler's
// contraction of multiply-adds); the passes after density() skip the scan of about six
// candidates per neighbour: DFSPH's dozen passes a step became 2.4x faster.
template <class F>
SPHFEM_HD void for_fluid_neighbors(const FluidView& f, const GridView& g, int i, const Vec3& xi,
                                   Real h2, F&& fn) {
  const int n = f.nbr ? f.nbr_n[i] : -1;
  if (n < 0) {
    for_neighbors(g, f.x, xi, h2, fn);
    return;
  }
  const std::uint32_t* list = f.nbr + list_start(f, i);
  for (int k = 0; k < n; ++k) {
    const std::uint32_t j = list[std::size_t(k) * f.nbr_sk];
    const Vec3 rij = xi - f.x[j];
    fn(j, rij, norm2(rij));
  }
}

// Where a listed particle's fluid neighbours end and its tank samples begin (kTankListed):
// the host pads its contiguous lists with the particle itself to whole groups of eight, which
// its vector lanes read without a tail (lanes::sum_pairs); a device list is not padded.
SPHFEM_HD int listed_end(const FluidView& f, int n) { return f.nbr_sk == 1 ? (n + 7) & ~7 : n; }

// a[j]: what a pair term reads at its neighbour j, written alike for the host's lanes
// (lanes::at, eight j at once).
SPHFEM_HD Vec3 at(const Vec3* a, std::uint32_t j) { return a[j]; }
SPHFEM_HD Real at(const Real* a, std::uint32_t j) { return a[j]; }
// The per-pair choice of ?: for a 3-vector term (lanes::select per lane).
SPHFEM_HD Vec3 select(bool m, const Vec3& a, const Vec3& b) { return m ? a : b; }

// Two pair sums at once (nested for more): a term returns both(a, b).
template <class A, class B>
struct Both {
  A a{};
  B b{};
  SPHFEM_HD Both& operator+=(const Both& o) {
    a += o.a;
    b += o.b;
    return *this;
  }
};
template <class A, class B>
SPHFEM_HD Both<A, B> both(const A& a, const B& b) {
  return {a, b};
}

#if SPHFEM_PAIR_LANES
// Both in the host's lanes (lanes::sum_pairs): its parts summed and reduced alike. Inlined
// like the lanes' own operators: g++ left the reduction of the density pass's sums as a call
// that took its vectors through memory.
template <class A, class B>
SPHFEM_LANE Both<A, B> operator+(const Both<A, B>& x, const Both<A, B>& y) {
  return {x.a + y.a, x.b + y.b};
}
template <class A, class B>
SPHFEM_LANE auto total(const Both<A, B>& x) {
  using lanes::total;
  return both(total(x.a), total(x.b));
}
template <class A, class B>
SPHFEM_LANE Both<A, B> select(lanes::I8 m, const Both<A, B>& x, const Both<A, B>& y) {
  using lanes::select;
  return {select(m, x.a, y.a), select(m, x.b, y.b)};
}
}  // namespace sphfem::stages
namespace sphfem::lanes {
template <class A, class B>
struct Of<stages::Both<A, B>> {
  using type = stages::Both<typename Of<A>::type, typename Of<B>::type>;
};
}  // namespace sphfem::lanes
namespace sphfem::stages {
#endif

// How many particles ahead a host pass asks for a list (lanes::prefetch_list): 1, 2, 4 and 8
// were within the noise of each other, all ahead of none.
constexpr int kListAhead = 4;

// The sum over the fluid neighbours j of particle i of term(j, rij, r2, W_ij, grad W_ij) (W
// only when WithW, else 0); T is a Real, a Vec3 or a Both of them, and the term reads its
// arrays through at().
// The host sums a listed particle's pairs in vector lanes (lanes::sum_pairs: the term is
// generic and is evaluated there on eight pairs at once); a device, or a particle without a
// list, sums them one by one in the list's order. Where the host keeps the pairs' kernel
// factors (FluidView::nbr_gs), StoreFactors stores them (the density pass), and a sum without
// W reads them.
template <bool WithW, class T, bool StoreFactors = false, class Term>
SPHFEM_HD_INLINE T sum_fluid_pairs(const FluidView& f, const GridView& g, const Kernel& K, int i,
                                   const Vec3& xi, Real h2, Term&& term) {
#if SPHFEM_PAIR_LANES
  const int n = f.nbr ? f.nbr_n[i] : -1;
  if (n >= 0 && f.nbr_sk == 1) {
    const std::size_t at = list_start(f, i);
    const std::uint32_t* list = f.nbr + at;
    Real* gs = f.nbr_gs ? f.nbr_gs + at : nullptr;
    if (i + kListAhead < f.n) {
      const std::size_t ahead = list_start(f, i + kListAhead);
      lanes::prefetch_list(f.nbr + ahead);
      if (gs && !StoreFactors) lanes::prefetch_list(f.nbr_gs + ahead);
    }
    if (!WithW && gs && !StoreFactors)
      return lanes::sum_pairs_stored<T>(list, gs, n, f.x, xi, term);
    if (K.kind == 0)
      return lanes::sum_pairs<WithW, T, StoreFactors>(K.cubic, list, n, lanes::ByIndex{f.x}, xi,
                                                      term, gs);
    return lanes::sum_pairs<WithW, T, StoreFactors>(K.wendland, list, n, lanes::ByIndex{f.x}, xi,
                                                    term, gs);
  }
#endif
  T sum{};
  for_fluid_neighbors(f, g, i, xi, h2, [&](std::uint32_t j, const Vec3& r, Real r2) {
    const Real rr = std::sqrt(r2);
    sum += term(j, r, r2, WithW ? K.W(rr) : Real(0), K.grad(r, rr));
  });
  return sum;
}

// What a fluid pair's term reads of its neighbour j besides its arrays (at(a, j)): v_j,
// p_j / rho_j^2 and m / rho_j, for one j or, in the host's lanes, eight.
template <class J, class V, class R>
struct FluidNeighbour {
  J j;
  V v;
  R p_rho2, m_rho;
};

// FluidNeighbour of j from the arrays; pair_records stores the same values (the same bits).
template <class J>
SPHFEM_HD_INLINE auto fluid_neighbour(const SphParams& P, const FluidView& f, const J& j) {
  const auto rhoj = at(f.rho, j);
  using R = std::decay_t<decltype(rhoj)>;
  using V = std::decay_t<decltype(at(f.v, j))>;
  return FluidNeighbour<J, V, R>{j, at(f.v, j), at(f.p, j) / (rhoj * rhoj), P.mass / rhoj};
}

// FluidView's records: (x_i, p_i / rho_i^2) and (v_i, m / rho_i) for the forces' pairs.
template <class Exec>
void pair_records(Exec& ex, const SphParams P, FluidView f) {
  parallel_for_light(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const FluidNeighbour<std::uint32_t, Vec3, Real> q = fluid_neighbour(P, f, std::uint32_t(i));
    const Vec3 x = f.x[i];
    Real* rx = f.rec_x + 4 * std::size_t(i);
    Real* rv = f.rec_v + 4 * std::size_t(i);
    rx[0] = x.x, rx[1] = x.y, rx[2] = x.z, rx[3] = q.p_rho2;
    rv[0] = q.v.x, rv[1] = q.v.y, rv[2] = q.v.z, rv[3] = q.m_rho;
  });
}

#if SPHFEM_PAIR_LANES
namespace lanes_records {
// Eight neighbours from FluidView's records (lanes::ByIndex's form).
struct Gather {
  using Of = FluidNeighbour<lanes::J8, lanes::V8, lanes::R8>;
  const Real* rec_x;
  const Real* rec_v;
  SPHFEM_LANE void operator()(const lanes::J8& j, lanes::V8& xj, Of& of) const {
    lanes::gather4(rec_x, 4, j, xj.x, xj.y, xj.z, of.p_rho2);
    lanes::gather4(rec_v, 4, j, of.v.x, of.v.y, of.v.z, of.m_rho);
    of.j = j;
  }
};
}  // namespace lanes_records
#endif

// sum_fluid_pairs with a term that takes FluidNeighbour instead of j: the host's lanes read
// the records where FluidView has them, any other path the arrays; the same bits either way.
template <bool WithW, class T, class Term>
SPHFEM_HD_INLINE T sum_fluid_neighbours(const SphParams& P, const FluidView& f, const GridView& g,
                                        int i, const Vec3& xi, Term&& term) {
#if SPHFEM_PAIR_LANES
  const int n = f.nbr && f.rec_x ? f.nbr_n[i] : -1;
  if (n >= 0 && f.nbr_sk == 1) {
    const std::uint32_t* list = f.nbr + list_start(f, i);
    if (i + kListAhead < f.n) lanes::prefetch_list(f.nbr + list_start(f, i + kListAhead));
    const lanes_records::Gather gather{f.rec_x, f.rec_v};
    if (P.kernel.kind == 0)
      return lanes::sum_pairs<WithW, T, false>(P.kernel.cubic, list, n, gather, xi, term, nullptr);
    return lanes::sum_pairs<WithW, T, false>(P.kernel.wendland, list, n, gather, xi, term, nullptr);
  }
#endif
  return sum_fluid_pairs<WithW, T>(
      f, g, P.kernel, i, xi, P.h2,
      [&](const auto& j, const auto& r, const auto& r2, const auto& wk, const auto& gw)
          SPHFEM_TERM { return term(fluid_neighbour(P, f, j), r, r2, wk, gw); });
}

// Bits of FluidView::flags, set by density() for the step's later passes.
constexpr int kFullSupport = 1;  // DFSPH: fluid and wall samples nearly fill the support
constexpr int kNearTank = 2;     // some of the tank's samples are in reach
// flags >> kTankListed: 1 + the number of the tank's samples in reach that density() listed
// from listed_end on, in the scan's order; 0: not listed (scan the grid).
constexpr int kTankListed = 8;

// Wall samples: the tank's (static) or those on body surfaces (moving).
struct BoundaryView {
  int n = 0;
  const Vec3* x = nullptr;
  const Real* psi = nullptr;
  const Real* rest = nullptr;    // density of the walls alone at the sample (wall_rest)
  const int* nb_rest = nullptr;  // wall samples in reach of the sample, itself included
  Real* pw = nullptr;            // WCSPH: p_b / rho_b^2 (wall_pressure), 0 away from fluid
  Real* rho = nullptr;           // DFSPH: rest + m sum_f W_bf
  Real* alpha = nullptr;         // DFSPH: inverse diagonal (wall_density), 0 without fluid
  int* full = nullptr;           // DFSPH: fluid and wall samples nearly fill the support
  Real* kappa = nullptr;         // DFSPH stiffness of the current sweep
  Real* kappa_sum = nullptr;     // DFSPH stiffness summed over the current solve
  Real* warm_div = nullptr;      // DFSPH warm starts (wall_density)
  Real* warm_dens = nullptr;
  const Vec3* v = nullptr;  // velocity of moving samples; nullptr: at rest
  // The host under DFSPH, from wall_density until the fluid moves (WallLists): the samples
  // with fluid in reach, ascending (n_listed); where each one's fluid neighbours lie in
  // fluid_list, in the grid scan's order; and per block of kSumBlock samples where its listed
  // ones begin (blocks + 1 entries). nullptr: the passes scan the fluid's grid.
  const std::uint32_t* listed = nullptr;
  const std::uint32_t* listed_at = nullptr;  // [listed_at[p], listed_end[p]) in fluid_list
  const std::uint32_t* listed_end = nullptr;
  const std::uint32_t* fluid_list = nullptr;
  const std::uint32_t* block_first = nullptr;
  int n_listed = 0;
  GridView grid;
  // No sample is within reach of a point strictly inside (quiet_lo, quiet_hi): for the tank,
  // the domain shrunk by the support (its samples all lie beyond its faces). Empty by default.
  Vec3 quiet_lo, quiet_hi;
};

// A point with no sample of b within reach (BoundaryView::quiet_lo): the tank's scan skipped
// for the particles away from its walls, with the same samples (none) found.
SPHFEM_HD bool in_quiet(const BoundaryView& b, const Vec3& x) {
  return x.x > b.quiet_lo.x && x.x < b.quiet_hi.x && x.y > b.quiet_lo.y && x.y < b.quiet_hi.y &&
         x.z > b.quiet_lo.z && x.z < b.quiet_hi.z;
}

// The quiet box of samples that all lie beyond the faces of [lo, hi] (the tank's, at x[0..n)):
// [lo, hi] shrunk by the support and a thousandth of it, or an empty box when a sample lies
// inside. Host code, once per model.
inline void quiet_box(const Vec3* x, int n, const Vec3& lo, const Vec3& hi, Real h,
                      BoundaryView& b) {
  bool clear = true;
  for (int k = 0; k < n && clear; ++k) {
    const Vec3 q = x[k];
    clear = !(q.x > lo.x && q.x < hi.x && q.y > lo.y && q.y < hi.y && q.z > lo.z && q.z < hi.z);
  }
  const Real reach = h * Real(1.001);
  b.quiet_lo = clear ? lo + Vec3(reach, reach, reach) : Vec3();
  b.quiet_hi = clear ? hi - Vec3(reach, reach, reach) : Vec3();
}

// A point with no fluid particle within reach (FluidView::reach_lo): a wall sample far from the
// water skips its scan of the fluid's grid, with the same particles (none) found.
SPHFEM_HD bool out_of_reach(const FluidView& f, const Vec3& x) {
  return f.reached && (x.x < f.reach_lo.x || x.x > f.reach_hi.x || x.y < f.reach_lo.y ||
                       x.y > f.reach_hi.y || x.z < f.reach_lo.z || x.z > f.reach_hi.z);
}

// The closest body surface of each particle (SurfaceProximity in sph/solver.h).
struct SurfaceView {
  const Real* dist = nullptr;  // nullptr: no surfaces
  const Vec3* normal = nullptr;
  const Vec3* vel = nullptr;   // nullptr: at rest
  Vec3* dv = nullptr;          // nullptr: not recorded; else the surface's pushes are added here
  const Real* slip = nullptr;  // per particle, its surface's C_s; nullptr: free slip
  HalfSpaceView half;
};

// Everything that bounds the fluid besides the last-resort box.
struct Walls {
  BoundaryView fixed;   // the tank's samples
  BoundaryView moving;  // samples on body surfaces, placed every step (n = 0: none)
  SurfaceView surface;  // the space beyond each particle's closest surface
};

// f(b, j, rij, r2) for the tank's samples j in reach of fluid particle i, by its flags of
// density(): from the particle's list where density() stored them after the fluid neighbours
// (the scan's samples in the scan's order; the particles by the walls then skip a scan of
// about 200 candidates a pass), else from the tank's grid where some are in reach (kNearTank;
// the others skip the scan, nine empty ranges a particle and pass).
template <class F>
SPHFEM_HD void for_tank_samples(const FluidView& fl, int i, int flags, const Walls& w,
                                const Vec3& xi, Real h2, F&& f) {
  const int listed = flags >> kTankListed;
  if (listed > 0) {
    const std::uint32_t* list = fl.nbr + list_start(fl, i);
    const int first = listed_end(fl, fl.nbr_n[i]);
    for (int k = first; k < first + listed - 1; ++k) {
      const std::uint32_t j = list[std::size_t(k) * fl.nbr_sk];
      const Vec3 rij = xi - w.fixed.x[j];
      f(w.fixed, j, rij, norm2(rij));
    }
  } else if (flags & kNearTank) {
    for_neighbors(w.fixed.grid, w.fixed.x, xi, h2,
                  [&](std::uint32_t j, const Vec3& r, Real r2) { f(w.fixed, j, r, r2); });
  }
}

// f(b, j, rij, r2) for the samples j of both sets within reach of fluid particle i, the tank's
// first, found by these flags.
template <class F>
SPHFEM_HD void for_wall_samples(const FluidView& fl, int i, int flags, const Walls& w,
                                const Vec3& xi, Real h2, F&& f) {
  for_tank_samples(fl, i, flags, w, xi, h2, f);
  for_neighbors(w.moving.grid, w.moving.x, xi, h2,
                [&](std::uint32_t j, const Vec3& r, Real r2) { f(w.moving, j, r, r2); });
}

// The same after density(), by the particle's flags.
template <class F>
SPHFEM_HD void for_wall_samples(const FluidView& fl, int i, const Walls& w, const Vec3& xi, Real h2,
                                F&& f) {
  for_wall_samples(fl, i, fl.flags ? fl.flags[i] : kNearTank, w, xi, h2, f);
}

// f(b, j, grad) for the wall samples of for_wall_samples, in its order, grad() giving grad W_ij.
// The tank's samples density() listed with their kernel factors (DFSPH on the host) take it
// from there, rij times the factor: Kernel::grad's bits, without its square root and
// polynomial in each of the step's six residual sweeps (dfsph_source). dfsph_apply keeps
// evaluating the kernel: with the stored factors its velocities came out differently rounded
// (not found why; the factors themselves are equal to the bit). The listed samples have a
// loop of their own rather than a branch in for_wall_samples' callback: that form also
// rounded some residuals differently (g++ contracting into fused multiply-adds elsewhere).
// SphCells.StoredTankFactorsGiveTheKernelsBits catches either.
template <class F>
SPHFEM_HD void for_wall_grads(const FluidView& fl, int i, const Walls& w, const Vec3& xi,
                              const Kernel& K, Real h2, F&& f) {
  const int flags = fl.flags ? fl.flags[i] : kNearTank;
  const int listed = flags >> kTankListed;
  auto computed = [&](const BoundaryView& b, std::uint32_t j, const Vec3& r, Real r2) {
    f(b, j, [&] { return K.grad(r, std::sqrt(r2)); });
  };
  if (listed > 0 && fl.nbr_gs) {
    const std::size_t at = list_start(fl, i);
    const std::uint32_t* list = fl.nbr + at;
    const Real* gs = fl.nbr_gs + at;
    const int first = listed_end(fl, fl.nbr_n[i]);
    for (int k = first; k < first + listed - 1; ++k) {
      const std::uint32_t j = list[k];
      const Vec3 rij = xi - w.fixed.x[j];
      const Real s = gs[k];
      f(w.fixed, j, [&] { return rij * s; });
    }
    for_neighbors(w.moving.grid, w.moving.x, xi, h2,
                  [&](std::uint32_t j, const Vec3& r, Real r2) { computed(w.moving, j, r, r2); });
    return;
  }
  for_wall_samples(fl, i, flags, w, xi, h2, computed);
}

// Velocity of particle i relative to wall sample j.
SPHFEM_HD Vec3 relative_to(const BoundaryView& b, std::uint32_t j, const Vec3& vi) {
  return b.v ? vi - b.v[j] : vi;
}

// The surface beyond particle i: Phi, its slope A = -dPhi/dd, a (sph/surface_density.h), the
// normal toward the particle, the surface velocity and q = d / h. False when out of reach.
struct NearSurface {
  Real phi = 0, slope = 0, normal2 = 0, q = 0;
  Vec3 n, vs;
  Real slip = 1;
  Real phi0 = 0;  // Phi at the surface itself
};

SPHFEM_HD bool near_surface(const SurfaceView& s, int i, NearSurface& o) {
  if (!s.dist) return false;
  const Vec3 n = s.normal[i];
  if (n.x == Real(0) && n.y == Real(0) && n.z == Real(0)) return false;
  const Real d = s.dist[i];
  s.half.lookup(d, o.phi, o.slope, o.normal2);
  if (!(o.phi > Real(0))) return false;
  o.q = d * s.half.inv_h;
  o.n = n;
  o.vs = s.vel ? s.vel[i] : Vec3();
  o.slip = s.slip ? s.slip[i] : Real(1);
  Real slope0, normal0;
  s.half.lookup(Real(0), o.phi0, slope0, normal0);
  return true;
}

// The surface's tangential coupling (its slip coefficient C_s, as in the ray-traced exchange's
// law u_t+ = C_s u_t): over one step the particle's velocity relative to the surface loses
// (1 - C_s) of its tangential part, weighted by the share Phi / Phi(0) of the kernel the
// surface fills (1 at the surface, 0 a support away). As an acceleration for the kick:
// -(1 - C_s) (Phi / Phi(0)) u_t / dt. It never overshoots (the weight is at most 1), and the
// opposite impulse goes to the surface with the pressure's (SurfaceProximity::dv).
SPHFEM_HD Vec3 surface_drag(const NearSurface& s, const Vec3& vi, Real inv_dt) {
  if (!(s.slip < Real(1)) || !(s.phi0 > Real(0))) return Vec3();
  const Vec3 rel = vi - s.vs;
  const Vec3 rel_t = rel - s.n * dot(rel, s.n);
  Real w = s.phi / s.phi0;
  w = w > Real(1) ? Real(1) : w;
  return rel_t * (-(Real(1) - s.slip) * w * inv_dt);
}

// Neighbours, fluid and wall, of a particle inside the fluid: two thirds of a full lattice
// neighbourhood (the free-surface test of Bender & Koschier's divergence solve). Wall samples
// count, or particles along a wall edge (12 fluid neighbours) would count as free surface.
SPHFEM_HD int full_neighborhood(const SphParams& P) { return (P.full_neighbors * 2) / 3; }

// Cell of every particle, and the identity permutation for the sort.
template <class Exec>
void cell_keys(Exec& ex, const GridView g, const Vec3* x, std::uint32_t* keys, std::uint32_t* perm,
               int n) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) {
    keys[i] = g.cell(x[i]);
    perm[i] = std::uint32_t(i);
  });
}

// start[c] = first index with key >= c, for sorted keys < cells (start[cells] = n, and an
// empty cell starts where the next non-empty one does). Parallel over blocks of cells: a
// binary search for the block's first cell, then a merge walk through the block's particles.
// No thread walks a long run of empty cells, as one thread per particle filling the gap
// before it did (up to 1e5 cells on one GPU thread, with the air above a tank's water). A
// device takes one cell a thread (the search alone); the host blocks of kHostCellBlock
// cells, O(cells + n) in all.
constexpr int kHostCellBlock = 1024;

template <class Exec>
void cell_starts(Exec& ex, const std::uint32_t* keys, std::uint32_t* start, int n, int cells) {
  constexpr int B = Exec::kSpace == MemSpace::Device ? 1 : kHostCellBlock;
  const int total = cells + 1;
  parallel_for_light(ex, (total + B - 1) / B, [=] SPHFEM_LAMBDA(int b) {
    const std::uint32_t c0 = std::uint32_t(b) * std::uint32_t(B);
    const std::uint32_t c1 = c0 + B < std::uint32_t(total) ? c0 + B : std::uint32_t(total);
    // lower_bound(keys, keys + n, c0)
    std::uint32_t lo = 0, hi = std::uint32_t(n);
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (keys[mid] < c0)
        lo = mid + 1;
      else
        hi = mid;
    }
    for (std::uint32_t c = c0; c < c1; ++c) {
      while (lo < std::uint32_t(n) && keys[lo] < c) ++lo;
      start[c] = lo;
    }
  });
}

// The positions as three planes (FluidView::planes).
template <class Exec>
void position_planes(Exec& ex, const FluidView f) {
  parallel_for_light(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 x = f.x[i];
    f.planes[i] = x.x;
    f.planes[f.planes_stride + i] = x.y;
    f.planes[2 * f.planes_stride + i] = x.z;
  });
}

template <class Exec, class T>
void gather(Exec& ex, const T* src, T* dst, const std::uint32_t* perm, int n) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) { dst[i] = src[perm[i]]; });
}

// The box of the fluid's supports: its particles' bounds widened by the support and a
// thousandth of it, so that a point outside is beyond reach of every particle in float
// arithmetic too (out_of_reach).
template <class Exec>
void fluid_reach(Exec& ex, const SphParams P, FluidView& f) {
  const FluidView c = f;
  const Real big = Real(3e38);
  Real lo[3], hi[3];
  if constexpr (Exec::kSpace == MemSpace::Host) {
    // The six bounds in one pass over the positions (the same values: a bound is exact).
    reduce_bounds(ex, c.n, c.x, lo, hi);
  } else {
    for (int a = 0; a < 3; ++a) {
      lo[a] = -reduce_max(ex, c.n, -big, [=] SPHFEM_LAMBDA(int i) -> Real { return -c.x[i][a]; });
      hi[a] = reduce_max(ex, c.n, -big, [=] SPHFEM_LAMBDA(int i) -> Real { return c.x[i][a]; });
    }
  }
  const Real reach = P.h * Real(1.001);
  f.reach_lo = Vec3(lo[0] - reach, lo[1] - reach, lo[2] - reach);
  f.reach_hi = Vec3(hi[0] + reach, hi[1] + reach, hi[2] + reach);
  f.reached = c.n > 0 && hi[0] >= lo[0] && hi[1] >= lo[1] && hi[2] >= lo[2] ? 1 : 0;
}

// The fluid pair's term of a sweep's velocity change (dfsph_apply): V (kappa_i + kappa_j)
// grad W_ij, kappa the sweep's stiffness (accelerations() sums it for the density solve's
// warm-start sweep).
template <class J, class G>
SPHFEM_HD_INLINE auto dfsph_pair_term(const SphParams& P, const Real* kappa, Real ki, const J& j,
                                      const G& grad) {
  return grad * (P.volume * (ki + at(kappa, j)));
}

// The fluid pairs' sum of dfsph_pair_term for particle i at xi with stiffness kappa.
SPHFEM_HD_INLINE Vec3 dfsph_fluid_dv(const SphParams& P, const FluidView& f, const GridView& g,
                                     const Real* kappa, int i, const Vec3& xi) {
  const Real ki = kappa[i];
  return sum_fluid_pairs<false, Vec3>(
      f, g, P.kernel, i, xi, P.h2,
      [&](const auto& j, const auto&, const auto&, const auto&, const auto& gw)
          SPHFEM_TERM { return dfsph_pair_term(P, kappa, ki, j, gw); });
}

// Density (and the DFSPH factor): rho_i = m sum_j W_ij + sum_b psi_b W_ib. WCSPH also sets
// the pressure from the state equation; DFSPH leaves p to its pressure solve.
//
// Near a surface without samples, rho_i += rho0 Phi(d) (the half-space beyond it at rest
// density); for DFSPH its gradient, Phi'(d) n = -A n, joins the wall gradient as the
// integral of the samples' psi_b / rho0 grad W would, and the share of the support it fills
// counts as wall neighbours.
//
// DFSPH (with_alpha) also takes the fluid pairs' sums of the density solve's warm-start filter,
// sum_j W_ij and sum_j W_ij warm_dens_j, into warm (dfsph_smooth_warm's fluid_w, fluid_kw): the
// filter has no loop over the pairs of its own.
//
// div_dv (DFSPH, or nullptr): also the fluid pairs of the divergence solve's warm-start sweep,
// sum_j V (w_i + w_j) grad W_ij with w = warm_div (dfsph_apply's term, the same bits), for that
// sweep to apply instead of a pass over the pairs of its own.
struct WarmSums {
  Real* dens_w = nullptr;
  Real* dens_kw = nullptr;
  Vec3* div_dv = nullptr;
};

// The most list entries (nbr_cap and its padding) whose squared distances density_at stages.
constexpr int kStagedPairs = 136;

// density() of particle i.
SPHFEM_HD_INLINE void density_at(const SphParams& P, const FluidView& f, const GridView& g,
                                 const Walls& w, bool with_alpha, const WarmSums& warm, int i) {
  const Vec3 xi = f.x[i];
  Real sum = 0, grad2 = 0;
  Vec3 gsum, gwall, gwall_v;
  int walls = 0;
  // The list first, in the grid's order (or into a scratch slot without a list); the last
  // slot takes the overflow, which nbr_n = -1 then marks unused.
  std::uint32_t scratch;
  std::uint32_t* list = f.nbr ? f.nbr + list_start(f, i) : &scratch;
  const std::size_t step = f.nbr ? f.nbr_sk : 0;
  const int last = f.nbr ? f.nbr_cap - 1 : 0;
#if SPHFEM_PAIR_LANES
  if (f.nbr && step == 1 && i + kListAhead < f.n)
    lanes::prefetch_list<true>(list + kListAhead * f.nbr_si);
#endif
#if SPHFEM_PAIR_LANES && SPHFEM_GRID_PACK
  // WCSPH's density sums W of the squared distances the scan staged: the x_j are not read
  // again (density stage 9 % faster at one thread, the same bits).
  alignas(32) Real dist2[kStagedPairs];
  const bool staged =
      !with_alpha && f.nbr && f.planes && step == 1 && f.nbr_cap <= kStagedPairs - 8;
#else
  Real* const dist2 = nullptr;
  const bool staged = false;
#endif
  const int count = collect_neighbors(g, f.x, xi, P.h2, list, step, last, 0, f.planes,
                                      f.planes_stride, staged ? dist2 : nullptr);
  // The padding up to listed_end fits, as nbr_cap is a multiple of eight (FluidBuffers).
  const bool kept = f.nbr && count <= last;
  const int end = kept ? listed_end(f, count) : count;
  if (f.nbr) f.nbr_n[i] = kept ? count : -1;
  for (int k = count; k < end; ++k) list[k] = std::uint32_t(i);
  if (with_alpha) {
    // W, V grad W and its square, and the warm-start filter's W warm_dens_j.
    auto pair = [&](const auto& j, const auto& wk, const auto& grad) SPHFEM_TERM {
      const auto gw = grad * P.volume;
      return both(both(wk, both(gw, norm2(gw))), wk * at(f.warm_dens, j));
    };
    using Sums = Both<Both<Real, Both<Vec3, Real>>, Real>;
    Sums t;
    // Summed with the rest only in the host's lanes, whose sums are the sweep's to the bit; a
    // pair at a time the sweep's own sum (g++ contracts the two into fused multiply-adds in
    // different places).
    if (warm.div_dv && SPHFEM_PAIR_LANES && kept) {
      const Real wi = f.warm_div[i];
      const auto td = sum_fluid_pairs<true, Both<Sums, Vec3>, true>(
          f, g, P.kernel, i, xi, P.h2,
          [&](const auto& j, const auto&, const auto&, const auto& wk, const auto& grad)
              SPHFEM_TERM {
                return both(pair(j, wk, grad), dfsph_pair_term(P, f.warm_div, wi, j, grad));
              });
      t = td.a;
      warm.div_dv[i] = td.b;
    } else {
      t = sum_fluid_pairs<true, Sums, true>(
          f, g, P.kernel, i, xi, P.h2,
          [&](const auto& j, const auto&, const auto&, const auto& wk, const auto& grad)
              SPHFEM_TERM { return pair(j, wk, grad); });
      if (warm.div_dv) warm.div_dv[i] = dfsph_fluid_dv(P, f, g, f.warm_div, i, xi);
    }
    const auto& s = t.a;
    warm.dens_w[i] = s.a;
    warm.dens_kw[i] = t.b;
    sum = s.a;
    gsum = s.b.a;
    grad2 = s.b.b;
  } else {
#if SPHFEM_PAIR_LANES && SPHFEM_GRID_PACK
    if (staged && kept)
      sum = P.kernel.kind == 0 ? lanes::sum_w_staged(P.kernel.cubic, dist2, count)
                               : lanes::sum_w_staged(P.kernel.wendland, dist2, count);
    else
#endif
      sum = sum_fluid_pairs<true, Real>(f, g, P.kernel, i, xi, P.h2,
                                        [&](const auto&, const auto&, const auto&, const auto& wk,
                                            const auto&) SPHFEM_TERM { return wk; });
  }
  Real rho = P.mass * sum;
  // The tank's samples in reach, listed after the fluid's where the list has room.
  const int near = in_quiet(w.fixed, xi) ? 0 : kNearTank;
  int listed = 0;
  if (kept && near && end <= last) {
    const int filled = collect_neighbors(w.fixed.grid, w.fixed.x, xi, P.h2, list, step, last, end);
    listed = filled <= last ? 1 + filled - end : 0;
  }
  int tank = 0;
  // DFSPH on the host: the listed tank samples' gradient factors beside them, as the fluid
  // pairs' (for_wall_grads).
  Real* tank_gs =
      with_alpha && listed > 0 && f.nbr_gs ? f.nbr_gs + list_start(f, i) + end : nullptr;
  for_wall_samples(f, i, (listed << kTankListed) | near, w, xi, P.h2,
                   [&](const BoundaryView& b, std::uint32_t j, const Vec3& r, Real r2) {
                     const Real rr = std::sqrt(r2);
                     rho += b.psi[j] * P.kernel.W(rr);
                     ++walls;
                     const bool fixed = &b == &w.fixed;
                     if (with_alpha) {
                       const Real gs = P.kernel.gscale(rr);
                       if (tank_gs && fixed) tank_gs[tank] = gs;
                       const Vec3 gw = r * gs;  // Kernel::grad
                       gwall += gw * (b.psi[j] / P.rho0);
                       gwall_v += gw * P.volume;
                     }
                     tank += fixed ? 1 : 0;
                   });
  NearSurface s;
  if (near_surface(w.surface, i, s)) {
    rho += P.rho0 * s.phi;
    walls += int(Real(P.full_neighbors) * half_space_volume(s.q) + Real(0.5));
    if (with_alpha) gwall -= s.n * s.slope;
  }
  f.rho[i] = rho;
  f.nb[i] = count;
  int flags = (tank > 0 ? kNearTank : 0) | (listed << kTankListed);
  if (!with_alpha) {
    const Real p = P.stiffness * (rho / P.rho0 - Real(1));
    f.p[i] = p > Real(0) ? p : Real(0);
  } else {
    // Diagonal of the pressure system: kappa_i moves i by -dt (gsum + gwall) kappa_i and each
    // fluid neighbour j by dt V grad W_ij kappa_i; the walls carry their own stiffness.
    const Real s = norm2(gsum + gwall) + grad2;
    f.alpha[i] = s > Real(1e-6) ? Real(1) / s : Real(0);
    flags |= count + walls >= full_neighborhood(P) ? kFullSupport : 0;
    f.gwall[i] = gwall_v;
  }
  f.flags[i] = flags;
}

// density() of every particle, its list where list_start puts it without nbr_at (room for
// nbr_cap a particle); the host's packed lists are written by density_packed.
template <class Exec>
void density(Exec& ex, const SphParams P, FluidView f, const GridView g, const Walls w,
             bool with_alpha, const WarmSums warm = WarmSums()) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) { density_at(P, f, g, w, with_alpha, warm, i); });
}

// Entries of particle i's list after density(): its fluid neighbours up to listed_end and the
// tank's samples listed after them; 0 without a list.
SPHFEM_HD int list_entries(const FluidView& f, int i) {
  const int n = f.nbr_n[i];
  if (n < 0) return 0;
  const int tank = f.flags[i] >> kTankListed;
  return listed_end(f, n) + (tank > 0 ? tank - 1 : 0);
}

// Particles a host thread lists at a time in density_packed.
constexpr int kPackBlock = 64;

// A host thread's blocks of lists in density_packed: two, one being listed while the one
// before waits for its place in the pool to be fetched.
struct PackStage {
  std::vector<std::uint32_t> nbr[2];
  std::vector<Real> gs[2];
  int next = 0;
  std::size_t at = 0, size = 0;  // where the waiting block goes, its entries (0: none)
  // Moves the waiting block to the pool.
  void flush(const FluidView& f) {
    const int w = next ^ 1;
    std::copy(nbr[w].data(), nbr[w].data() + size, f.nbr + at);
    if (f.nbr_gs) std::copy(gs[w].data(), gs[w].data() + size, f.nbr_gs + at);
    size = 0;
  }
};

// density() with the host's lists packed into a pool of `room` entries (FluidView::nbr_at):
// a thread takes kPackBlock particles and lists and sums them one after another in a block of
// its own (hot in its cache; each list has room for nbr_cap entries where it begins), takes
// the block's place at the pool's next free entry and asks for those lines, and moves the
// block there once it has listed the next one (a copy at once waited on every line). Where a
// block goes depends on which thread came first, what a list holds does not, so neither do
// the sums. Returns the entries all lists took: more than room, and some lists were not kept
// (the caller grows the pool and runs it again).
template <class Exec>
std::size_t density_packed(Exec& ex, const SphParams P, FluidView f, const GridView g,
                           const Walls w, bool with_alpha, std::size_t room,
                           const WarmSums warm = WarmSums()) {
  std::atomic<std::size_t> used{0};
  thread_local PackStage stage;
  const std::size_t block = std::size_t(f.nbr_cap) * kPackBlock;
  parallel_blocks(
      ex, f.n, kPackBlock,
      [&](int b0, int b1) {
        PackStage& st = stage;
        const int k = st.next;
        st.nbr[k].resize(block);
        FluidView s = f;
        s.n = 0;  // nothing to read ahead: the block's lists are in the cache
        s.nbr = st.nbr[k].data();
        if (f.nbr_gs) {
          st.gs[k].resize(block);
          s.nbr_gs = st.gs[k].data();
        }
        std::size_t total = 0;
        for (int i = b0; i < b1; ++i) {
          f.nbr_at[i] = std::uint32_t(total);
          density_at(P, s, g, w, with_alpha, warm, i);
          total += std::size_t(list_entries(f, i));
        }
        if (st.size) st.flush(f);
        const std::size_t at = used.fetch_add(total);
        st.next = k ^ 1;
        if (at + total > room) return;
        for (int i = b0; i < b1; ++i) f.nbr_at[i] += std::uint32_t(at);
        for (std::size_t e = at & ~std::size_t(15); e < at + total; e += 16) {
          __builtin_prefetch(f.nbr + e, 1);
          if (f.nbr_gs) __builtin_prefetch(f.nbr_gs + e, 1);
        }
        st.at = at;
        st.size = total;
      },
      [&] {
        if (stage.size) stage.flush(f);
      });
  return used.load();
}

// No-slip viscous acceleration of a particle with velocity vi from wall sample j, rij = x_i -
// x_j: the fluid pair term with the wall's velocity, across the pair direction only.
SPHFEM_HD Vec3 wall_viscous(const SphParams& P, const BoundaryView& b, std::uint32_t j,
                            const Vec3& vi, const Vec3& r, Real r2, const Vec3& gw, Real eps2) {
  const Vec3 u = relative_to(b, j, vi);
  const Real vol = b.psi[j] / P.rho0;
  const Vec3 across = u - r * (dot(u, r) / r2);
  return across * (Real(2) * P.viscosity * vol * dot(r, gw) / (r2 + eps2));
}

// WCSPH pressure acceleration of a particle (pi_rho2 = p_i / rho_i^2) from wall sample j,
// with the sign of a term subtracted from it.
SPHFEM_HD Vec3 wall_pressure_term(const BoundaryView& b, std::uint32_t j, const Vec3& gw,
                                  Real pi_rho2) {
  return gw * (b.psi[j] * (pi_rho2 + b.pw[j]));
}

// WCSPH push of a surface without samples: the symmetric pair force of the wall samples,
// -psi_b (p_i / rho_i^2 + p_b / rho_b^2) grad W, integrated over the half-space beyond it
// (psi_b -> rho0 dV). The pressure there continues the particle's own with the hydrostatic
// head, p_b(y) = p_i + rho_i g . (y - x_i), as the tank's samples extrapolate it (Adami et
// al. 2012, eq. 27), and rho_b follows from the inverse state equation. With the integrals of
// surface_density.h this is
//   rho0 [(p_i / rho_i^2 + p_i / rho_b^2) A n - rho_i / rho_b^2 (a (g . n) n + Phi g_t)].
// Without the head a particle next to the surface lacks part of its buoyancy (along a wall,
// all of the part the wall's side of the support gives). Like p_b >= 0, the normal part
// only pushes.
SPHFEM_HD Vec3 surface_pressure(const SphParams& P, const NearSurface& s, Real p, Real rho) {
  const Real rhob = P.rho0 * (Real(1) + p / P.stiffness);
  const Real inv_b2 = Real(1) / (rhob * rhob);
  const Real gn = dot(P.gravity, s.n);
  const Vec3 gt = P.gravity - s.n * gn;
  Real push = P.rho0 * ((p / (rho * rho) + p * inv_b2) * s.slope - rho * inv_b2 * s.normal2 * gn);
  if (push < Real(0)) push = Real(0);
  return s.n * push - gt * (P.rho0 * rho * inv_b2 * s.phi);
}

// DFSPH push of a surface without samples: the stiffness the tank's samples would carry there
// (wall_density: the fluid's warm start continued with the hydrostatic head), kappa_b(y) =
// kappa_i + g . (y - x_i) with kappa_i the particle's warm start, acting as the samples' own
// term V kappa_b grad W integrated over the half-space:
//   kappa_i A n - (a (g . n) n + Phi g_t),  normal part >= 0.
// It is explicit (known before the solve); the solve's kappa_i Phi' n term (dfsph_apply)
// stays the projection. With that term alone a resting column's bottom layer sank to the
// skin distance (the surface pushed with half the pair's stiffness) and the layers above it
// lost their spacing.
SPHFEM_HD Vec3 surface_stiffness(const SphParams& P, const NearSurface& s, Real kappa) {
  const Real gn = dot(P.gravity, s.n);
  const Vec3 gt = P.gravity - s.n * gn;
  Real push = kappa * s.slope - s.normal2 * gn;
  if (push < Real(0)) push = Real(0);
  return s.n * push - gt * s.phi;
}

// Accelerations: gravity, viscosity (Morris et al. 1997 Laplacian, Monaghan 1992 artificial
// viscosity, XSPH as a velocity-smoothing force) and, for WCSPH, the symmetric pressure force.
// Walls are no-slip: the viscous term of a fluid pair, with the wall at rest, acting on the
// velocity across the pair direction only (along it the pressure answers); with free-slip
// walls more pressure noise stayed in a settled tank. WCSPH walls push as
// particles of pressure p_b (wall_pressure): psi_b (p_i / rho_i^2 + p_b / rho_b^2) grad W.
// Akinci et al. 2012 eq. 10 alone (p_i / rho_i^2) is too weak for the frozen-lattice walls:
// particles sank into them and the bottom pressure doubled. Moving samples act alike with
// the velocity relative to them; a surface without samples pushes by surface_pressure.
//
// DFSPH (without the pressure): the fluid pairs' part of the density solve's warm-start sweep
// with warm_k (its warm start, as dfsph_smooth_warm left it) goes to warm_dv (dfsph_apply's
// fluid_dv), summed over the same pairs with the same bits; it reads no velocity. WCSPH:
// nullptr, nullptr.
template <class Exec>
void accelerations(Exec& ex, const SphParams P, FluidView f, const GridView g, const Walls w,
                   bool with_pressure, Real dt, const Real* warm_k, Vec3* warm_dv) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i], vi = f.v[i];
    const Real rhoi = f.rho[i];
    const Real pi_rho2 = with_pressure ? f.p[i] / (rhoi * rhoi) : Real(0);
    const Real eps2 = Real(0.01) * P.spacing * P.spacing;
    const Real hs = Real(0.5) * P.h;  // smoothing length of the artificial viscosity
    const Real inv_dt = dt > Real(0) ? Real(1) / dt : Real(0);
    const Real* rho = f.rho;
    // The pair sum with its switches fixed at compile time: a branch on a switch inside the
    // pair loop kept g++ from vectorising it.
    auto pairs = [&, rho](auto press, auto av, auto xsph) {
      auto pair = [&](const auto& of_j, const auto& r, const auto& r2, const auto& wk,
                      const auto& gw) SPHFEM_TERM {
        using R = std::decay_t<decltype(r2)>;
        const auto vij = vi - of_j.v;
        const R vr = dot(vij, r);
        R s{};
        if (decltype(press)::value) s -= P.mass * (pi_rho2 + of_j.p_rho2);
        s += Real(10) * P.viscosity * of_j.m_rho * vr / (r2 + eps2);
        if (decltype(av)::value) {
          const R mu = hs * vr / (r2 + eps2);
          const R push =
              P.mass * P.alpha_av * P.sound_speed * mu / (Real(0.5) * (rhoi + at(rho, of_j.j)));
          s += vr < Real(0) ? push : R{};
        }
        auto a = gw * s;
        if (decltype(xsph)::value) a = a - vij * (P.xsph * inv_dt * of_j.m_rho * wk);
        return select(r2 > Real(0), a, decltype(a){});
      };
      // W only for XSPH.
      constexpr bool W = decltype(xsph)::value;
      if (decltype(press)::value) {  // WCSPH; DFSPH takes the warm-start sweep along
        return sum_fluid_neighbours<W, Vec3>(P, f, g, i, xi, pair);
      } else {  // (not if constexpr: nvcc's lambdas may not capture there)
        const Real ki = warm_k[i];
        const auto t = sum_fluid_neighbours<W, Both<Vec3, Vec3>>(
            P, f, g, i, xi,
            [&](const auto& of_j, const auto& r, const auto& r2, const auto& wk,
                const auto& gw) SPHFEM_TERM {
              return both(pair(of_j, r, r2, wk, gw), dfsph_pair_term(P, warm_k, ki, of_j.j, gw));
            });
        warm_dv[i] = t.b;
        return t.a;
      }
    };
    using On = std::true_type;
    using Off = std::false_type;
    auto with_av = [&](auto press, auto xsph) {
      return P.alpha_av > Real(0) ? pairs(press, On(), xsph) : pairs(press, Off(), xsph);
    };
    auto with_xsph = [&](auto press) {
      return P.xsph > Real(0) ? with_av(press, On()) : with_av(press, Off());
    };
    Vec3 acc = P.gravity + (with_pressure ? with_xsph(On()) : with_xsph(Off()));
    for_wall_samples(f, i, w, xi, P.h2,
                     [&](const BoundaryView& b, std::uint32_t j, const Vec3& r, Real r2) {
                       if (r2 <= Real(0)) return;
                       const Vec3 gw = P.kernel.grad(r, std::sqrt(r2));
                       acc += wall_viscous(P, b, j, vi, r, r2, gw, eps2);
                       if (with_pressure) acc -= wall_pressure_term(b, j, gw, pi_rho2);
                     });
    NearSurface s;
    if (near_surface(w.surface, i, s)) {
      const Vec3 push = (with_pressure ? surface_pressure(P, s, f.p[i], rhoi)
                                       : surface_stiffness(P, s, f.warm_dens[i])) +
                        surface_drag(s, vi, inv_dt);
      acc += push;
      if (w.surface.dv) w.surface.dv[i] += push * dt;
    }
    f.a[i] = acc;
  });
}

// WCSPH wall pressure (Adami, Hu & Adams 2012, eqs. 27-28): every sample with fluid in reach
// takes the Shepard average of the fluid pressure plus the hydrostatic head between fluid and
// sample, p_b = (sum_f p_f W_bf + g . sum_f rho_f (x_b - x_f) W_bf) / sum_f W_bf, and the
// density of the inverse state equation; samples without fluid only look up empty cells.
// Mirroring p_i onto the wall instead (alone or with the head in pair form) is not an
// interaction between particles with their own pressure: it fed energy into a resting tank.
// Moving samples take the same (without the wall's own acceleration in the head).
template <class Exec>
void wall_pressure(Exec& ex, const SphParams P, const FluidView f, const GridView g,
                   BoundaryView b) {
  parallel_for(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    const Vec3 xb = b.x[k];
    Real sw = 0, sp = 0;
    Vec3 srw;
    if (!out_of_reach(f, xb))
      for_neighbors(g, f.x, f.planes, f.planes_stride, xb, P.h2,
                    [&](std::uint32_t j, const Vec3& r, Real r2) {
                      const Real w = P.kernel.W(std::sqrt(r2));
                      sw += w;
                      sp += f.p[j] * w;
                      srw += r * (f.rho[j] * w);
                    });
    Real pb = sw > Real(0) ? (sp + dot(P.gravity, srw)) / sw : Real(0);
    if (pb < Real(0)) pb = Real(0);
    const Real rhob = P.rho0 * (Real(1) + pb / P.stiffness);
    b.pw[k] = pb / (rhob * rhob);
  });
}

// Largest squared speed; +inf when any velocity or position is not finite.
template <class Exec>
Real max_speed2(Exec& ex, const FluidView f) {
  return reduce_max(ex, f.n, Real(0), [=] SPHFEM_LAMBDA(int i) -> Real {
    const Vec3 v = f.v[i], x = f.x[i];
    const Real s = norm2(v) + Real(0) * (x.x + x.y + x.z);
    return s == s && s < Real(3e38) ? s : Real(3.0e38);
  });
}

template <class Exec>
void kick(Exec& ex, FluidView f, Real dt) {
  parallel_for_light(ex, f.n, [=] SPHFEM_LAMBDA(int i) { f.v[i] += f.a[i] * dt; });
}

// x += dt v, then the last-resort box; returns how many particles it had to stop. With travel
// (a coupling hook's limits, DriftLimits in sph/solver.h) the displacement relative to the
// surface a particle's ray hit is scaled: x += dt (s + travel (v - s)), s = surface_v or 0.
template <class Exec>
int drift(Exec& ex, const SphParams P, FluidView f, Real dt, const Real* travel = nullptr,
          const Vec3* surface_v = nullptr) {
  const double clamped = reduce_sum(ex, f.n, [=] SPHFEM_LAMBDA(int i) -> double {
    Vec3 v = f.v[i];
    Vec3 step = v;
    if (travel) {
      const Vec3 s = surface_v ? surface_v[i] : Vec3();
      step = s + (v - s) * travel[i];
    }
    Vec3 x = f.x[i] + step * dt;
    int hit = 0;
    for (int c = 0; c < 3; ++c) {
      if (x[c] < P.clamp_lo[c]) {
        x[c] = P.clamp_lo[c];
        if (v[c] < Real(0)) v[c] = Real(0);
        hit = 1;
      } else if (x[c] > P.clamp_hi[c]) {
        x[c] = P.clamp_hi[c];
        if (v[c] > Real(0)) v[c] = Real(0);
        hit = 1;
      }
    }
    f.x[i] = x;
    f.v[i] = v;
    return double(hit);
  });
  return int(clamped + 0.5);
}

// Relaxation of the DFSPH Jacobi sweeps. With the exact diagonal (omega = 1) a sweep
// over-shoots: on the lattice the largest eigenvalue of D^-1 A is 2.8 for the cubic spline and
// 2.6 for Wendland C2 at h = 2d (a mode of wavelength 6d along the diagonal), so omega = 1
// diverges; summing only positive corrections hid that as extra pressure, and the overshoot
// kept a resting tank moving. 0.5 damps every mode, as the relaxed Jacobi of IISPH (Ihmsen et
// al. 2014, eq. 16).
constexpr Real kDfsphOmega = Real(0.5);

// The density solve's warm start is a running mean over about kDfsphWarmTime seconds of the
// stiffness summed per solve. The last step's sum alone also holds that step's correction of
// its density error; started from it, every step pushed the particles a second time and a
// resting tank kept boiling (rms speed 0.1 m/s). The divergence solve has no such part and
// keeps its last sum.
// The mean must also be slow: the sweeps hardly see a column's lowest mode (a nearly uniform
// compression), so the warm start alone holds it, an integral controller on a mass. That is
// stable only while its time exceeds the mode's own damping time: over 20 steps of 2 ms
// (40 ms) and over 0.1 s a resting column breathed at ~30 Hz with a growing swing until the
// tolerance capped it (docs/validation.md, "Soak"); over 0.2 s the swing decays. The weight
// of a step is dt / kDfsphWarmTime, bias-corrected at the start (SolverT::warm_weight).
constexpr double kDfsphWarmTime = 0.3;
// Strength of dfsph_smooth_warm per unit of the running mean's weight: the filter takes out
// what the memory lets in at a fixed ratio, so the warm start's bias at a surface without
// samples (a one-sided average) stays the same however slow the mean: 0.3 a step at the old
// weight 0.05 a step; kept at 0.3 a step when the mean slowed, the bottom pressure on a
// triangle-mesh floor rose from -1 % to +9 %. (That bias is gone since the filter continues
// a surface's far side; 12 then gave a better hydrostatic tank but a sampled cup whose bottom
// pressure swung by -5 % to +7 % over the lanes' summation orders, against -1 % to +5 % with 6.)
constexpr double kDfsphWarmSmoothing = 6.0;

// Coefficient of grad W_ib in a DFSPH velocity update of particle i from wall sample b: the
// pair term psi_b / rho0 (kappa_i + kappa_b) of wall_source, symmetric like a fluid pair's.
SPHFEM_HD Real dfsph_wall_pair(const SphParams& P, const BoundaryView& b, std::uint32_t j,
                               Real kappa_i, Real kappa_b) {
  return (b.psi[j] / P.rho0) * (kappa_i + kappa_b);
}

// One projected, relaxed Jacobi update (Bender & Koschier 2017, eqs. 9 and 12, with omega).
// The pressure may only push: kappa_sum + kappa >= 0, compression where kappa_sum > 0 must
// vanish and expansion is free where kappa_sum = 0 (a complementarity problem); the
// projection also lets a sweep take back pressure the warm start over-estimated. Returns the
// complementarity residual in relative density: the compression, or the expansion that taking
// back the remaining pressure could still undo.
SPHFEM_HD Real dfsph_update(Real err, Real alpha, Real kappa_sum, Real dt, Real& kappa) {
  kappa = kDfsphOmega * err * alpha / (dt * dt);
  if (kappa < -kappa_sum) kappa = -kappa_sum;
  if (err >= Real(0) || alpha <= Real(0)) return err > Real(0) ? err : Real(0);
  const Real releasable = kappa_sum * dt * dt / alpha;
  return -err < releasable ? -err : releasable;
}

// DFSPH residual of every fluid particle and its stiffness update: the predicted relative
// density (density solve, eq. 9) or its change over the step (divergence solve, eq. 13;
// compression only counts where the neighbourhood is nearly full, at the free surface
// particles may close up). The density error of the step's start is corrected at the pace of
// a full step (pos_rate = dt / CFL step): a short step that lands on an output time would
// otherwise turn it into a huge velocity. Returns the summed residual.
template <class Exec>
double dfsph_source(Exec& ex, const SphParams P, FluidView f, const GridView g, const Walls w,
                    Real dt, Real pos_rate, bool divergence) {
  return reduce_sum(ex, f.n, [=] SPHFEM_LAMBDA(int i) -> double {
    const Vec3 xi = f.x[i], vi = f.v[i];
    Real d = sum_fluid_pairs<false, Real>(
        f, g, P.kernel, i, xi, P.h2,
        [&](const auto& j, const auto&, const auto&, const auto&, const auto& gw)
            SPHFEM_TERM { return P.volume * dot(vi - at(f.v, j), gw); });
    for_wall_grads(f, i, w, xi, P.kernel, P.h2,
                   [&](const BoundaryView& b, std::uint32_t j, const auto& grad) {
                     d += (b.psi[j] / P.rho0) * dot(relative_to(b, j, vi), grad());
                   });
    NearSurface s;
    if (near_surface(w.surface, i, s)) d -= s.slope * dot(vi - s.vs, s.n);
    Real err = divergence ? d * dt : (f.rho[i] / P.rho0 - Real(1)) * pos_rate + dt * d;
    if (divergence && !(f.flags[i] & kFullSupport) && err > Real(0)) err = Real(0);
    return double(dfsph_update(err, f.alpha[i], f.kappa_sum[i], dt, f.kappa[i]));
  });
}

// Wall samples as pressure carriers of the same solve, as the wall particles in the pressure
// Poisson equation of Shao & Lo 2003: a sample's density rest + m sum_f W_bf may not exceed
// rho0, and its stiffness pushes the fluid by psi_b / rho0 kappa_b grad W. With the fluid's own
// wall term psi_b / rho0 kappa_i grad W the pair force is psi_b / rho0 (kappa_i + kappa_b)
// grad W: the wall pressure continues the fluid's, hydrostatic head included, and the velocity
// update is the transpose of the density change, an orthogonal projection that cannot add
// kinetic energy. Mirroring kappa_i onto the walls instead (kappa_b = kappa_i) is no
// projection: it fed energy into a resting tank until it blew up.
// The constraint is weighted by psi_b / m, (psi_b / m) (rho_b / rho0 - 1) <= 0, which leaves
// where it holds unchanged and makes its gradient the psi_b / rho0 grad W of the push. On the
// tank's lattice psi_b = m and nothing changes. A one-layer moving surface is sampled more
// densely than the lattice (psi_b ~ 0.56 m for 1.8 samples per s^2): with V kappa_b each
// sample pushed as hard as a lattice sample, the warm start (the fluid's stiffness continued
// to the sample) pushed about 1.8 times too hard, the sweeps took it back every step, and a
// resting column kept boiling (kinetic energy 30 times WCSPH's, the force on the nodes off
// by +-20 % from step to step, the pressure 15-20 % low).
// wall_source of sample k; fluid(f) calls f(j, r, r2) for its fluid neighbours in the grid
// scan's order.
template <class Fluid>
SPHFEM_HD_INLINE Real wall_source_at(const SphParams& P, const FluidView& f, const BoundaryView& b,
                                     Real dt, Real pos_rate, bool divergence, int k,
                                     const Fluid& fluid) {
  const Real alpha = b.alpha[k];
  if (alpha <= Real(0)) {
    b.kappa[k] = Real(0);
    return Real(0);
  }
  Real d = 0;
  const Vec3 vb = b.v ? b.v[k] : Vec3();
  const Real vol = b.psi[k] / P.rho0;
  fluid([&](std::uint32_t j, const Vec3& r, Real r2) {
    const Vec3 vj = b.v ? f.v[j] - vb : f.v[j];
    d -= vol * dot(vj, P.kernel.grad(r, std::sqrt(r2)));
  });
  const Real scale = b.psi[k] / P.mass;
  Real err = divergence ? d * dt : (b.rho[k] / P.rho0 - Real(1)) * scale * pos_rate + dt * d;
  if (divergence && !b.full[k] && err > Real(0)) err = Real(0);
  return dfsph_update(err, alpha, b.kappa_sum[k], dt, b.kappa[k]);
}

// The fluid neighbours of listed sample p (BoundaryView::listed), as for_neighbors gives them.
template <class F>
SPHFEM_HD_INLINE void for_listed_fluid(const BoundaryView& b, const FluidView& f, int p, F&& fn) {
  const Vec3 xb = b.x[b.listed[p]];
  for (std::uint32_t q = b.listed_at[p]; q < b.listed_end[p]; ++q) {
    const std::uint32_t j = b.fluid_list[q];
    const Vec3 r = xb - f.x[j];
    fn(j, r, norm2(r));
  }
}

template <class Exec>
double wall_source(Exec& ex, const SphParams P, const FluidView f, const GridView g, BoundaryView b,
                   Real dt, Real pos_rate, bool divergence) {
  if constexpr (Exec::kSpace == MemSpace::Host) {
    // The samples without fluid in reach hold kappa 0 from their warm start (wall_density
    // gave them none) and add 0 to the sum: only the listed ones are visited.
    if (b.listed)
      return reduce_sum_listed(ex, b.n, b.block_first, [=](int p) -> double {
        return double(wall_source_at(P, f, b, dt, pos_rate, divergence, int(b.listed[p]),
                                     [&](auto&& fn) { for_listed_fluid(b, f, p, fn); }));
      });
  }
  return reduce_sum(ex, b.n, [=] SPHFEM_LAMBDA(int k) -> double {
    return double(wall_source_at(P, f, b, dt, pos_rate, divergence, k,
                                 [&](auto&& fn) { for_neighbors(g, f.x, b.x[k], P.h2, fn); }));
  });
}

// Per step, for the wall samples with fluid in reach (the others only look up their empty
// cells): density, diagonal, free-surface flag and warm starts. The diagonal is the larger of
// sum_f |V_b grad W_bf|^2 and what all samples around the same particles do together, the sum
// over f of V_b grad W_bf . sum_b' V grad W_b'f (V_b = psi_b / rho0, wall_source's weight;
// the sum over b' as density() keeps it): the samples around a particle all push it the
// same way, and with the exact diagonal a lone particle in a corner was pushed by each of them
// as if it were the only one (the Jacobi sweep blew up). The warm starts are the Shepard
// average of the fluid's, plus the hydrostatic head g . (x_b - x_f) for the density solve
// (Adami et al. 2012, eq. 27): a sample keeps no stiffness of its own, as the fluid in front of
// it changes. Returns how many samples take part.
// wall_density of sample k; hit(j) is called for each fluid neighbour j in the scan's order.
// Returns their number.
template <class Hit>
SPHFEM_HD_INLINE int wall_density_at(const SphParams& P, const FluidView& f, const GridView& g,
                                     const BoundaryView& b, int k, const Hit& hit) {
  const Vec3 xb = b.x[k];
  Real sum = 0, grad2 = 0, shared = 0, kdiv = 0, kdens = 0;
  Vec3 srw;
  int count = 0;
  const Real vol = b.psi[k] / P.rho0;
  if (!out_of_reach(f, xb))
    for_neighbors(g, f.x, f.planes, f.planes_stride, xb, P.h2,
                  [&](std::uint32_t j, const Vec3& r, Real r2) {
                    hit(j);
                    const Real rr = std::sqrt(r2);
                    const Vec3 gw = P.kernel.grad(r, rr) * vol;
                    const Real w = P.kernel.W(rr);
                    sum += w;
                    grad2 += norm2(gw);
                    shared -= dot(gw, f.gwall[j]);
                    kdiv += f.warm_div[j] * w;
                    kdens += f.warm_dens[j] * w;
                    srw += r * w;
                    ++count;
                  });
  b.rho[k] = b.rest[k] + P.mass * sum;
  b.full[k] = b.nb_rest[k] + count >= full_neighborhood(P) ? 1 : 0;
  const Real diag = shared > grad2 ? shared : grad2;
  b.alpha[k] = grad2 > Real(1e-6) ? Real(1) / diag : Real(0);
  Real wdiv = 0, wdens = 0;
  if (count > 0) {
    wdiv = kdiv / sum;
    wdens = (kdens + dot(P.gravity, srw)) / sum;
  }
  b.warm_div[k] = wdiv > Real(0) ? wdiv : Real(0);
  b.warm_dens[k] = wdens > Real(0) ? wdens : Real(0);
  return count;
}

// The samples' part of the step (above); returns how many have fluid in reach. The host's
// WallLists::density also lists their fluid neighbours for the sweeps.
template <class Exec>
int wall_density(Exec& ex, const SphParams P, const FluidView f, const GridView g, BoundaryView b) {
  const double active = reduce_sum(ex, b.n, [=] SPHFEM_LAMBDA(int k) -> double {
    return wall_density_at(P, f, g, b, k, [](std::uint32_t) {}) > 0 ? 1.0 : 0.0;
  });
  return int(active + 0.5);
}

// Partial Shepard filter of the density solve's warm start, fluid, wall samples and the far side
// of a surface without samples together: warm_i += rate (sum_j warm_j W_ij / sum_j W_ij -
// warm_i), into out. The sweeps cannot see a stiffness that alternates layer by layer (on the
// lattice its SPH gradient vanishes), so once in the warm start it stayed there and showed as
// a static +-5 % zigzag in the pressure; the filter lets it decay while the smooth hydrostatic
// part passes unchanged.
// The fluid's sums come from density() (WarmSums: fluid_w, fluid_kw); this pass adds the walls'
// and a surface's.
template <class Exec>
void dfsph_smooth_warm(Exec& ex, const SphParams P, const FluidView f, const Walls w, Real rate,
                       const Real* fluid_w, const Real* fluid_kw, Real* out) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i];
    Real sw = fluid_w[i], sk = fluid_kw[i];
    for_wall_samples(f, i, w, xi, P.h2,
                     [&](const BoundaryView& b, std::uint32_t j, const Vec3&, Real r2) {
                       const Real wk = P.kernel.W(std::sqrt(r2));
                       sw += wk;
                       sk += wk * b.warm_dens[j];
                     });
    const Real own = f.warm_dens[i];
    // A surface without samples: the space beyond it as the tank's samples would fill it,
    // with the particle's own warm start continued by the hydrostatic head (as wall_density
    // gives the samples). Without it the average was one-sided there and pulled the bottom
    // layer's warm start toward the lower values above it.
    NearSurface s;
    if (near_surface(w.surface, i, s)) {
      const Real beyond = P.rho0 / P.mass;  // sum_b W_ib = beyond Phi
      const Real head = -dot(P.gravity, s.n) * w.surface.half.moment(s.q * P.h);
      sw += beyond * s.phi;
      sk += beyond * (s.phi * own + head);
    }
    out[i] = own + rate * (sk / sw - own);
  });
}

// Density of the walls alone at each sample and the samples in reach; once for the tank
// (share 1), every step for moving samples (share moving_rest_share).
template <class Exec>
void wall_rest(Exec& ex, const SphParams P, Real* rest, int* nb_rest, const BoundaryView b,
               Real share = Real(1)) {
  parallel_for(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    Real sum = 0;
    int count = 0;
    for_neighbors(b.grid, b.x, b.x[k], P.h2, [&](std::uint32_t j, const Vec3&, Real r2) {
      sum += b.psi[j] * P.kernel.W(std::sqrt(r2));
      ++count;
    });
    rest[k] = share * sum;
    nb_rest[k] = count;
  });
}

// Warm start (Bender & Koschier 2017, sec. 4.3): the remembered stiffness is the first sweep.
// kappa has units of pressure / density (an acceleration potential), so it carries over
// unchanged when dt changes.
template <class Exec>
void dfsph_warm_start(Exec& ex, FluidView f, bool divergence) {
  parallel_for_light(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    f.kappa[i] = divergence ? f.warm_div[i] : f.warm_dens[i];
    f.kappa_sum[i] = Real(0);
  });
}

template <class Exec>
void wall_warm_start(Exec& ex, const BoundaryView b, bool divergence) {
  parallel_for_light(ex, b.n, [=] SPHFEM_LAMBDA(int k) {
    b.kappa[k] = divergence ? b.warm_div[k] : b.warm_dens[k];
    b.kappa_sum[k] = Real(0);
  });
}

// After a solve: warm += weight (kappa_sum - warm). The weight is scaled by the step's length
// (dt / CFL step, dt / kDfsphWarmTime), so a short step, whose corrections are impulses of
// size ~ 1 / dt, hardly moves the memory.
template <class Exec>
void dfsph_remember(Exec& ex, FluidView f, Real weight, bool divergence) {
  parallel_for_light(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    Real* warm = divergence ? f.warm_div : f.warm_dens;
    warm[i] += weight * (f.kappa_sum[i] - warm[i]);
  });
}

// v_i -= dt (sum_j V (kappa_i + kappa_j) grad W_ij + sum_b psi_b / rho0 (kappa_i + kappa_b)
// grad W_ib); the sweep's stiffness joins the sums, and the fluid's the pressure
// p_i = rho_i^2 / rho0 kappa_i (gauges, output). A surface without samples adds
// kappa_i Phi'(d) n, the transpose of its term in the density change (dfsph_source), so the
// update stays a projection; it carries no stiffness of its own (wall_accumulate).
// fluid_dv: the fluid pairs' sum where a pass before has taken it (accelerations(), warm_dv),
// else nullptr.
template <class Exec>
void dfsph_apply(Exec& ex, const SphParams P, FluidView f, const GridView g, const Walls w, Real dt,
                 const Vec3* fluid_dv = nullptr) {
  parallel_for(ex, f.n, [=] SPHFEM_LAMBDA(int i) {
    const Vec3 xi = f.x[i];
    const Real ki = f.kappa[i];
    Vec3 dv = fluid_dv ? fluid_dv[i] : dfsph_fluid_dv(P, f, g, f.kappa, i, xi);
    for_wall_samples(f, i, w, xi, P.h2,
                     [&](const BoundaryView& b, std::uint32_t j, const Vec3& r, Real r2) {
                       const Real k = dfsph_wall_pair(P, b, j, ki, b.kappa[j]);
                       if (k != Real(0)) dv += P.kernel.grad(r, std::sqrt(r2)) * k;
                     });
    NearSurface s;
    if (near_surface(w.surface, i, s)) {
      const Vec3 push = s.n * (s.slope * ki);
      dv -= push;
      if (w.surface.dv) w.surface.dv[i] += push * dt;
    }
    f.v[i] -= dv * dt;
    f.kappa_sum[i] += ki;
    f.p[i] += ki * f.rho[i] * f.rho[i] / P.rho0;
  });
}

// After a sweep: the samples' stiffness joins their sums.
template <class Exec>
void wall_accumulate(Exec& ex, const BoundaryView b) {
  if constexpr (Exec::kSpace == MemSpace::Host) {
    // The others' kappa is 0 (wall_source).
    if (b.listed) {
      parallel_for_light(ex, b.n_listed, [=](int p) {
        const std::uint32_t k = b.listed[p];
        b.kappa_sum[k] += b.kappa[k];
      });
      return;
    }
  }
  parallel_for_light(ex, b.n, [=] SPHFEM_LAMBDA(int k) { b.kappa_sum[k] += b.kappa[k]; });
}

// Appends one emitter layer at slots [first, first + count), at rest in the solver's memory.
template <class Exec>
void emit_layer(Exec& ex, FluidView f, const Vec3* disc, int count, int first, Vec3 origin,
                Vec3 velocity, std::uint32_t first_id) {
  parallel_for(ex, count, [=] SPHFEM_LAMBDA(int k) {
    const int i = first + k;
    f.x[i] = origin + disc[k];
    f.v[i] = velocity;
    f.id[i] = first_id + std::uint32_t(k);
    f.p[i] = Real(0);
    f.warm_div[i] = Real(0);
    f.warm_dens[i] = Real(0);
  });
}

}  // namespace sphfem::stages
