// Renumbering a tetrahedral mesh so that nearby nodes, and the elements on them, sit near
// each other in the arrays.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "collide/lbvh.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

void order_for_locality(TetMesh& m) {
  if (m.x.empty()) return;
  Vec3d lo = m.x[0], hi = m.x[0];
  for (const Vec3d& p : m.x)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  // One scale for the three axes: the curve's cells are cubes, not stretched with the box.
  // The BVH's 30-bit codes (1,024 cells an axis); nodes sharing a cell keep their old order.
  const double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const double inv = side > 0 ? 1.0 / side : 0.0;
  std::vector<std::pair<std::uint32_t, int>> key(m.x.size());
  for (std::size_t i = 0; i < m.x.size(); ++i)
    key[i] = {collide::morton30(Vec3((m.x[i] - lo) * inv)), int(i)};
  std::sort(key.begin(), key.end());  // ties by old index: the pair's second
  std::vector<int> to(m.x.size());
  std::vector<Vec3d> x(m.x.size());
  for (std::size_t k = 0; k < key.size(); ++k) {
    to[std::size_t(key[k].second)] = int(k);
    x[k] = m.x[std::size_t(key[k].second)];
  }
  m.x = std::move(x);
  for (Tet& t : m.tets)
    for (int& v : t.v) v = to[std::size_t(v)];
  auto sum = [](const Tet& t) { return long(t.v[0]) + t.v[1] + t.v[2] + t.v[3]; };
  std::stable_sort(m.tets.begin(), m.tets.end(),
                   [&](const Tet& p, const Tet& q) { return sum(p) < sum(q); });
}

}  // namespace sphfem
