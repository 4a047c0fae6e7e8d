#include "collide/host_build.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace sphfem::collide {

namespace {

constexpr int kBins = 16;
constexpr int kMedianDepth = 32;  // below this depth, splits are object medians

// The bin of a centroid coordinate c in [lo, lo + kBins / scale], in range whatever the input:
// coordinates near FLT_MAX or not finite make a centroid or its extent infinite, and then
// (c - lo) * scale NaN or out of range, which int() does not bring back (found by fuzzing the
// checkpoint reader: a body state loaded from a damaged checkpoint indexed bin -16).
int bin_of(Real c, Real lo, Real scale) {
  const Real t = (c - lo) * scale;
  return t >= Real(0) ? (t < Real(kBins - 1) ? int(t) : kBins - 1) : 0;
}

struct Box {
  Vec3 lo = Vec3(FLT_MAX, FLT_MAX, FLT_MAX), hi = Vec3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
  void grow(const Vec3& p) { lo = vmin(lo, p), hi = vmax(hi, p); }
  void grow(const Box& b) { lo = vmin(lo, b.lo), hi = vmax(hi, b.hi); }
  Real area() const { return lo.x <= hi.x ? half_area(lo, hi) : Real(0); }
};

class SahBuilder {
 public:
  SahBuilder(const Vec3* x, const Tri* tris, int n, int max_leaf, HostTree& out)
      : max_leaf_(max_leaf), out_(out), box_(n), centre_(n) {
    for (int f = 0; f < n; ++f) {
      for (int k = 0; k < 3; ++k) box_[f].grow(x[tris[f].v[k]]);
      centre_[f] = (box_[f].lo + box_[f].hi) * Real(0.5);
    }
    out_.prims.resize(n);
    for (int f = 0; f < n; ++f) out_.prims[f] = f;
    out_.nodes.reserve(2 * std::size_t(n));
    out_.parent.reserve(2 * std::size_t(n));
    out_.nodes.push_back(BvhNode{});
    out_.parent.push_back(-1);
    split(0, 0, n, 0);
  }

 private:
  void leaf(int node, int begin, int end, const Box& b, int depth) {
    out_.nodes[node] = BvhNode{b.lo, begin, b.hi, -(end - begin)};
    out_.leaves.push_back(node);
    out_.depth = std::max(out_.depth, depth);
  }

