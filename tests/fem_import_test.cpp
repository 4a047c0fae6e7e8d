// Importing bodies: surfaces through Assimp (vertex and triangle counts after merging), the
// surface checks that stand before TetGen (each failure its own message, naming the file and
// the fix), tetrahedralisation (positive tetrahedra filling exactly the enclosed volume), and
// tetrahedral-mesh files (TetGen, Gmsh 2.2 and 4.1) with their orientation check.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>

#include "sphfem/fem/import.h"
#include "sphfem/fem/tetrahedralize.h"

using namespace sphfem;
namespace fs = std::filesystem;

namespace {

std::string data(const std::string& name) {
  return std::string(SPHFEM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

class FemImportFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("sphfem_import_" + std::string(info->name()) + "_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  void spit(const std::string& name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
  }

  fs::path dir_;
};

// The message of the MeshError that f throws ("" when it throws none), checked to be one line.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const MeshError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  ADD_FAILURE() << "no MeshError";
  return "";
}

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

// Icosahedron subdivided `levels` times onto the sphere; outward, counter-clockwise.
SurfaceMesh icosphere(double r, int levels) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  SurfaceMesh s;
  s.x = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
         {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  s.tris = {{{0, 11, 5}}, {{0, 5, 1}},  {{0, 1, 7}},   {{0, 7, 10}}, {{0, 10, 11}},
            {{1, 5, 9}},  {{5, 11, 4}}, {{11, 10, 2}}, {{10, 7, 6}}, {{7, 1, 8}},
            {{3, 9, 4}},  {{3, 4, 2}},  {{3, 2, 6}},   {{3, 6, 8}},  {{3, 8, 9}},
            {{4, 9, 5}},  {{2, 4, 11}}, {{6, 2, 10}},  {{8, 6, 7}},  {{9, 8, 1}}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      s.x.push_back((s.x[a] + s.x[b]) * 0.5);
      return mid[key] = int(s.x.size()) - 1;
    };
    std::vector<Tri> finer;
    for (const Tri& t : s.tris) {
      const int a = midpoint(t.v[0], t.v[1]), b = midpoint(t.v[1], t.v[2]),
                c = midpoint(t.v[2], t.v[0]);
      finer.push_back({{t.v[0], a, c}});
      finer.push_back({{t.v[1], b, a}});
      finer.push_back({{t.v[2], c, b}});
      finer.push_back({{a, b, c}});
    }
    s.tris = finer;
  }
  for (Vec3d& x : s.x) x = x * (r / norm(x));
  return s;
}

// Binary STL: 80-byte header, triangle count, then per triangle a normal, three corners and a
// 16-bit attribute, all little-endian (this test runs on little-endian machines only).
void write_binary_stl(const std::string& path, const SurfaceMesh& s) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = "binary STL written by fem_import_test";
  out.write(header, 80);
  const std::uint32_t n = std::uint32_t(s.tris.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const Tri& t : s.tris) {
    const Vec3d nrm = cross(s.x[t.v[1]] - s.x[t.v[0]], s.x[t.v[2]] - s.x[t.v[0]]);
    float f[12] = {float(nrm.x), float(nrm.y), float(nrm.z)};
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 3; ++k) f[3 + 3 * a + k] = float(s.x[t.v[a]][k]);
    out.write(reinterpret_cast<const char*>(f), sizeof f);
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

double min_tet_volume(const TetMesh& m) {
  double v = 1e300;
  for (std::size_t t = 0; t < m.tets.size(); ++t) v = std::min(v, tet_volume(m, int(t)));
  return v;
}

double max_tet_volume(const TetMesh& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.tets.size(); ++t) v = std::max(v, tet_volume(m, int(t)));
  return v;
}

}  // namespace

// --- surface import ---

TEST(FemImportSurface, ObjQuadsSplitByNormalAndObjectMergeIntoEightCorners) {
  const SurfaceMesh s = load_surface(data("cube.obj"));
  EXPECT_EQ(s.x.size(), 8u);
  EXPECT_EQ(s.tris.size(), 12u);
  EXPECT_EQ(s.source, data("cube.obj"));
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), 1.0, 1e-12);  // outward, as written
  EXPECT_NO_THROW(check_surface(s));
}

