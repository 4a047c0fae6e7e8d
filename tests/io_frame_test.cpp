// Frame writers: VTU and PLY round trips, file layout, and atomic replacement on failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/frame.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/vtu.h"

namespace sphfem::io {
namespace {
namespace fs = std::filesystem;

// A scratch folder per test, removed afterwards.
class IoFrameTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("sphfem_io_" + std::string(info->test_suite_name()) + "_" +
                                        info->name() + "_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void spit(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Values that only survive a bit-exact path: signed zero, subnormals, NaN payloads, infinities.
float tricky(std::size_t i) {
  switch (i % 7) {
    case 0:
      return -0.0f;
    case 1:
      return std::numeric_limits<float>::denorm_min();
    case 2: {
      std::uint32_t bits = 0x7fc01234u;
      float f;
      std::memcpy(&f, &bits, 4);
      return f;
    }
    case 3:
      return -std::numeric_limits<float>::infinity();
    case 4:
      return std::numeric_limits<float>::max();
    case 5:
      return 0.1f * static_cast<float>(i);
    default:
      return -1.0f / 3.0f;
  }
}

PointSet cloud(std::size_t n) {
  PointSet f;
  for (std::size_t i = 0; i < 3 * n; ++i) f.positions.push_back(tricky(i) + (i % 3 ? 0 : 1e-3f));
  DataArray density{"density", 1, {}, {}};
  DataArray velocity{"velocity", 3, {}, {}};
  DataArray id{"id", 1, {}, {}};
  DataArray stress{"stress", 6, {}, {}};
  for (std::size_t i = 0; i < n; ++i) {
    density.values.push_back(1000.0f + tricky(i + 5));
    id.ivalues.push_back(static_cast<std::int32_t>(i) * -7 + 3);
    for (int c = 0; c < 3; ++c) velocity.values.push_back(tricky(3 * i + c + 1));
    for (int c = 0; c < 6; ++c) stress.values.push_back(tricky(6 * i + c + 2) * 2.0f);
  }
  f.point_data = {density, velocity, id, stress};
  return f;
}

// Two triangles sharing an edge, with one array per cell.
PointSet two_triangles() {
  PointSet f;
  f.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  f.point_data.push_back({"pressure", 1, {1.5f, 2.5f, 3.5f, 4.5f}, {}});
  f.connectivity = {0, 1, 2, 0, 2, 3};
  f.offsets = {3, 6};
  f.types = {kVtkTriangle, kVtkTriangle};
  f.cell_data.push_back({"area", 1, {0.5f, 0.5f}, {}});
  f.cell_data.push_back({"label", 1, {}, {7, 9}});
  return f;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), 4 * a.size()) == 0);
}

void expect_same_points(const PointSet& want, const PointSet& got) {
  EXPECT_TRUE(same_bits(want.positions, got.positions));
  ASSERT_EQ(want.point_data.size(), got.point_data.size());
  for (std::size_t i = 0; i < want.point_data.size(); ++i) {
    const auto& w = want.point_data[i];
    const auto& g = got.point_data[i];
    EXPECT_EQ(w.name, g.name);
    EXPECT_EQ(w.components, g.components) << w.name;
    EXPECT_TRUE(same_bits(w.values, g.values)) << w.name;
    EXPECT_EQ(w.ivalues, g.ivalues) << w.name;
  }
}

// The raw bytes between the '_' marker and the closing tag of the appended section.
std::string appended_bytes(const std::string& text) {
  const std::size_t start = text.find('_', text.find("<AppendedData")) + 1;
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  EXPECT_EQ(text.compare(text.size() - tail.size(), tail.size(), tail), 0);
  return text.substr(start, text.size() - tail.size() - start);
}

std::uint64_t u64_at(const std::string& s, std::size_t at) {
  std::uint64_t v;
  std::memcpy(&v, s.data() + at, 8);
  return v;
}

TEST_F(IoFrameTest, VtuRoundTripIsBitExact) {
  const PointSet f = cloud(23);
  write_vtu(file("a.vtu"), f);
  expect_same_points(f, read_vtu_points(file("a.vtu")));
}

