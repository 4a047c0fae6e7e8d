// Flat caps on a nearly flat base: a soft block whose base is a fine grid with small bumps
// (like a scanned shape's "flat" bottom), tetrahedralised by TetGen, resting on the floor.
// TetGen leaves elements whose four nodes all lie in the base; the floor presses them to zero
// volume. Peeling them (peel_flat_caps) keeps the surface closed and the volume, and no
// element is flattened.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sphfem/fem/contact.h"
#include "sphfem/fem/import.h"
#include "sphfem/fem/tetrahedralize.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

constexpr double kBump = 4e-4;  // m, height of the base's bumps

// The boundary of a 0.1 x 0.05 x 0.1 m box lattice of 10 x 2 x 10 cells, its base's inner
// nodes raised by up to kBump (a fixed pseudo-random pattern).
SurfaceMesh bumpy_block() {
  const TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(0.1, 0.05, 0.1), 10, 2, 10);
  SurfaceMesh s;
  s.source = "bumpy block";
  s.x = box.x;
  s.tris = boundary_faces(box.tets);
  unsigned h = 12345;
  for (Vec3d& x : s.x) {
    h = h * 1103515245u + 12345u;
    const bool inner = x.x > 1e-9 && x.x < 0.1 - 1e-9 && x.z > 1e-9 && x.z < 0.1 - 1e-9;
    if (x.y < 1e-9 && inner) x.y = kBump * double((h >> 16) % 1000) / 1000.0;
  }
  return s;
}

// Elements with all four nodes in the base's layer: a floor flattens them.
int elements_in_the_base(const TetMesh& m) {
  int n = 0;
  for (const Tet& t : m.tets) {
    bool all = true;
    for (int v : t.v) all = all && m.x[std::size_t(v)].y <= kBump + 1e-12;
    n += all;
  }
  return n;
}

// Meshed as it is (TetGen adds no inner node: every element spans surface nodes) and with a
// volume bound (inner nodes); in both, what leaves is in the bumps' layer: the block's edges,
// where large elements are flat for their size but not for the surface's, are kept.
TEST(FemPeelCaps, PeelsTheBaseCapsAndKeepsAClosedSurface) {
  const SurfaceMesh s = bumpy_block();
  for (double max_volume : {0.0, 2e-7}) {
    TetgenOptions o;
    o.quality = 0;
    o.max_volume = max_volume;
    const TetMesh raw = tetrahedralize(s, o);
    o.peel_caps = 0.3;
    const TetMesh peeled = tetrahedralize(s, o);
    const double v0 = mesh_volume(raw), v1 = mesh_volume(peeled);
    std::printf(
        "[ measured ] max_volume %g: %zu -> %zu elements, %d -> %d in the base, volume %.3e of "
        "the whole\n",
        max_volume, raw.tets.size(), peeled.tets.size(), elements_in_the_base(raw),
        elements_in_the_base(peeled), (v0 - v1) / v0);
    if (max_volume == 0.0) {
      EXPECT_GT(elements_in_the_base(raw), 0) << "the input no longer has caps to test with";
    }
    EXPECT_EQ(elements_in_the_base(peeled), 0);
    EXPECT_NO_THROW(validate_mesh(peeled, "peeled"));
    // The surface stays closed, manifold and consistently oriented, and encloses the mesh.
    SurfaceMesh b;
    b.source = "peeled block";
    b.x = peeled.x;
    b.tris = boundary_faces(peeled.tets);
    EXPECT_NO_THROW(check_surface(b));
    EXPECT_NEAR(enclosed_volume(b.x, b.tris), v1, 1e-12);
    // At most a tenth of the bumps' layer under the base (0.1 x 0.1 m) leaves.
    EXPECT_LT(v0 - v1, 0.1 * kBump * 0.1 * 0.1);
    EXPECT_GE(v0 - v1, 0.0);
    TetMesh again = peeled;
    EXPECT_EQ(peel_flat_caps(again, 0.0), 0);
  }
}

