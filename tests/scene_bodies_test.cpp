// Bodies in scene files: every field read, meshes built from shapes and files, and each bad
// body input rejected with one line naming the file, the JSON path and the fix.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "sphfem/scene/bodies.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string mesh_data(const std::string& name) {
  return std::string(SPHFEM_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// A valid scene with one body and no fluid that each test changes in one place.
json beam_scene() {
  return json::parse(R"({
    "domain": { "min": [0, -0.5, -0.2], "max": [1.2, 0.2, 0.2] },
    "bodies": [ {
      "name": "beam", "shape": "box", "position": [0.5, 0, 0], "size": [1, 0.1, 0.1],
      "resolution": 10,
      "material": { "density": 1000, "young": 2e7, "poisson": 0.3 },
      "pinned": { "boxes": [ { "min": [0, -0.05, -0.05], "max": [0, 0.05, 0.05] } ] }
    } ],
    "gauges": [ { "name": "tip", "type": "node", "body": "beam", "position": [1, 0, 0] } ]
  })");
}

class SceneBodies : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("sphfem_scene_bodies_" + test + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string write(const json& scene) {
    const fs::path p = dir_ / "scene.json";
    std::ofstream(p) << scene.dump(2);
    return p.string();
  }

  // The message load_scene throws for the scene, or "" (and a failure) if it loads.
  std::string error_of(const json& scene) {
    const std::string path = write(scene);
    try {
      load_scene(path);
    } catch (const SceneError& e) { return e.what(); }
    ADD_FAILURE() << "the scene loaded without an error";
    return "";
  }

  // One line that starts with the file and the JSON path and contains every other part.
  void expect_message(const json& scene, const std::string& at,
                      std::initializer_list<std::string> parts) {
    const std::string m = error_of(scene);
    const std::string head = (dir_ / "scene.json").string() + ": " + at + ": ";
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_EQ(m.rfind(head, 0), 0u) << "expected to start with \"" << head << "\": " << m;
    for (const std::string& part : parts)
      EXPECT_NE(m.find(part), std::string::npos) << "missing \"" << part << "\" in: " << m;
  }

  fs::path dir_;
};

TEST_F(SceneBodies, ABodyWithoutFluidIsAScene) {
  const SceneSpec s = load_scene(write(beam_scene()));
  EXPECT_FALSE(s.has_fluid());
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].name, "beam");
}

TEST_F(SceneBodies, ReadsEveryBodyAndFemField) {
  json s = beam_scene();
  s["bodies"][0] = json::parse(R"({
    "name": "cup-1", "shape": "cup", "position": [0.5, -0.4, 0], "size": [0.2, 0.3, 0.4],
    "radius": 0.1, "inner_radius": 0.08, "length": 0.3, "height": 0.15, "thickness": 0.02,
    "resolution": 6, "file": "unused.obj", "scale": 2, "offset": [1, 2, 3], "max_volume": 1e-6,
    "quality": 2, "velocity": [0.1, 0.2, 0.3], "restitution": 0.25, "slip": 0.75,
    "material": { "density": 1100, "young": 3e5, "poisson": -0.2, "damping_alpha": 1.5,
                  "damping_beta": 0.002 },
    "pinned": { "boxes": [ { "min": [0.3, -0.4, -0.2], "max": [0.7, -0.4, 0.2] } ],
                "nodes": [0, 3] }
  })");
  s["gauges"][0]["body"] = "cup-1";
  s["fem"] = {{"cg_tolerance", 1e-4},
              {"cg_max_iterations", 50},
              {"newton_iterations", 2},
              {"rotation_iterations", 4},
              {"friction", 0.3}};
  const SceneSpec spec = load_scene(write(s));
  const BodySpec& b = spec.bodies.at(0);
  EXPECT_EQ(b.name, "cup-1");
  EXPECT_EQ(b.shape, BodyShape::Cup);
  EXPECT_DOUBLE_EQ(b.position.y, -0.4);
  EXPECT_DOUBLE_EQ(b.size.z, 0.4);
  EXPECT_DOUBLE_EQ(b.radius, 0.1);
  EXPECT_DOUBLE_EQ(b.inner_radius, 0.08);
  EXPECT_DOUBLE_EQ(b.length, 0.3);
  EXPECT_DOUBLE_EQ(b.height, 0.15);
  EXPECT_DOUBLE_EQ(b.thickness, 0.02);
  EXPECT_EQ(b.resolution, 6);
  EXPECT_EQ(b.file, "unused.obj");
  EXPECT_DOUBLE_EQ(b.scale, 2);
  EXPECT_DOUBLE_EQ(b.offset.z, 3);
  EXPECT_DOUBLE_EQ(b.max_volume, 1e-6);
  EXPECT_DOUBLE_EQ(b.quality, 2);
  EXPECT_DOUBLE_EQ(b.velocity.y, 0.2);
  EXPECT_DOUBLE_EQ(b.restitution, 0.25);
  EXPECT_DOUBLE_EQ(b.slip, 0.75);
  EXPECT_DOUBLE_EQ(b.material.density, 1100);
  EXPECT_DOUBLE_EQ(b.material.young, 3e5);
  EXPECT_DOUBLE_EQ(b.material.poisson, -0.2);
  EXPECT_DOUBLE_EQ(b.material.alpha, 1.5);
  EXPECT_DOUBLE_EQ(b.material.beta, 0.002);
  ASSERT_EQ(b.pinned.boxes.size(), 1u);
  EXPECT_DOUBLE_EQ(b.pinned.boxes[0].hi.x, 0.7);
  EXPECT_EQ(b.pinned.nodes, (std::vector<int>{0, 3}));
  EXPECT_DOUBLE_EQ(spec.fem.cg_tolerance, 1e-4);
  EXPECT_EQ(spec.fem.cg_max_iterations, 50);
  EXPECT_EQ(spec.fem.newton_iterations, 2);
  EXPECT_EQ(spec.fem.rotation_iterations, 4);
  EXPECT_DOUBLE_EQ(spec.fem.friction, 0.3);
  EXPECT_EQ(spec.gauges.at(0).kind, GaugeKind::Node);
  EXPECT_EQ(spec.gauges.at(0).body, "cup-1");
}