TEST(FemImportSurface, AsciiStlRepeatsCornersPerFacetAndMergesThem) {
  const SurfaceMesh s = load_surface(data("cube_ascii.stl"));
  EXPECT_EQ(s.x.size(), 8u);
  EXPECT_EQ(s.tris.size(), 12u);
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), 1.0, 1e-12);
  EXPECT_NO_THROW(check_surface(s));
}

TEST(FemImportSurface, PlyQuadsAreTriangulated) {
  const SurfaceMesh s = load_surface(data("cube.ply"));
  EXPECT_EQ(s.x.size(), 8u);
  EXPECT_EQ(s.tris.size(), 12u);
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), 1.0, 1e-12);
}

TEST_F(FemImportFiles, BinaryStlOfAnIcosphereKeepsItsTopology) {
  const SurfaceMesh ico = icosphere(0.5, 2);  // 162 vertices, 320 triangles
  write_binary_stl(file("ico.stl"), ico);
  const SurfaceMesh s = load_surface(file("ico.stl"));
  EXPECT_EQ(s.x.size(), 162u);
  EXPECT_EQ(s.tris.size(), 320u);
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), enclosed_volume(ico.x, ico.tris), 1e-6);
  EXPECT_NO_THROW(check_surface(s));
}

TEST(FemImportSurface, TransformScalesThenTranslates) {
  SurfaceMesh s = load_surface(data("cube.obj"));
  transform(s, 0.2, Vec3d(1, 2, 3));
  const auto [lo, hi] = bounds(s.x);
  EXPECT_NEAR(lo.x, 1.0, 1e-12);
  EXPECT_NEAR(lo.y, 2.0, 1e-12);
  EXPECT_NEAR(lo.z, 3.0, 1e-12);
  EXPECT_NEAR(hi.x, 1.2, 1e-12);
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), 0.008, 1e-12);
}

