// The sphfem command: run, check, bench, render and view. Bad input exits with code 2 and one line
// that names the file, the field and the fix; a run that blows up exits with code 3, one whose
// output cannot be written (a full disk, a read-only folder) with code 4.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>

#include "bench.h"
#include "render_cmd.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/compile.h"
#include "sphfem/scene/fields.h"
#include "sphfem/scene/limits.h"
#include "sphfem/scene/load.h"
#include "sphfem/scene/obstacles.h"
#include "sphfem/sim/run.h"
#include "sphfem/sim/state.h"
#include "sphfem/sph/solver.h"
#include "view_cmd.h"

namespace {

using namespace sphfem;

Backend parse_backend(const std::string& s) { return s == "cuda" ? Backend::Cuda : Backend::Cpu; }

std::string default_out(const std::string& scene) {
  return "out/" + std::filesystem::path(scene).stem().string();
}

// The scene-file name of a body's shape, from the field table.
std::string shape_name(BodyShape shape) {
  const scene::ObjectTable& body = *scene::scene_table().find("bodies")->table;
  return body.find("shape")->choices.at(std::size_t(shape));
}

int cmd_check(const std::string& path) {
  const SceneSpec s = load_scene(path);
  std::printf("scene       %s%s%s\n", path.c_str(), s.name.empty() ? "" : " — ", s.name.c_str());
  double fluid_b = 0, body_b = 0, particles = 0, tets = 0;
  if (s.has_fluid()) {
    const FluidModel m = compile_fluid(s);
    const double cells = double(m.grid.nx) * double(m.grid.ny) * double(m.grid.nz);
    fluid_b =
        fluid_bytes(m.capacity, double(m.boundary_x.size()), cells, m.solver == SolverKind::DFSPH);
    const bool rays = s.coupling.method == CouplingMethod::RayTraced;
    if (rays && (!s.bodies.empty() || s.coupling.tank_rays || !s.obstacles.empty())) {
      SceneSize z;
      z.capacity = m.capacity;
      z.wall_samples = double(m.boundary_x.size());
      fluid_b += coupling_bytes(m.capacity, contact_bound(z), !s.obstacles.empty());
    }
    particles = m.capacity;
    std::printf("solver      %s, %s kernel, support %.4g m\n",
                s.simulation.solver == SolverKind::DFSPH ? "DFSPH" : "WCSPH",
                s.fluid.kernel == KernelKind::CubicSpline ? "cubic spline" : "Wendland C2",
                double(m.params.h));
    std::printf("particles   %zu at start, up to %d with emitters (%zu emitters)\n", m.x0.size(),
                m.capacity, m.emitters.size());
    std::printf("walls       %zu samples\n", m.boundary_x.size());
    std::printf("grid        %d x %d x %d cells\n", m.grid.nx, m.grid.ny, m.grid.nz);
    if (s.simulation.solver == SolverKind::WCSPH)
      std::printf("stiffness   %.4g Pa (sound speed %.3g m/s), step <= %.3g s\n",
                  double(m.params.stiffness), double(m.params.sound_speed),
                  std::min(s.simulation.dt_max, wcsph_dt_limit(s, 0.0)));
  } else {
    std::printf("fluid       none: the bodies step with simulation.dt_max = %.4g s\n",
                s.simulation.dt_max);
  }
  if (!s.bodies.empty()) {
    const BodiesModel b = compile_scene_bodies(s);
    for (std::size_t i = 0; i < b.bodies.size(); ++i) {
      const BodyModel& body = b.bodies[i];
      double mass = 0;
      for (double m : body.mass) mass += m;
      int pinned = 0;
      for (std::uint8_t p : body.pinned) pinned += p;
      std::printf(
          "body        %s (%s): %zu nodes, %zu tets, %zu surface triangles, %.4g kg, %d "
          "pinned nodes\n",
          body.name.c_str(), shape_name(s.bodies[i].shape).c_str(), body.rest.size(),
          body.tets.size(), body.surface.size(), mass, pinned);
    }
    body_b =
        body_bytes(b.nodes, b.elements, double(b.surface.size()), s.fem.contact, s.has_fluid());
    tets = b.elements;
  }
  if (!s.obstacles.empty()) {
    const ObstaclesModel ob = compile_obstacles(s, path);
    for (int k = 0; k < ob.count(); ++k) {
      const ObstacleSpec& o = s.obstacles[std::size_t(k)];
      std::printf("obstacle    %s (%s): %d triangles, ", o.name.c_str(),
                  o.shape == ObstacleShape::Box ? "box" : "mesh",
                  ob.tri_offset[std::size_t(k) + 1] - ob.tri_offset[std::size_t(k)]);
      if (o.path.empty())
        std::printf("fixed\n");
      else
        std::printf("on a %zu-key path from %.4g s to %.4g s\n", o.path.size(), o.path.front().time,
                    o.path.back().time);
    }
  }
  std::printf("time        %.4g s, frames every %.4g s (%.0f frames)\n", s.simulation.duration,
              1.0 / s.output.fps, frame_count(s.simulation.duration, s.output.fps));
  std::printf("memory      about %.1f MiB", (fluid_b + body_b) / (1024.0 * 1024.0));
  if (particles > 0) std::printf(", %.0f B a particle (walls included)", fluid_b / particles);
  if (tets > 0) std::printf(", %.0f B a tetrahedron (nodes included)", body_b / tets);
  std::printf("\n");
  std::printf("ok\n");
  return 0;
}

int cmd_run(const std::string& path, const std::string& out, const std::string& backend,
            int threads, double duration, double checkpoint_every, bool quiet, bool resume) {
  SceneSpec s = load_scene(path);
  // Not part of the scene's identity, so a run may resume with another interval.
  if (checkpoint_every > 0) s.output.checkpoint_every = checkpoint_every;
  RunOptions opt;
  opt.out_dir = out.empty() ? default_out(path) : out;
  opt.backend = parse_backend(backend);
  opt.threads = threads;
  opt.duration = duration;
  opt.progress = !quiet;
  opt.resume = resume;
  try {
    const RunSummary r = run_scene(s, opt);
    std::printf(
        "%d particles, %d body nodes (%d bodies), %ld steps, %.3f s simulated in %.1f s "
        "wall (%.1f steps/s)\n",
        r.particles, r.body_nodes, r.bodies, r.steps, r.sim_seconds, r.wall_seconds,
        r.wall_seconds > 0 ? r.steps / r.wall_seconds : 0.0);
    if (r.bodies > 0 && s.has_fluid())
      std::printf(
          "leaks: %ld particles crossed a body surface; at most %ld inside a body at a frame\n",
          r.crossed, r.inside_max);
    std::string files = s.has_fluid() ? "fluid.pvd, " : "";
    if (r.bodies > 0) files += "bodies.pvd, bodies_tets.pvd, ";
    std::printf("state hash %s at t = %.6g s\n", hash_hex(r.state_hash).c_str(), r.sim_seconds);
    std::printf("output: %s (%d frames in frames/, %sgauges.csv, checkpoint.bin)\n",
                r.out_dir.c_str(), r.frames, files.c_str());
  } catch (const SimulationError& e) {
    std::fprintf(stderr, "error: %s: %s\n", path.c_str(), e.what());
    std::fprintf(stderr, "frames written so far are kept in %s\n", opt.out_dir.c_str());
    return 3;
  } catch (const io::WriteError& e) {
    std::fprintf(stderr,
                 "error: %s; free space on the disk, or give --out a folder you can write to\n",
                 e.what());
    std::fprintf(stderr, "frames written so far are kept in %s\n", opt.out_dir.c_str());
    return 4;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) then fails the write with EFBIG, which is reported and exits
  // with code 4, instead of the signal killing the run without a word.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"sphfem: SPH fluids coupled with FEM soft bodies by ray tracing"};
  app.require_subcommand(1);

  std::string scene, out, backend = "cpu";
  int threads = 0;
  double duration = -1;
  bool quiet = false;
  auto* run = app.add_subcommand("run", "run a JSON scene, writing frames and gauges.csv");
  run->add_option("scene", scene, "scene file (JSON)")->required();
  run->add_option("--out", out, "output folder (default out/<scene name>)");
  run->add_option("--backend", backend, "cpu or cuda")->check(CLI::IsMember({"cpu", "cuda"}));
  run->add_option("--threads", threads, "CPU threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  run->add_option("--duration", duration, "simulated seconds (overrides the scene)")
      ->check(CLI::NonNegativeNumber);
  run->add_flag("--quiet", quiet, "no progress line");
  double checkpoint_every = -1;
  run->add_option("--checkpoint-every", checkpoint_every,
                  "write checkpoint.bin every S simulated seconds (overrides "
                  "output.checkpoint_every)")
      ->check(CLI::PositiveNumber);
  bool resume = false;
  run->add_flag("--resume", resume,
                "continue from the checkpoint in the output folder (output.checkpoint_every)");

  auto* check = app.add_subcommand("check", "validate a scene and print what would run");
  check->add_option("scene", scene, "scene file (JSON)")->required();

  BenchOptions bench_opt;
  auto* bench = app.add_subcommand(
      "bench", "dam-break benchmark: ms/step per phase; with --fem the FEM bodies of Table 1");
  bench->add_option("--steps", bench_opt.steps, "measured steps")->check(CLI::PositiveNumber);
  bench->add_option("--solver", bench_opt.solver, "wcsph, dfsph or both")
      ->check(CLI::IsMember({"wcsph", "dfsph", "both"}));
  bench->add_option("--threads", bench_opt.threads, "CPU threads (default: all cores)");
  bench->add_option("--backend", bench_opt.backend, "cpu or cuda")
      ->check(CLI::IsMember({"cpu", "cuda"}));
  bench->add_option("--out", bench_opt.out_dir, "folder for the result file (none = print only)");
  bench->add_option("--particles-per-side", bench_opt.side, "block of N^3 particles (default 40)");
  bench->add_flag("--paper", bench_opt.paper,
                  "the paper's Table 1: each scene of scenes/paper with a 64,800-particle block, "
                  "ray-traced vs boundary-particle coupling");
  bench
      ->add_option("--method", bench_opt.method,
                   "--paper: raytraced (with near-surface density), raytraced_paper (without: "
                   "the paper's exchange alone), boundary_particles, both (raytraced and "
                   "boundary_particles) or all")
      ->check(CLI::IsMember({"raytraced", "raytraced_paper", "boundary_particles", "both", "all"}));
  bench->add_option("--scenes", bench_opt.scenes, "--paper: folder of the scenes (scenes/paper)");
  bench->add_flag("--fem", bench_opt.fem,
                  "FEM ms/step for spheres and the bunny at the tetrahedron counts of the paper's "
                  "Table 1, instead of the fluid");
  bench->add_option("--mesh", bench_opt.mesh,
                    "--fem: closed surface to tetrahedralise (default build/assets/bunny.obj, "
                    "written by scripts/fetch-bunny.sh build/assets)");
  bench
      ->add_option(
          "--young", bench_opt.young,
          "--fem: Young's modulus of the bodies in Pa (default 100 kPa; 10 MPa for stiff rubber)")
      ->check(CLI::PositiveNumber);
  bench->add_flag("--two-level", bench_opt.two_level,
                  "--fem: the CG with its coarse level (fem.preconditioner two_level); with "
                  "--young, rows go to fem_options.csv");
  bench->add_flag("--resting", bench_opt.resting,
                  "--fem: only the bunny resting on the tank floor, surface contact off and on "
                  "(fem_contact.csv)");

  RenderOptions render_opt;
  auto* render = add_render_command(app, render_opt);
  bool render_after = false, bench_render = false;
  run->add_flag("--render", render_after, "then draw every frame as `sphfem render OUT` does");
  bench->add_flag("--render", bench_render,
                  "ms per frame of the OpenGL and software renderers at 1280x720, ~65k particles");
  ViewOptions view_opt;
  auto* view = add_view_command(app, view_opt);

  CLI11_PARSE(app, argc, argv);
  try {
    if (*check) return cmd_check(scene);
    if (*run) {
      const int code =
          cmd_run(scene, out, backend, threads, duration, checkpoint_every, quiet, resume);
      if (code != 0 || !render_after) return code;
      render_opt.out_dir = out.empty() ? default_out(scene) : out;
      return run_render(render_opt);
    }
    if (*bench) {
      if (bench_render) return run_render_bench(bench_opt.out_dir);
      if (bench_opt.paper) {
        if (bench->count("--steps") == 0) bench_opt.steps = kPaperBenchSteps;
        return run_paper_bench(bench_opt);
      }
      if (bench_opt.fem && bench->count("--steps") == 0) bench_opt.steps = kFemBenchSteps;
      return bench_opt.fem ? run_fem_bench(bench_opt) : run_bench(bench_opt);
    }
    if (*render) return run_render(render_opt);
    if (*view) return run_view(view_opt);
  } catch (const SceneError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s%s%s\n", scene.empty() ? "" : scene.c_str(),
                 scene.empty() ? "" : ": ", e.what());
    return 2;
  }
  return 0;
}
