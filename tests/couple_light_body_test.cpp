// Light bodies in water: a soft ball of 200 kg/m3 released under the surface rises, comes to
// rest floating, and its kinetic energy decays without a growing oscillation, in both
// ray-traced modes; no particle crosses its surface. A light cloth under a falling column
// (disabled: not yet stable).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

// Both ray-traced modes: with the near-surface density (the default) and the paper's
// exchange alone. The paper's mode keeps more motion in the ball's nodes at rest (its light
// nodes meet the particles one contact at a time), so its energy bound is 10 % of the peak
// instead of 1 %; both must rise, settle at one height and decay.
class CoupleLightBall : public ::testing::TestWithParam<bool> {};

TEST_P(CoupleLightBall, RisesAndComesToRestFloating) {
  const bool near_surface = GetParam();
  nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.006, "viscosity": 1e-5,
              "blocks": [{"min": [0, 0, 0], "max": [0.24, 0.34, 0.24]}]},
    "domain": {"min": [0, 0, 0], "max": [0.24, 0.5, 0.24]},
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.12, 0.14, 0.12],
                "radius": 0.04, "resolution": 6,
                "material": {"density": 200, "young": 2e5, "poisson": 0.3,
                             "damping_alpha": 1.0, "damping_beta": 0.002}}]
  })");
  j["coupling"]["near_surface_density"] = near_surface;
  // By hand: SPHFEM_TEST_IMPLICIT_EXCHANGE=1, the exchange through the ball's step operator.
  if (const char* e = std::getenv("SPHFEM_TEST_IMPLICIT_EXCHANGE"))
    j["coupling"]["implicit_exchange"] = std::string(e) == "1";
  const SceneSpec scene = parse_scene(j, "ball.json");
  validate_scene(scene, "ball.json");
  Simulation sim(scene, Backend::Cpu);
  const BodiesModel& m = sim.bodies_model();
  // Centre of mass height and kinetic energy of the ball, every 0.05 s.
  std::vector<double> height, energy;
  auto measure = [&] {
    BodySnapshot b;
    sim.bodies()->snapshot(b);
    double mass = 0, y = 0, e = 0;
    for (int i = 0; i < b.n; ++i) {
      const double mi = double(m.mass[std::size_t(i)]);
      mass += mi;
      y += mi * double(b.x[i].y);
      e += 0.5 * mi * double(norm2(b.v[i]));
    }
    height.push_back(y / mass);
    energy.push_back(e);
  };
  long crossed = 0;
  measure();
  for (int frame = 1; frame <= 40; ++frame) {
    const double until = 0.05 * frame;
    while (sim.time() < until - 1e-9) sim.step(until - sim.time());
    crossed += sim.coupling()->stats().crossed;
    sim.coupling()->reset_stats();
    measure();
  }
  const double peak = *std::max_element(energy.begin(), energy.end());
  const double late = *std::max_element(energy.begin() + 30, energy.end());        // 1.5-2 s
  const double mid = *std::max_element(energy.begin() + 20, energy.begin() + 30);  // 1-1.5 s
  const auto settled = std::minmax_element(height.begin() + 30, height.end());
  const long inside = sim.count_inside();
  std::printf(
      "near-surface %d: height %.3f -> %.3f m (%.4f over 1.5-2 s); kinetic energy peak %.3g J, "
      "1-1.5 s %.3g, 1.5-2 s %.3g; %ld crossed, %ld inside\n",
      int(near_surface), height.front(), height.back(), *settled.second - *settled.first, peak, mid,
      late, crossed, inside);
  EXPECT_GT(height.back() - height.front(), 0.1) << "the ball did not rise";
  // At rest: its height within a particle spacing (12 mm, the water surface's own roughness).
  EXPECT_LT(*settled.second - *settled.first, 0.012) << "the ball does not rest at one height";
  EXPECT_LT(late, (near_surface ? 0.01 : 0.1) * peak) << "the ball did not come to rest";
  EXPECT_LT(late, mid * 1.5) << "the motion grows instead of decaying";
  EXPECT_EQ(crossed, 0);
  EXPECT_EQ(inside, 0);
}

INSTANTIATE_TEST_SUITE_P(Modes, CoupleLightBall, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return std::string(i.param ? "NearSurfaceDensity" : "PaperMode");
                         });

// A light cloth (0.2 kg/m2, pinned along two opposite edges) under a falling column of water
// 55 times heavier, in both ray-traced modes. Disabled: it fails in both modes, with either
// exchange (the open item of docs/validation.md, "A light cloth under a falling column"); run
// it by hand with --gtest_also_run_disabled_tests. Knobs for that: SPHFEM_TEST_IMPLICIT_EXCHANGE=1
// (the implicit exchange), SPHFEM_TEST_DT_MAX (seconds), SPHFEM_TEST_SOLVER (wcsph, dfsph),
// SPHFEM_TEST_PIN_ALL=1 (the whole cloth pinned: the same water on an immovable sheet),
// SPHFEM_TEST_CLOTH_DENSITY (kg/m3; 50 is 0.2 kg/m2),
// SPHFEM_TEST_TRACE=1 (a line per step).
// The water lands at about 1 m/s; the cloth sags nearly to the floor and the water runs off its
// free edges. Asserted, as laws: the total energy (kinetic, gravitational and elastic, water and
// cloth) never rises above the start's (the impact, damping and viscosity only take it); no node
// is shot off (at most 3 m/s, above the 2.4 m/s of a fall from the column's top to the floor);
// the cloth's kinetic energy decays at the end; nothing crosses the cloth.
class CoupleLightCloth : public ::testing::TestWithParam<bool> {};