TEST_F(FemImportFiles, SurfaceFileErrorsNameTheFile) {
  const std::string missing = file("nothing.obj");
  std::string m = error_of([&] { load_surface(missing); });
  EXPECT_EQ(m.rfind(missing + ": ", 0), 0u) << m;
  EXPECT_HAS(m, "cannot open");

  spit("noise.xyz", "this is not a mesh format\n");
  m = error_of([&] { load_surface(file("noise.xyz")); });
  EXPECT_EQ(m.rfind(file("noise.xyz") + ": ", 0), 0u) << m;
  EXPECT_HAS(m, "cannot read it as a surface mesh");
  EXPECT_HAS(m, "OBJ, PLY or STL");

  spit("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
  m = error_of([&] { load_surface(file("lines.obj")); });
  EXPECT_HAS(m, "no triangles");
}

// Assimp allocates for the counts a PLY header gives (a face count of 2^32 - 1 asked for 64 GiB:
// found by fuzzing), so the counts must fit in the bytes after the header.
TEST_F(FemImportFiles, PlyHeaderCountsMustFitTheFile) {
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string faces = "property list uchar int vertex_indices\nend_header\n";
  spit("faces.ply", "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz +
                        "element face 4294967295\n" + faces + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  std::string m = error_of([&] { load_surface(file("faces.ply")); });
  EXPECT_EQ(m.rfind(file("faces.ply") + ": the PLY header announces 4294967295 'face' elements", 0),
            0u)
      << m;

  spit("wraps.ply", "ply\nformat ascii 1.0\nelement vertex 18446744073709551615\n" + xyz +
                        "end_header\n0 0 0\n");
  m = error_of([&] { load_surface(file("wraps.ply")); });
  EXPECT_HAS(m, "announces 18446744073709551615 'vertex' elements");

  // Assimp never returns from a header whose only "end_header" ends a comment.
  spit("comment.ply", "ply\nformat ascii 1.0\ncomment the end_header\n0 0 0\n");
  m = error_of([&] { load_surface(file("comment.ply")); });
  EXPECT_HAS(m, "no end_header line");

  // Assimp sizes the vertices by the first "element vertex" and writes those of the second.
  spit("twice.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "element vertex 3\n" + xyz +
                        "end_header\n0 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  m = error_of([&] { load_surface(file("twice.ply")); });
  EXPECT_HAS(m, "declares the element 'vertex' twice");

  spit("minus.ply", "ply\nformat ascii 1.0\nelement vertex -1\n" + xyz + "end_header\n");
  m = error_of([&] { load_surface(file("minus.ply")); });
  EXPECT_HAS(m, "element 'vertex' has no count");

  // Binary: 8 vertices of 12 bytes and 6 quads of 17 bytes; 100 bytes cannot hold the vertices
  // and 6 lists of at least their count's byte.
  std::string body;
  auto put = [&](const void* p, std::size_t n) { body.append(static_cast<const char*>(p), n); };
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) {
      const float c = float((i >> k) & 1);
      put(&c, 4);
    }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    const std::uint8_t four = 4;
    put(&four, 1);
    put(q, 16);
  }
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 8\n" + xyz + "element face 6\n" + faces;
  spit("cube.ply", head + body);
  const SurfaceMesh s = load_surface(file("cube.ply"));
  EXPECT_EQ(s.tris.size(), 12u);
  EXPECT_NEAR(enclosed_volume(s.x, s.tris), 1.0, 1e-12);
  spit("short.ply", head + body.substr(0, 100));
  m = error_of([&] { load_surface(file("short.ply")); });
  EXPECT_HAS(m, "announces 6 'face' elements, more than the 100 bytes after the header");
}

// --- surface checks ---

TEST(FemImportCheck, OpenSurfaceCountsItsBoundaryEdges) {
  const SurfaceMesh s = load_surface(data("open_cube.obj"));
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_EQ(m.rfind(data("open_cube.obj") + ": the surface is open: 4 boundary edges", 0), 0u) << m;
  EXPECT_HAS(m, ", 1)");  // the first one is on the missing top face, z = 1
  EXPECT_HAS(m, "Close Holes");
}

TEST(FemImportCheck, ThreeTrianglesOnOneEdgeAreNotManifold) {
  const SurfaceMesh s = load_surface(data("fin_cube.obj"));
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_HAS(m, data("fin_cube.obj") + ": the surface is not manifold");
  EXPECT_HAS(m, "shared by 3 triangles");
  EXPECT_HAS(m, "(0, 0, 0)");
}

TEST(FemImportCheck, InterpenetratingSurfacesIntersect) {
  const SurfaceMesh s = load_surface(data("two_tets.obj"));
  const auto [a, b] = find_self_intersection(s);
  EXPECT_GE(a, 0);
  EXPECT_LT(a, 4);  // one triangle of each tetrahedron
  EXPECT_GE(b, 4);
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_HAS(m, data("two_tets.obj") + ": the surface intersects itself");
  EXPECT_HAS(m, "Self Intersecting Faces");
}

TEST(FemImportCheck, ApartTetrahedraAndFineSpheresDoNotIntersect) {
  SurfaceMesh s = load_surface(data("two_tets.obj"));
  for (int v = 4; v < 8; ++v) s.x[v] += Vec3d(1.5, 0, 0);  // move the second one clear
  EXPECT_EQ(find_self_intersection(s), std::make_pair(-1, -1));
  EXPECT_NO_THROW(check_surface(s));
  EXPECT_EQ(find_self_intersection(icosphere(1.0, 4)), std::make_pair(-1, -1));
}

TEST(FemImportCheck, OverlappingSpheresIntersectSeparateOnesDoNot) {
  // Two spheres of radius 1 whose centres are 1.9 apart overlap; 2.1 apart they do not.
  for (double gap : {1.9, 2.1}) {
    SurfaceMesh a = icosphere(1.0, 3), b = icosphere(1.0, 3);
    const int n = int(a.x.size());
    for (Vec3d& x : b.x) a.x.push_back(x + Vec3d(gap, 0.01, 0.02));
    for (Tri t : b.tris) {
      for (int& v : t.v) v += n;
      a.tris.push_back(t);
    }
    EXPECT_EQ(find_self_intersection(a).first >= 0, gap < 2.0) << gap;
  }
}

TEST(FemImportCheck, NeighboursCountOnlyWhenTheyOverlap) {
  // Pairs of triangles in the plane z = 0, sharing a vertex or an edge.
  auto crossing = [](std::vector<Vec3d> x, std::vector<Tri> t) {
    SurfaceMesh s;
    s.x = std::move(x);
    s.tris = std::move(t);
    return find_self_intersection(s).first >= 0;
  };
  const Vec3d o(0, 0, 0), a(1, 0, 0), b(0, 1, 0), c(1, 1, 0), d(-1, 1, 0);
  EXPECT_FALSE(crossing({o, a, c, b}, {{{0, 1, 2}}, {{0, 2, 3}}}));  // flat across edge 0-2
  EXPECT_TRUE(crossing({o, a, c, Vec3d(2, 1, 0)}, {{{0, 1, 2}}, {{0, 2, 3}}}));  // folded
  EXPECT_FALSE(crossing({o, a, b, d}, {{{0, 1, 2}}, {{0, 2, 3}}}));              // edge 0-2, fan
  EXPECT_FALSE(crossing({o, a, c, b, d}, {{{0, 1, 2}}, {{0, 3, 4}}}));           // vertex 0, a gap
  EXPECT_TRUE(crossing({o, a, c, Vec3d(2, 1, 0), b}, {{{0, 1, 2}}, {{0, 3, 4}}}));  // overlap
  // Vertex 0 shared, the second triangle standing up through the first.
  EXPECT_TRUE(
      crossing({o, a, b, Vec3d(0.3, 0.3, -1), Vec3d(0.3, 0.3, 1)}, {{{0, 1, 2}}, {{0, 3, 4}}}));
  EXPECT_FALSE(
      crossing({o, a, b, Vec3d(-0.3, -0.3, -1), Vec3d(-0.3, -0.3, 1)}, {{{0, 1, 2}}, {{0, 3, 4}}}));
}

TEST(FemImportCheck, GeneratedMeshSurfacesPassAndMeshAgain) {
  // Boundaries of the lattice generators: large flat fans of coplanar triangles (box) and a
  // curved, finely split surface (ball); TetGen must fill the same volume.
  for (const TetMesh& g :
       {make_box(Vec3d(0, 0, 0), Vec3d(0.4, 0.3, 0.2), 8, 6, 4), make_sphere(Vec3d(), 0.1, 6)}) {
    SurfaceMesh s;
    s.x = g.x;
    s.tris = boundary_faces(g.tets);
    EXPECT_NO_THROW(check_surface(s));
    const TetMesh m = tetrahedralize(s, {});
    EXPECT_NEAR(mesh_volume(m), mesh_volume(g), 1e-9 * mesh_volume(g));
  }
}

TEST(FemImportCheck, PartsThatOnlyTouchAreRejected) {
  // A small tetrahedron standing with one vertex on the cube's top face: closed, manifold
  // and crossing nothing, but TetGen cannot mesh parts in contact.
  SurfaceMesh s = load_surface(data("cube.obj"));
  const int n = int(s.x.size());
  for (const Vec3d& x :
       {Vec3d(0.3, 0.4, 1.0), Vec3d(0.2, 0.3, 1.5), Vec3d(0.5, 0.3, 1.5), Vec3d(0.3, 0.6, 1.5)})
    s.x.push_back(x);
  for (const Tri& t : {Tri{{1, 2, 3}}, Tri{{0, 3, 2}}, Tri{{0, 1, 3}}, Tri{{0, 2, 1}}})
    s.tris.push_back(Tri{{n + t.v[0], n + t.v[1], n + t.v[2]}});
  EXPECT_HAS(error_of([&] { tetrahedralize(s, {}); }), "the surface intersects itself");
  for (int v = n; v < n + 4; ++v) s.x[v].z += 1e-3;  // lifted clear, it meshes
  EXPECT_NO_THROW(tetrahedralize(s, {}));
}

TEST(FemImportCheck, FlippedTriangleBreaksOrientation) {
  SurfaceMesh s = load_surface(data("cube.obj"));
  std::swap(s.tris[5].v[0], s.tris[5].v[1]);
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_HAS(m, "not consistently oriented");
  EXPECT_HAS(m, "Re-Orient all faces coherently");
}

TEST(FemImportCheck, SolidsTouchingInOneVertexAreNotManifold) {
  // Two tetrahedra sharing only vertex 0: every edge has two triangles, the vertex two fans.
  SurfaceMesh s;
  s.source = "bowtie";
  s.x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  s.tris = {{{1, 2, 3}}, {{0, 3, 2}}, {{0, 1, 3}}, {{0, 2, 1}},
            {{4, 5, 6}}, {{0, 6, 5}}, {{0, 4, 6}}, {{0, 5, 4}}};
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_EQ(m.rfind("bowtie: the surface is not manifold at vertex 0 (0, 0, 0)", 0), 0u) << m;
}

TEST(FemImportCheck, DegenerateTriangleIsReported) {
  SurfaceMesh s = load_surface(data("cube.obj"));
  s.x[s.tris[0].v[2]] = (s.x[s.tris[0].v[0]] + s.x[s.tris[0].v[1]]) * 0.5;  // collinear
  const std::string m = error_of([&] { check_surface(s); });
  EXPECT_HAS(m, "triangle 0");
  EXPECT_HAS(m, "zero area");
}

// --- tetrahedralisation ---

TEST(FemImportTetgen, SwitchesFollowTheOptions) {
  EXPECT_EQ(tetgen_switches({}), "pq1.414Q");
  TetgenOptions o;
  o.max_volume = 1e-6;
  EXPECT_EQ(tetgen_switches(o), "pq1.414a1e-06Q");
  o.quality = 0.0;
  o.quiet = false;
  o.max_volume = 0.0;
  EXPECT_EQ(tetgen_switches(o), "p");
}

TEST(FemImportTetgen, CubeFillsItsVolumeWithPositiveTets) {
  const SurfaceMesh s = load_surface(data("cube.obj"));
  TetgenOptions o;
  o.max_volume = 0.002;
  const TetMesh m = tetrahedralize(s, o);
  EXPECT_NO_THROW(validate_mesh(m, "cube"));
  EXPECT_GT(min_tet_volume(m), 0.0);
  EXPECT_LE(max_tet_volume(m), o.max_volume * (1 + 1e-9));
  EXPECT_GE(m.tets.size(), 500u);  // 1 m^3 in pieces of at most 0.002 m^3
  EXPECT_NEAR(mesh_volume(m), 1.0, 0.01);
  EXPECT_NEAR(enclosed_volume(m.x, boundary_faces(m.tets)), 1.0, 1e-9);
  // Every vertex of the surface is a node (renumbered for locality: tests/fem_mesh_order_test).
  std::map<std::tuple<double, double, double>, int> node;
  for (std::size_t i = 0; i < m.x.size(); ++i) node[{m.x[i].x, m.x[i].y, m.x[i].z}] = int(i);
  for (const Vec3d& p : s.x) EXPECT_EQ(node.count({p.x, p.y, p.z}), 1u);
}

TEST_F(FemImportFiles, IcosphereFromBinaryStlMatchesItsEnclosedVolume) {
  write_binary_stl(file("ico.stl"), icosphere(0.1, 3));
  const SurfaceMesh s = load_surface(file("ico.stl"));
  const double enclosed = enclosed_volume(s.x, s.tris);
  for (double max_volume : {0.0, 2e-5}) {
    TetgenOptions o;
    o.max_volume = max_volume;
    const TetMesh m = tetrahedralize(s, o);
    EXPECT_GT(min_tet_volume(m), 0.0);
    EXPECT_NEAR(mesh_volume(m), enclosed, 0.01 * enclosed);
    EXPECT_NEAR(mesh_volume(m), enclosed, 1e-9 * enclosed);  // TetGen keeps the surface
    if (max_volume > 0) { EXPECT_LE(max_tet_volume(m), max_volume * (1 + 1e-9)); }
  }
}

TEST(FemImportTetgen, UnfitSurfacesStopBeforeTetgen) {
  for (const char* name : {"open_cube.obj", "fin_cube.obj", "two_tets.obj"}) {
    const SurfaceMesh s = load_surface(data(name));
    std::string check, mesh;
    try {
      check_surface(s);
    } catch (const MeshError& e) { check = e.what(); }
    mesh = error_of([&] { tetrahedralize(s, {}); });
    EXPECT_FALSE(check.empty()) << name;
    EXPECT_EQ(mesh, check) << name;
  }
}

// --- tetrahedral-mesh files ---

TEST(FemImportTetMesh, TetgenCubeNumberedFromOneByEitherFile) {
  for (const char* name : {"cube.node", "cube.ele"}) {
    const TetMesh m = load_tet_mesh(data(name));
    EXPECT_EQ(m.x.size(), 8u);
    EXPECT_EQ(m.tets.size(), 6u);
    EXPECT_NEAR(mesh_volume(m), 1.0, 1e-12);
    EXPECT_EQ(m.tets[0].v[3], 7);  // node 8 of the file
    EXPECT_EQ(m.x[7].x, 1.0);
  }
}

TEST(FemImportTetMesh, TetgenNumberedFromZeroWithAttributesAndMarkers) {
  const TetMesh m = load_tet_mesh(data("single_tet.node"));
  ASSERT_EQ(m.x.size(), 4u);
  ASSERT_EQ(m.tets.size(), 1u);
  EXPECT_EQ(m.tets[0].v[0], 0);
  EXPECT_EQ(m.tets[0].v[3], 3);
  EXPECT_NEAR(mesh_volume(m), 4.0, 1e-12);
}

TEST(FemImportTetMesh, GmshFormatsSkipOtherElementsAndUnusedNodes) {
  for (const char* name : {"cube_v22.msh", "cube_v41.msh"}) {
    const TetMesh m = load_tet_mesh(data(name));
    EXPECT_EQ(m.x.size(), 8u) << name;  // node 9 belongs to a point element only
    EXPECT_EQ(m.tets.size(), 6u) << name;
    EXPECT_NEAR(mesh_volume(m), 1.0, 1e-12) << name;
    EXPECT_NEAR(enclosed_volume(m.x, boundary_faces(m.tets)), 1.0, 1e-12) << name;
  }
}

TEST(FemImportTetMesh, InvertedTetIsAnErrorNotARepair) {
  const std::string m = error_of([] { load_tet_mesh(data("inverted.ele")); });
  EXPECT_EQ(m.rfind(data("inverted.ele") + ": tet 4 has negative volume (-0.167 m^3)", 0), 0u) << m;
  EXPECT_HAS(m, "clockwise");
  EXPECT_HAS(m, "reorder them");
}

TEST_F(FemImportFiles, FlatTetIsAnError) {
  spit("flat.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n");
  spit("flat.ele", "1 4 0\n7 1 2 3 4\n");
  const std::string m = error_of([&] { load_tet_mesh(file("flat.node")); });
  EXPECT_HAS(m, "tet 7 has zero volume");
}

TEST_F(FemImportFiles, TetMeshFileErrors) {
  std::string m = error_of([&] { load_tet_mesh(file("absent.msh")); });
  EXPECT_EQ(m.rfind(file("absent.msh") + ": cannot open the file", 0), 0u) << m;

  m = error_of([&] { load_tet_mesh(file("absent.node")); });
  EXPECT_HAS(m, "cannot open");

  m = error_of([&] { load_tet_mesh(file("mesh.vtk")); });
  EXPECT_HAS(m, "unknown tetrahedral mesh format '.vtk'");

  spit("bin.msh", "$MeshFormat\n2.2 1 8\n$EndMeshFormat\n");
  m = error_of([&] { load_tet_mesh(file("bin.msh")); });
  EXPECT_HAS(m, "binary");
  EXPECT_HAS(m, "-format msh22");

  spit("old.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n");
  EXPECT_HAS(error_of([&] { load_tet_mesh(file("old.msh")); }), "format 4 is not supported");

  spit("hex.msh",
       "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n"
       "5 5 0 1 1 1 1 1 1 1 1\n$EndElements\n");
  m = error_of([&] { load_tet_mesh(file("hex.msh")); });
  EXPECT_HAS(m, "line 10: element 5 is a volume element of type 5");

  spit("short.node", "8 3 0 0\n1 0 0 0\n");
  spit("short.ele", "1 4 0\n1 1 2 3 4\n");
  EXPECT_HAS(error_of([&] { load_tet_mesh(file("short.ele")); }), "the file ends before");

  spit("bad.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 x 0\n4 0 0 1\n");
  spit("bad.ele", "1 4 0\n1 1 2 3 4\n");
  EXPECT_HAS(error_of([&] { load_tet_mesh(file("bad.ele")); }),
             "line 4: expected a number (y), found 'x'");

  spit("dangling.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  spit("dangling.ele", "1 4 0\n1 1 2 3 5\n");
  EXPECT_HAS(error_of([&] { load_tet_mesh(file("dangling.ele")); }),
             "tet 1 refers to node 5, which the file does not define");
}
