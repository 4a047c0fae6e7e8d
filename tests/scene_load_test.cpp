// Loading valid scene files: every field read, defaults filled in, the example round-trips.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "sphfem/scene/fields.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Each test writes its scenes into its own scratch directory.
class SceneLoad : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("sphfem_scene_load_" + test + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }

  fs::path dir_;
};

void expect_vec(const Vec3d& v, double x, double y, double z) {
  EXPECT_DOUBLE_EQ(v.x, x);
  EXPECT_DOUBLE_EQ(v.y, y);
  EXPECT_DOUBLE_EQ(v.z, z);
}

TEST_F(SceneLoad, ReadsEveryFieldOfAFullScene) {
  const std::string path = write("dam.json", R"({
    "name": "dam break",
    "simulation": { "duration": 0.5, "solver": "wcsph", "dt_max": 0.001, "dt_min": 1e-6,
                    "cfl": 0.3, "gravity": [0, -9.81, 0], "density_tolerance": 0.002,
                    "divergence_tolerance": 0.01, "max_iterations": 50 },
    "fluid": {
      "particle_radius": 0.0025, "rest_density": 998, "viscosity": 1e-6, "xsph": 0.1,
      "artificial_viscosity": 0.02, "stiffness": 5e4, "max_speed": 3, "kernel": "wendland_c2",
      "max_particles": 20000,
      "blocks": [ { "min": [0, 0, 0], "max": [0.05715, 0.1143, 0.02], "velocity": [0.1, 0, 0] } ],
      "emitters": [ { "position": [0.3, 0.15, 0.01], "direction": [0, -2, 0], "radius": 0.005,
                      "speed": 1.5, "start": 0.1, "end": 2 } ]
    },
    "domain": { "min": [0, 0, 0], "max": [0.4, 0.2, 0.02], "open_top": true },
    "output": { "fps": 60, "vtu": false, "ply": true },
    "gauges": [ { "name": "p_bottom", "type": "pressure", "position": [0.1, 0.01, 0.01] },
                { "name": "h_wall", "type": "height", "position": [0.0, 0, 0.01] } ]
  })");

  const SceneSpec s = load_scene(path);
  EXPECT_EQ(s.path, path);
  EXPECT_EQ(s.name, "dam break");
  EXPECT_DOUBLE_EQ(s.simulation.duration, 0.5);
  EXPECT_EQ(s.simulation.solver, SolverKind::WCSPH);
  EXPECT_DOUBLE_EQ(s.simulation.dt_max, 0.001);
  EXPECT_DOUBLE_EQ(s.simulation.dt_min, 1e-6);
  EXPECT_DOUBLE_EQ(s.simulation.cfl, 0.3);
  expect_vec(s.simulation.gravity, 0, -9.81, 0);
  EXPECT_DOUBLE_EQ(s.simulation.density_tolerance, 0.002);
  EXPECT_DOUBLE_EQ(s.simulation.divergence_tolerance, 0.01);
  EXPECT_EQ(s.simulation.max_iterations, 50);

  EXPECT_DOUBLE_EQ(s.fluid.particle_radius, 0.0025);
  EXPECT_DOUBLE_EQ(s.fluid.rest_density, 998);
  EXPECT_DOUBLE_EQ(s.fluid.viscosity, 1e-6);
  EXPECT_DOUBLE_EQ(s.fluid.xsph, 0.1);
  EXPECT_DOUBLE_EQ(s.fluid.artificial_viscosity, 0.02);
  EXPECT_DOUBLE_EQ(s.fluid.stiffness, 5e4);
  EXPECT_DOUBLE_EQ(s.fluid.max_speed, 3);
  EXPECT_EQ(s.fluid.kernel, KernelKind::WendlandC2);
  EXPECT_EQ(s.fluid.max_particles, 20000);
  ASSERT_EQ(s.fluid.blocks.size(), 1u);
  expect_vec(s.fluid.blocks[0].lo, 0, 0, 0);
  expect_vec(s.fluid.blocks[0].hi, 0.05715, 0.1143, 0.02);
  expect_vec(s.fluid.blocks[0].velocity, 0.1, 0, 0);
  ASSERT_EQ(s.fluid.emitters.size(), 1u);
  const EmitterSpec& e = s.fluid.emitters[0];  // radius is set: the default is below one spacing
  expect_vec(e.position, 0.3, 0.15, 0.01);
  expect_vec(e.direction, 0, -1, 0);  // normalised on load
  EXPECT_DOUBLE_EQ(e.radius, 0.005);
  EXPECT_DOUBLE_EQ(e.speed, 1.5);
  EXPECT_DOUBLE_EQ(e.start, 0.1);
  EXPECT_DOUBLE_EQ(e.end, 2);

  expect_vec(s.domain.lo, 0, 0, 0);
  expect_vec(s.domain.hi, 0.4, 0.2, 0.02);
  EXPECT_TRUE(s.domain.open_top);
  EXPECT_DOUBLE_EQ(s.output.fps, 60);
  EXPECT_FALSE(s.output.vtu);
  EXPECT_TRUE(s.output.ply);
  ASSERT_EQ(s.gauges.size(), 2u);
  EXPECT_EQ(s.gauges[0].name, "p_bottom");
  EXPECT_EQ(s.gauges[0].kind, GaugeKind::Pressure);
  expect_vec(s.gauges[0].position, 0.1, 0.01, 0.01);
  EXPECT_EQ(s.gauges[1].name, "h_wall");
  EXPECT_EQ(s.gauges[1].kind, GaugeKind::Height);
}

