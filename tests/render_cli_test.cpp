// `sphfem render` and `sphfem view` as a user meets them: pictures of fluid and body-only
// runs drawn by OpenGL here, videos through ffmpeg, the fallback to the software renderer
// said once, and clear one-line errors without ffmpeg or without a display.
#include <gtest/gtest.h>
#include <zlib.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "cli_harness.h"

namespace fs = std::filesystem;

namespace {

using sphfem::testing_cli::cli;
using sphfem::testing_cli::Result;

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Pixels of a PNG written by render::write_png (8-bit RGB, every row with the Up filter).
struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

Picture read_png(const fs::path& path) {
  const std::string png = read_bytes(path);
  Picture pic;
  std::string idat;
  auto be32 = [&](std::size_t at) {
    return std::uint32_t(std::uint8_t(png[at])) << 24 |
           std::uint32_t(std::uint8_t(png[at + 1])) << 16 |
           std::uint32_t(std::uint8_t(png[at + 2])) << 8 | std::uint32_t(std::uint8_t(png[at + 3]));
  };
  for (std::size_t at = 8; at + 8 <= png.size();) {
    const std::uint32_t len = be32(at);
    const std::string type = png.substr(at + 4, 4);
    if (type == "IHDR") {
      pic.width = int(be32(at + 8));
      pic.height = int(be32(at + 12));
    }
    if (type == "IDAT") idat += png.substr(at + 8, len);
    at += 12 + len;
  }
  const std::size_t row = std::size_t(pic.width) * 3;
  std::vector<unsigned char> raw((row + 1) * pic.height);
  uLongf n = uLongf(raw.size());
  if (uncompress(raw.data(), &n, reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size())) !=
      Z_OK)
    return Picture();
  pic.rgb.resize(row * pic.height);
  for (int y = 0; y < pic.height; ++y)
    for (std::size_t i = 0; i < row; ++i)
      pic.rgb[y * row + i] =
          std::uint8_t(raw[y * (row + 1) + 1 + i] + (y > 0 ? pic.rgb[(y - 1) * row + i] : 0));
  return pic;
}

// Pixels where red leads blue by 60 (the bodies' warm colours) or blue leads red by 40 (water).
int count_pixels(const Picture& p, bool warm) {
  int n = 0;
  for (std::size_t i = 0; i + 2 < p.rgb.size(); i += 3) {
    const int r = p.rgb[i], b = p.rgb[i + 2];
    n += warm ? r - b > 60 : b - r > 40;
  }
  return n;
}

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sphfem_render_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  // A small run of `scene` in dir_/out; fails the test when the run does.
  fs::path run(const std::string& scene, const std::string& extra = "") {
    const fs::path out = dir_ / "out";
    const Result r =
        cli("run " + write("scene.json", scene) + " --quiet --out " + out.string() + " " + extra);
    EXPECT_EQ(r.code, 0) << r.out;
    return out;
  }
  fs::path dir_;
};

const char* kFluidScene = R"({
  "simulation": { "duration": 0.02, "solver": "dfsph", "dt_max": 0.002 },
  "fluid": { "particle_radius": 0.01, "blocks": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ] },
  "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "output": { "fps": 100 }
})";

const char* kBodyScene = R"({
  "simulation": { "duration": 0.02, "dt_max": 0.002 },
  "domain": { "min": [-0.3, 0, -0.3], "max": [0.3, 0.4, 0.3] },
  "bodies": [ { "name": "block", "shape": "box", "position": [0, 0.15, 0],
                "size": [0.2, 0.2, 0.2], "resolution": 4,
                "material": { "density": 1000, "young": 1e6, "poisson": 0.3 } } ],
  "output": { "fps": 100 }
})";

// Pictures only the OpenGL renderer draws (bodies, obstacles, no fallback note): a build
// without it (SPHFEM_ENABLE_GL=OFF, as the sanitizer build) has nothing to check.
#define REQUIRE_GL() \
  if (!SPHFEM_TEST_GL) GTEST_SKIP() << "built without the OpenGL renderer (SPHFEM_ENABLE_GL=OFF)"

TEST_F(RenderCli, ViewWithoutADisplayExitsWithCodeTwoAndOneLine) {
  const Result r = cli("view " + std::string(SPHFEM_SOURCE_DIR) + "/scenes/dam_break.json",
                       "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(count(r.out, "\n"), 1u) << r.out;
  EXPECT_NE(r.out.find("needs a display"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--render"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sphfem render"), std::string::npos) << r.out;
}

TEST_F(RenderCli, FluidRunIsDrawnWithOpenGl) {
  REQUIRE_GL();
  const fs::path out = run(kFluidScene);
  const Result r = cli("render " + out.string() + " --frames last --size 320x240");
  ASSERT_EQ(r.code, 0) << r.out;
  // Drawn by OpenGL, not by the fallback.
  EXPECT_EQ(r.out.find("note:"), std::string::npos) << r.out;
  const Picture p = read_png(out / "images" / "fluid_000002.png");
  ASSERT_EQ(p.width, 320);
  ASSERT_EQ(p.height, 240);
  EXPECT_GT(count_pixels(p, false), 1000);
}

TEST_F(RenderCli, BodyOnlyRunIsDrawn) {
  REQUIRE_GL();
  const fs::path out = run(kBodyScene);
  const Result r = cli("render " + out.string() + " --size 320x240");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("3 images in"), std::string::npos) << r.out;
  for (int f = 0; f <= 2; ++f) {
    const Picture p = read_png(out / "images" / ("bodies_00000" + std::to_string(f) + ".png"));
    ASSERT_EQ(p.width, 320) << f;
    EXPECT_GT(count_pixels(p, true), 1000) << f;
  }
}

