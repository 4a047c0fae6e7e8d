// Resource limits: a scene is counted from its fields before anything is allocated, and one
// that passes a cap or the free memory is refused at once, naming the file, the field and the
// fix. The counts are checked against the lattices compile_fluid and the shapes really build.
#include <gtest/gtest.h>
#include <malloc.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "cli_harness.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/compile.h"
#include "sphfem/scene/limits.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

#if defined(__SANITIZE_ADDRESS__)
// The sanitizer runtime's count of bytes handed out (its allocator_interface.h, which GCC does
// not install).
extern "C" size_t __sanitizer_get_current_allocated_bytes();
#endif

namespace sphfem {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

class SceneLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("sphfem_limits_" + test + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& text, const std::string& name = "scene.json") {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  // The message load_scene throws, and that it came at once (no lattice was filled).
  std::string refused(const std::string& text) {
    const std::string path = write(text);
    const auto t0 = Clock::now();
    std::string msg;
    try {
      load_scene(path);
      ADD_FAILURE() << text << " loaded";
    } catch (const SceneError& e) { msg = e.what(); }
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 2.0) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(msg.rfind(path, 0), 0u) << msg;
    return msg;
  }
  fs::path dir_;
};

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST_F(SceneLimits, TinyParticlesAreRefusedWithCountAndMemory) {
  // ~1.6e13 particles: it used to allocate for minutes.
  const std::string m = refused(
      R"({"fluid": {"blocks": [{"min": [0,0,0], "max": [0.5,0.5,0.5]}], "particle_radius": 1e-5}})");
  EXPECT_TRUE(has(m, "fluid.particle_radius")) << m;
  EXPECT_TRUE(has(m, "1.56e+13 particles")) << m;
  EXPECT_TRUE(has(m, "GiB")) << m;
  EXPECT_TRUE(has(m, "set particle_radius to at least")) << m;
}

TEST_F(SceneLimits, EndlessDurationIsRefusedNamingTheFrames) {
  const std::string m = refused(
      R"({"fluid": {"blocks": [{"min": [0,0,0], "max": [0.1,0.1,0.1]}], "particle_radius": 0.01},
          "simulation": {"duration": 1e308}})");
  EXPECT_TRUE(has(m, "simulation.duration")) << m;
  EXPECT_TRUE(has(m, "frames")) << m;
  EXPECT_TRUE(has(m, "1000000")) << m;
}

TEST_F(SceneLimits, EmittersOverALongRunAreCounted) {
  // 1e5 s of a 1 cm nozzle at 10 m/s: about 4e8 particles of 1 cm.
  const std::string m = refused(R"({"domain": {"min": [0,0,0], "max": [1,1,1]},
      "simulation": {"duration": 1e5}, "output": {"fps": 1},
      "fluid": {"particle_radius": 0.005, "emitters": [{"position": [0.5,0.9,0.5],
                "direction": [0,-1,0], "radius": 0.02, "speed": 10}]}})");
  EXPECT_TRUE(has(m, "fluid.emitters")) << m;
  EXPECT_TRUE(has(m, "from the emitters")) << m;
}

TEST_F(SceneLimits, MaxParticlesBeyondTheCapIsRefused) {
  const std::string m = refused(R"({"fluid": {"blocks": [{"min": [0,0,0], "max": [0.1,0.1,0.1]}],
      "particle_radius": 0.01, "max_particles": 2000000000}})");
  EXPECT_TRUE(has(m, "fluid.max_particles")) << m;
}

TEST_F(SceneLimits, HugeDomainIsRefusedByItsGrid) {
  // Few particles, but a grid of 1e17 cells over the domain.
  const std::string m = refused(R"({"domain": {"min": [0,0,0], "max": [1e4,1e4,1e4]},
      "fluid": {"blocks": [{"min": [0,0,0], "max": [0.1,0.1,0.1]}], "particle_radius": 0.01}})");
  EXPECT_TRUE(has(m, "fluid.particle_radius")) << m;
  EXPECT_TRUE(has(m, "cells")) << m;
}

TEST_F(SceneLimits, MemoryBeyondWhatIsFreeIsRefused) {
  const std::string path = write(R"({"fluid": {"blocks": [{"min": [0,0,0], "max": [0.2,0.2,0.2]}],
      "particle_radius": 0.005}})");
  const SceneSpec s = load_scene(path);  // fits this machine
  const SceneSize z = scene_size(s);
  EXPECT_NO_THROW(check_limits(s, path, z.bytes() * 1.01));
  try {
    check_limits(s, path, z.bytes() * 0.99);
    ADD_FAILURE() << "not refused";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(has(m, path + ": fluid.particle_radius:")) << m;
    EXPECT_TRUE(has(m, "free on this machine")) << m;
  }
  EXPECT_GT(available_memory_bytes(), 0.0);
}

