// Bad scene files: each message is one line naming the file, the JSON path and a fix.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A valid scene that each test breaks in one place.
json good_scene() {
  return json::parse(R"({
    "domain": { "min": [0, 0, 0], "max": [0.4, 0.2, 0.02] },
    "simulation": { "dt_min": 1e-6, "dt_max": 1e-3 },
    "fluid": {
      "particle_radius": 0.0025,
      "blocks": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.02] } ],
      "emitters": [ { "position": [0.3, 0.15, 0.01], "direction": [0, -1, 0], "radius": 0.005 } ]
    },
    "gauges": [ { "name": "p", "position": [0.1, 0.01, 0.01] } ]
  })");
}

class SceneErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("sphfem_scene_errors_" + test + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string write_text(const std::string& text) {
    const fs::path p = dir_ / "scene.json";
    std::ofstream(p) << text;
    return p.string();
  }
  std::string write(const json& scene) { return write_text(scene.dump(2)); }

  // The message load_scene throws for the file, or "" (and a failure) if it loads.
  static std::string error_of(const std::string& path) {
    try {
      load_scene(path);
    } catch (const SceneError& e) { return e.what(); }
    ADD_FAILURE() << path << " loaded without an error";
    return "";
  }

  // One line that contains every part (file name, JSON path, problem, fix hint).
  static void expect_message(const std::string& message, std::initializer_list<std::string> parts) {
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const std::string& part : parts)
      EXPECT_NE(message.find(part), std::string::npos)
          << "missing \"" << part << "\" in: " << message;
  }

  fs::path dir_;
};

TEST_F(SceneErrors, GoodSceneLoads) { EXPECT_NO_THROW(load_scene(write(good_scene()))); }

TEST_F(SceneErrors, UnknownFieldSuggestsTheNearestKey) {
  json s = good_scene();
  s["fluid"]["visocsity"] = 1e-6;
  const std::string path = write(s);
  expect_message(error_of(path),
                 {path + ": fluid.visocsity: unknown field", "did you mean \"viscosity\"?"});
}

TEST_F(SceneErrors, UnknownFieldFarFromAnyKeyListsTheAllowedOnes) {
  json s = good_scene();
  s["domain"]["colour"] = "blue";
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": domain.colour: unknown field",
                                  "allowed here are \"min\", \"max\", \"open_top\""});
}

TEST_F(SceneErrors, WrongTypeNamesTheExpectedTypeAndUnit) {
  json s = good_scene();
  s["fluid"]["emitters"][0]["speed"] = "fast";
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid.emitters[0].speed: expected a number in m/s, "
                                         "got a string (\"fast\")",
                                  "; write a number without quotes, e.g. 1"});
}

TEST_F(SceneErrors, OutOfRangeValueShowsTheRangeAndAnExample) {
  json s = good_scene();
  s["fluid"]["particle_radius"] = -0.01;
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid.particle_radius: must be > 0 (got -0.01)",
                                  "; set a value > 0 in m, e.g. 0.0125"});
}

TEST_F(SceneErrors, MissingFileSaysToCheckThePath) {
  const std::string path = (dir_ / "no_such_scene.json").string();
  expect_message(error_of(path),
                 {path + ": file not found", "; check the path", "current directory"});
}

TEST_F(SceneErrors, MalformedJsonGivesLineAndColumn) {
  const std::string path = write_text(
      "{\n"
      "  \"fluid\": {\n"
      "    \"particle_radius\": 0.0025,\n"
      "  }\n"
      "}\n");
  expect_message(error_of(path), {path + ": line 4, column 3: invalid JSON: ", "unexpected '}'",
                                  "; fix the syntax at that position"});
}

TEST_F(SceneErrors, NumberTooLargeForADoubleIsRejected) {
  const std::string text = "{\n  \"simulation\": { \"duration\": 1e999 }\n}\n";
  const std::string path = write_text(text);
  expect_message(error_of(path), {path + ": line 2, column ", "1e999", "; write numbers"});
}