// An obstacle on a path is drawn where it is in each frame (frames/obstacles_*.vtu): the last
// picture of a run where it moves matches that of a run where it stands at its end pose, and
// not that of one where it stands at its start.
TEST_F(RenderCli, MovingObstacleIsDrawnWhereItIs) {
  REQUIRE_GL();
  auto picture = [&](const std::string& name, const std::string& obstacle) {
    const fs::path out = dir_ / name;
    const std::string scene = R"({
      "simulation": { "duration": 0.02, "dt_max": 0.002 },
      "domain": { "min": [-0.3, 0, -0.3], "max": [0.3, 0.4, 0.3] },
      "bodies": [ { "name": "block", "shape": "box", "position": [0, 0.1, 0],
                    "size": [0.1, 0.1, 0.1], "resolution": 2,
                    "pinned": { "boxes": [ { "min": [-1, -1, -1], "max": [1, 1, 1] } ] },
                    "material": { "density": 1000, "young": 1e6, "poisson": 0.3 } } ],
      "obstacles": [ )" + obstacle +
                              R"( ],
      "output": { "fps": 100 }
    })";
    EXPECT_EQ(cli("run " + write(name + ".json", scene) + " --quiet --out " + out.string()).code,
              0);
    const Result r = cli("render " + out.string() + " --frames last --size 320x240");
    EXPECT_EQ(r.code, 0) << r.out;
    return read_png(out / "images" / "bodies_000002.png");
  };
  auto differ = [](const Picture& a, const Picture& b) {
    int n = 0;
    for (std::size_t i = 0; i + 2 < a.rgb.size() && i + 2 < b.rgb.size(); i += 3)
      n += a.rgb[i] != b.rgb[i] || a.rgb[i + 1] != b.rgb[i + 1] || a.rgb[i + 2] != b.rgb[i + 2];
    return n;
  };
  const Picture moving = picture("moving", R"({ "min": [-0.25, 0.05, 0.1],
      "max": [-0.15, 0.15, 0.2],
      "path": [ { "time": 0 }, { "time": 0.02, "translate": [0.35, 0, 0] } ] })");
  const Picture end = picture("end", R"({ "min": [0.1, 0.05, 0.1], "max": [0.2, 0.15, 0.2] })");
  const Picture start =
      picture("start", R"({ "min": [-0.25, 0.05, 0.1], "max": [-0.15, 0.15, 0.2] })");
  ASSERT_GT(moving.width, 0);
  EXPECT_LT(differ(moving, end), 50);
  EXPECT_GT(differ(moving, start), 500);
}

TEST_F(RenderCli, RunWithRenderDrawsEveryFrame) {
  const fs::path out = run(kFluidScene, "--render");
  for (int f = 0; f <= 2; ++f)
    EXPECT_TRUE(fs::exists(out / "images" / ("fluid_00000" + std::to_string(f) + ".png"))) << f;
}

TEST_F(RenderCli, Mp4GoesThroughFfmpeg) {
  const fs::path out = run(kFluidScene);
  const Result r = cli("render " + out.string() + " --format mp4 --size 161x121");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("3 frames in"), std::string::npos) << r.out;
  const std::string mp4 = read_bytes(out / "video.mp4");
  ASSERT_GT(mp4.size(), 100u);
  EXPECT_EQ(mp4.substr(4, 4), "ftyp");
}

TEST_F(RenderCli, Mp4WithoutFfmpegIsAClearError) {
  const fs::path out = run(kFluidScene);
  const Result r =
      cli("render " + out.string() + " --format mp4", "env PATH=" + (dir_ / "empty").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(count(r.out, "\n"), 1u) << r.out;
  EXPECT_NE(r.out.find("needs ffmpeg"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--format png"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(out / "video.mp4"));
}

TEST_F(RenderCli, NoEglFallsBackToSoftwareAndSaysSoOnce) {
  const fs::path out = run(kFluidScene);
  // No EGL vendor library: glvnd finds no driver, as on a machine without Mesa's EGL.
  const std::string no_egl = "env __EGL_VENDOR_LIBRARY_FILENAMES=" + (dir_ / "none.json").string();
  const Result r = cli("render " + out.string() + " --size 160x120", no_egl);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(count(r.out, "software renderer"), 1u) << r.out;
  EXPECT_GT(count_pixels(read_png(out / "images" / "fluid_000000.png"), false), 100);
  // Asked for OpenGL by name, the command fails instead.
  const Result gl = cli("render " + out.string() + " --renderer gl --size 160x120", no_egl);
  EXPECT_EQ(gl.code, 2) << gl.out;
  EXPECT_NE(gl.out.find("--renderer splat"), std::string::npos) << gl.out;
}

TEST_F(RenderCli, CameraOptionsMoveTheView) {
  const fs::path out = run(kFluidScene);
  ASSERT_EQ(cli("render " + out.string() + " --frames 0 --size 160x120").code, 0);
  const std::string automatic = read_bytes(out / "images" / "fluid_000000.png");
  const Result r = cli("render " + out.string() +
                       " --frames 0 --size 160x120 --camera-pos 0.1,0.6,0.05 "
                       "--camera-target 0.1,0,0.05 --fov 50");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(read_bytes(out / "images" / "fluid_000000.png"), automatic);
  const Result same = cli("render " + out.string() + " --camera-pos 1,1,1 --camera-target 1,1,1");
  EXPECT_EQ(same.code, 2) << same.out;
  EXPECT_NE(same.out.find("coincide"), std::string::npos) << same.out;
}

}  // namespace
