// Static obstacles (scene `obstacles[]`): water poured into an open funnel mesh runs through
// its hole and never crosses its wall (each particle's path over every step checked against
// the funnel's triangles, an independent count); a soft ball dropped on a tilted plate mesh
// never passes through it; a box obstacle stops the fluid as a wall does; bad obstacles are
// refused with the file, the field and the fix; water at rest against a box has the density
// of the water away from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/collide/collider.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("sphfem_obstacles_" + name);
  fs::create_directories(d);
  return d;
}

// An open cone frustum along y (no caps): radius r0 at y0, r1 at y1 < y0, centred on (cx, cz).
void write_funnel(const fs::path& file, double cx, double cz, double y0, double r0, double y1,
                  double r1, int segments) {
  std::ofstream f(file);
  const double pi = 3.14159265358979323846;
  for (int ring = 0; ring < 2; ++ring)
    for (int k = 0; k < segments; ++k) {
      const double a = 2 * pi * k / segments, r = ring ? r1 : r0, y = ring ? y1 : y0;
      f << "v " << cx + r * std::cos(a) << " " << y << " " << cz + r * std::sin(a) << "\n";
    }
  for (int k = 0; k < segments; ++k) {
    const int a = 1 + k, b = 1 + (k + 1) % segments, c = a + segments, d = b + segments;
    f << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
  }
}

SceneSpec load(const nlohmann::json& j, const fs::path& file) {
  std::ofstream(file) << j.dump(2);
  SceneSpec s = parse_scene(j, file.string());
  validate_scene(s, file.string());
  return s;
}

TEST(SimObstacles, WaterRunsThroughAnOpenFunnelWithoutCrossingIt) {
  const fs::path dir = temp_dir("funnel");
  write_funnel(dir / "funnel.obj", 0.15, 0.15, 0.22, 0.09, 0.12, 0.025, 32);
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0.1, 0.23, 0.1], "max": [0.2, 0.33, 0.2]}]},
    "domain": {"min": [0, 0, 0], "max": [0.3, 0.4, 0.3]},
    "obstacles": [{"name": "funnel", "shape": "mesh", "file": "funnel.obj"}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  const ObstaclesModel& ob = sim.obstacles();
  ASSERT_EQ(ob.tris.size(), 64u);
  EXPECT_EQ(ob.closed[0], 0);
  auto check = make_collider(Backend::Cpu);
  check->build(ob.x, ob.tris);
  auto positions = [&] {
    FluidSnapshot f;
    sim.snapshot(f);
    std::map<std::uint32_t, Vec3> by_id;
    for (int i = 0; i < f.n; ++i) by_id[f.id[i]] = f.x[i];
    return by_id;
  };
  std::map<std::uint32_t, Vec3> prev = positions();
  const long n0 = long(prev.size());
  long crossings = 0;
  while (sim.time() < 0.6 - 1e-9) {
    sim.step(0.6 - sim.time());
    const std::map<std::uint32_t, Vec3> now = positions();
    std::vector<Vec3> from, to;
    for (const auto& [id, x] : now) {
      auto it = prev.find(id);
      if (it == prev.end()) continue;
      from.push_back(it->second);
      to.push_back(x);
    }
    for (int c : check->count_crossings(from, to)) crossings += c;
    prev = now;
  }
  long below = 0;
  for (const auto& [id, x] : prev) below += x.y < 0.11 ? 1 : 0;
  std::printf("%ld particles, %ld below the funnel's hole after 0.6 s, %ld carved, %ld crossings\n",
              n0, below, sim.carved_particles(), crossings);
  EXPECT_EQ(crossings, 0);
  EXPECT_GT(below, n0 / 4) << "the water should run through the hole";
}

// A soft ball dropped at 2 m/s onto a plate tilted by 30 degrees about z (two triangles, open):
// no node ever passes below the plate's plane inside its extent, and the ball moves down the
// slope.
TEST(SimObstacles, SoftBallOnASlideNeverPassesThrough) {
  const fs::path dir = temp_dir("slide");
  const double t = std::tan(3.14159265358979323846 / 6);  // slope: y = 0.2 - t (x - 0.2)
  {
    std::ofstream f(dir / "slide.obj");
    for (double x : {0.02, 0.38})
      for (double z : {0.02, 0.38})
        f << "v " << x << " " << 0.2 - t * (x - 0.2) << " " << z << "\n";
    f << "f 1 2 4\nf 1 4 3\n";
  }
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.001, "duration": 0.4},
    "domain": {"min": [0, 0, 0], "max": [0.4, 0.5, 0.4]},
    "obstacles": [{"name": "slide", "shape": "mesh", "file": "slide.obj"}],
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.2, 0.3, 0.2], "radius": 0.04,
                "resolution": 6, "velocity": [0, -2, 0],
                "material": {"density": 1000, "young": 2e5, "poisson": 0.3,
                             "damping_beta": 0.002}}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  double worst = 1, x0 = 0, x1 = 0;
  auto centre_x = [&](const BodySnapshot& b) {
    double s = 0;
    for (const Vec3& p : b.x) s += double(p.x);
    return s / b.n;
  };
  BodySnapshot b;
  sim.bodies()->snapshot(b);
  x0 = centre_x(b);
  while (sim.time() < 0.4 - 1e-9) {
    sim.step(0.001);
    sim.bodies()->snapshot(b);
    for (const Vec3& p : b.x) {
      if (p.x < 0.02 || p.x > 0.38 || p.z < 0.02 || p.z > 0.38) continue;
      // Signed distance above the plane y + t x - 0.2 - 0.2 t = 0.
      const double d = (double(p.y) + t * double(p.x) - 0.2 - 0.2 * t) / std::sqrt(1 + t * t);
      worst = std::min(worst, d);
    }
  }
  x1 = centre_x(b);
  std::printf("lowest node %.3g m above the slide; the ball moved %.3f m along x\n", worst,
              x1 - x0);
  EXPECT_GE(worst, -1e-6) << "a node passed through the slide";
  EXPECT_GT(x1 - x0, 0.01) << "the ball should move down the slope";
}

