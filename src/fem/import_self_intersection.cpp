// Self-intersection search over a triangle surface: candidate pairs from a uniform grid over
// the triangles' bounds, then a separating-axis test per pair.
//
// Neighbours touch by construction, so a pair sharing an edge only counts when it is folded
// flat onto itself, and a pair sharing a vertex is tested with that vertex as the origin: it
// then projects to exactly 0 on every axis and touching there is never mistaken for crossing.
// Triangles that share no vertex must stay apart: touching is as fatal to TetGen as crossing
// (a vertex resting on another part's face stops it on an internal assertion).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

using Tri3 = std::array<Vec3d, 3>;

// True when the axis separates the triangles: one ends at most `margin` past the other's
// start (a negative margin asks for a gap).
bool separates(Vec3d axis, const Tri3& a, const Tri3& b, double margin) {
  const double len = norm(axis);
  if (!(len > 0.0)) return false;
  axis = axis / len;
  double a_lo = 1e300, a_hi = -1e300, b_lo = 1e300, b_hi = -1e300;
  for (int k = 0; k < 3; ++k) {
    const double pa = dot(a[k], axis), pb = dot(b[k], axis);
    a_lo = std::min(a_lo, pa);
    a_hi = std::max(a_hi, pa);
    b_lo = std::min(b_lo, pb);
    b_hi = std::max(b_hi, pb);
  }
  return a_hi <= b_lo + margin || b_hi <= a_lo + margin;
}

bool within_plane(const Tri3& t, const Vec3d& p, const Vec3d& unit_n, double tol) {
  for (const Vec3d& q : t)
    if (std::fabs(dot(q - p, unit_n)) > tol) return false;
  return true;
}

// Separating-axis test of two triangles, coordinates relative to a common origin. Coplanar
// pairs are tested in their plane (edge normals); others on the two face normals and the
// nine edge-edge cross products, which suffice for triangles (Eberly, "Intersection of
// Convex Objects: The Method of Separating Axes"). `margin` as for separates.
bool triangles_cross(const Tri3& a, const Tri3& b, double tol, double margin) {
  const Vec3d ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
  const Vec3d eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
  Vec3d na = cross(ea[0], ea[1]), nb = cross(eb[0], eb[1]);
  na = na / norm(na);
  nb = nb / norm(nb);
  const bool b_on_a = within_plane(b, a[0], na, tol);
  if (b_on_a || within_plane(a, b[0], nb, tol)) {
    const Vec3d n = b_on_a ? na : nb;
    for (int k = 0; k < 3; ++k)
      if (separates(cross(n, ea[k]), a, b, margin) || separates(cross(n, eb[k]), a, b, margin))
        return false;
    return true;
  }
  if (separates(na, a, b, margin) || separates(nb, a, b, margin)) return false;
  for (const Vec3d& u : ea)
    for (const Vec3d& w : eb) {
      const Vec3d c = cross(u, w);
      if (norm(c) <= 1e-12 * norm(u) * norm(w)) continue;  // parallel edges: no axis
      if (separates(c, a, b, margin)) return false;
    }
  return true;
}

// Whether triangles ta and tb of the surface intersect other than where they must touch.
bool pair_crosses(const SurfaceMesh& s, const Tri& ta, const Tri& tb, double tol) {
  int shared = 0, sa[3], sb[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (ta.v[i] == tb.v[j]) {
        sa[shared] = i;
        sb[shared] = j;
        ++shared;
      }
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 2) {
    // Apart from their edge, two triangles on it can only meet when folded onto each other:
    // the far vertex of one lies in the other's plane, on the same side of the edge.
    const Vec3d p = s.x[ta.v[sa[0]]], e = s.x[ta.v[sa[1]]] - p;
    const Vec3d ca = s.x[ta.v[3 - sa[0] - sa[1]]], cb = s.x[tb.v[3 - sb[0] - sb[1]]];
    Vec3d n = cross(e, ca - p);
    n = n / norm(n);
    return std::fabs(dot(cb - p, n)) <= tol && dot(cross(e, ca - p), cross(e, cb - p)) > 0.0;
  }
  const Vec3d o = shared == 1 ? s.x[ta.v[sa[0]]] : s.x[ta.v[0]];
  Tri3 a, b;
  for (int k = 0; k < 3; ++k) {
    a[k] = s.x[ta.v[k]] - o;
    b[k] = s.x[tb.v[k]] - o;
  }
  return triangles_cross(a, b, tol, shared == 1 ? tol : -tol);
}

