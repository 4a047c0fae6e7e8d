// A light body in water with the default coupling (near-surface density): a soft ball of
// 200 kg/m3 released under the surface rises, comes to rest floating, and its kinetic energy
// decays without a growing oscillation; no particle crosses its surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

TEST(CoupleLightBody, LightBallRisesAndComesToRestFloating) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.006, "viscosity": 1e-5,
              "blocks": [{"min": [0, 0, 0], "max": [0.24, 0.34, 0.24]}]},
    "domain": {"min": [0, 0, 0], "max": [0.24, 0.5, 0.24]},
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.12, 0.14, 0.12],
                "radius": 0.04, "resolution": 6,
                "material": {"density": 200, "young": 2e5, "poisson": 0.3,
                             "damping_alpha": 1.0, "damping_beta": 0.002}}]
  })");
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
  std::printf(
      "height %.3f -> %.3f m; kinetic energy peak %.3g J, 1-1.5 s %.3g, 1.5-2 s %.3g; "
      "%ld crossed\n",
      height.front(), height.back(), peak, mid, late, crossed);
  EXPECT_GT(height.back() - height.front(), 0.1) << "the ball did not rise";
  EXPECT_LT(late, 0.01 * peak) << "the ball did not come to rest";
  EXPECT_LT(late, mid * 1.5) << "the motion grows instead of decaying";
  EXPECT_EQ(crossed, 0);
}

}  // namespace
}  // namespace sphfem
