// Obstacles on a prescribed path (`obstacles[].path`): the path's poses are rigid motions that
// meet their keys; a paddle turning through water never has a particle inside it (counted by
// an independent point-in-box test in the paddle's frame) and sets the water moving its way; a
// soft ball on a rising lift never sinks into it and rises with it; a run writes the obstacle
// where it is in each frame; bad paths are refused with the file, the field and the fix.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/io/vtu.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/run.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("sphfem_moving_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

SceneSpec load(const nlohmann::json& j, const fs::path& file) {
  std::ofstream(file) << j.dump(2);
  SceneSpec s = parse_scene(j, file.string());
  validate_scene(s, file.string());
  return s;
}

ObstacleKeySpec key(double t, Vec3d translate, Vec3d axis, double angle) {
  ObstacleKeySpec k;
  k.time = t;
  k.translate = translate;
  k.axis = axis;
  k.angle = angle;
  return k;
}

TEST(ObstaclePath, PosesAreRigidAndMeetTheirKeys) {
  const Vec3d pivot(1, 2, 3);
  const std::vector<ObstacleKeySpec> path = {key(0.5, Vec3d(0, 0, 0), Vec3d(0, 0, 2), 0),
                                             key(1.5, Vec3d(1, -2, 4), Vec3d(0, 0, 2), 720),
                                             key(2.5, Vec3d(1, -2, 4), Vec3d(1, 0, 0), 90)};
  const Vec3d p(3, -1, 0.5), q(-2, 0.25, 7);
  // Held before the first key (the identity, bit for bit) and after the last.
  const RigidPose before = path_pose(path, pivot, 0.1);
  EXPECT_TRUE(before.identity);
  EXPECT_EQ(before.apply(p).x, p.x);
  const RigidPose last = path_pose(path, pivot, 9.0);
  const Vec3d rx = last.apply(p) - Vec3d(1, -2, 4) - pivot;  // p - pivot turned 90 deg about x
  EXPECT_NEAR(rx.x, 2, 1e-12);
  EXPECT_NEAR(rx.y, 2.5, 1e-12);
  EXPECT_NEAR(rx.z, -3, 1e-12);
  // One axis: 720 degrees over a second is two whole turns, a quarter of the way is 180.
  const RigidPose half = path_pose(path, pivot, 1.0);
  const Vec3d h = half.apply(p) - Vec3d(0.5, -1, 2);
  EXPECT_NEAR(h.x, p.x, 1e-12);
  EXPECT_NEAR(h.y, p.y, 1e-12);
  const RigidPose quarter = path_pose(path, pivot, 0.75);
  const Vec3d r = quarter.apply(p) - Vec3d(0.25, -0.5, 1) - pivot;
  EXPECT_NEAR(r.x, -(p.x - pivot.x), 1e-12);
  EXPECT_NEAR(r.y, -(p.y - pivot.y), 1e-12);
  EXPECT_NEAR(r.z, p.z - pivot.z, 1e-12);
  // Every pose keeps distances and undoes exactly; the turn between two axes is even.
  for (double t = 0; t < 3; t += 0.0625) {
    const RigidPose m = path_pose(path, pivot, t);
    EXPECT_NEAR(norm(m.apply(p) - m.apply(q)), norm(p - q), 1e-12) << t;
    EXPECT_NEAR(norm(m.inverse(m.apply(q)) - q), 0, 1e-12) << t;
  }
  const Vec3d a0 = path_pose(path, pivot, 1.5).apply(q), a1 = path_pose(path, pivot, 2.0).apply(q),
              a2 = path_pose(path, pivot, 2.5).apply(q);
  EXPECT_NEAR(norm(a1 - a0), norm(a2 - a1), 1e-9) << "slerp turns evenly";
}

// Is p inside the box [lo, hi] as the pose carries it?
bool inside_box(const RigidPose& pose, const Vec3d& lo, const Vec3d& hi, const Vec3& p) {
  const Vec3d l = pose.inverse(Vec3d(p));
  return l.x > lo.x && l.x < hi.x && l.y > lo.y && l.y < hi.y && l.z > lo.z && l.z < hi.z;
}

