// A set of wall samples sorted into their own cell grid: the buffers behind one
// stages::BoundaryView, one type for the tank's samples and for those on moving surfaces.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "sph/stages.h"
#include "sphfem/core/memory.h"

namespace sphfem {

// Width of the radix sort's keys for a grid of `cells` cells.
inline int cell_key_bits(long long cells) {
  int bits = 1;
  while ((1ll << bits) < cells) ++bits;
  return bits;
}

// Per sample, in cell order: position, psi and the wall quantities of stages::BoundaryView;
// start holds the cells' ranges. Who fills x, psi and start (once for the tank, every step
// for moving samples) is the owner's business; the stages fill the rest.
template <class Exec>
class SampleSet {
 public:
  // Room for n samples (at least one, so no view holds a null array) on a grid shaped like
  // `geometry`, every value 0.
  void resize(int n, const GridView& geometry) {
    const MemSpace s = Exec::kSpace;
    const std::size_t cap = std::size_t(std::max(n, 1));
    x = Buffer<Vec3>(s, cap);
    x.zero();
    for (Buffer<Real>* b :
         {&psi, &rest, &pw, &rho, &alpha, &kappa, &kappa_sum, &warm_div, &warm_dens}) {
      *b = Buffer<Real>(s, cap);
      b->zero();
    }
    for (Buffer<int>* b : {&nb_rest, &full}) {
      *b = Buffer<int>(s, cap);
      b->zero();
    }
    geometry_ = geometry;
    start = Buffer<std::uint32_t>(s, std::size_t(geometry.cells()) + 1);
    start.zero();
  }

  // The cell grid the samples are sorted into.
  GridView grid() const {
    GridView g = geometry_;
    g.start = start.data();
    return g;
  }

  // The first n samples as the stages see them, at rest; n = 0 leaves the grid empty, so
  // neighbour queries find nothing.
  stages::BoundaryView view(int n) {
    stages::BoundaryView b;
    b.n = n;
    b.x = x.data();
    b.psi = psi.data();
    b.rest = rest.data();
    b.nb_rest = nb_rest.data();
    b.pw = pw.data();
    b.rho = rho.data();
    b.alpha = alpha.data();
    b.full = full.data();
    b.kappa = kappa.data();
    b.kappa_sum = kappa_sum.data();
    b.warm_div = warm_div.data();
    b.warm_dens = warm_dens.data();
    b.grid = grid();
    if (!n) b.grid.nx = 0;
    return b;
  }

  Buffer<Vec3> x;
  Buffer<Real> psi, rest, pw, rho, alpha, kappa, kappa_sum, warm_div, warm_dens;
  Buffer<int> nb_rest, full;
  Buffer<std::uint32_t> start;

 private:
  GridView geometry_;
};

}  // namespace sphfem