// An ear: one element standing on a face of a cube's mesh, its tip held by nothing else. A
// tip lower than 0.3 of the surface's median edge is peeled with its node; a tall one stays.
TEST(FemPeelCaps, PeelsLowEarsWithTheirTip) {
  for (double height : {0.1, 0.5}) {
    TetMesh m = make_box(Vec3d(0, 0, 0), Vec3d(1, 1, 1), 2, 2, 2);
    const std::size_t nodes = m.x.size(), elements = m.tets.size();
    const std::vector<Tri> faces = boundary_faces(m.tets);
    const Tri& f = faces.front();
    const Vec3d a = m.x[std::size_t(f.v[0])], b = m.x[std::size_t(f.v[1])],
                c = m.x[std::size_t(f.v[2])];
    const Vec3d n = cross(b - a, c - a) / norm(cross(b - a, c - a));  // outward
    m.x.push_back((a + b + c) / 3.0 + n * height);
    // The face is counter-clockwise seen from outside: with the tip above it, (a, b, c, tip)
    // is positively oriented.
    m.tets.push_back(Tet{{f.v[0], f.v[1], f.v[2], int(nodes)}});
    ASSERT_GT(tet_volume(m, int(elements)), 0.0);
    const int peeled = peel_flat_caps(m, 0.3);
    std::printf("[ measured ] ear %.1f of the cube's half-edge high: %d peeled\n", height / 0.5,
                peeled);
    EXPECT_EQ(peeled, height < 0.15 ? 1 : 0);
    EXPECT_EQ(m.x.size(), height < 0.15 ? nodes : nodes + 1);
    EXPECT_NO_THROW(validate_mesh(m, "ear"));
  }
}

// The block, soft and heavy (E = 30 kPa, 1,500 kg/m3, as the paper's bunny), set on the floor:
// its weight presses the bumpy base flat. Without peeling, elements end at zero volume.
int worst_inverted_on_the_floor(double peel) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sphfem_peel_" + std::to_string(peel));
  std::filesystem::create_directories(dir);
  const SurfaceMesh s = bumpy_block();
  {
    std::ofstream obj(dir / "block.obj");
    obj.precision(17);
    for (const Vec3d& x : s.x) obj << "v " << x.x << ' ' << x.y << ' ' << x.z << '\n';
    for (const Tri& t : s.tris)
      obj << "f " << t.v[0] + 1 << ' ' << t.v[1] + 1 << ' ' << t.v[2] + 1 << '\n';
  }
  nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.002},
    "domain": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]},
    "bodies": [{"name": "block", "shape": "mesh", "file": "block.obj", "offset": [0.05, 0.0002, 0.05],
                "quality": 0,
                "material": {"density": 1500, "young": 3e4, "poisson": 0.4,
                             "damping_alpha": 1.0, "damping_beta": 0.002}}]
  })");
  j["bodies"][0]["peel_caps"] = peel;
  const std::string file = (dir / "block.json").string();
  const SceneSpec scene = parse_scene(j, file);
  validate_scene(scene, file);
  Simulation sim(scene, Backend::Cpu);
  const BodiesModel& m = sim.bodies_model();
  int worst = 0;
  BodySnapshot b;
  while (sim.time() < 0.3 - 1e-9) {
    sim.step(0.002);  // without fluid the caller sets the step (as run.cpp does)
    sim.bodies()->snapshot(b);
    worst = std::max(worst, inverted_elements(m, b.x));
  }
  std::filesystem::remove_all(dir);
  return worst;
}

TEST(FemPeelCaps, NoElementIsFlattenedOnTheFloor) {
  const int raw = worst_inverted_on_the_floor(0.0), peeled = worst_inverted_on_the_floor(0.3);
  std::printf("[ measured ] elements of zero or negative volume at most: %d raw, %d peeled\n", raw,
              peeled);
  EXPECT_GT(raw, 0) << "the floor no longer flattens the raw mesh's caps: a weaker test";
  EXPECT_EQ(peeled, 0);
}

}  // namespace
}  // namespace sphfem
