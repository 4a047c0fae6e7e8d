// Generated tetrahedral meshes: every tetrahedron positively oriented, total volume equal to
// the shape's (exactly for boxes and for the tube's polygonal prism, within the stated
// discretisation error for curved surfaces), and a boundary surface that is closed and
// consistently oriented, has the expected Euler characteristic, and encloses (divergence
// theorem) exactly the sum of the tetrahedron volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <utility>

#include "sphfem/fem/mesh.h"

using namespace sphfem;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct SurfaceReport {
  bool closed_oriented = true;  // every directed edge once, and its reverse once
  int euler = 0;                // V - E + F over the surface
};

SurfaceReport check_surface(const std::vector<Tri>& tris) {
  SurfaceReport r;
  std::map<std::pair<int, int>, int> directed;
  std::set<int> verts;
  for (const Tri& t : tris)
    for (int a = 0; a < 3; ++a) {
      ++directed[{t.v[a], t.v[(a + 1) % 3]}];
      verts.insert(t.v[a]);
    }
  for (const auto& [e, count] : directed) {
    auto rev = directed.find({e.second, e.first});
    if (count != 1 || rev == directed.end() || rev->second != 1) r.closed_oriented = false;
  }
  const int edges = int(directed.size()) / 2;
  r.euler = int(verts.size()) - edges + int(tris.size());
  return r;
}

double min_volume(const TetMesh& m) {
  double v = 1e300;
  for (std::size_t t = 0; t < m.tets.size(); ++t) v = std::min(v, tet_volume(m, int(t)));
  return v;
}

void expect_valid(const TetMesh& m, int euler) {
  EXPECT_GT(min_volume(m), 0.0);
  EXPECT_NO_THROW(validate_mesh(m, "generated"));
  const std::vector<Tri> s = boundary_faces(m.tets);
  const SurfaceReport r = check_surface(s);
  EXPECT_TRUE(r.closed_oriented);
  EXPECT_EQ(r.euler, euler);
  const double v = mesh_volume(m);
  EXPECT_NEAR(enclosed_volume(m.x, s), v, 1e-12 * std::fabs(v) + 1e-15);
}

}  // namespace

TEST(FemMesh, BoxIsExactAndClosed) {
  const TetMesh m = make_box(Vec3d(-0.1, 0.2, 0.3), Vec3d(0.4, 0.5, 0.9), 5, 3, 4);
  EXPECT_EQ(m.tets.size(), 6u * 5 * 3 * 4);
  EXPECT_EQ(m.x.size(), 6u * 4 * 5);
  EXPECT_NEAR(mesh_volume(m), 0.5 * 0.3 * 0.6, 1e-12);
  expect_valid(m, 2);
}

TEST(FemMesh, ClothIsOneLayerSlab) {
  const TetMesh m = make_cloth(Vec3d(0.5, 0.8, 0.5), 0.6, 0.4, 0.005, 12, 8);
  EXPECT_EQ(m.tets.size(), 6u * 12 * 8);
  EXPECT_EQ(m.x.size(), 2u * 13 * 9);
  EXPECT_NEAR(mesh_volume(m), 0.6 * 0.4 * 0.005, 1e-14);
  expect_valid(m, 2);
}

TEST(FemMesh, SphereIsBallWithConvergingVolume) {
  // The mesh is inscribed: its surface nodes lie on the sphere, so its volume is below
  // 4/3 pi R^3 by a relative error of order (cell / R)^2: 7.1 %, 1.9 %, 0.47 % at 4, 8 and
  // 16 cells across, each halving of the cell size cutting it about fourfold.
  const double R = 0.25, exact = 4.0 / 3.0 * kPi * R * R * R;
  double last_err = 1.0;
  for (int cells : {4, 8, 16}) {
    const TetMesh m = make_sphere(Vec3d(1, 2, 3), R, cells);
    EXPECT_EQ(m.tets.size(), 6u * cells * cells * cells);
    expect_valid(m, 2);
    for (const Vec3d& x : m.x) EXPECT_LE(norm(x - Vec3d(1, 2, 3)), R * (1 + 1e-12));
    const double err = (exact - mesh_volume(m)) / exact;
    std::printf("[ measured ] sphere, %d cells across: volume error %.3g %%\n", cells, 100 * err);
    EXPECT_GT(err, 0.0);
    EXPECT_LT(err, 0.3 * last_err) << cells;
    last_err = err;
  }
  EXPECT_LT(last_err, 0.005);
}

TEST(FemMesh, TubeIsPolygonalPrismAnnulus) {
  // Nodes on circles: the mesh is exactly the annulus between two regular N-gons, area
  // N/2 sin(2 pi / N) (r_out^2 - r_in^2); its boundary is a torus (Euler characteristic 0).
  const double ri = 0.05, ro = 0.08, L = 0.3;
  for (int seg : {8, 24}) {
    const TetMesh m = make_tube(Vec3d(0.3, 0.1, 0.3), ri, ro, L, seg, 2, 10);
    EXPECT_EQ(m.tets.size(), 6u * seg * 2 * 10);
    const double prism = 0.5 * seg * std::sin(2 * kPi / seg) * (ro * ro - ri * ri) * L;
    EXPECT_NEAR(mesh_volume(m), prism, 1e-12);
    expect_valid(m, 0);
  }
}

TEST(FemMesh, CupIsOpenHollowCylinderWithBottom) {
  // Wall between r_in and r_out on the outer lattice rings, a solid bottom below: a ball
  // topologically (Euler characteristic 2). Inscribed polygons on the outer and the inner
  // wall make errors of opposite sign; the net is under 1 % from 8 cells across.
  const double ri = 0.08, ro = 0.1, H = 0.2, hb = 0.02;
  const double exact = kPi * ro * ro * hb + kPi * (ro * ro - ri * ri) * (H - hb);
  for (int cells : {8, 16}) {
    const TetMesh m = make_cup(Vec3d(0.5, 0.0, 0.5), ri, ro, H, hb, cells);
    expect_valid(m, 2);
    const double err = (exact - mesh_volume(m)) / exact;
    std::printf("[ measured ] cup, %d cells across: volume error %.3g %%\n", cells, 100 * err);
    EXPECT_LT(std::fabs(err), 0.01) << cells;
    double ymax = 0, rmin_top = 1;
    for (const Vec3d& x : m.x) {
      ymax = std::max(ymax, x.y);
      if (x.y > H - 1e-9) rmin_top = std::min(rmin_top, std::hypot(x.x - 0.5, x.z - 0.5));
    }
    EXPECT_NEAR(ymax, H, 1e-12);
    EXPECT_NEAR(rmin_top, ri * std::cos(kPi / (4 * cells)), 0.2 * ri);  // open inside
  }
}

TEST(FemMesh, ValidationNamesTheProblem) {
  TetMesh m = make_box(Vec3d(0, 0, 0), Vec3d(1, 1, 1), 1, 1, 1);
  std::swap(m.tets[2].v[0], m.tets[2].v[1]);
  try {
    validate_mesh(m, "body 'jelly'");
    FAIL() << "an inverted tetrahedron passed validation";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tetrahedron 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("jelly"), std::string::npos) << e.what();
  }
}