TEST_F(SceneLoad, FillsOmittedFieldsWithSpecDefaults) {
  const std::string path = write("minimal.json", R"({
    "fluid": { "blocks": [ { "min": [0, 0, 0], "max": [0.5, 0.5, 0.5] } ],
               "emitters": [ { "position": [0.5, 0.9, 0.5], "radius": 0.05 } ] },
    "gauges": [ { "position": [0.5, 0.1, 0.5] }, { "type": "height" } ]
  })");

  const SceneSpec s = load_scene(path);
  // Compare with default-constructed specs, so the test follows spec.h.
  const json defaults = scene_to_json(SceneSpec{});
  const json loaded = scene_to_json(s);
  for (const char* section : {"simulation", "domain", "output"})
    EXPECT_EQ(loaded[section], defaults[section]) << section;
  for (const char* key :
       {"particle_radius", "rest_density", "viscosity", "xsph", "artificial_viscosity", "stiffness",
        "max_speed", "kernel", "max_particles"})
    EXPECT_EQ(loaded["fluid"][key], defaults["fluid"][key]) << key;
  EXPECT_EQ(s.name, "");

  expect_vec(s.fluid.blocks[0].velocity, 0, 0, 0);
  const EmitterSpec emitter_defaults;
  const EmitterSpec& e = s.fluid.emitters[0];  // radius is set: the default is below one spacing
  expect_vec(e.direction, emitter_defaults.direction.x, emitter_defaults.direction.y,
             emitter_defaults.direction.z);
  EXPECT_DOUBLE_EQ(e.speed, emitter_defaults.speed);
  EXPECT_DOUBLE_EQ(e.start, emitter_defaults.start);
  EXPECT_DOUBLE_EQ(e.end, emitter_defaults.end);

  ASSERT_EQ(s.gauges.size(), 2u);
  EXPECT_EQ(s.gauges[0].name, "gauge0");
  EXPECT_EQ(s.gauges[0].kind, GaugeKind::Pressure);
  EXPECT_EQ(s.gauges[1].name, "gauge1");
  EXPECT_EQ(s.gauges[1].kind, GaugeKind::Height);
}

TEST_F(SceneLoad, AcceptsComments) {
  const std::string path = write("commented.json", R"({
    // One block of water.
    "fluid": { "blocks": [ { "min": [0, 0, 0], "max": [0.5, 0.5, 0.5] } ] } /* the rest: defaults */
  })");
  EXPECT_EQ(load_scene(path).fluid.blocks.size(), 1u);
}

TEST_F(SceneLoad, ExampleSceneRoundTripsThroughJson) {
  const SceneSpec example = scene::example_scene();
  const json written = scene_to_json(example);
  const std::string path = write("example.json", written.dump(2));
  const SceneSpec read = load_scene(path);
  EXPECT_EQ(scene_to_json(read), written);
}

}  // namespace
}  // namespace sphfem
