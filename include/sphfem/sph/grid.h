// Uniform cell grid of cell size h over the padded domain. Particles are sorted by the
// linear cell index (x fastest), so the three cells of a row are one contiguous range and
// a neighbour query visits 9 ranges instead of 27 cells.
#pragma once

#include <cstddef>
#include <cstdint>

#include "sphfem/core/vec.h"

// The host's list builder packs its hits with AVX2 (collect_neighbors).
#if !defined(__CUDACC__) && defined(__GNUC__) && defined(__AVX2__) && !defined(SPHFEM_DOUBLE)
#define SPHFEM_GRID_PACK 1
#include <immintrin.h>

#include <array>
#else
#define SPHFEM_GRID_PACK 0
#endif

namespace sphfem {

struct GridView {
  Vec3 lo;        // corner of cell (0,0,0)
  Real inv_cell;  // 1 / cell size
  int nx = 0, ny = 0, nz = 0;
  // nx*ny*nz + 1 entries; cell c holds [start[c], start[c+1])
  const std::uint32_t* start = nullptr;

  SPHFEM_HD int clampi(int v, int hi) const { return v < 0 ? 0 : (v > hi ? hi : v); }
  SPHFEM_HD void coords(const Vec3& p, int& ix, int& iy, int& iz) const {
    ix = clampi(int((p.x - lo.x) * inv_cell), nx - 1);
    iy = clampi(int((p.y - lo.y) * inv_cell), ny - 1);
    iz = clampi(int((p.z - lo.z) * inv_cell), nz - 1);
  }
  SPHFEM_HD std::uint32_t cell(const Vec3& p) const {
    int ix, iy, iz;
    coords(p, ix, iy, iz);
    return std::uint32_t((iz * ny + iy) * nx + ix);
  }
  SPHFEM_HD int cells() const { return nx * ny * nz; }
};

// The cells a query at xi visits: the 3 x 3 rows of up to three cells around its own, each
// trimmed to the cells that can hold a point within sqrt(h2) (cell size h: about a quarter of
// the 27 cells, the corners and most edges, are out of reach). The bound is the distance to
// the cell's faces less 1e-4 of a cell, so a cell whose index rounding put a point there is
// never skipped: the points found and their order are those of the full 27 cells.
struct CellRows {
  int ix, x0, x1, y0, y1, z0, z1, iy, iz;
  Real gap_lo[3], gap_hi[3], reach2;  // in cells: to the faces of xi's cell, squared; h2

  SPHFEM_HD CellRows(const GridView& g, const Vec3& xi, Real h2) {
    g.coords(xi, ix, iy, iz);
    x0 = ix > 0 ? ix - 1 : 0;
    x1 = ix < g.nx - 1 ? ix + 1 : g.nx - 1;
    y0 = iy > 0 ? iy - 1 : 0;
    y1 = iy < g.ny - 1 ? iy + 1 : g.ny - 1;
    z0 = iz > 0 ? iz - 1 : 0;
    z1 = iz < g.nz - 1 ? iz + 1 : g.nz - 1;
    const int own[3] = {ix, iy, iz};
    for (int a = 0; a < 3; ++a) {
      const Real f = (xi[a] - g.lo[a]) * g.inv_cell - Real(own[a]);
      Real lo = f - Real(1e-4), hi = Real(1) - f - Real(1e-4);
      lo = lo > Real(0) ? lo : Real(0);
      hi = hi > Real(0) ? hi : Real(0);
      gap_lo[a] = lo * lo;
      gap_hi[a] = hi * hi;
    }
    reach2 = h2 * g.inv_cell * g.inv_cell;
  }
  // f(b, e) for the index range [b, e) of each of the 3 x 3 rows in the grid's order (z outer,
  // y inner), trimmed to the cells within reach of xi, empty where none is. Without a branch:
  // a row beyond the grid's edge lies at an infinite distance (and reads its neighbour's
  // starts); the branches of the row loops were mispredicted several times a query.
  template <class F>
  SPHFEM_HD_INLINE void for_rows(const GridView& g, F&& f) const {
    const Real far = Real(3e38);
    const Real gy[3] = {iy > 0 ? gap_lo[1] : far, Real(0), iy < g.ny - 1 ? gap_hi[1] : far};
    const Real gz[3] = {iz > 0 ? gap_lo[2] : far, Real(0), iz < g.nz - 1 ? gap_hi[2] : far};
    const int ys[3] = {y0, iy, y1}, zs[3] = {z0, iz, z1};
    for (int dz = 0; dz < 3; ++dz)
      for (int dy = 0; dy < 3; ++dy) {
        const Real yz = gy[dy] + gz[dz];
        const int row = (zs[dz] * g.ny + ys[dy]) * g.nx;
        const int first = yz + gap_lo[0] < reach2 ? x0 : ix;
        const int last = yz + gap_hi[0] < reach2 ? x1 : ix;
        const std::uint32_t lo = g.start[row + first], hi = g.start[row + last + 1];
        const std::uint32_t in_reach = 0u - std::uint32_t(yz < reach2);  // g++ branched on ?:
        f(lo, lo + ((hi - lo) & in_reach));
      }
  }
};

// Calls f(j, rij, r2) for every particle j of `xs` (sorted into grid g) with
// |xi - xj|^2 < h2, i itself included.
template <class F>
SPHFEM_HD void for_neighbors(const GridView& g, const Vec3* xs, const Vec3& xi, Real h2, F&& f) {
  if (g.nx == 0) return;
  CellRows(g, xi, h2).for_rows(g, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t j = b; j < e; ++j) {
      const Vec3 rij = xi - xs[j];
      const Real r2 = norm2(rij);
      if (r2 < h2) f(j, rij, r2);
    }
  });
}

