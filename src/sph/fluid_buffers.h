// The fluid particles' buffers in one memory space: the state a step hands to the next, and
// the scratch every step recomputes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "sph/stages.h"
#include "sphfem/core/memory.h"

namespace sphfem {

// Per particle, in the particles' present order (cell order after a sort).
//
// State (FluidSolver::save / load): x, v, id and the DFSPH warm starts warm_div, warm_dens;
// the sort gathers them, emitters append to them.
//
// Scratch: everything else, written by a step before it reads it. p is the last solve's
// pressure, which FluidSolver::snapshot reports; the sort gathers it along, density() zeroes
// it (DFSPH) or writes it (WCSPH), and load() zeroes it.
struct FluidBuffers {
  // State.
  Buffer<Vec3> x, v;
  Buffer<std::uint32_t> id;
  Buffer<Real> warm_div, warm_dens;

  // Scratch of a step.
  Buffer<Vec3> a;
  Buffer<Vec3> tmp3;  // the sort's gather target, then FluidView::gwall until the next sort
  Buffer<Real> rho, p, alpha, kappa, ksum;
  Buffer<Real> tmpr;  // gather target; the smoothed warm start (dfsph_smooth_warm)
  Buffer<int> nb, flags;
  Buffer<std::uint32_t> nbr;  // fluid neighbour lists of the step (FluidView::nbr)
  Buffer<int> nbr_n;
  Buffer<std::uint32_t> nbr_at;  // the host's: where each list begins (FluidView::nbr_at)
  Buffer<Real> nbr_gs;           // the host's, DFSPH: the pairs' kernel factors (FluidView::nbr_gs)
  Buffer<Vec3> warm_dv;  // the host's, DFSPH: the divergence warm start's pairs (WarmSums::div_dv)
  Buffer<Real> records;  // the host's, WCSPH: FluidView::rec_x, then rec_v (4 Reals a particle)
  int nbr_cap = 0;
  int cap = 0;                   // particles there is room for
  bool nbr_interleaved = false;  // the layout of nbr (FluidView::nbr_si, view())
  bool packed = false;           // the host packs the lists, with their kernel factors (allocate)
  Buffer<std::uint32_t> keys, perm;  // the sort's keys and order; keys: id's gather target
  Buffer<std::uint32_t> start;       // cell starts of the fluid's grid

  // The host's first pool: entries a particle, too few for a full support's list, so that it
  // grows to what the lists take (list_and_density).
  static constexpr int kFirstListRoom = 8;

  // Room for cap particles on a grid of `cells` cells; the warm starts begin at 0. dfsph: the
  // pressure solve's alpha, kappa and kappa_sum, and on the host the pairs' kernel factors
  // (DFSPH's passes read them a dozen times a step); otherwise (WCSPH) the host's records of
  // the forces' neighbours.
  void allocate(MemSpace s, int capacity, int full_neighbors, long long cells, bool dfsph = false) {
    cap = capacity;
    // One Vec3 more than the particles: the host's pair lanes read a fourth Real past x_j
    // (lanes::at). They swap with each other, so all four have it.
    for (Buffer<Vec3>* b : {&x, &v, &tmp3}) *b = Buffer<Vec3>(s, std::size_t(cap) + 1);
    // a also holds the positions as planes for the list build, which reads up to seven Reals
    // past the last plane's end (collect_from_planes): two Vec3s more.
    a = Buffer<Vec3>(s, std::size_t(cap) + 3);
    for (Buffer<Real>* b : {&rho, &p, &warm_div, &warm_dens, &tmpr}) *b = Buffer<Real>(s, cap);
    // WCSPH's passes never read them: 12 B a particle it does not hold.
    if (dfsph)
      for (Buffer<Real>* b : {&alpha, &kappa, &ksum}) *b = Buffer<Real>(s, cap);
    warm_div.zero();
    warm_dens.zero();
    nb = Buffer<int>(s, cap);
    flags = Buffer<int>(s, cap);
    // Lists of up to about twice a full support's neighbours; a particle compressed beyond that
    // scans the grid instead (stages::for_fluid_neighbors). A multiple of eight: the host pads
    // each list to whole groups of eight (stages::listed_end).
    nbr_cap = std::max(32, (2 * full_neighbors) & ~7);
    // A device reads the lists interleaved, entry k of particle i at k * cap + i, so the
    // threads of a warp read consecutive words; the host reads each contiguously. Both keep
    // room for nbr_cap a particle, except where the host keeps the pairs' kernel factors
    // (DFSPH): it then packs each list after the one before (stages::density_packed), in a
    // pool as large as they are, which grows as they do (list_and_density), so that a list
    // takes its length, not nbr_cap, which pays for the factors beside it. Without factors
    // (WCSPH) the packing's copy would cost time for nothing.
    nbr_interleaved = s == MemSpace::Device;
    packed = !nbr_interleaved && dfsph;
    if (packed) {
      nbr_at = Buffer<std::uint32_t>(s, cap);
      warm_dv = Buffer<Vec3>(s, cap);
      grow_lists(std::size_t(cap) * kFirstListRoom);
    } else {
      nbr = Buffer<std::uint32_t>(s, std::size_t(cap) * std::size_t(nbr_cap));
    }
    nbr_n = Buffer<int>(s, cap);
    // WCSPH on the host: the forces' records (FluidView::rec_x, rec_v), 32 B a particle; a
    // device reads the arrays, one neighbour a thread.
    if (s == MemSpace::Host && !dfsph) records = Buffer<Real>(s, 8 * std::size_t(cap));
    for (Buffer<std::uint32_t>* b : {&id, &keys, &perm}) *b = Buffer<std::uint32_t>(s, cap);
    start = Buffer<std::uint32_t>(s, std::size_t(cells) + 1);
    start.zero();  // no earlier sort (sort_moved)
  }

