// The sphfem command as a user meets it: outputs, exit codes, messages, nothing written on
// bad input, frames kept when a run blows up.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_harness.h"
#include "sphfem/core/vec.h"
#include "sphfem/io/vtu.h"

namespace fs = std::filesystem;

namespace {

using sphfem::testing_cli::cli;
using sphfem::testing_cli::Result;

std::string last_line(const std::string& s) {
  std::string t = s;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  return t.substr(t.rfind('\n') == std::string::npos ? 0 : t.rfind('\n') + 1);
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sphfem_cli_" +
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
  fs::path dir_;
};

const char* kSmallScene = R"({
  "simulation": { "duration": 0.05, "solver": "dfsph", "dt_max": 0.002 },
  "fluid": { "particle_radius": 0.01, "blocks": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ] },
  "domain": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "output": { "fps": 100, "vtu": true, "ply": true },
  "gauges": [ { "name": "p0", "type": "pressure", "position": [0.05, 0.02, 0.05] } ]
})";

TEST_F(Cli, RunWritesFramesGaugesAndNamesTheFolderLast) {
  const std::string scene = write("small.json", kSmallScene);
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + scene + " --out " + out.string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(last_line(r.out).find(out.string()), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(out / "fluid.pvd"));
  // Frames at t = 0, 0.01, ..., 0.05.
  for (int f = 0; f <= 5; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "fluid_%06d", f);
    EXPECT_TRUE(fs::exists(out / "frames" / (std::string(name) + ".vtu"))) << name;
    EXPECT_TRUE(fs::exists(out / "frames" / (std::string(name) + ".ply"))) << name;
  }
  const sphfem::io::PointSet ps =
      sphfem::io::read_vtu_points((out / "frames" / "fluid_000005.vtu").string());
  EXPECT_EQ(ps.size(), 125u);
  std::ifstream g(out / "gauges.csv");
  std::string header, line;
  std::getline(g, header);
  for (const char* col :
       {"time", "step", "dt", "n_fluid", "fluid_front_x", "max_density_error", "kinetic_energy",
        "momentum_x", "momentum_y", "momentum_z", "ms_density", "p0"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  int rows = 0;
  while (std::getline(g, line)) ++rows;
  EXPECT_EQ(rows, 6);
}

TEST_F(Cli, CheckPrintsParticleCountAndMemory) {
  const Result r = cli("check " + write("small.json", kSmallScene));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("125 at start"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MiB"), std::string::npos) << r.out;
}

TEST_F(Cli, BadInputExitsWithCodeTwoAndWritesNothing) {
  std::string bad = kSmallScene;
  bad.replace(bad.find("\"particle_radius\""), 17, "\"particle_radios\"");
  const std::string scene = write("bad.json", bad);
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + scene + " --out " + out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("bad.json"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fluid.particle_radios"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("particle_radius"), std::string::npos) << r.out;  // did you mean
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, MissingSceneFileIsAClearError) {
  const Result r = cli("run " + (dir_ / "nope.json").string() + " --out " + (dir_ / "o").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("nope.json"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

TEST_F(Cli, CflViolationIsRejectedBeforeRunning) {
  std::string s = kSmallScene;
  s.replace(s.find("\"dfsph\", \"dt_max\": 0.002"), 25,
            "\"wcsph\", \"dt_min\": 0.002, \"dt_max\": 0.002");
  const Result r = cli("run " + write("cfl.json", s) + " --out " + (dir_ / "o").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("simulation.dt_min"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("CFL"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// A fixed step that is stable at rest but not once the column collapses: the run must stop
// with the step number and advice, keeping every complete frame written before.
TEST_F(Cli, BlowUpStopsWithStepNumberAndKeepsFrames) {
  const std::string scene = write("blow.json", R"({
    "simulation": { "duration": 1.0, "solver": "wcsph", "dt_min": 0.0012, "dt_max": 0.0012, "cfl": 1.0 },
    "fluid": { "particle_radius": 0.01, "stiffness": 200000,
               "blocks": [ { "min": [0, 0, 0], "max": [0.1, 0.3, 0.1] } ] },
    "domain": { "min": [0, 0, 0], "max": [0.5, 0.4, 0.1] },
    "output": { "fps": 100 }
  })");
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + scene + " --out " + out.string());
  ASSERT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("step "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("dt_max"), std::string::npos) << r.out;  // what to change
  int frames = 0;
  for (const auto& e : fs::directory_iterator(out / "frames")) {
    EXPECT_EQ(e.path().extension(), ".vtu") << "left-over temporary file " << e.path();
    EXPECT_NO_THROW(sphfem::io::read_vtu_points(e.path().string())) << e.path();
    ++frames;
  }
  EXPECT_GE(frames, 2);
}

TEST_F(Cli, CudaWithoutGpuIsAClearError) {
  const Result r = cli("run " + write("small.json", kSmallScene) + " --backend cuda --out " +
                       (dir_ / "o").string());
  if (r.code == 0) GTEST_SKIP() << "a CUDA device is present";
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--backend cpu"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

std::string source_file(const std::string& relative) {
  return std::string(SPHFEM_SOURCE_DIR) + "/" + relative;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(Cli, CheckPrintsBodies) {
  const Result r = cli("check " + source_file("scenes/cantilever.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("beam (box): 1025 nodes, 3840 tets, 1344 surface triangles, 10 kg"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("fluid       none"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MiB"), std::string::npos) << r.out;
}

TEST_F(Cli, RunOfABodySceneWritesBodyFrames) {
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + source_file("scenes/cloth_hanging.json") +
                       " --duration 0.1 --quiet --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("882 body nodes (1 bodies)"), std::string::npos) << r.out;
  EXPECT_NE(last_line(r.out).find("bodies.pvd"), std::string::npos) << r.out;
  for (int f = 0; f <= 3; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.vtu", f);
    EXPECT_TRUE(fs::exists(out / "frames" / (std::string("bodies_") + name))) << name;
    EXPECT_TRUE(fs::exists(out / "frames" / (std::string("bodies_tets_") + name))) << name;
  }
  const std::string header = read_text(out / "gauges.csv").substr(0, 4096);
  for (const char* col :
       {"ms_fem", "free_corner_dy", "cloth_kinetic_energy", "cloth_elastic_energy"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  EXPECT_NE(read_text(out / "run.json").find("\"cloth\""), std::string::npos);
}

// The obstacles are written once, as triangles ParaView opens beside the collections.
TEST_F(Cli, RunOfAnObstacleSceneWritesItsSurface) {
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + source_file("scenes/funnel.json") +
                       " --duration 0.02 --quiet --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const sphfem::io::PointSet ps = sphfem::io::read_vtu((out / "obstacles.vtu").string());
  EXPECT_EQ(ps.size(), 64u);
  EXPECT_EQ(ps.types.size(), 64u);
  ASSERT_EQ(ps.cell_data.size(), 1u);
  EXPECT_EQ(ps.cell_data[0].name, "obstacle");
}

// The paddle scene: `check` names the obstacle's path, and a short run writes its frames.
TEST_F(Cli, PaddleSceneChecksAndRuns) {
  const std::string scene = source_file("scenes/paddle.json");
  const Result c = cli("check " + scene);
  ASSERT_EQ(c.code, 0) << c.out;
  EXPECT_NE(c.out.find("obstacle    paddle (box): 12 triangles, on a 3-key path from 0 s to 2 s"),
            std::string::npos)
      << c.out;
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + scene + " --duration 0.04 --quiet --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(out / "obstacles.pvd"));
  EXPECT_TRUE(fs::exists(out / "frames" / "obstacles_000001.vtu"));
  EXPECT_NE(r.out.find("0 particles crossed"), std::string::npos) << r.out;
}

TEST_F(Cli, BadBodyExitsWithCodeTwoAndWritesNothing) {
  std::string scene = read_text(source_file("scenes/cantilever.json"));
  const std::string poisson = "\"poisson\": 0.3";
  scene.replace(scene.find(poisson), poisson.size(), "\"poisson\": 0.5");
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + write("beam.json", scene) + " --out " + out.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("beam.json: bodies[0].material.poisson: must be > -1 and < 0.5 (got 0.5)"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, BodyBlowUpExitsWithCodeThreeAndKeepsFrames) {
  if (sizeof(sphfem::Real) != sizeof(float)) GTEST_SKIP() << "needs single-precision bodies";
  std::string scene = read_text(source_file("scenes/cantilever.json"));
  const std::string young = "\"young\": 2e7";
  scene.replace(scene.find(young), young.size(), "\"young\": 1e39");
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + write("blow.json", scene) + " --out " + out.string());
  ASSERT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("step 1 (t = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("simulation.dt_max"), std::string::npos) << r.out;
  EXPECT_NO_THROW(sphfem::io::read_vtu_points((out / "frames" / "bodies_000000.vtu").string()));
}

TEST_F(Cli, FemBenchWithAMissingMeshIsAClearError) {
  const Result r = cli("bench --fem --steps 1 --mesh " + (dir_ / "nope.obj").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("nope.obj: cannot open the file"), std::string::npos) << r.out;
}

}  // namespace
