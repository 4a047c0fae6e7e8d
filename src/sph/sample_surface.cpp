// Boundary samples on triangle surfaces (sph/moving_boundary.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "sphfem/sph/moving_boundary.h"

namespace sphfem {

namespace {

struct Key {
  long long x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
};

struct KeyHash {
  std::size_t operator()(const Key& k) const {
    std::uint64_t h = std::uint64_t(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= std::uint64_t(k.y) + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= std::uint64_t(k.z) + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
    return std::size_t(h);
  }
};

template <class V>
std::vector<SurfaceSample> sample(const std::vector<V>& x, const std::vector<Tri>& tris,
                                  double spacing) {
  if (!(spacing > 0))
    throw std::invalid_argument("sample_surface: spacing must be positive (got " +
                                std::to_string(spacing) + ")");
  // Two triangles compute a shared corner in a different order: equal within round-off, so
  // positions are compared on a grid far finer than the spacing. A pair that still rounds
  // apart stays as two samples on one spot, which psi weighs as one.
  const double tol = 1e-6 * spacing;
  std::unordered_map<Key, int, KeyHash> seen;
  std::vector<SurfaceSample> out;
  const int nodes = int(x.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Tri& tr = tris[t];
    for (int c = 0; c < 3; ++c)
      if (tr.v[c] < 0 || tr.v[c] >= nodes)
        throw std::invalid_argument("sample_surface: triangle " + std::to_string(t) +
                                    " names node " + std::to_string(tr.v[c]) + " of " +
                                    std::to_string(nodes));
    const Vec3d a(x[tr.v[0]]), b(x[tr.v[1]]), c(x[tr.v[2]]);
    const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    const int n = std::max(1, int(std::ceil(longest / spacing - 1e-9)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double w1 = double(i) / n, w2 = double(j) / n, w0 = double(n - i - j) / n;
        const Vec3d p = a * w0 + b * w1 + c * w2;
        const Key key{std::llround(p.x / tol), std::llround(p.y / tol), std::llround(p.z / tol)};
        if (!seen.emplace(key, int(out.size())).second) continue;
        SurfaceSample s;
        s.tri = int(t);
        s.w[0] = Real(w0);
        s.w[1] = Real(w1);
        s.w[2] = Real(w2);
        out.push_back(s);
      }
  }
  return out;
}

}  // namespace

std::vector<SurfaceSample> sample_surface(const std::vector<Vec3d>& x, const std::vector<Tri>& tris,
                                          double spacing) {
  return sample(x, tris, spacing);
}

std::vector<SurfaceSample> sample_surface(const std::vector<Vec3>& x, const std::vector<Tri>& tris,
                                          double spacing) {
  return sample(x, tris, spacing);
}

}  // namespace sphfem