// Calls visit(ta, tb, tol) once for each pair of triangles whose bounds overlap.
template <class Visit>
void overlapping_pairs(const SurfaceMesh& s, Visit&& visit) {
  const int nt = int(s.tris.size());
  if (nt < 2) return;
  const auto [lo, hi] = bounds(s.x);
  const double tol = 1e-9 * norm(hi - lo);

  std::vector<Vec3d> box_lo(nt), box_hi(nt);
  double mean_extent = 0.0;
  for (int t = 0; t < nt; ++t) {
    const Tri& tri = s.tris[t];
    box_lo[t] = vmin(s.x[tri.v[0]], vmin(s.x[tri.v[1]], s.x[tri.v[2]]));
    box_hi[t] = vmax(s.x[tri.v[0]], vmax(s.x[tri.v[1]], s.x[tri.v[2]]));
    const Vec3d d = box_hi[t] - box_lo[t];
    mean_extent += std::max(d.x, std::max(d.y, d.z)) / nt;
  }

  // Cells about the size of a triangle; coarser when large triangles would fill too many.
  double h = std::max(mean_extent, 1e-6 * norm(hi - lo));
  std::vector<std::pair<std::int64_t, int>> entries;  // (cell, triangle)
  auto cell = [&](double v, double o) { return std::int64_t(std::floor((v - o) / h)); };
  auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return (i * 2097152 + j) * 2097152 + k;  // 2^21 cells a side at most
  };
  for (;;) {
    entries.clear();
    bool fits = true;
    for (int t = 0; t < nt && fits; ++t) {
      const Vec3d a = box_lo[t] - Vec3d(tol, tol, tol), b = box_hi[t] + Vec3d(tol, tol, tol);
      for (std::int64_t i = cell(a.x, lo.x); i <= cell(b.x, lo.x); ++i)
        for (std::int64_t j = cell(a.y, lo.y); j <= cell(b.y, lo.y); ++j)
          for (std::int64_t k = cell(a.z, lo.z); k <= cell(b.z, lo.z); ++k)
            entries.push_back({key(i + 1, j + 1, k + 1), t});
      fits = entries.size() <= std::size_t(64) * nt;
    }
    if (fits) break;
    h *= 2.0;
  }
  std::sort(entries.begin(), entries.end());

  for (std::size_t g = 0; g < entries.size();) {
    std::size_t e = g + 1;
    while (e < entries.size() && entries[e].first == entries[g].first) ++e;
    for (std::size_t p = g; p < e; ++p)
      for (std::size_t q = p + 1; q < e; ++q) {
        const int ta = entries[p].second, tb = entries[q].second;
        const Vec3d olo = vmax(box_lo[ta], box_lo[tb]), ohi = vmin(box_hi[ta], box_hi[tb]);
        if (olo.x > ohi.x + tol || olo.y > ohi.y + tol || olo.z > ohi.z + tol) continue;
        // A pair overlaps in several cells; test it only in the cell of its overlap's corner.
        const Vec3d c = olo - Vec3d(tol, tol, tol);
        if (key(cell(c.x, lo.x) + 1, cell(c.y, lo.y) + 1, cell(c.z, lo.z) + 1) != entries[g].first)
          continue;
        visit(std::min(ta, tb), std::max(ta, tb), tol);
      }
    g = e;
  }
}

}  // namespace

std::pair<int, int> find_self_intersection(const SurfaceMesh& s) {
  std::pair<int, int> first{-1, -1};
  overlapping_pairs(s, [&](int ta, int tb, double tol) {
    const std::pair<int, int> pr{ta, tb};
    if (first.first >= 0 && pr >= first) return;  // report the lowest pair
    if (pair_crosses(s, s.tris[ta], s.tris[tb], tol)) first = pr;
  });
  return first;
}

long count_self_intersections(const SurfaceMesh& s) {
  long n = 0;
  overlapping_pairs(s, [&](int ta, int tb, double tol) {
    if (pair_crosses(s, s.tris[ta], s.tris[tb], tol)) ++n;
  });
  return n;
}

}  // namespace sphfem