// A thin paddle through resting water, turning about the vertical axis at 1.5 turns a second
// after a quarter-second start-up: its faces reach 0.8 m/s, pushing particles ahead at 40 times
// their spacing per second.
TEST(SimMovingObstacles, TurningPaddleStirsWaterAndNothingGetsInside) {
  const fs::path dir = temp_dir("paddle");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0.0, 0.0, 0.0], "max": [0.24, 0.08, 0.24]}]},
    "domain": {"min": [0, 0, 0], "max": [0.24, 0.2, 0.24]},
    "obstacles": [{"name": "paddle", "shape": "box", "min": [0.04, 0.01, 0.11],
                   "max": [0.2, 0.15, 0.13], "pivot": [0.12, 0, 0.12],
                   "path": [{"time": 0, "axis": [0, 1, 0], "angle": 0},
                            {"time": 0.25, "axis": [0, 1, 0], "angle": 67.5},
                            {"time": 1.25, "axis": [0, 1, 0], "angle": 607.5}]}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  const ObstaclesModel& ob = sim.obstacles();
  ASSERT_TRUE(ob.moving());
  const Vec3d lo(0.04, 0.01, 0.11), hi(0.2, 0.15, 0.13);
  long inside_max = 0, crossed = 0;
  double l_max = 0;  // angular momentum of the water about the axis
  FluidSnapshot f;
  const double m = double(sim.fluid_model().params.mass);
  const double end = 0.5;
  while (sim.time() < end - 1e-9) {
    sim.step(end - sim.time());
    sim.snapshot(f);
    const RigidPose pose = ob.pose(0, sim.time());
    long inside = 0;
    double l = 0;
    for (int i = 0; i < f.n; ++i) {
      inside += inside_box(pose, lo, hi, f.x[i]) ? 1 : 0;
      const double rx = double(f.x[i].x) - 0.12, rz = double(f.x[i].z) - 0.12;
      l += m * (rz * double(f.v[i].x) - rx * double(f.v[i].z));
    }
    inside_max = std::max(inside_max, inside);
    l_max = std::max(l_max, l);
    ASSERT_TRUE(std::isfinite(l)) << "at " << sim.time() << " s";
  }
  crossed = sim.coupling()->stats().crossed;
  double v_max = 0;
  for (int i = 0; i < f.n; ++i) v_max = std::max(v_max, double(norm(f.v[i])));
  std::printf(
      "%d particles, %ld carved; most inside the paddle %ld, crossed %ld; the water's angular "
      "momentum about the axis up to %.3g kg m^2/s, fastest particle %.2f m/s\n",
      f.n, sim.carved_particles(), inside_max, crossed, l_max, v_max);
  EXPECT_EQ(inside_max, 0) << "particles inside the moving paddle";
  EXPECT_EQ(crossed, 0);
  // Turning counter-clockwise seen from +y (right-handed about +y), the paddle gives the water
  // positive angular momentum about +y: L_y = z v_x - x v_z.
  EXPECT_GT(l_max, 1e-3) << "the paddle should stir the water its way";
  // No ejection: nothing leaves faster than a few times the paddle's tip speed.
  EXPECT_LT(v_max, 3 * 0.08 * 3 * kPi);
}

// A press: a plate lowered onto a layer of water down to a particle spacing off the floor. The
// water is squeezed out from under it; none is trapped inside the plate or pushed through the
// floor, and none is shot out faster than the squeeze itself drives it (mass conservation:
// plate speed times half its width over the gap, 0.8 m/s at the end).
TEST(SimMovingObstacles, PressSqueezesWaterOutFromUnderIt) {
  const fs::path dir = temp_dir("press");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"solver": "dfsph", "dt_max": 0.002},
    "fluid": {"particle_radius": 0.005, "viscosity": 1e-5,
              "blocks": [{"min": [0, 0, 0], "max": [0.2, 0.03, 0.2]}]},
    "domain": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]},
    "obstacles": [{"name": "plate", "shape": "box", "min": [0.04, 0.05, 0.04],
                   "max": [0.16, 0.07, 0.16],
                   "path": [{"time": 0}, {"time": 0.3, "translate": [0, -0.04, 0]}]}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  const Vec3d lo(0.04, 0.05, 0.04), hi(0.16, 0.07, 0.16);
  long inside_max = 0, below = 0, under_end = 0;
  double v_max = 0;
  FluidSnapshot f;
  const double end = 0.4;
  while (sim.time() < end - 1e-9) {
    sim.step(end - sim.time());
    sim.snapshot(f);
    const RigidPose pose = sim.obstacles().pose(0, sim.time());
    long inside = 0;
    for (int i = 0; i < f.n; ++i) {
      inside += inside_box(pose, lo, hi, f.x[i]) ? 1 : 0;
      below += f.x[i].y < 0 ? 1 : 0;
      v_max = std::max(v_max, double(norm(f.v[i])));
    }
    inside_max = std::max(inside_max, inside);
  }
  for (int i = 0; i < f.n; ++i)
    under_end +=
        f.x[i].x > 0.05 && f.x[i].x < 0.15 && f.x[i].z > 0.05 && f.x[i].z < 0.15 && f.x[i].y < 0.01;
  std::printf(
      "%d particles; most inside the plate %ld, below the floor %ld, crossed %ld; fastest "
      "%.2f m/s; %ld left under the plate's middle\n",
      f.n, inside_max, below, sim.coupling()->stats().crossed, v_max, under_end);
  EXPECT_EQ(inside_max, 0);
  EXPECT_EQ(below, 0);
  EXPECT_EQ(sim.coupling()->stats().crossed, 0);
  EXPECT_LT(v_max, 3 * 0.8);
}