TEST_F(SceneLimits, CountsMatchWhatIsBuilt) {
  // Blocks, walls (one open top) and grid exactly; the emitters' estimate near the capacity.
  const std::string path = write(R"({
      "domain": {"min": [0,0,0], "max": [0.4,0.3,0.2], "open_top": true},
      "simulation": {"duration": 0.7},
      "fluid": {"particle_radius": 0.0035,
        "blocks": [{"min": [0,0,0], "max": [0.1,0.13,0.2]}, {"min": [0.2,0,0], "max": [0.37,0.05,0.1]}],
        "emitters": [{"position": [0.3,0.25,0.1], "direction": [0,-1,0], "radius": 0.02,
                      "speed": 1.5, "end": 0.5}]}})");
  const SceneSpec s = load_scene(path);
  const SceneSize z = scene_size(s);
  const FluidModel m = compile_fluid(s);
  EXPECT_EQ(z.particles, double(m.x0.size()));
  EXPECT_EQ(z.wall_samples, double(m.boundary_x.size()));
  EXPECT_EQ(z.grid_cells, double(m.grid.nx) * m.grid.ny * m.grid.nz);
  const double emitted = double(m.capacity) - double(m.x0.size());
  EXPECT_NEAR(z.emitted, emitted, 0.05 * emitted);
  EXPECT_GE(z.emitted, emitted);
  EXPECT_EQ(frame_count(0.7, 30), 22.0);
}

namespace {
// Bytes the heap holds now. AddressSanitizer replaces malloc, and glibc's mallinfo2 then sees
// nothing, so under it the sanitizer's allocator is asked instead.
double heap_in_use() {
#if defined(__SANITIZE_ADDRESS__)
  return double(__sanitizer_get_current_allocated_bytes());
#else
  const struct mallinfo2 m = mallinfo2();
  return double(m.uordblks + m.hblkhd);
#endif
}

// The heap a simulation of the scene holds after its first three steps.
double held_by_run(const SceneSpec& s) {
  malloc_trim(0);
  const double before = heap_in_use();
  Simulation sim(s, Backend::Cpu);
  for (int k = 0; k < 3; ++k) sim.step(0.001);
  return heap_in_use() - before;
}
}  // namespace

// The memory estimate (what `check` prints and the limits compare with the free memory) against
// the heap a simulation really holds after its first steps (bytes in use, mapped chunks
// included): never below it, and within a quarter above it. Fluid alone, with
// the tank's faces in the rays (the ray coupling's buffers), and with a box obstacle too,
// under each solver (their lists and buffers differ).
TEST_F(SceneLimits, MemoryEstimateBoundsWhatARunHolds) {
  for (const std::string solver : {"dfsph", "wcsph"}) {
    const std::string fluid = R"("simulation": {"solver": ")" + solver + R"("},
      "fluid": {"blocks": [{"min": [0,0,0], "max": [0.3,0.15,0.3]}], "particle_radius": 0.004},
      "domain": {"min": [0,0,0], "max": [0.3,0.3,0.3]})";
    const char* extra[] = {R"("coupling": {"tank_rays": false})", R"("coupling": {})",
                           R"("obstacles": [{"min": [0.1,0,0.1], "max": [0.2,0.25,0.2]}])"};
    for (const char* e : extra) {
      const SceneSpec s = load_scene(write("{" + fluid + ", " + e + "}"));
      const SceneSize z = scene_size(s);
      const double held = held_by_run(s);
      std::printf("%s, %s: estimate %.0f B a particle, held %.0f B a particle (%.0f particles)\n",
                  solver.c_str(), e, z.bytes() / z.capacity, held / z.capacity, z.capacity);
      EXPECT_GE(z.bytes(), held) << solver << ", " << e;
      EXPECT_LE(z.bytes(), 1.25 * held) << solver << ", " << e;
    }
  }
}

