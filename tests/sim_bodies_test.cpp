// Runs with deformable bodies: body frames and gauge columns, pinned nodes, the no-fluid step
// rule, per-body energies, bodies beside fluid, and a body that blows up.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "sphfem/fem/energy.h"
#include "sphfem/io/vtu.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/run.h"
#include "sphfem/sph/solver.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& what) {
  const fs::path p = fs::temp_directory_path() /
                     ("sphfem_sim_bodies_" + what + "_" + std::to_string(std::random_device{}()));
  fs::create_directories(p);
  return p;
}

RunOptions quiet_run(const fs::path& out, double duration) {
  RunOptions o;
  o.out_dir = out.string();
  o.duration = duration;
  o.progress = false;
  return o;
}

struct Csv {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;

  int col(const std::string& name) const {
    for (std::size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == name) return int(i);
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  double at(std::size_t row, const std::string& name) const { return rows.at(row).at(col(name)); }
};

Csv read_csv(const fs::path& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line, cell;
  std::getline(in, line);
  std::istringstream header(line);
  while (std::getline(header, cell, ',')) csv.columns.push_back(cell);
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::vector<double> values;
    while (std::getline(row, cell, ',')) values.push_back(std::stod(cell));
    csv.rows.push_back(values);
  }
  return csv;
}

const io::DataArray& array(const io::PointSet& ps, const std::string& name) {
  for (const io::DataArray& a : ps.point_data)
    if (a.name == name) return a;
  throw std::runtime_error("no point array " + name);
}

std::string frame_name(const char* stem, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "%s_%06d.vtu", stem, frame);
  return name;
}

// scenes/cantilever.json run once for 0.2 s (7 frames at 30 fps) and shared by the tests.
class SimBodies : public ::testing::Test {
 protected:
  static constexpr double kDuration = 0.2;
  static constexpr int kFrames = 7;

  static void SetUpTestSuite() {
    dir_ = new fs::path(scratch("cantilever"));
    scene_ = new SceneSpec(load_scene(std::string(SPHFEM_SOURCE_DIR) + "/scenes/cantilever.json"));
    summary_ = new RunSummary(run_scene(*scene_, quiet_run(*dir_, kDuration)));
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*dir_, ec);
    delete dir_;
    delete scene_;
    delete summary_;
  }

  static io::PointSet frame(const char* stem, int f) {
    return io::read_vtu_points((*dir_ / "frames" / frame_name(stem, f)).string());
  }

  static fs::path* dir_;
  static SceneSpec* scene_;
  static RunSummary* summary_;
};

fs::path* SimBodies::dir_ = nullptr;
SceneSpec* SimBodies::scene_ = nullptr;
RunSummary* SimBodies::summary_ = nullptr;

TEST_F(SimBodies, CantileverWritesBodyFramesThatReadBack) {
  EXPECT_EQ(summary_->particles, 0);
  EXPECT_EQ(summary_->bodies, 1);
  EXPECT_EQ(summary_->body_nodes, 41 * 5 * 5);  // 40 x 4 x 4 cells
  EXPECT_EQ(summary_->frames, kFrames);
  EXPECT_TRUE(fs::exists(*dir_ / "bodies.pvd"));
  EXPECT_TRUE(fs::exists(*dir_ / "bodies_tets.pvd"));
  EXPECT_FALSE(fs::exists(*dir_ / "fluid.pvd"));
  for (int f = 0; f < kFrames; ++f) {
    const io::PointSet tets = frame("bodies_tets", f);
    EXPECT_EQ(tets.size(), std::size_t(41 * 5 * 5)) << f;
    const io::PointSet surface = frame("bodies", f);
    EXPECT_EQ(surface.size(), std::size_t(41 * 5 * 5 - 39 * 3 * 3)) << f;  // interior dropped
    EXPECT_EQ(array(surface, "velocity").size(), 3 * surface.size());
  }
  const nlohmann::json info = nlohmann::json::parse(std::ifstream(*dir_ / "run.json"));
  EXPECT_EQ(info.at("bodies"), nlohmann::json::array({"beam"}));
}