// A soft ball resting on a box lifted by 0.1 m over 0.4 s, then held: no node ever sinks into
// the lift (checked in the lift's frame), and the ball ends up on it, 0.1 m higher.
TEST(SimMovingObstacles, SoftBallRidesARisingLift) {
  const fs::path dir = temp_dir("lift");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.001, "duration": 0.8},
    "domain": {"min": [0, 0, 0], "max": [0.4, 0.5, 0.4]},
    "obstacles": [{"name": "lift", "shape": "box", "min": [0.05, 0.05, 0.05],
                   "max": [0.35, 0.1, 0.35],
                   "path": [{"time": 0.2}, {"time": 0.6, "translate": [0, 0.1, 0]}]}],
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.2, 0.141, 0.2], "radius": 0.04,
                "resolution": 6,
                "material": {"density": 1000, "young": 2e5, "poisson": 0.3,
                             "damping_beta": 0.002}}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  BodySnapshot b;
  auto lowest = [&] {
    sim.bodies()->snapshot(b);
    double y = 1;
    for (const Vec3& p : b.x) y = std::min(y, double(p.y));
    return y;
  };
  const double y0 = lowest();
  double worst = 1;  // the lowest node's height above the lift's top
  while (sim.time() < 0.8 - 1e-9) {
    sim.step(0.001);
    const double top = 0.1 + sim.obstacles().pose(0, sim.time()).t.y;
    worst = std::min(worst, lowest() - top);
  }
  const double y1 = lowest();
  std::printf("lowest node %.3g m above the lift at worst; it rose %.4f m (the lift 0.1 m)\n",
              worst, y1 - y0);
  EXPECT_GE(worst, -1e-6) << "a node sank into the lift";
  EXPECT_NEAR(y1 - y0, 0.1, 0.005) << "the ball should ride the lift up";
}

// A body's pinned nodes are held: an obstacle sweeping through them leaves them where they are,
// while it pushes the free ones ahead of it.
TEST(SimMovingObstacles, PinnedNodesHoldWhileFreeOnesArePushed) {
  const fs::path dir = temp_dir("pinned");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.001, "duration": 0.1},
    "domain": {"min": [-0.3, 0, -0.3], "max": [0.3, 0.4, 0.3]},
    "bodies": [{"name": "beam", "shape": "box", "position": [0, 0.2, 0], "size": [0.3, 0.04, 0.04],
                "resolution": 8, "pinned": {"boxes": [{"min": [-1, -1, -1], "max": [0, 1, 1]}]},
                "material": {"density": 1000, "young": 1e6, "poisson": 0.3}}],
    "obstacles": [{"min": [-0.2, 0.1, -0.1], "max": [0.2, 0.15, 0.1],
                   "path": [{"time": 0}, {"time": 0.1, "translate": [0, 0.1, 0]}]}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  Simulation sim(scene, Backend::Cpu);
  const BodiesModel& m = sim.bodies_model();
  while (sim.time() < 0.1 - 1e-9) sim.step(0.001);
  BodySnapshot b;
  sim.bodies()->snapshot(b);
  double pinned_moved = 0, free_lowest = 1;
  for (int i = 0; i < b.n; ++i) {
    if (m.pinned[std::size_t(i)])
      pinned_moved = std::max(pinned_moved, double(norm(b.x[i] - m.x0[std::size_t(i)])));
    else if (m.x0[std::size_t(i)].x > 0.05)
      free_lowest = std::min(free_lowest, double(b.x[i].y));
  }
  std::printf("pinned nodes moved %.3g m; the free end's lowest node at %.4f m (lift top 0.25)\n",
              pinned_moved, free_lowest);
  EXPECT_EQ(pinned_moved, 0.0);
  EXPECT_GE(free_lowest, 0.25 - 1e-6) << "the free end should be lifted on the obstacle";
}