TEST_F(SceneBodies, UnnamedBodiesAreNumbered) {
  json s = beam_scene();
  s["bodies"][0].erase("name");
  s["gauges"][0]["body"] = "body0";
  EXPECT_EQ(load_scene(write(s)).bodies.at(0).name, "body0");
}

TEST_F(SceneBodies, EveryGeneratedShapeBuildsInsideTheDomain) {
  json s = beam_scene();
  s["domain"] = {{"min", {-1, -1, -1}}, {"max", {1, 1, 1}}};
  s.erase("gauges");
  for (const char* shape : {"box", "tube", "cup", "sphere", "cloth"}) {
    s["bodies"][0] = {{"name", shape}, {"shape", shape}, {"resolution", 6}};
    const SceneSpec spec = load_scene(write(s));
    const BodyMesh m = build_body_mesh(spec, 0, spec.path);
    EXPECT_GT(m.mesh.tets.size(), 0u) << shape;
    EXPECT_GT(mesh_volume(m.mesh), 0.0) << shape;
  }
}

TEST_F(SceneBodies, PinnedBoxesAndNodesSelectTheirNodes) {
  json s = beam_scene();
  s["bodies"][0]["pinned"]["nodes"] = {5};
  const SceneSpec spec = load_scene(write(s));
  const BodyMesh m = build_body_mesh(spec, 0, spec.path);
  int pinned = 0;
  for (std::size_t i = 0; i < m.mesh.x.size(); ++i) {
    const bool at_root = m.mesh.x[i].x == 0.0;
    if (at_root || i == 5) { EXPECT_EQ(m.pinned[i], 1) << i; }
    pinned += m.pinned[i];
  }
  EXPECT_EQ(pinned, 2 * 2 + (m.mesh.x[5].x == 0.0 ? 0 : 1));  // 10 x 1 x 1 cells: 4 root nodes
}