  void split(int node, int begin, int end, int depth) {
    int* prims = out_.prims.data();
    Box b, cb;
    for (int k = begin; k < end; ++k) {
      b.grow(box_[prims[k]]);
      cb.grow(centre_[prims[k]]);
    }
    const int n = end - begin;
    if (n <= 1) return leaf(node, begin, end, b, depth);

    // Best binned SAH split over the three axes; costs in units of one triangle test, with
    // one box-pair test per internal node.
    int best_axis = -1, best_bin = 0;
    Real best_cost = Real(FLT_MAX);
    if (depth < kMedianDepth) {
      for (int axis = 0; axis < 3; ++axis) {
        const Real lo = cb.lo[axis], ext = cb.hi[axis] - lo;
        if (!(ext > 0)) continue;
        const Real scale = Real(kBins) / ext;
        Box bins[kBins];
        int count[kBins] = {0};
        for (int k = begin; k < end; ++k) {
          const int f = prims[k];
          const int i = bin_of(centre_[f][axis], lo, scale);
          bins[i].grow(box_[f]);
          ++count[i];
        }
        Real right_area[kBins];
        int right_count[kBins];
        Box r;
        int rc = 0;
        for (int i = kBins - 1; i > 0; --i) {
          r.grow(bins[i]);
          rc += count[i];
          right_area[i] = r.area();
          right_count[i] = rc;
        }
        Box l;
        int lc = 0;
        for (int i = 0; i < kBins - 1; ++i) {
          l.grow(bins[i]);
          lc += count[i];
          if (lc == 0 || right_count[i + 1] == 0) continue;
          const Real cost = l.area() * lc + right_area[i + 1] * right_count[i + 1];
          if (cost < best_cost) best_cost = cost, best_axis = axis, best_bin = i;
        }
      }
    }
    const Real area = b.area();
    const bool fits = n <= max_leaf_;
    if (best_axis >= 0 && fits && Real(n) * area <= area + best_cost)
      return leaf(node, begin, end, b, depth);
    if (best_axis < 0 && fits) return leaf(node, begin, end, b, depth);

    int mid;
    if (best_axis >= 0) {
      const Real lo = cb.lo[best_axis];
      const Real scale = Real(kBins) / (cb.hi[best_axis] - lo);
      int* m = std::partition(prims + begin, prims + end, [&](int f) {
        return bin_of(centre_[f][best_axis], lo, scale) <= best_bin;
      });
      mid = int(m - prims);
    } else {
      // No usable split plane (all centroids equal, or too deep): object median on the
      // widest centroid axis, ties by id so the result is deterministic.
      const Vec3 e = cb.hi - cb.lo;
      const int axis = e.x >= e.y ? (e.x >= e.z ? 0 : 2) : (e.y >= e.z ? 1 : 2);
      mid = begin + n / 2;
      std::nth_element(prims + begin, prims + mid, prims + end, [&](int f, int g) {
        const Real a = centre_[f][axis], c = centre_[g][axis];
        return a < c || (a == c && f < g);
      });
    }
    const int left = int(out_.nodes.size());
    out_.nodes.push_back(BvhNode{});
    out_.nodes.push_back(BvhNode{});
    out_.parent.push_back(node);
    out_.parent.push_back(node);
    out_.nodes[node] = BvhNode{b.lo, left, b.hi, left + 1};
    split(left, begin, mid, depth + 1);
    split(left + 1, mid, end, depth + 1);
  }

  int max_leaf_;
  HostTree& out_;
  std::vector<Box> box_;
  std::vector<Vec3> centre_;
};

}  // namespace

HostTree build_sah_tree(const Vec3* x, const Tri* tris, int ntris, int max_leaf) {
  HostTree t;
  if (ntris <= 0) return t;
  SahBuilder(x, tris, ntris, std::max(1, max_leaf), t);
  return t;
}

SurfaceTopology surface_topology(const Tri* tris, int ntris) {
  SurfaceTopology s;
  int nv = 0;
  for (int f = 0; f < ntris; ++f)
    for (int k = 0; k < 3; ++k) {
      if (tris[f].v[k] < 0)
        throw std::invalid_argument("collide: triangle " + std::to_string(f) +
                                    " has a negative vertex index");
      nv = std::max(nv, tris[f].v[k] + 1);
    }
  s.nverts = nv;
  // Edges keyed by their sorted vertex pair; a key held by exactly two faces joins them.
  std::vector<std::pair<std::uint64_t, int>> edges;
  edges.reserve(3 * std::size_t(ntris));
  for (int f = 0; f < ntris; ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = std::uint32_t(tris[f].v[k]),
                          b = std::uint32_t(tris[f].v[(k + 1) % 3]);
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      edges.emplace_back(key, 3 * f + k);
    }
  std::sort(edges.begin(), edges.end());
  s.nbr.assign(3 * std::size_t(ntris), -1);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 2) {
      s.nbr[edges[i].second] = edges[i + 1].second / 3;
      s.nbr[edges[i + 1].second] = edges[i].second / 3;
    }
    i = j;
  }
  s.vstart.assign(nv + 1, 0);
  for (int f = 0; f < ntris; ++f)
    for (int k = 0; k < 3; ++k) ++s.vstart[tris[f].v[k] + 1];
  for (int i = 0; i < nv; ++i) s.vstart[i + 1] += s.vstart[i];
  s.vfaces.resize(3 * std::size_t(ntris));
  std::vector<int> fill(s.vstart.begin(), s.vstart.end() - 1);
  for (int f = 0; f < ntris; ++f)
    for (int k = 0; k < 3; ++k) s.vfaces[fill[tris[f].v[k]]++] = f;
  return s;
}

}  // namespace sphfem::collide