TEST_F(IoFrameTest, VtuRoundTripWithCells) {
  const PointSet f = two_triangles();
  write_vtu(file("tri.vtu"), f);
  expect_same_points(f, read_vtu_points(file("tri.vtu")));
}

TEST_F(IoFrameTest, VtuHeaderIsAppendedRawXml) {
  write_vtu(file("a.vtu"), cloud(4));
  const std::string text = slurp(file("a.vtu"));
  EXPECT_EQ(text.rfind("<?xml", 0), 0u);
  EXPECT_NE(text.find("type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(text.find("<UnstructuredGrid>"), std::string::npos);
  EXPECT_NE(text.find("header_type=\"UInt64\""), std::string::npos);
  EXPECT_NE(text.find("byte_order=\"LittleEndian\""), std::string::npos);
  EXPECT_NE(text.find("format=\"appended\""), std::string::npos);
  EXPECT_NE(text.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_NE(text.find("NumberOfPoints=\"4\" NumberOfCells=\"4\""), std::string::npos);
  EXPECT_NE(text.find("type=\"Int32\" Name=\"id\""), std::string::npos);
}

TEST_F(IoFrameTest, VtuCloudGetsOneVertexCellPerPoint) {
  const std::size_t n = 9;
  const PointSet f = cloud(n);
  write_vtu(file("a.vtu"), f);
  const std::string bytes = appended_bytes(slurp(file("a.vtu")));

  // Layout: each point array, then points, connectivity, offsets, types; each block is a
  // UInt64 byte count followed by the bytes.
  std::size_t expected = 0;
  for (const auto& a : f.point_data) expected += 8 + 4 * a.size();
  expected += 8 + 12 * n;  // points
  expected += 8 + 4 * n;   // connectivity
  expected += 8 + 4 * n;   // offsets
  expected += 8 + n;       // types
  EXPECT_EQ(bytes.size(), expected);

  const std::size_t types_at = bytes.size() - n - 8;
  EXPECT_EQ(u64_at(bytes, types_at), n);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(bytes[types_at + 8 + i], char(kVtkVertex));
  const std::size_t offsets_at = types_at - 4 * n - 8;
  EXPECT_EQ(u64_at(bytes, offsets_at), 4 * n);
  const std::size_t conn_at = offsets_at - 4 * n - 8;
  for (std::size_t i = 0; i < n; ++i) {
    std::int32_t c, o;
    std::memcpy(&c, bytes.data() + conn_at + 8 + 4 * i, 4);
    std::memcpy(&o, bytes.data() + offsets_at + 8 + 4 * i, 4);
    EXPECT_EQ(c, static_cast<std::int32_t>(i));
    EXPECT_EQ(o, static_cast<std::int32_t>(i + 1));
  }
}

TEST_F(IoFrameTest, VtuAppendedSizeWithCellsAndCellData) {
  const PointSet f = two_triangles();
  write_vtu(file("tri.vtu"), f);
  const std::string text = slurp(file("tri.vtu"));
  EXPECT_NE(text.find("NumberOfPoints=\"4\" NumberOfCells=\"2\""), std::string::npos);
  EXPECT_NE(text.find("<CellData>\n        <DataArray type=\"Float32\" Name=\"area\""),
            std::string::npos);
  EXPECT_NE(text.find("type=\"Int32\" Name=\"label\""), std::string::npos);
  const std::string bytes = appended_bytes(text);
  const std::size_t expected = (8 + 16) + (8 + 8) + (8 + 8) + (8 + 48) + (8 + 24) + (8 + 8) +
                               (8 + 2);  // pressure, area, label, points, conn, offsets, types
  EXPECT_EQ(bytes.size(), expected);
  EXPECT_EQ(bytes.substr(bytes.size() - 2), std::string(2, char(kVtkTriangle)));
}

TEST_F(IoFrameTest, VtuEmptyFrame) {
  write_vtu(file("empty.vtu"), PointSet{});
  const PointSet back = read_vtu_points(file("empty.vtu"));
  EXPECT_EQ(back.size(), 0u);
  // Only the four block headers: points, connectivity, offsets, types.
  EXPECT_EQ(appended_bytes(slurp(file("empty.vtu"))).size(), 4u * 8u);
}

TEST_F(IoFrameTest, NoTempFileRemainsAfterSuccess) {
  write_vtu(file("a.vtu"), cloud(5));
  write_vtu(file("a.vtu"), cloud(6));  // replacing an existing frame
  write_ply(file("a.ply"), cloud(5));
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"a.ply", "a.vtu"}));
  EXPECT_EQ(read_vtu_points(file("a.vtu")).size(), 6u);
}