TEST_F(SimBodies, TheTipMovesDown) {
  const io::PointSet last = frame("bodies_tets", kFrames - 1);
  const std::vector<float>& d = array(last, "displacement").values;
  int tip = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    const double rest_x = last.positions[3 * i] - d[3 * i];
    if (rest_x < 1.0 - 1e-4) continue;
    EXPECT_LT(d[3 * i + 1], -0.01) << "tip node " << i;
    ++tip;
  }
  EXPECT_EQ(tip, 25);
}

TEST_F(SimBodies, NodeGaugeReportsTheTipGoingDown) {
  const Csv g = read_csv(*dir_ / "gauges.csv");
  ASSERT_EQ(g.rows.size(), std::size_t(kFrames));
  for (const char* c : {"tip_dx", "tip_dy", "tip_dz", "beam_kinetic_energy", "beam_elastic_energy",
                        "ms_fem", "fem_cg_iterations"})
    g.col(c);
  EXPECT_EQ(g.at(0, "tip_dy"), 0.0);
  const std::size_t last = g.rows.size() - 1;
  EXPECT_LT(g.at(last, "tip_dy"), -0.01);
  EXPECT_GT(g.at(last, "beam_elastic_energy"), 0.0);
  EXPECT_GT(g.at(last, "fem_cg_iterations"), 0.0);
  // The gauge follows the node at the centre of the tip face, which the frame also holds.
  const io::PointSet f = frame("bodies_tets", kFrames - 1);
  const std::vector<float>& d = array(f, "displacement").values;
  bool found = false;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double x = f.positions[3 * i] - d[3 * i], y = f.positions[3 * i + 1] - d[3 * i + 1],
                 z = f.positions[3 * i + 2] - d[3 * i + 2];
    if (std::fabs(x - 1) + std::fabs(y) + std::fabs(z) > 1e-5) continue;
    EXPECT_NEAR(d[3 * i + 1], g.at(last, "tip_dy"), 1e-6);
    found = true;
  }
  EXPECT_TRUE(found);
}

TEST_F(SimBodies, PinnedNodesNeverMove) {
  for (int f = 0; f < kFrames; ++f) {
    const io::PointSet ps = frame("bodies_tets", f);
    const std::vector<float>& d = array(ps, "displacement").values;
    const std::vector<float>& v = array(ps, "velocity").values;
    int pinned = 0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (std::fabs(ps.positions[3 * i] - d[3 * i]) > 1e-6) continue;  // rest x = 0: clamped
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(d[3 * i + c], 0.0f) << "frame " << f << " node " << i;
        EXPECT_EQ(v[3 * i + c], 0.0f) << "frame " << f << " node " << i;
      }
      ++pinned;
    }
    EXPECT_EQ(pinned, 25) << f;
  }
}

TEST_F(SimBodies, WithoutFluidStepsAreAtMostDtMaxAndEndOnEveryFrame) {
  const Csv g = read_csv(*dir_ / "gauges.csv");
  for (std::size_t r = 1; r < g.rows.size(); ++r) {
    EXPECT_LE(g.at(r, "dt"), scene_->simulation.dt_max * (1 + 1e-12)) << r;
    EXPECT_NEAR(g.at(r, "time"), double(r) / scene_->output.fps, 1e-9) << r;
  }
  // 1/30 s in steps of at most 2 ms: 17 equal steps a frame.
  EXPECT_EQ(g.at(1, "step"), 17.0);
  EXPECT_EQ(summary_->steps, 17L * (kFrames - 1));
}

TEST(SimBodyEnergy, PerBodyEnergiesSumToTheSolversTotals) {
  SceneSpec s = load_scene(std::string(SPHFEM_SOURCE_DIR) + "/scenes/cantilever.json");
  BodySpec second = s.bodies[0];
  second.name = "cube";
  second.position = Vec3d(0.5, -0.3, 0);
  second.size = Vec3d(0.1, 0.1, 0.1);
  second.resolution = 3;
  second.pinned = PinSpec();
  second.velocity = Vec3d(0.5, 0, 0);
  s.bodies.push_back(second);
  const BodiesModel model = compile_scene_bodies(s);
  auto solver = make_body_solver(model, Backend::Cpu);
  for (int i = 0; i < 50; ++i) solver->step(2e-3);
  BodySnapshot snap;
  solver->snapshot(snap);
  BodyEnergyMeter meter(model);
  std::vector<double> kinetic, elastic;
  meter.measure(snap, kinetic, elastic);
  ASSERT_EQ(kinetic.size(), 2u);
  EXPECT_GT(kinetic[1], 0.0);
  EXPECT_GT(elastic[0], 0.0);
  EXPECT_NEAR(kinetic[0] + kinetic[1], solver->kinetic_energy(), 1e-4 * solver->kinetic_energy());
  EXPECT_NEAR(elastic[0] + elastic[1], solver->elastic_energy(), 1e-3 * solver->elastic_energy());
}