// The same for bodies, with the surface triangles counted as `check` counts them: a ball
// alone, with surface contact, a thin plate with contact (many surface triangles a
// tetrahedron), and the ball in water (the fluid's estimate and the body's together).
TEST_F(SceneLimits, BodyMemoryEstimateBoundsWhatARunHolds) {
  const std::string ball =
      R"("bodies": [{"name": "b", "shape": "sphere", "position": [0.15,0.2,0.15],
      "radius": 0.06, "resolution": 12}])";
  const std::string plate = R"("bodies": [{"name": "p", "shape": "box", "position": [0.15,0.2,0.15],
      "size": [0.2,0.02,0.1], "resolution": 20}])";
  const std::string contact = R"(, "fem": {"contact": true})";
  const std::string water = R"("fluid": {"blocks": [{"min": [0,0,0], "max": [0.3,0.1,0.3]}],
      "particle_radius": 0.006}, )";
  const std::string scenes[] = {ball, ball + contact, plate + contact, water + ball};
  for (const std::string& e : scenes) {
    const SceneSpec s =
        load_scene(write(R"({"domain": {"min": [0,0,0], "max": [0.3,0.3,0.3]}, )" + e + "}"));
    const BodiesModel m = compile_scene_bodies(s);
    const double estimate =
        scene_size(s).fluid_bytes +
        body_bytes(m.nodes, m.elements, double(m.surface.size()), s.fem.contact, s.has_fluid());
    const double held = held_by_run(s);
    std::printf("%s\n  %d nodes, %d tets, %zu triangles: estimate %.0f B, held %.0f B\n", e.c_str(),
                m.nodes, m.elements, m.surface.size(), estimate, held);
    EXPECT_GE(estimate, held) << e;
    EXPECT_LE(estimate, 1.25 * held) << e;
  }
}

TEST_F(SceneLimits, ShapeSizesBoundWhatIsGenerated) {
  const char* shapes[] = {
      R"({"name": "b", "shape": "box", "size": [0.2, 0.1, 0.05], "resolution": 7})",
      R"({"name": "b", "shape": "sphere", "radius": 0.1, "resolution": 6})",
      R"({"name": "b", "shape": "cup", "radius": 0.1, "inner_radius": 0.08, "height": 0.15,
          "thickness": 0.02, "resolution": 8})",
      R"({"name": "b", "shape": "tube", "radius": 0.05, "inner_radius": 0.04, "length": 0.2,
          "resolution": 6})",
      R"({"name": "b", "shape": "cloth", "size": [0.3, 0.005, 0.2], "resolution": 9})"};
  for (const char* body : shapes) {
    const std::string text = std::string(R"({"domain": {"min": [-1,-1,-1], "max": [1,1,1]},
        "bodies": [)") + body +
                             "]}";
    const SceneSpec s = load_scene(write(text));
    const ShapeSize z = shape_size(s.bodies[0]);
    const TetMesh mesh = body_rest_mesh(s.bodies[0], "bodies[0]", s.path);
    EXPECT_GE(z.tets, double(mesh.tets.size())) << body;
    EXPECT_GE(z.nodes, double(mesh.x.size())) << body;
    // scene_size's bound on the surface triangles (2 a node) for the memory it counts
    EXPECT_LE(double(boundary_faces(mesh.tets).size()), 2.0 * z.nodes) << body;
    EXPECT_LE(z.tets, 2.0 * double(mesh.tets.size())) << body;  // the cup: its hollow is cut
  }
}

TEST_F(SceneLimits, TinyTetrahedraOfAMeshFileAreRefusedBeforeMeshing) {
  const std::string mesh = std::string(SPHFEM_SOURCE_DIR) + "/tests/data/meshes/cube.obj";
  const std::string m = refused(R"({"domain": {"min": [-2,-2,-2], "max": [2,2,2]},
      "bodies": [{"name": "c", "shape": "mesh", "file": ")" +
                                mesh + R"(", "max_volume": 1e-12}]})");
  EXPECT_TRUE(has(m, "bodies[0].max_volume")) << m;
  EXPECT_TRUE(has(m, "tetrahedra")) << m;
}

TEST_F(SceneLimits, CheckAnswersAtOnceAndRunRefusesAnEndlessDuration) {
  using testing_cli::cli;
  const auto t0 = Clock::now();
  const testing_cli::Result c = cli("check " + write(R"({"fluid": {"blocks": [{"min": [0,0,0],
      "max": [0.5,0.5,0.5]}], "particle_radius": 1e-5}})"));
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 5.0);
  EXPECT_EQ(c.code, 2) << c.out;
  EXPECT_TRUE(has(c.out, "particles")) << c.out;

  const std::string small = write(R"({"fluid": {"blocks": [{"min": [0,0,0], "max": [0.1,0.1,0.1]}],
      "particle_radius": 0.01}, "simulation": {"duration": 2}})");
  const testing_cli::Result ok = cli("check " + small);
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_TRUE(has(ok.out, "(61 frames)")) << ok.out;
  const fs::path out = dir_ / "out";
  const testing_cli::Result r =
      cli("run " + small + " --quiet --duration 1e300 --out " + out.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_TRUE(has(r.out, "--duration")) << r.out;
  EXPECT_FALSE(fs::exists(out / "frames")) << "nothing is written on bad input";
}

}  // namespace
}  // namespace sphfem