TEST_F(SceneBodies, MeshFilesLoadRelativeToTheSceneFolder) {
  fs::copy_file(mesh_data("cube.obj"), dir_ / "cube.obj");
  fs::copy_file(mesh_data("cube.node"), dir_ / "cube.node");
  fs::copy_file(mesh_data("cube.ele"), dir_ / "cube.ele");
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"name", "surface"}, {"shape", "mesh"},          {"file", "cube.obj"},
                    {"scale", 0.1},      {"offset", {0.5, -0.1, 0}}, {"max_volume", 1e-5},
                    {"quality", 1.414}};
  s["bodies"][1] = {{"name", "tets"},
                    {"shape", "mesh"},
                    {"file", "cube.ele"},
                    {"scale", 0.1},
                    {"offset", {0.8, -0.1, 0}}};
  const SceneSpec spec = load_scene(write(s));
  const BodyMesh surface = build_body_mesh(spec, 0, spec.path);
  EXPECT_NEAR(mesh_volume(surface.mesh), 1e-3, 1e-12);
  EXPECT_GT(surface.mesh.tets.size(), 12u);  // max_volume refines the 8-corner cube
  const BodyMesh tets = build_body_mesh(spec, 1, spec.path);
  EXPECT_NEAR(mesh_volume(tets.mesh), 1e-3, 1e-12);
  EXPECT_NEAR(bounds(tets.mesh.x).first.x, 0.8, 1e-12);
}

TEST_F(SceneBodies, PoissonRatioAtOneHalf) {
  json s = beam_scene();
  s["bodies"][0]["material"]["poisson"] = 0.5;
  expect_message(s, "bodies[0].material.poisson",
                 {"must be > -1 and < 0.5 (got 0.5)", "; set a value > -1 and < 0.5"});
}

TEST_F(SceneBodies, PoissonRatioAtMinusOne) {
  json s = beam_scene();
  s["bodies"][0]["material"]["poisson"] = -1;
  expect_message(s, "bodies[0].material.poisson", {"must be > -1 and < 0.5 (got -1)"});
}

TEST_F(SceneBodies, NonPositiveDensity) {
  json s = beam_scene();
  s["bodies"][0]["material"]["density"] = 0;
  expect_message(s, "bodies[0].material.density",
                 {"must be > 0 (got 0)", "; set a value > 0 in kg/m^3, e.g. 1000"});
}

TEST_F(SceneBodies, NonPositiveYoungsModulus) {
  json s = beam_scene();
  s["bodies"][0]["material"]["young"] = -5;
  expect_message(s, "bodies[0].material.young",
                 {"must be > 0 (got -5)", "; set a value > 0 in Pa, e.g. 100000"});
}

TEST_F(SceneBodies, PinnedBoxThatHoldsNoNode) {
  json s = beam_scene();
  s["bodies"][0]["pinned"]["boxes"][0] = {{"min", {0.01, -0.05, -0.05}},
                                          {"max", {0.02, 0.05, 0.05}}};
  expect_message(s, "bodies[0].pinned.boxes[0]",
                 {"holds no node of the body", "; move or enlarge the box onto the body",
                  "[0, -0.05, -0.05] .. [1, 0.05, 0.05]"});
}

TEST_F(SceneBodies, PinnedBoxWithCornersSwapped) {
  json s = beam_scene();
  s["bodies"][0]["pinned"]["boxes"][0] = {{"min", {0, 0.05, 0}}, {"max", {0, -0.05, 0}}};
  expect_message(s, "bodies[0].pinned.boxes[0].max",
                 {"must not be below min (y: -0.05 < 0.05)", "; swap or correct the corners"});
}

TEST_F(SceneBodies, PinnedNodeOutOfRange) {
  json s = beam_scene();
  s["bodies"][0]["pinned"]["nodes"] = {0, 5000};
  expect_message(s, "bodies[0].pinned.nodes[1]",
                 {"node 5000 does not exist: the body has 44 nodes", "; use indices from 0 to 43"});
}

TEST_F(SceneBodies, PinnedNodeThatIsNoInteger) {
  json s = beam_scene();
  s["bodies"][0]["pinned"]["nodes"] = {1.5};
  expect_message(s, "bodies[0].pinned.nodes[0]", {"expected an integer, got a number (1.5)"});
}

TEST_F(SceneBodies, MissingMeshFile) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", "nowhere/bunny.obj"}};
  const std::string mesh = (dir_ / "nowhere/bunny.obj").string();
  expect_message(s, "bodies[0].file", {mesh + ": cannot open the file", "; check the path"});
}

TEST_F(SceneBodies, MeshBodyWithoutAFile) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}};
  expect_message(s, "bodies[0].file", {"a mesh body needs a file", "relative to the scene file"});
}