TEST_F(SceneErrors, EmitterOutsideTheDomain) {
  json s = good_scene();
  s["fluid"]["emitters"][0]["position"] = {0.5, 0.15, 0.01};
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid.emitters[0].position: ",
                                  "outside the domain on x (0.5 > domain.max 0.4)",
                                  "; move the emitter inside the domain"});
}

TEST_F(SceneErrors, EmitterNozzleDiscCrossingAWall) {
  json s = good_scene();
  s["fluid"]["emitters"][0]["position"] = {0.3, 0.15, 0.018};  // disc reaches z = 0.023
  const std::string path = write(s);
  expect_message(error_of(path),
                 {path + ": fluid.emitters[0].position: the nozzle disc", "outside the domain on z",
                  "; move the emitter at least 0.005 m"});
}

TEST_F(SceneErrors, BlockOutsideTheDomain) {
  json s = good_scene();
  s["fluid"]["blocks"][0]["max"] = {0.5, 0.1, 0.02};
  const std::string path = write(s);
  expect_message(error_of(path),
                 {path + ": fluid.blocks[0].max: ",
                  "outside the domain on x (0.5 > domain.max 0.4)", "; move or shrink the block"});
}

TEST_F(SceneErrors, BlockThinnerThanOneParticleSpacing) {
  json s = good_scene();
  s["fluid"]["blocks"][0]["max"] = {0.1, 0.1, 0.004};
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid.blocks[0]: the block is 0.004 m thick on z",
                                  "; make the block at least 0.005 m"});
}

TEST_F(SceneErrors, BadEnumNameSuggestsTheNearestName) {
  json s = good_scene();
  s["simulation"]["solver"] = "dfshp";
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": simulation.solver: unknown solver \"dfshp\"",
                                  "; did you mean \"dfsph\"?", "\"wcsph\", \"dfsph\""});
}

TEST_F(SceneErrors, Vec3OfWrongLength) {
  json s = good_scene();
  s["domain"]["max"] = {0.4, 0.2};
  const std::string path = write(s);
  expect_message(error_of(path),
                 {path + ": domain.max: expected an array of 3 numbers [x, y, z] in m, "
                         "got an array of 2 elements",
                  "; write three numbers, e.g. [1, 1, 1]"});
}

TEST_F(SceneErrors, DtMinAboveDtMax) {
  json s = good_scene();
  s["simulation"]["dt_min"] = 0.01;
  const std::string path = write(s);
  expect_message(error_of(path),
                 {path + ": simulation.dt_min: must not exceed simulation.dt_max (0.01 > 0.001)",
                  "; lower simulation.dt_min or raise simulation.dt_max"});
}

TEST_F(SceneErrors, NoFluidAtAll) {
  json s = good_scene();
  s["fluid"]["blocks"] = json::array();
  s["fluid"].erase("emitters");
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid: the scene has no fluid",
                                  "; add a box to fluid.blocks, e.g. {\"min\": [0, 0, 0]"});
}

TEST_F(SceneErrors, DomainTooNarrowForTheParticleSize) {
  json s = good_scene();
  s["fluid"]["particle_radius"] = 0.004;
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": fluid.particle_radius: the domain is only 2.5 "
                                         "particle spacings wide on z",
                                  "; set particle_radius to at most 0.0025 m"});
}

TEST_F(SceneErrors, DuplicateGaugeNames) {
  json s = good_scene();
  s["gauges"].push_back({{"name", "p"}, {"position", {0.2, 0.01, 0.01}}});
  const std::string path = write(s);
  expect_message(error_of(path), {path + ": gauges[1].name: \"p\" is already the name of gauges[0]",
                                  "; give each gauge a different name"});
}

TEST_F(SceneErrors, ValidateChecksRangesOfScenesBuiltInCode) {
  SceneSpec s;
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.5, 0.5, 0.5), Vec3d()});
  s.output.fps = 0;
  try {
    validate_scene(s, "built.json");
    ADD_FAILURE() << "fps = 0 passed validation";
  } catch (const SceneError& e) {
    expect_message(e.what(), {"built.json: output.fps: must be > 0 (got 0)", "e.g. 30"});
  }
}

}  // namespace
}  // namespace sphfem