  // Re-orders the first n particles by cell for locality (a radix sort of their cell keys in
  // g): the cells' ranges, then the state follows, with p, the warm starts under DFSPH only.
  template <class Exec>
  void sort(Exec& ex, const GridView& g, int n, int key_bits, bool dfsph) {
    stages::cell_keys(ex, g, x.data(), keys.data(), perm.data(), n);
    // The host merges the few particles that changed cell since the last sort (start still
    // holds its ranges); a device sorts them all.
    bool sorted = false;
    if constexpr (Exec::kSpace == MemSpace::Host)
      sorted = sort_moved(ex, keys.data(), perm.data(), n, start.data(), int(g.cells()));
    if (!sorted) sort_pairs(ex, keys.data(), perm.data(), n, key_bits);
    stages::cell_starts(ex, keys.data(), start.data(), n, g.cells());
    stages::gather(ex, x.data(), tmp3.data(), perm.data(), n);
    x.swap(tmp3);
    stages::gather(ex, v.data(), tmp3.data(), perm.data(), n);
    v.swap(tmp3);
    // The keys are spent once the cells' ranges are known: they take the ids, which saves a
    // buffer of their own.
    stages::gather(ex, id.data(), keys.data(), perm.data(), n);
    id.swap(keys);
    stages::gather(ex, p.data(), tmpr.data(), perm.data(), n);
    p.swap(tmpr);
    if (dfsph) {
      stages::gather(ex, warm_div.data(), tmpr.data(), perm.data(), n);
      warm_div.swap(tmpr);
      stages::gather(ex, warm_dens.data(), tmpr.data(), perm.data(), n);
      warm_dens.swap(tmpr);
    }
  }

  // The host's pool for `entries` list entries (and as many factors), what it held lost.
  void grow_lists(std::size_t entries) {
    if (entries > std::size_t(0xffffffffu))
      throw std::length_error("fluid: the neighbour lists would take more than 2^32 entries");
    nbr = Buffer<std::uint32_t>(MemSpace::Host, entries);
    nbr_gs = Buffer<Real>(MemSpace::Host, entries);
  }

  // stages::density over the view f of view(), its lists stored: on the host packed, the pool
  // grown to an eighth beyond what they took, scaled to the capacity, and the pass run again
  // where they did not fit (the first step, and steps whose lists outgrow the slack; the sums
  // are the same).
  template <class Exec>
  void list_and_density(Exec& ex, const SphParams& P, stages::FluidView f, const GridView& g,
                        const stages::Walls& w, bool with_alpha,
                        const stages::WarmSums& warm = stages::WarmSums()) {
    if constexpr (Exec::kSpace == MemSpace::Host) {
      if (packed) {
        for (;;) {
          const std::size_t need =
              stages::density_packed(ex, P, f, g, w, with_alpha, nbr.size(), warm);
          if (need <= nbr.size()) return;
          // As long as the lists are now a particle, for all the particles there is room for
          // (emitters add them), and an eighth more.
          const double each = double(need) / double(f.n);
          grow_lists(std::max(need + need / 8, std::size_t(1.125 * each * double(cap))));
          f.nbr = nbr.data();
          if (f.nbr_gs) f.nbr_gs = nbr_gs.data();
        }
      }
    }
    stages::density(ex, P, f, g, w, with_alpha, warm);
  }

  // Points f at the forces' records (FluidView::rec_x, rec_v); false where there are none.
  bool see_records(stages::FluidView& f) {
    if (!records.size()) return false;
    f.rec_x = records.data();
    f.rec_v = f.rec_x + 4 * std::size_t(cap);
    return true;
  }

  // The first n particles as the stages see them.
  stages::FluidView view(int n) {
    stages::FluidView f;
    f.n = n;
    f.x = x.data();
    f.v = v.data();
    f.a = a.data();
    f.rho = rho.data();
    f.p = p.data();
    f.alpha = alpha.data();
    f.kappa = kappa.data();
    f.kappa_sum = ksum.data();
    f.warm_div = warm_div.data();
    f.warm_dens = warm_dens.data();
    f.flags = flags.data();
    f.gwall = tmp3.data();  // free between the sort and the next one
    f.nb = nb.data();
    f.id = id.data();
    f.nbr = nbr.data();
    f.nbr_n = nbr_n.data();
    f.nbr_at = packed ? nbr_at.data() : nullptr;
    f.nbr_gs = packed ? nbr_gs.data() : nullptr;
    f.nbr_cap = nbr_cap;
    f.nbr_si = nbr_interleaved ? 1 : std::size_t(nbr_cap);
    f.nbr_sk = nbr_interleaved ? std::size_t(cap) : 1;
    return f;
  }
};

}  // namespace sphfem