TEST_F(SceneBodies, NonManifoldSurface) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", mesh_data("fin_cube.obj")}, {"scale", 0.1}};
  expect_message(s, "bodies[0].file",
                 {mesh_data("fin_cube.obj") + ": the surface is not manifold", "MeshLab"});
}

TEST_F(SceneBodies, OpenSurface) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", mesh_data("open_cube.obj")}, {"scale", 0.1}};
  expect_message(s, "bodies[0].file",
                 {mesh_data("open_cube.obj") + ": the surface is open", "close the holes"});
}

TEST_F(SceneBodies, InvertedTetMesh) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", mesh_data("inverted.ele")}, {"scale", 0.1}};
  expect_message(s, "bodies[0].file", {mesh_data("inverted.ele") + ": tet 4 has negative volume"});
}

TEST_F(SceneBodies, BodyOutsideTheDomain) {
  json s = beam_scene();
  s["bodies"][0]["position"] = {0.8, 0, 0};
  expect_message(s, "bodies[0].position",
                 {"the body reaches outside the domain on x (", " > domain.max 1.2)",
                  "; move or shrink the body to fit inside the domain [0, -0.5, -0.2] .. "
                  "[1.2, 0.2, 0.2]"});
}

TEST_F(SceneBodies, MeshOutsideTheDomainNamesTheOffset) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", mesh_data("cube.ele")}, {"offset", {0, 0, 0}}};
  expect_message(s, "bodies[0].offset", {"the body reaches outside the domain on y"});
}

TEST_F(SceneBodies, TubeInnerRadiusNotBelowRadius) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "tube"}, {"radius", 0.05}, {"inner_radius", 0.05}};
  expect_message(s, "bodies[0].inner_radius", {"must be below radius (0.05 >= 0.05)"});
}

TEST_F(SceneBodies, ResolutionMakingTooManyTetrahedra) {
  json s = beam_scene();
  s["bodies"][0]["resolution"] = 100000;
  expect_message(s, "bodies[0].resolution", {"tetrahedra, more than", "; lower the resolution"});
}

TEST_F(SceneBodies, TetgenQualityTooLow) {
  json s = beam_scene();
  s.erase("gauges");
  s["bodies"][0] = {{"shape", "mesh"}, {"file", mesh_data("cube.obj")}, {"quality", 0.5}};
  expect_message(s, "bodies[0].quality", {"must be 0 or at least 1.1 (got 0.5)"});
}

TEST_F(SceneBodies, DuplicateBodyNames) {
  json s = beam_scene();
  s["bodies"][1] = s["bodies"][0];
  expect_message(s, "bodies[1].name",
                 {"\"beam\" is already the name of bodies[0]", "; give each body a different"});
}

TEST_F(SceneBodies, BodyNameThatCannotHeadAColumn) {
  json s = beam_scene();
  s["bodies"][0]["name"] = "my beam,1";
  expect_message(s, "bodies[0].name", {"has characters other than letters, digits"});
}

TEST_F(SceneBodies, NodeGaugeOfAnUnknownBody) {
  json s = beam_scene();
  s["gauges"][0]["body"] = "bean";
  expect_message(s, "gauges[0].body",
                 {"there is no body named \"bean\"", "; set body to one of \"beam\""});
}

TEST_F(SceneBodies, NodeGaugeWithoutABody) {
  json s = beam_scene();
  s["gauges"][0].erase("body");
  expect_message(s, "gauges[0].body", {"a node gauge needs the body it follows"});
}

TEST_F(SceneBodies, FluidGaugeThatNamesABody) {
  json s = beam_scene();
  s["gauges"][0]["type"] = "pressure";
  expect_message(s, "gauges[0].body", {"only node gauges follow a body"});
}

TEST_F(SceneBodies, GaugeColumnThatRepeatsABodyColumn) {
  json s = beam_scene();
  s["gauges"][1] = {{"name", "beam_kinetic_energy"}, {"position", {0.5, 0, 0}}};
  expect_message(s, "gauges[1].name",
                 {"its column \"beam_kinetic_energy\" is also a column of bodies[0]"});
}

TEST_F(SceneBodies, NothingToSimulate) {
  json s = beam_scene();
  s.erase("bodies");
  s.erase("gauges");
  expect_message(s, "fluid", {"has no fluid", "and no bodies", "or a body to bodies"});
}

}  // namespace
}  // namespace sphfem