// A run writes the obstacle per frame (obstacles.pvd and frames/obstacles_*.vtu) where it is.
TEST(SimMovingObstacles, RunWritesTheObstacleWhereItIsInEachFrame) {
  const fs::path dir = temp_dir("frames");
  const nlohmann::json j = nlohmann::json::parse(R"({
    "simulation": {"dt_max": 0.005, "duration": 0.2},
    "output": {"fps": 10},
    "domain": {"min": [0, 0, 0], "max": [0.4, 0.5, 0.4]},
    "obstacles": [{"name": "lift", "shape": "box", "min": [0.05, 0.05, 0.05],
                   "max": [0.35, 0.1, 0.35],
                   "path": [{"time": 0}, {"time": 0.2, "translate": [0, 0.1, 0]}]}],
    "bodies": [{"name": "ball", "shape": "sphere", "position": [0.2, 0.3, 0.2], "radius": 0.04,
                "resolution": 3, "material": {"density": 1000, "young": 2e5, "poisson": 0.3}}]
  })");
  const SceneSpec scene = load(j, dir / "scene.json");
  RunOptions o;
  o.out_dir = (dir / "out").string();
  o.progress = false;
  run_scene(scene, o);
  EXPECT_TRUE(fs::exists(dir / "out" / "obstacles.pvd"));
  EXPECT_FALSE(fs::exists(dir / "out" / "obstacles.vtu"));
  for (int frame = 0; frame <= 2; ++frame) {
    char name[64];
    std::snprintf(name, sizeof name, "obstacles_%06d.vtu", frame);
    const io::PointSet ps = io::read_vtu((dir / "out" / "frames" / name).string());
    double top = -1;
    for (std::size_t i = 1; i < ps.positions.size(); i += 3)
      top = std::max(top, double(ps.positions[i]));
    EXPECT_NEAR(top, 0.1 + 0.05 * frame, 1e-6) << name;
  }
}

TEST(SimMovingObstacles, BadPathsAreRefusedWithFileFieldAndFix) {
  const fs::path dir = temp_dir("errors");
  auto error_of = [&](const std::string& path) {
    const nlohmann::json j = nlohmann::json::parse(
        R"({"fluid": {"particle_radius": 0.01, "blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]},
            "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
            "obstacles": [{"min": [0.4, 0.4, 0.4], "max": [0.6, 0.6, 0.6], "pivot": [0.5, 0.5, 0.5],
                           "path": )" +
        path + "}]}");
    try {
      load(j, dir / "bad.json");
    } catch (const SceneError& e) { return std::string(e.what()); }
    return std::string("accepted");
  };
  const std::string order = error_of(R"([{"time": 1}, {"time": 0.5}])");
  EXPECT_NE(order.find("bad.json: obstacles[0].path[1].time"), std::string::npos) << order;
  EXPECT_NE(order.find("increasing time"), std::string::npos) << order;
  const std::string axis = error_of(R"([{"time": 0, "axis": [0, 0, 0], "angle": 30}])");
  EXPECT_NE(axis.find("obstacles[0].path[0].axis"), std::string::npos) << axis;
  // Inside the domain at every key and between them.
  const std::string out = error_of(
      R"([{"time": 0, "translate": [0.3, 0, 0]}, {"time": 2, "translate": [-0.3, 0, 0]}])");
  EXPECT_EQ(out, "accepted");
  // Inside at both keys, out half way between them: the turn sweeps the corners out.
  const std::string swept = error_of(R"([{"time": 0, "translate": [0.38, 0, 0]},
                   {"time": 1, "translate": [0.38, 0, 0], "axis": [0, 0, 1], "angle": 90}])");
  EXPECT_NE(swept.find("obstacles[0].path"), std::string::npos) << swept;
  EXPECT_NE(swept.find("outside the domain"), std::string::npos) << swept;
  EXPECT_NE(swept.find(" s, reaching"), std::string::npos) << swept;
}

}  // namespace
}  // namespace sphfem