TEST_P(CoupleLightCloth, DISABLED_SagsUnderAFallingColumnWithoutJitter) {
  const bool near_surface = GetParam();
  nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0.11, 0.2, 0.11], "max": [0.19, 0.3, 0.19]}]},
    "domain": {"min": [0, 0, 0], "max": [0.3, 0.35, 0.3]},
    "bodies": [{"name": "cloth", "shape": "cloth", "position": [0.15, 0.15, 0.15],
                "size": [0.24, 0.01, 0.24], "thickness": 0.004, "resolution": 24,
                "material": {"density": 50, "young": 1e5, "poisson": 0.3, "damping_beta": 0.001},
                "pinned": {"boxes": [{"min": [0, 0, 0], "max": [0.035, 0.3, 0.3]},
                                     {"min": [0.265, 0, 0], "max": [0.3, 0.3, 0.3]}]}}]
  })");
  j["coupling"]["near_surface_density"] = near_surface;
  if (std::getenv("SPHFEM_TEST_PIN_ALL")) j["bodies"][0]["pinned"]["boxes"][0]["max"][0] = 0.3;
  if (const char* e = std::getenv("SPHFEM_TEST_DT_MAX")) j["simulation"]["dt_max"] = std::atof(e);
  if (const char* e = std::getenv("SPHFEM_TEST_SOLVER")) j["simulation"]["solver"] = e;
  if (const char* e = std::getenv("SPHFEM_TEST_CLOTH_DENSITY"))
    j["bodies"][0]["material"]["density"] = std::atof(e);
  if (const char* e = std::getenv("SPHFEM_TEST_IMPLICIT_EXCHANGE"))
    j["coupling"]["implicit_exchange"] = std::string(e) == "1";
  const SceneSpec scene = parse_scene(j, "cloth.json");
  validate_scene(scene, "cloth.json");
  Simulation sim(scene, Backend::Cpu);
  const Vec3 g = sim.fluid_model().params.gravity;
  const double mp = double(sim.fluid_model().params.mass);
  const std::vector<Real>& node_mass = sim.bodies_model().mass;
  // Kinetic, gravitational and elastic energy of water and cloth, from snapshots.
  auto total_energy = [&](const FluidSnapshot& f, const BodySnapshot& b) {
    double e = sim.bodies()->kinetic_energy() + sim.bodies()->elastic_energy();
    for (int i = 0; i < b.n; ++i) e -= double(node_mass[std::size_t(i)]) * double(dot(g, b.x[i]));
    for (int i = 0; i < f.n; ++i) e += mp * (0.5 * double(norm2(f.v[i])) - double(dot(g, f.x[i])));
    return e;
  };
  const double duration = 0.5;
  double node_max = 0, fluid_max = 0, e_mid = 0, e_late = 0, e_start = 0, e_peak = 0, t_peak = 0;
  long crossed = 0;
  while (sim.time() < duration - 1e-9) {
    if (sim.steps() == 0) {
      BodySnapshot b;
      sim.bodies()->snapshot(b);
      FluidSnapshot f;
      sim.snapshot(f);
      e_start = e_peak = total_energy(f, b);
    }
    const double dt = sim.step(duration - sim.time()).dt;
    BodySnapshot b;
    sim.bodies()->snapshot(b);
    FluidSnapshot f;
    sim.snapshot(f);
    double vn = 0, vf = 0;
    const double ek = sim.bodies()->kinetic_energy(), E = total_energy(f, b);
    for (const Vec3& v : b.v) vn = std::max(vn, double(norm(v)));
    for (int i = 0; i < f.n; ++i) vf = std::max(vf, double(norm(f.v[i])));
    node_max = std::max(node_max, vn);
    fluid_max = std::max(fluid_max, vf);
    if (E > e_peak) e_peak = E, t_peak = sim.time();
    if (sim.time() > 0.3 && sim.time() <= 0.4) e_mid = std::max(e_mid, ek);
    if (sim.time() > 0.4) e_late = std::max(e_late, ek);
    const RayCouplingStats& st = sim.coupling()->stats();
    if (std::getenv("SPHFEM_TEST_TRACE"))
      std::printf("E %.6f t %.4f dt %.2e node %.3f fluid %.3f contacts %ld rounds %ld cg %ld\n", E,
                  sim.time(), dt, vn, vf, st.contacts, st.joint_rounds, st.joint_iterations);
    crossed += st.crossed;
    sim.coupling()->reset_stats();
  }
  std::printf(
      "near-surface %d: total energy %.4f J at the start, at most %.4f J (%.3f s); fastest node "
      "%.3f m/s, fastest particle %.3f m/s; cloth kinetic energy 0.3-0.4 s %.3g J, 0.4-0.5 s "
      "%.3g J; %ld crossed\n",
      int(near_surface), e_start, e_peak, t_peak, node_max, fluid_max, e_mid, e_late, crossed);
  // 0.1 % for the float sums of 640 particles' energies.
  EXPECT_LE(e_peak, e_start * 1.001) << "energy created";
  EXPECT_LT(node_max, 3.0);
  EXPECT_LE(e_late, e_mid * 1.2);
  EXPECT_EQ(crossed, 0);
}

INSTANTIATE_TEST_SUITE_P(Modes, CoupleLightCloth, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return std::string(i.param ? "NearSurfaceDensity" : "PaperMode");
                         });

}  // namespace
}  // namespace sphfem