TEST_F(IoFrameTest, InvalidFrameThrowsAndKeepsOldFile) {
  spit(file("a.vtu"), "old contents");
  spit(file("a.ply"), "old contents");
  PointSet f = cloud(5);
  f.point_data[1].values.pop_back();  // velocity one value short
  EXPECT_THROW(write_vtu(file("a.vtu"), f), std::invalid_argument);
  EXPECT_THROW(write_ply(file("a.ply"), f), std::invalid_argument);
  EXPECT_EQ(slurp(file("a.vtu")), "old contents");
  EXPECT_EQ(slurp(file("a.ply")), "old contents");
  EXPECT_FALSE(fs::exists(file("a.vtu.tmp")));
  EXPECT_FALSE(fs::exists(file("a.ply.tmp")));
}

TEST_F(IoFrameTest, ValidateCatchesBadCells) {
  PointSet f = two_triangles();
  f.connectivity[4] = 4;  // only 4 points
  EXPECT_THROW(validate(f), std::invalid_argument);
  f = two_triangles();
  f.offsets = {3, 5};
  EXPECT_THROW(validate(f), std::invalid_argument);
  f = two_triangles();
  f.types.pop_back();
  EXPECT_THROW(validate(f), std::invalid_argument);
  f = two_triangles();
  f.cell_data[0].values.push_back(1.0f);
  EXPECT_THROW(validate(f), std::invalid_argument);
  f = two_triangles();
  f.positions.pop_back();
  EXPECT_THROW(validate(f), std::invalid_argument);
  EXPECT_NO_THROW(validate(two_triangles()));
}

