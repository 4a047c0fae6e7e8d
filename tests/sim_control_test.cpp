// Control of a Simulation between steps and its gauges in memory: an emitter turned off emits
// nothing until turned on; moving a body's pinned nodes carries the body along; a GaugeSeries
// recorded at the frame times equals the gauges.csv of `sphfem run` for the same scene.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/scene/load.h"
#include "sphfem/sim/gauge_series.h"
#include "sphfem/sim/run.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

// The paper's cup, coarse: 9 mm particles, a coarser cup (a few hundred tetrahedra).
SceneSpec small_cup() {
  SceneSpec s = load_scene(std::string(SPHFEM_SOURCE_DIR) + "/scenes/paper/cup.json");
  s.fluid.particle_radius = 0.009;
  s.fluid.max_particles = 4000;
  s.bodies[0].resolution = 5;
  return s;
}

TEST(SimControl, EmitterOffEmitsNothingUntilTurnedOn) {
  Simulation sim(small_cup(), Backend::Cpu);
  ASSERT_TRUE(sim.emitter_enabled(0));
  sim.set_emitter_enabled(0, false);
  EXPECT_FALSE(sim.emitter_enabled(0));
  while (sim.time() < 0.05) sim.step(0.002);
  EXPECT_EQ(sim.fluid()->count(), 0);
  sim.set_emitter_enabled(0, true);
  const double t_on = sim.time();
  while (sim.time() < t_on + 0.05) sim.step(0.002);
  EXPECT_GT(sim.fluid()->count(), 0);
  EXPECT_THROW(sim.set_emitter_enabled(1, false), std::out_of_range);
  EXPECT_THROW(sim.emitter_enabled(-1), std::out_of_range);
}

TEST(SimControl, MovingPinnedNodesCarriesTheBody) {
  SceneSpec scene = small_cup();
  scene.fluid.emitters.clear();  // the cup alone
  Simulation sim(scene, Backend::Cpu);
  const std::vector<int> pinned = sim.pinned_nodes(0);
  ASSERT_FALSE(pinned.empty());
  const BodiesModel& m = sim.bodies_model();
  ASSERT_LT(int(pinned.size()), m.nodes);
  // The base slides 1 mm along x per step for 10 steps, then the cup settles.
  for (int k = 1; k <= 10; ++k) {
    std::vector<Vec3d> x;
    for (int i : pinned) x.push_back(Vec3d(m.x0[std::size_t(i)]) + Vec3d(0.001 * k, 0, 0));
    sim.move_pinned(pinned, x);
    sim.step(0.002);
  }
  for (int k = 0; k < 100; ++k) sim.step(0.002);
  BodySnapshot b;
  sim.bodies()->snapshot(b);
  double free_dx = 0;
  int free = 0;
  for (int i = 0; i < m.nodes; ++i) {
    if (m.pinned[std::size_t(i)]) {
      EXPECT_NEAR(double(b.x[std::size_t(i)].x - m.x0[std::size_t(i)].x), 0.01, 1e-6);
      continue;
    }
    free_dx += double(b.x[std::size_t(i)].x - m.x0[std::size_t(i)].x);
    ++free;
  }
  // The cup follows its base, the nodes resting on the floor held back by its friction; left
  // alone it stays where it was.
  EXPECT_GT(free_dx / free, 0.003);
  EXPECT_LT(free_dx / free, 0.012);
  Simulation still(scene, Backend::Cpu);
  while (still.time() < sim.time() - 1e-9) still.step(0.002);
  BodySnapshot s;
  still.bodies()->snapshot(s);
  double still_dx = 0;
  for (int i = 0; i < m.nodes; ++i)
    if (!m.pinned[std::size_t(i)])
      still_dx += double(s.x[std::size_t(i)].x - m.x0[std::size_t(i)].x);
  EXPECT_LT(std::fabs(still_dx / free), 0.0005);
  int unpinned = 0;
  while (m.pinned[std::size_t(unpinned)]) ++unpinned;
  EXPECT_THROW(sim.move_pinned({unpinned}, {Vec3d()}), std::invalid_argument);
  EXPECT_THROW(sim.move_pinned({m.nodes}, {Vec3d()}), std::invalid_argument);
  EXPECT_THROW(sim.move_pinned(pinned, {}), std::invalid_argument);
  EXPECT_THROW(sim.pinned_nodes(1), std::out_of_range);
}

// gauges.csv as columns by name.
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

TEST(SimControl, GaugeSeriesEqualsTheRunsGaugeFile) {
  SceneSpec scene = small_cup();
  scene.output.vtu = false;
  const double duration = 0.2;  // 6 frames at 30 fps
  const std::string dir =
      (std::filesystem::temp_directory_path() / "sphfem_gauge_series_test").string();
  std::filesystem::remove_all(dir);
  RunOptions opt;
  opt.out_dir = dir;
  opt.duration = duration;
  opt.progress = false;
  run_scene(scene, opt);

  // The run loop's steps: each ends on the next frame time at the latest.
  Simulation sim(scene, Backend::Cpu);
  GaugeSeries g(sim);
  g.record();
  const double frame_dt = 1.0 / scene.output.fps;
  for (int frame = 1; sim.time() < duration - 1e-12; ++frame) {
    const double next = std::min(duration, frame * frame_dt);
    while (sim.time() < next - 1e-9 * std::max(1.0, next)) sim.step(next - sim.time());
    g.record();
  }

  std::ifstream in(dir + "/gauges.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = split(line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> r;
    for (const std::string& c : split(line)) r.push_back(std::stod(c));
    rows.push_back(r);
  }
  ASSERT_EQ(rows.size(), g.rows());
  int compared = 0;
  for (std::size_t c = 0; c < g.columns().size(); ++c) {
    std::size_t k = 0;
    while (k < header.size() && header[k] != g.columns()[c]) ++k;
    ASSERT_LT(k, header.size()) << g.columns()[c] << " is not a column of gauges.csv";
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const double want = rows[r][k], got = g.column(c)[r];
      // gauges.csv prints 9 significant digits.
      EXPECT_NEAR(got, want, 1e-8 * std::max(1.0, std::fabs(want)) + 2e-9 * std::fabs(want))
          << g.columns()[c] << " at row " << r;
    }
    ++compared;
  }
  EXPECT_EQ(compared, 16);           // the fluid's 11, cup_rim_dx/dy/dz and the cup's energies
  EXPECT_GT(g.column(2).back(), 0);  // n_fluid: the emitter has run
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sphfem
