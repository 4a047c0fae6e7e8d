// The node order of meshes we make: nodes along a space-filling curve, elements by their
// lowest node, so that each thread's static share of the elements writes what its share of
// the nodes gathers (docs/design.md, "Node order").
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "sphfem/fem/import.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/fem/tetrahedralize.h"

namespace sphfem {
namespace {

// The fraction of (element, node) incidences whose element and node fall in different halves
// when two threads split the elements and the nodes statically: what crosses between cores.
double crossing_share(const TetMesh& m) {
  const std::size_t ne = m.tets.size(), nn = m.x.size();
  long crossing = 0;
  for (std::size_t t = 0; t < ne; ++t)
    for (int v : m.tets[t].v) crossing += (2 * t >= ne) != (2 * std::size_t(v) >= nn);
  return double(crossing) / double(4 * ne);
}

// Each element as its four positions, in its own vertex order: the mesh up to numbering.
std::vector<std::vector<std::tuple<double, double, double>>> elements(const TetMesh& m) {
  std::vector<std::vector<std::tuple<double, double, double>>> e;
  for (const Tet& t : m.tets) {
    e.emplace_back();
    for (int v : t.v) e.back().emplace_back(m.x[v].x, m.x[v].y, m.x[v].z);
  }
  std::sort(e.begin(), e.end());
  return e;
}

TetMesh tetgen_box() {
  const TetMesh g = make_box(Vec3d(0, 0, 0), Vec3d(0.4, 0.3, 0.2), 8, 6, 4);
  SurfaceMesh s;
  s.x = g.x;
  s.tris = boundary_faces(g.tets);
  TetgenOptions o;
  o.max_volume = 2e-5;
  return tetrahedralize(s, o);
}

TEST(FemMeshOrder, ShuffledMeshRenumberedKeepsItsElementsAndLocality) {
  TetMesh m = make_sphere(Vec3d(), 0.1, 10);
  const auto before = elements(m);
  const double lattice_share = crossing_share(m);
  // The worst order a mesher could leave: nodes and elements shuffled.
  std::mt19937 rng(7);
  std::vector<int> perm(m.x.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = int(i);
  std::shuffle(perm.begin(), perm.end(), rng);
  TetMesh shuffled;
  shuffled.x.resize(m.x.size());
  for (std::size_t i = 0; i < perm.size(); ++i) shuffled.x[perm[i]] = m.x[i];
  for (Tet t : m.tets) {
    for (int& v : t.v) v = perm[v];
    shuffled.tets.push_back(t);
  }
  std::shuffle(shuffled.tets.begin(), shuffled.tets.end(), rng);
  const double shuffled_share = crossing_share(shuffled);
  order_for_locality(shuffled);
  const double ordered_share = crossing_share(shuffled);
  std::printf(
      "[ measured ] crossing share: the lattice's order %.3f, shuffled %.3f, renumbered %.3f\n",
      lattice_share, shuffled_share, ordered_share);
  // Shuffled, half the incidences cross; renumbered, about as few as the lattice's own slabs
  // (only the elements along the cut between the halves).
  EXPECT_GT(shuffled_share, 0.4);
  EXPECT_LT(ordered_share, 1.5 * lattice_share);
  // The same elements with the same vertex order (so the same orientation), renumbered.
  EXPECT_EQ(elements(shuffled), before);
  EXPECT_NO_THROW(validate_mesh(shuffled, "renumbered sphere"));
}

TEST(FemMeshOrder, TetgenMeshesComeOrderedAndKeepTheSurfaceVertices) {
  const TetMesh g = make_box(Vec3d(0, 0, 0), Vec3d(0.4, 0.3, 0.2), 8, 6, 4);
  const TetMesh m = tetgen_box();
  ASSERT_GT(m.tets.size(), 2000u);
  const double share = crossing_share(m);
  std::printf("[ measured ] TetGen box, %zu elements: crossing share %.3f\n", m.tets.size(), share);
  EXPECT_LT(share, 0.1);  // TetGen's own order: 0.47
  // Renumbered, but every vertex of the surface is still a node, at the same position.
  std::map<std::tuple<double, double, double>, int> at;
  for (std::size_t i = 0; i < m.x.size(); ++i) at[{m.x[i].x, m.x[i].y, m.x[i].z}] = int(i);
  for (const Vec3d& p : g.x)
    if (p.x == 0 || p.x == 0.4 || p.y == 0 || p.y == 0.3 || p.z == 0 || p.z == 0.2)
      EXPECT_EQ(at.count({p.x, p.y, p.z}), 1u);
  // A second run gives the same numbering (the order is a function of the positions).
  const TetMesh again = tetgen_box();
  ASSERT_EQ(again.x.size(), m.x.size());
  for (std::size_t i = 0; i < m.x.size(); ++i) EXPECT_EQ(again.x[i].x, m.x[i].x);
}

}  // namespace
}  // namespace sphfem