#if SPHFEM_GRID_PACK
// kPackHits[mask]: byte b is the lane of the b-th set bit of mask (the hits' lanes in order,
// for a permutation that packs them to the front).
constexpr std::array<std::uint64_t, 256> pack_hits_table() {
  std::array<std::uint64_t, 256> t{};
  for (int mask = 0; mask < 256; ++mask) {
    int b = 0;
    for (int lane = 0; lane < 8; ++lane)
      if (mask & (1 << lane)) t[std::size_t(mask)] |= std::uint64_t(lane) << (8 * b++);
  }
  return t;
}
inline constexpr std::array<std::uint64_t, 256> kPackHits = pack_hits_table();
#endif

#if SPHFEM_GRID_PACK
// collect_neighbors over the positions as planes into a contiguous list (step 1), eight
// candidates a time straight from the planes. The rows' groups of eight are laid out first,
// without a branch, and then scanned in one loop: a loop per row, whose length changed from
// row to row, had its exit missed by the branch predictor at nearly every row (nine a
// particle), and the scan had taken 6-8 ms of WCSPH's 19 ms step. A group's lanes past its
// row's end are masked out of the hits; their loads read up to seven Reals past the row, so
// each plane is followed by seven readable Reals (the z plane too: FluidBuffers::a). Masked
// loads instead made the scan 1.2x slower.
inline int collect_from_planes(const GridView& g, const Vec3& xi, Real h2, std::uint32_t* list,
                               int last, int count, const Real* planes, std::size_t stride,
                               Real* dist2 = nullptr) {
  typedef float F8 __attribute__((vector_size(32)));
  constexpr int kRowGroups = 4;  // a row of three cells at rest holds about 24 candidates
  const CellRows c(g, xi, h2);
  std::uint32_t from[9 * kRowGroups], to[9 * kRowGroups];
  int groups = 0;
  bool long_row = false;
  c.for_rows(g, [&](std::uint32_t b, std::uint32_t e) {
    const int n = int((e - b + 7) >> 3);
    long_row |= n > kRowGroups;
    for (int k = 0; k < kRowGroups; ++k) {
      from[groups + k] = b + 8 * std::uint32_t(k);
      to[groups + k] = e;
    }
    groups += n < kRowGroups ? n : kRowGroups;
  });
  const __m256 lim = _mm256_set1_ps(h2);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const F8 cx = F8(_mm256_set1_ps(xi.x)), cy = F8(_mm256_set1_ps(xi.y)),
           cz = F8(_mm256_set1_ps(xi.z));
  const Real *px = planes, *py = planes + stride, *pz = planes + 2 * stride;
  auto scan = [&](std::uint32_t j0, std::uint32_t end) {
    const __m256i in_row = _mm256_cmpgt_epi32(_mm256_set1_epi32(int(end - j0)), lane);
    // The scan's own arithmetic, lane by lane: (xi - x_j)^2 summed x, y, z.
    const F8 dx = cx - F8(_mm256_loadu_ps(px + j0));
    const F8 dy = cy - F8(_mm256_loadu_ps(py + j0));
    const F8 dz = cz - F8(_mm256_loadu_ps(pz + j0));
    const F8 r2 = dx * dx + dy * dy + dz * dz;
    const int hits = _mm256_movemask_ps(
        _mm256_and_ps(_mm256_cmp_ps(__m256(r2), lim, _CMP_LT_OQ), _mm256_castsi256_ps(in_row)));
    if (count + 8 <= last) {
      const __m256i to_front =
          _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kPackHits[hits])));
      const __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(int(j0)), lane);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + count),
                          _mm256_permutevar8x32_epi32(idx, to_front));
      if (dist2) _mm256_storeu_ps(dist2 + count, _mm256_permutevar8x32_ps(__m256(r2), to_front));
      count += __builtin_popcount(unsigned(hits));
    } else {
      for (int k = 0; k < 8; ++k)
        if (hits & (1 << k)) {
          if (dist2) dist2[count < last ? count : last] = r2[k];
          list[count < last ? count : last] = j0 + std::uint32_t(k), ++count;
        }
    }
  };
  if (!long_row) {
    for (int k = 0; k < groups; ++k) scan(from[k], to[k]);
    return count;
  }
  // A crowded row (rare): row by row, the scan's own loop over a row written out again;
  // behind a callback shared with for_neighbors the fast path above became 1.18x slower
  // (g++ 12).
  c.for_rows(g, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t j0 = b; j0 < e; j0 += 8) scan(j0, e);
  });
  return count;
}
#endif

