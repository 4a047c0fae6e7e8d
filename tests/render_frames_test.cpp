// From frame files to what the renderers draw: body surfaces read back from VTU with their
// cells, split into one mesh per body; smooth normals; the bounds of a frame.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "sphfem/io/vtu.h"
#include "sphfem/render/frame.h"
#include "sphfem/render/frame_io.h"

namespace sphfem::render {
namespace {

namespace fs = std::filesystem;

// Two bodies: a triangle (body 0) and a quad of two triangles (body 1), plus a stray vertex.
io::PointSet two_bodies() {
  io::PointSet ps;
  ps.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0,           // body 0
                  2, 0, 0, 3, 0, 0, 3, 1, 0, 2, 1, 0,  // body 1
                  9, 9, 9};                            // unused
  ps.connectivity = {0, 1, 2, 3, 4, 5, 3, 5, 6};
  ps.offsets = {3, 6, 9};
  ps.types = {io::kVtkTriangle, io::kVtkTriangle, io::kVtkTriangle};
  ps.cell_data.push_back({"body", 1, {}, {0, 1, 1}});
  ps.point_data.push_back({"velocity", 3, std::vector<float>(3 * 8, 0.5f), {}});
  return ps;
}

TEST(RenderFrames, BodySurfacesReadBackAndSplitByBody) {
  const fs::path dir =
      fs::temp_directory_path() / ("sphfem_render_frames_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "bodies_000000.vtu").string();
  io::write_vtu(path, two_bodies());
  const io::PointSet back = io::read_vtu(path);
  fs::remove_all(dir);
  EXPECT_EQ(back.connectivity, two_bodies().connectivity);
  EXPECT_EQ(back.offsets, two_bodies().offsets);
  EXPECT_EQ(back.types, two_bodies().types);
  ASSERT_EQ(back.cell_data.size(), 1u);
  EXPECT_EQ(back.cell_data[0].ivalues, (std::vector<std::int32_t>{0, 1, 1}));

  const std::vector<TriangleMesh> meshes = body_meshes(back);
  ASSERT_EQ(meshes.size(), 2u);
  EXPECT_EQ(meshes[0].positions.size(), 9u);
  EXPECT_EQ(meshes[0].indices, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(meshes[1].positions.size(), 12u);
  EXPECT_EQ(meshes[1].indices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(meshes[1].positions[0], 2.0f);
  // Each body its own colour.
  EXPECT_GT(norm(meshes[0].color - meshes[1].color), 0.1);
}

TEST(RenderFrames, PointCloudReadsBackWithoutCells) {
  const fs::path dir =
      fs::temp_directory_path() / ("sphfem_render_cloud_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "fluid_000000.vtu").string();
  io::PointSet cloud;
  cloud.positions = {0, 0, 0, 1, 2, 3};
  io::write_vtu(path, cloud);
  const io::PointSet back = io::read_vtu(path);
  fs::remove_all(dir);
  EXPECT_EQ(back.positions, cloud.positions);
  EXPECT_TRUE(back.types.empty());
  EXPECT_TRUE(body_meshes(back).empty());
}

TEST(RenderFrames, SmoothNormalsOfAFoldAverageItsFaces) {
  TriangleMesh m;
  // Two triangles sharing the edge (0,0,0)-(1,0,0): one in the z = 0 plane, one in y = 0.
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, -1};
  m.indices = {0, 1, 2, 0, 1, 3};
  const std::vector<float> n = smooth_normals(m);
  ASSERT_EQ(n.size(), 12u);
  // Vertex 2 only in the first face: +z. Vertex 3 only in the second: +y.
  EXPECT_NEAR(n[8], 1.0f, 1e-6);
  EXPECT_NEAR(n[10], 1.0f, 1e-6);
  // Shared vertices: halfway, unit length.
  EXPECT_NEAR(n[1], std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(n[2], std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(std::hypot(n[3], n[4], n[5]), 1.0, 1e-6);
}

TEST(RenderFrames, BoundsCoverTankParticlesAndMeshes) {
  RenderFrame f;
  Vec3d lo, hi;
  EXPECT_FALSE(frame_bounds(f, &lo, &hi));
  f.radius = 0.1f;
  f.particles = {0, 0, 0, 1, 1, 1, NAN, 0, 0};
  TriangleMesh m;
  m.positions = {-2, 0, 0, 0, 3, 0, 0, 0, 0};
  m.indices = {0, 1, 2};
  f.meshes.push_back(m);
  ASSERT_TRUE(frame_bounds(f, &lo, &hi));
  EXPECT_NEAR(lo.x, -2, 1e-6);
  EXPECT_NEAR(lo.y, -0.1, 1e-6);
  EXPECT_NEAR(hi.y, 3, 1e-6);
  EXPECT_NEAR(hi.z, 1.1, 1e-6);
}

}  // namespace
}  // namespace sphfem::render
