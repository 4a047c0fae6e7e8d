// run.json: every field survives a write and a read; missing and malformed files are clear errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "sphfem/io/run_info.h"

namespace sphfem::io {
namespace {
namespace fs = std::filesystem;

// A scratch folder per test, removed afterwards.
class RunInfoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("sphfem_run_info_" + std::string(info->name()) + "_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string dir() const { return dir_.string(); }
  void spit(const std::string& text) const {
    std::ofstream(run_json_path(dir()), std::ios::binary) << text;
  }
  // The message read_run_info throws, or "" when it reads.
  std::string error() const {
    try {
      read_run_info(dir());
    } catch (const std::runtime_error& e) { return e.what(); }
    return "";
  }

  fs::path dir_;
};

// Values with no short decimal form, so a lossy number format would show.
RunInfo full() {
  RunInfo r;
  r.scene = "scenes/dam \"break\".json";
  r.name = "dam break";
  r.particle_radius = 0.1 / 3;
  r.domain_min = Vec3d(-0.25, 0, 1.0 / 7);
  r.domain_max = Vec3d(1.5, 2.0 / 3, 3e-5);
  r.solver = "dfsph";
  r.backend = "cuda";
  r.fps = 24.5;
  r.bodies = {"cup", "cloth"};
  r.camera = RunCamera{Vec3d(0.1, 0.6, 0.05), Vec3d(0.1, 0, 0.05), 50};
  return r;
}

void expect_vec(const Vec3d& a, const Vec3d& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
}

TEST_F(RunInfoTest, PathsAreInTheRunFolder) {
  EXPECT_EQ(run_json_path("out"), "out/run.json");
  EXPECT_EQ(frames_dir("out"), "out/frames");
  EXPECT_EQ(gauges_path("out"), "out/gauges.csv");
  EXPECT_EQ(checkpoint_path("out"), "out/checkpoint.bin");
  EXPECT_EQ(run_json_path("out/"), "out/run.json");
}

TEST_F(RunInfoTest, EveryFieldSurvivesARoundTrip) {
  const RunInfo w = full();
  EXPECT_FALSE(run_info_exists(dir()));
  write_run_info(dir(), w);
  EXPECT_TRUE(run_info_exists(dir()));
  EXPECT_FALSE(fs::exists(run_json_path(dir()) + ".tmp"));
  const RunInfo r = read_run_info(dir());
  EXPECT_EQ(r.scene, w.scene);
  EXPECT_EQ(r.name, w.name);
  EXPECT_EQ(r.particle_radius, w.particle_radius);
  expect_vec(r.domain_min, w.domain_min);
  expect_vec(r.domain_max, w.domain_max);
  EXPECT_EQ(r.solver, w.solver);
  EXPECT_EQ(r.backend, w.backend);
  EXPECT_EQ(r.fps, w.fps);
  EXPECT_EQ(r.bodies, w.bodies);
  ASSERT_TRUE(r.camera);
  ASSERT_TRUE(r.camera->position);
  ASSERT_TRUE(r.camera->target);
  expect_vec(*r.camera->position, *w.camera->position);
  expect_vec(*r.camera->target, *w.camera->target);
  EXPECT_EQ(r.camera->fov, w.camera->fov);
}

TEST_F(RunInfoTest, NoCameraStaysNoCamera) {
  RunInfo w = full();
  w.camera.reset();
  w.bodies.clear();
  write_run_info(dir(), w);
  const RunInfo r = read_run_info(dir());
  EXPECT_FALSE(r.camera);
  EXPECT_TRUE(r.bodies.empty());
}

// The layout runs already on disk have: the renderer must keep reading them.
TEST_F(RunInfoTest, ReadsTheLayoutOfEarlierRuns) {
  spit(R"({
  "backend": "cpu",
  "bodies": [],
  "camera": { "fov": 40.0, "position": [0.5, 1.0, 2.0], "target": [0.5, 0.0, 0.25] },
  "domain": { "max": [1.0, 0.6, 0.2], "min": [0.0, 0.0, 0.0] },
  "fps": 30,
  "name": "dam",
  "particle_radius": 0.005,
  "scene": "scenes/dam.json",
  "solver": "wcsph"
})");
  const RunInfo r = read_run_info(dir());
  EXPECT_EQ(r.particle_radius, 0.005);
  expect_vec(r.domain_max, Vec3d(1.0, 0.6, 0.2));
  EXPECT_EQ(r.fps, 30);
  EXPECT_EQ(r.solver, "wcsph");
  ASSERT_TRUE(r.camera && r.camera->target);
  expect_vec(*r.camera->target, Vec3d(0.5, 0, 0.25));

  // The first runs wrote only the radius and the tank.
  spit(R"({"particle_radius": 0.01, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}})");
  const RunInfo old = read_run_info(dir());
  EXPECT_EQ(old.particle_radius, 0.01);
  EXPECT_EQ(old.fps, 30);
  EXPECT_TRUE(old.bodies.empty());
  EXPECT_FALSE(old.camera);
}

TEST_F(RunInfoTest, MissingFileNamesItAndTheFix) {
  EXPECT_FALSE(run_info_exists(dir()));
  const std::string e = error();
  EXPECT_NE(e.find(run_json_path(dir())), std::string::npos) << e;
  EXPECT_NE(e.find("not found"), std::string::npos) << e;
  EXPECT_NE(e.find("sphfem run"), std::string::npos) << e;
}

TEST_F(RunInfoTest, MalformedFieldNamesTheFileTheFieldAndTheFix) {
  const std::string file = "'" + run_json_path(dir()) + "'";
  const std::string fix = "run the scene again";
  struct Case {
    const char* json;
    const char* field;
  };
  for (const Case& c : {
           Case{R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]}})", "particle_radius: missing"},
           Case{R"({"particle_radius": "big", "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}})",
                "particle_radius: expected a number"},
           Case{R"({"particle_radius": 0.01, "domain": {"min": [0, 0], "max": [1, 1, 1]}})",
                "domain.min: expected three numbers"},
           Case{R"({"particle_radius": 0.01, "domain": {"min": [0, 0, 0]}})",
                "domain.max: missing"},
           Case{R"({"particle_radius": 0.01, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
                   "camera": {"target": [0, "up", 0]}})",
                "camera.target: expected three numbers"},
           Case{R"({"particle_radius": 0.01, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
                   "bodies": ["cup", 3]})",
                "bodies[1]: expected a string"},
           Case{R"({"particle_radius": 0.01, "domain": )", "JSON: "},
           Case{R"({"particle_radius": 0, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}})",
                "particle_radius <= 0"},
       }) {
    spit(c.json);
    const std::string e = error();
    EXPECT_NE(e.find(file), std::string::npos) << e;
    EXPECT_NE(e.find(c.field), std::string::npos) << e;
    EXPECT_NE(e.find(fix), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace sphfem::io