#if SPHFEM_GRID_PACK
// for_neighbors whose candidates are first sifted eight at a time by their squared distances
// from the positions as planes (collect_neighbors' planes), against a bound a thousandth wider
// than h2; each candidate that passes is then tested and handed on exactly as for_neighbors
// does, so the calls, their arguments and their order are the same whatever the rounding of
// the sifting's arithmetic. The scalar test branched on every candidate, about one in six of
// them a hit.
template <class F>
__attribute__((always_inline)) inline void for_neighbors_planes(const GridView& g, const Vec3* xs,
                                                                const Real* planes,
                                                                std::size_t stride, const Vec3& xi,
                                                                Real h2, F&& f) {
  typedef float F8 __attribute__((vector_size(32)));
  if (g.nx == 0) return;
  const __m256 lim = _mm256_set1_ps(h2 * Real(1.001));
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const F8 cx = F8(_mm256_set1_ps(xi.x)), cy = F8(_mm256_set1_ps(xi.y)),
           cz = F8(_mm256_set1_ps(xi.z));
  const Real *px = planes, *py = planes + stride, *pz = planes + 2 * stride;
  CellRows(g, xi, h2).for_rows(g, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t j0 = b; j0 < e; j0 += 8) {
      const __m256i in_row = _mm256_cmpgt_epi32(_mm256_set1_epi32(int(e - j0)), lane);
      const F8 dx = cx - F8(_mm256_loadu_ps(px + j0));
      const F8 dy = cy - F8(_mm256_loadu_ps(py + j0));
      const F8 dz = cz - F8(_mm256_loadu_ps(pz + j0));
      const F8 r2 = dx * dx + dy * dy + dz * dz;
      unsigned near = unsigned(_mm256_movemask_ps(
          _mm256_and_ps(_mm256_cmp_ps(__m256(r2), lim, _CMP_LT_OQ), _mm256_castsi256_ps(in_row))));
      while (near) {
        const std::uint32_t j = j0 + std::uint32_t(__builtin_ctz(near));
        near &= near - 1;
        const Vec3 rij = xi - xs[j];
        const Real d2 = norm2(rij);
        if (d2 < h2) f(j, rij, d2);
      }
    }
  });
}
#endif

// for_neighbors, through for_neighbors_planes where the host has the positions as planes.
template <class F>
SPHFEM_HD void for_neighbors(const GridView& g, const Vec3* xs, const Real* planes,
                             std::size_t stride, const Vec3& xi, Real h2, F&& f) {
#if SPHFEM_GRID_PACK && !defined(__CUDA_ARCH__)
  if (planes) {
    for_neighbors_planes(g, xs, planes, stride, xi, h2, f);
    return;
  }
#endif
  for_neighbors(g, xs, xi, h2, f);
}