// A fluid block and a sphere falling beside it: no coupling yet, so the sphere falls freely
// while the fluid settles, both on the fluid's clock.
TEST(SimBodiesWithFluid, FluidAndBodyRunTogether) {
  SceneSpec s;
  s.simulation.duration = 0.1;
  s.simulation.dt_max = 2e-3;
  s.fluid.particle_radius = 0.01;
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.1, 0.1, 0.1), Vec3d()});
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.4, 0.4, 0.2);
  s.output.fps = 30;
  BodySpec ball;
  ball.name = "ball";
  ball.shape = BodyShape::Sphere;
  ball.position = Vec3d(0.3, 0.25, 0.1);
  ball.radius = 0.05;
  ball.resolution = 4;
  s.bodies.push_back(ball);
  s.gauges.push_back({"ball_centre", GaugeKind::Node, Vec3d(0.3, 0.25, 0.1), "ball"});
  s.gauges.push_back({"p_floor", GaugeKind::Pressure, Vec3d(0.05, 0.01, 0.05), ""});
  validate_scene(s, "fluid_and_ball.json");

  const fs::path dir = scratch("fluid_and_ball");
  const RunSummary r = run_scene(s, quiet_run(dir, -1));
  EXPECT_EQ(r.particles, 125);
  EXPECT_EQ(r.bodies, 1);
  EXPECT_EQ(r.frames, 4);
  for (const char* f : {"fluid_000003.vtu", "bodies_000003.vtu", "bodies_tets_000003.vtu"})
    EXPECT_TRUE(fs::exists(dir / "frames" / f)) << f;
  const Csv g = read_csv(dir / "gauges.csv");
  const std::size_t last = g.rows.size() - 1;
  EXPECT_EQ(g.at(last, "n_fluid"), 125.0);
  EXPECT_GT(g.at(last, "p_floor"), 0.0);
  // Free fall for 0.1 s: -g t^2 / 2 = -4.9 cm (implicit Euler lags by g t dt / 2).
  EXPECT_NEAR(g.at(last, "ball_centre_dy"), -0.5 * 9.81 * 0.1 * 0.1, 2e-3);
  EXPECT_GT(g.at(last, "ball_kinetic_energy"), 0.0);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// Young's modulus beyond the float range makes the first step's forces NaN: the run stops with
// the step and advice, keeping the frame written before.
TEST(SimBodyBlowUp, StopsWithStepAndAdviceAndKeepsFrames) {
  if (sizeof(Real) != sizeof(float)) GTEST_SKIP() << "needs single-precision bodies";
  SceneSpec s = load_scene(std::string(SPHFEM_SOURCE_DIR) + "/scenes/cantilever.json");
  s.bodies[0].material.young = 1e39;
  const fs::path dir = scratch("blow_up");
  try {
    run_scene(s, quiet_run(dir, 0.1));
    ADD_FAILURE() << "the run did not stop";
  } catch (const SimulationError& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.step, 1);
    EXPECT_NE(m.find("step 1 (t = "), std::string::npos) << m;
    EXPECT_NE(m.find("non-finite (NaN)"), std::string::npos) << m;
    EXPECT_NE(m.find("simulation.dt_max"), std::string::npos) << m;
    EXPECT_NE(m.find("fem.cg_max_iterations"), std::string::npos) << m;
  }
  EXPECT_NO_THROW(io::read_vtu_points((dir / "frames" / "bodies_000000.vtu").string()));
  for (const auto& e : fs::directory_iterator(dir / "frames"))
    EXPECT_EQ(e.path().extension(), ".vtu") << "left-over temporary file " << e.path();
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace sphfem