TEST_F(IoFrameTest, MissingFolderThrowsWithPath) {
  const std::string path = file("missing/sub/a.vtu");
  try {
    write_vtu(path, cloud(3));
    FAIL() << "expected a throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_ply(file("missing/a.ply"), cloud(3)), std::runtime_error);
}

TEST_F(IoFrameTest, FailedRenameKeepsWhatIsThere) {
  // A folder where the frame should go makes the final rename fail after the data is written.
  const std::string path = file("frame.vtu");
  fs::create_directories(path);
  spit(path + "/keep.txt", "kept");
  try {
    write_vtu(path, cloud(3));
    FAIL() << "expected a throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(path));
  EXPECT_EQ(slurp(path + "/keep.txt"), "kept");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(IoFrameTest, FailureWhileFillingKeepsOldFile) {
  spit(file("x.bin"), "old contents");
  EXPECT_THROW(write_file_atomic(file("x.bin"),
                                 [](AtomicFile& f) {
                                   f.write("partial");
                                   throw std::runtime_error("boom");
                                 }),
               std::runtime_error);
  EXPECT_EQ(slurp(file("x.bin")), "old contents");
  EXPECT_FALSE(fs::exists(file("x.bin.tmp")));
  {
    AtomicFile f(file("x.bin"));
    f.write("never committed");
  }
  EXPECT_EQ(slurp(file("x.bin")), "old contents");
  EXPECT_FALSE(fs::exists(file("x.bin.tmp")));
  write_file_atomic(file("x.bin"), "new");
  EXPECT_EQ(slurp(file("x.bin")), "new");
}

TEST_F(IoFrameTest, EnsureDirectory) {
  const std::string nested = file("out/frames/deep");
  ensure_directory(nested);
  EXPECT_TRUE(fs::is_directory(nested));
  ensure_directory(nested);  // existing folders are fine
  ensure_directory("");

  spit(file("blocker"), "x");
  for (const std::string& dir : {file("blocker"), file("blocker/sub")}) {
    try {
      ensure_directory(dir);
      FAIL() << "expected a throw for " << dir;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(slurp(file("blocker")), "x");
}

TEST_F(IoFrameTest, ReadRejectsForeignFiles) {
  spit(file("bad.vtu"), "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"></VTKFile>\n");
  EXPECT_THROW(read_vtu_points(file("bad.vtu")), std::runtime_error);
  spit(file("bad.ply"), "ply\nformat ascii 1.0\nend_header\n");
  EXPECT_THROW(read_ply_points(file("bad.ply")), std::runtime_error);
  EXPECT_THROW(read_vtu_points(file("none.vtu")), std::runtime_error);
  // A frame cut short is reported, not read past its end.
  write_vtu(file("cut.vtu"), cloud(50));
  std::string text = slurp(file("cut.vtu"));
  for (std::size_t cut : {30, 400, 1200}) {
    spit(file("cut.vtu"), text.substr(0, text.size() - cut));
    EXPECT_THROW(read_vtu_points(file("cut.vtu")), std::runtime_error) << cut;
  }
}

TEST_F(IoFrameTest, PlyRoundTripIsBitExact) {
  PointSet f = cloud(17);
  DataArray uv{"uv", 2, {}, {}};
  for (std::size_t i = 0; i < f.size(); ++i) uv.values.insert(uv.values.end(), {tricky(i), 2.f});
  f.point_data.push_back(uv);
  write_ply(file("a.ply"), f);
  expect_same_points(f, read_ply_points(file("a.ply")));

  const std::string text = slurp(file("a.ply"));
  EXPECT_EQ(text.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(text.find("property float velocity_x\nproperty float velocity_y\n"
                      "property float velocity_z\n"),
            std::string::npos);
  EXPECT_NE(text.find("property int id\n"), std::string::npos);
  EXPECT_NE(text.find("property float stress_5\n"), std::string::npos);
  EXPECT_NE(text.find("property float uv_y\n"), std::string::npos);
  EXPECT_EQ(text.find("element face"), std::string::npos);
  const std::size_t header = text.find("end_header\n") + 11;
  EXPECT_EQ(text.size(), header + f.size() * 4 * (3 + 1 + 3 + 1 + 6 + 2));
}

TEST_F(IoFrameTest, PlyWritesTriangleFaces) {
  const PointSet f = two_triangles();
  write_ply(file("tri.ply"), f);
  const std::string text = slurp(file("tri.ply"));
  EXPECT_NE(text.find("element vertex 4\n"), std::string::npos);
  EXPECT_NE(text.find("element face 2\nproperty list uchar int vertex_indices\n"),
            std::string::npos);
  const std::size_t header = text.find("end_header\n") + 11;
  const std::size_t faces = header + 4 * 4 * (3 + 1);
  ASSERT_EQ(text.size(), faces + 2 * (1 + 12));
  for (std::size_t c = 0; c < 2; ++c) {
    EXPECT_EQ(text[faces + 13 * c], char(3));
    std::int32_t idx[3];
    std::memcpy(idx, text.data() + faces + 13 * c + 1, 12);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(idx[k], f.connectivity[3 * c + k]);
  }
  expect_same_points(f, read_ply_points(file("tri.ply")));
}

TEST_F(IoFrameTest, PlySkipsNonTriangleCells) {
  PointSet f;
  f.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  f.connectivity = {0, 1, 2, 3};
  f.offsets = {4};
  f.types = {kVtkTetra};
  write_ply(file("tet.ply"), f);
  EXPECT_EQ(slurp(file("tet.ply")).find("element face"), std::string::npos);
  EXPECT_EQ(read_ply_points(file("tet.ply")).positions, f.positions);
}

TEST_F(IoFrameTest, PlyRejectsNamesWithSpaces) {
  PointSet f = cloud(2);
  f.point_data[0].name = "bad name";
  EXPECT_THROW(write_ply(file("a.ply"), f), std::invalid_argument);
  EXPECT_FALSE(fs::exists(file("a.ply")));
}

}  // namespace
}  // namespace sphfem::io
