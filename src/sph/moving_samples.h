// The samples of the boundary-particle coupling (sph/moving_boundary.h) in a solver: placed
// on the moving surface every step, sorted into their grid, their impulses gathered back to
// the surface's nodes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "sph/moving_stages.h"
#include "sph/sample_set.h"
#include "sphfem/core/memory.h"
#include "sphfem/sph/moving_boundary.h"

namespace sphfem {

template <class Exec>
class MovingSamples {
 public:
  // DFSPH: the walls-alone share of a sample's density (stages::moving_rest_share).
  void set_rest_share(Real share) { share_ = share; }

  // The samples, fixed on triangles of a surface of `nodes` nodes, on a grid shaped like
  // `geometry`; none are placed until the next place().
  void set(const std::vector<SurfaceSample>& samples, const std::vector<Tri>& tris, int nodes,
           const GridView& geometry) {
    const int n = int(samples.size());
    std::vector<int> tri(n);
    std::vector<Vec3> w(n);
    // Gather lists node -> (sample, weight), so the nodes sum their samples' impulses in a
    // fixed order without atomics.
    std::vector<int> start(std::size_t(std::max(nodes, 0)) + 1, 0);
    for (int k = 0; k < n; ++k) {
      const SurfaceSample& sm = samples[k];
      if (sm.tri < 0 || sm.tri >= int(tris.size()))
        throw std::invalid_argument("set_moving_samples: sample " + std::to_string(k) +
                                    " names triangle " + std::to_string(sm.tri) + " of " +
                                    std::to_string(tris.size()));
      tri[k] = sm.tri;
      w[k] = Vec3(sm.w[0], sm.w[1], sm.w[2]);
      for (int c = 0; c < 3; ++c) {
        const int node = tris[sm.tri].v[c];
        if (node < 0 || node >= nodes)
          throw std::invalid_argument("set_moving_samples: triangle " + std::to_string(sm.tri) +
                                      " names node " + std::to_string(node) + " of " +
                                      std::to_string(nodes));
        if (sm.w[c] != Real(0)) ++start[node + 1];
      }
    }
    for (int i = 0; i < nodes; ++i) start[i + 1] += start[i];
    std::vector<int> sample(start.back());
    std::vector<Real> weight(start.back());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) {
        if (samples[k].w[c] == Real(0)) continue;
        const int e = fill[tris[samples[k].tri].v[c]]++;
        sample[e] = k;
        weight[e] = samples[k].w[c];
      }
    const MemSpace s = Exec::kSpace;
    const std::size_t cap = std::size_t(std::max(n, 1));
    samples_ = n;
    nodes_ = n ? nodes : 0;
    tri_ = Buffer<int>(s, cap);
    tri_.upload(tri.data(), n);
    w_ = Buffer<Vec3>(s, cap);
    w_.upload(w.data(), n);
    for (Buffer<Vec3>* b : {&v_, &tmpx_, &tmpv_, &imp_}) *b = Buffer<Vec3>(s, cap);
    set_.resize(n, geometry);
    for (Buffer<std::uint32_t>* b : {&keys_, &perm_, &slot_}) *b = Buffer<std::uint32_t>(s, cap);
    node_start_ = Buffer<int>(s, start.size());
    node_start_.upload(start.data(), start.size());
    node_sample_ = Buffer<int>(s, std::max<std::size_t>(sample.size(), 1));
    node_sample_.upload(sample.data(), sample.size());
    node_w_ = Buffer<Real>(s, std::max<std::size_t>(weight.size(), 1));
    node_w_.upload(weight.data(), weight.size());
    active_ = 0;
  }

  // Samples set (placed or not).
  int count() const { return samples_; }

  // The samples on the given surface as it is now, sorted into their own cell grid, with psi
  // and (DFSPH) their walls-alone density; impulses start at 0. A surface without nodes
  // places none this step.
  void place(Exec& ex, const SphParams& P, const MovingSurface& surface, int key_bits) {
    active_ = 0;
    surface_ = MovingSurface();
    if (!samples_) return;
    surface_ = surface;
    if (surface_.nodes == 0 || !surface_.x || !surface_.tri) return;
    if (surface_.space != Exec::kSpace)
      throw std::runtime_error(
          "moving_boundary: the surface is in another memory space than the fluid "
          "solver's; pass the body solver's arrays of the same backend");
    if (surface_.nodes != nodes_)
      throw std::runtime_error("moving_boundary: the surface has " +
                               std::to_string(surface_.nodes) + " nodes, set_moving_samples " +
                               std::to_string(nodes_));
    const int n = samples_;
    const GridView g = set_.grid();
    stages::place_samples(ex, n, tri_.data(), w_.data(), surface_.tri, surface_.x, surface_.v,
                          tmpx_.data(), surface_.v ? tmpv_.data() : nullptr);
    stages::cell_keys(ex, g, tmpx_.data(), keys_.data(), perm_.data(), n);
    sort_pairs(ex, keys_.data(), perm_.data(), n, key_bits);
    stages::gather(ex, tmpx_.data(), set_.x.data(), perm_.data(), n);
    if (surface_.v) stages::gather(ex, tmpv_.data(), v_.data(), perm_.data(), n);
    stages::invert(ex, perm_.data(), slot_.data(), n);
    stages::cell_starts(ex, keys_.data(), set_.start.data(), n, g.cells());
    active_ = n;
    const stages::BoundaryView b = view();
    stages::sample_psi(ex, P, b, set_.psi.data());
    stages::wall_rest(ex, P, set_.rest.data(), set_.nb_rest.data(), b, share_);
    imp_.zero();
  }

  // The samples placed this step (n = 0 when none were).
  stages::BoundaryView view() {
    stages::BoundaryView b = set_.view(active_);
    b.v = active_ && surface_.v ? v_.data() : nullptr;
    return b;
  }

  // The impulses the fluid gave the placed samples this step, in cell order.
  Vec3* impulse() { return imp_.data(); }

  // Adds the placed samples' impulses to the surface's nodes, by their weights (when the
  // surface takes them).
  void to_nodes(Exec& ex) {
    if (!active_ || !surface_.impulse) return;
    stages::node_impulse(ex, nodes_, node_start_.data(), node_sample_.data(), node_w_.data(),
                         slot_.data(), imp_.data(), surface_.impulse);
  }

 private:
  int samples_ = 0, nodes_ = 0, active_ = 0;
  Real share_ = 1;
  MovingSurface surface_;  // of this step
  // Per sample in the original order: its triangle and weights.
  Buffer<int> tri_;
  Buffer<Vec3> w_;
  // Per placed sample in cell order: the wall quantities, velocity and impulse.
  SampleSet<Exec> set_;
  Buffer<Vec3> v_, imp_;
  // The placement's scratch: unsorted positions and velocities, keys, order and its inverse
  // (slot[k]: where sample k went).
  Buffer<Vec3> tmpx_, tmpv_;
  Buffer<std::uint32_t> keys_, perm_, slot_;
  // Node n gathers node_w_[e] times sample node_sample_[e]'s impulse, e in
  // [node_start_[n], node_start_[n + 1]).
  Buffer<int> node_start_, node_sample_;
  Buffer<Real> node_w_;
};

}  // namespace sphfem