// The j of for_neighbors, in its order, stored from list[count * step] on; returns count plus
// their number. Entries from `last` on all land in list[last * step], so the list holds them
// all only when the count returned is at most `last`. The host stores every candidate and
// advances only over the hits (a branch on the hit, taken by about one candidate in six, was
// mispredicted at every turn), and takes a row's distances a chunk at a time in a vectorised
// loop first: the scan was half of a WCSPH step. With AVX2 the hits of eight candidates are
// packed and stored at once (the scalar loop took seven instructions a candidate).
//
// planes: the same positions as three arrays (all x, then all y, then all z, each `stride`
// long), or nullptr. The host reads eight candidates' coordinates there as three whole vectors
// instead of taking apart eight Vec3s (six permutes and six blends), with the same arithmetic.
// dist2: where that path (host, planes, step 1) also stores each hit's squared distance at its
// list index, as the scan computed it; nullptr, or any other path: nothing stored.
SPHFEM_HD int collect_neighbors(const GridView& g, const Vec3* xs, const Vec3& xi, Real h2,
                                std::uint32_t* list, std::size_t step, int last, int count,
                                const Real* planes = nullptr, std::size_t stride = 0,
                                Real* dist2 = nullptr) {
  if (g.nx == 0) return count;
#if SPHFEM_GRID_PACK && !defined(__CUDA_ARCH__)
  if (planes && step == 1)
    return collect_from_planes(g, xi, h2, list, last, count, planes, stride, dist2);
#endif
  CellRows(g, xi, h2).for_rows(g, [&](std::uint32_t first, std::uint32_t end) {
#if defined(__CUDA_ARCH__)
    for (std::uint32_t j = first; j < end; ++j) {
      const bool hit = norm2(xi - xs[j]) < h2;
      if (hit) list[std::size_t(count < last ? count : last) * step] = j;
      count += hit ? 1 : 0;
    }
#else
    constexpr int kChunk = 32;
    for (std::uint32_t j0 = first; j0 < end; j0 += kChunk) {
      const int m = end - j0 < std::uint32_t(kChunk) ? int(end - j0) : kChunk;
      // The positions as the floats they are (Vec3 is three Reals, no padding): g++ does not
      // vectorise member reads of a struct array.
      static_assert(sizeof(Vec3) == 3 * sizeof(Real), "Vec3 read as three Reals");
      Real r2[kChunk];
      if (planes) {
        const Real *px = planes + j0, *py = px + stride, *pz = py + stride;
#pragma omp simd
        for (int k = 0; k < m; ++k) {
          const Real dx = xi.x - px[k], dy = xi.y - py[k], dz = xi.z - pz[k];
          r2[k] = dx * dx + dy * dy + dz * dz;
        }
      } else {
        const Real* x = &xs[j0].x;
#pragma omp simd
        for (int k = 0; k < m; ++k) {
          const Real dx = xi.x - x[3 * k], dy = xi.y - x[3 * k + 1], dz = xi.z - x[3 * k + 2];
          r2[k] = dx * dx + dy * dy + dz * dz;
        }
      }
      if (step == 1 && count + m <= last) {
        int k = 0;
#if SPHFEM_GRID_PACK
        // Eight candidates a time: the hits' indices packed to the front of one vector and
        // stored whole (the slots past the hits are overwritten later or unused; they stay
        // below count + m <= last), the count advanced by the hits.
        const __m256 lim = _mm256_set1_ps(h2);
        __m256i idx =
            _mm256_add_epi32(_mm256_set1_epi32(int(j0)), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
        for (; k + 8 <= m; k += 8) {
          const int hits =
              _mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(r2 + k), lim, _CMP_LT_OQ));
          const __m256i to_front = _mm256_cvtepu8_epi32(
              _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kPackHits[hits])));
          _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + count),
                              _mm256_permutevar8x32_epi32(idx, to_front));
          count += __builtin_popcount(unsigned(hits));
          idx = _mm256_add_epi32(idx, _mm256_set1_epi32(8));
        }
#endif
        for (; k < m; ++k) {
          list[count] = j0 + std::uint32_t(k);
          count += r2[k] < h2 ? 1 : 0;
        }
      } else {
        for (int k = 0; k < m; ++k) {
          list[std::size_t(count < last ? count : last) * step] = j0 + std::uint32_t(k);
          count += r2[k] < h2 ? 1 : 0;
        }
      }
    }
#endif
  });
  return count;
}

}  // namespace sphfem