// Water at rest around a box standing in it: the particles against the box's faces have the
// density of those away from it (the near-surface density sees closed obstacles), and the
// water settles.
TEST(SimObstacles, WaterAtRestAgainstABoxHasItsRestDensity) {
  const fs::path dir = temp_dir("rest");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0, 0, 0], "max": [0.2, 0.1, 0.2]}]},
    "domain": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]},
    "obstacles": [{"name": "post", "shape": "box", "min": [0.07, 0, 0.07],
                   "max": [0.13, 0.15, 0.13]}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  while (sim.time() < 0.6 - 1e-9) sim.step(0.6 - sim.time());
  FluidSnapshot f;
  sim.snapshot(f);
  const double rho0 = scene.fluid.rest_density;
  double near_sum = 0, far_sum = 0, v_max = 0;
  long near_n = 0, far_n = 0;
  for (int i = 0; i < f.n; ++i) {
    const Vec3& p = f.x[i];
    v_max = std::max(v_max, double(norm(f.v[i])));
    if (p.y < 0.02 || p.y > 0.07) continue;  // away from the floor and the free surface
    // Distance outside the post's square, and from the tank's walls.
    const double dx = std::max({0.07 - double(p.x), double(p.x) - 0.13, 0.0});
    const double dz = std::max({0.07 - double(p.z), double(p.z) - 0.13, 0.0});
    const double d = std::sqrt(dx * dx + dz * dz);
    const double wall = std::min({double(p.x), 0.2 - double(p.x), double(p.z), 0.2 - double(p.z)});
    if (wall < 0.02) continue;
    if (d < 0.01) {
      near_sum += double(f.rho[std::size_t(i)]);
      ++near_n;
    } else if (d > 0.02) {
      far_sum += double(f.rho[std::size_t(i)]);
      ++far_n;
    }
  }
  ASSERT_GT(near_n, 20);
  ASSERT_GT(far_n, 20);
  const double near = near_sum / near_n / rho0, far = far_sum / far_n / rho0;
  std::printf(
      "density against the post %.4f rho0 (%ld particles), away from it %.4f (%ld); "
      "fastest particle %.3g m/s\n",
      near, near_n, far, far_n, v_max);
  EXPECT_NEAR(near, far, 0.002);
  EXPECT_LT(v_max, 0.3) << "the water should settle, not blow up";
}

TEST(SimObstacles, BadObstaclesAreRefusedWithFileFieldAndFix) {
  const fs::path dir = temp_dir("errors");
  auto error_of = [&](const std::string& obstacle) {
    const nlohmann::json j = nlohmann::json::parse(
        R"({"fluid": {"particle_radius": 0.01, "blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]},
            "domain": {"min": [0, 0, 0], "max": [1, 1, 1]}, "obstacles": [)" +
        obstacle + "]}");
    try {
      load(j, dir / "bad.json");
    } catch (const SceneError& e) { return std::string(e.what()); }
    return std::string("accepted");
  };
  const std::string flat =
      error_of(R"({"shape": "box", "min": [0.2, 0.2, 0.2], "max": [0.5, 0.2, 0.5]})");
  EXPECT_NE(flat.find("bad.json: obstacles[0].max: must be above min on y"), std::string::npos)
      << flat;
  const std::string missing = error_of(R"({"shape": "mesh", "file": "nowhere.obj"})");
  EXPECT_NE(missing.find("obstacles[0].file"), std::string::npos) << missing;
  EXPECT_NE(missing.find("nowhere.obj"), std::string::npos) << missing;
  const std::string outside =
      error_of(R"({"shape": "box", "min": [0.5, 0.5, 0.5], "max": [1.5, 0.6, 0.6]})");
  EXPECT_NE(outside.find("outside the domain"), std::string::npos) << outside;
  EXPECT_NE(outside.find("move or shrink it"), std::string::npos) << outside;
  const std::string no_file = error_of(R"({"shape": "mesh"})");
  EXPECT_NE(no_file.find("obstacles[0].file: a mesh obstacle needs a file"), std::string::npos)
      << no_file;
}

}  // namespace
}  // namespace sphfem
