#include "sphfem/sim/run.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/gauges.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/pvd.h"
#include "sphfem/io/vtu.h"
#include "sphfem/sim/metrics.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

namespace {

using Clock = std::chrono::steady_clock;

io::PointSet fluid_frame(const FluidSnapshot& s) {
  io::PointSet ps;
  ps.positions.resize(3 * std::size_t(s.n));
  io::DataArray vel{"velocity", 3, std::vector<float>(3 * std::size_t(s.n)), {}};
  io::DataArray rho{"density", 1, std::vector<float>(s.n), {}};
  io::DataArray p{"pressure", 1, std::vector<float>(s.n), {}};
  io::DataArray id{"id", 1, {}, std::vector<std::int32_t>(s.n)};
  io::DataArray nb{"neighbors", 1, {}, std::vector<std::int32_t>(s.n)};
  for (int i = 0; i < s.n; ++i) {
    for (int c = 0; c < 3; ++c) {
      ps.positions[3 * i + c] = float(s.x[i][c]);
      vel.values[3 * i + c] = float(s.v[i][c]);
    }
    rho.values[i] = float(s.rho[i]);
    p.values[i] = float(s.p[i]);
    id.ivalues[i] = std::int32_t(s.id[i]);
    nb.ivalues[i] = s.neighbors[i];
  }
  ps.point_data = {std::move(vel), std::move(rho), std::move(p), std::move(id), std::move(nb)};
  // An empty int array would read as float; a frame with no particles keeps float arrays only.
  if (s.n == 0) ps.point_data.resize(3);
  return ps;
}

std::vector<std::string> gauge_columns(const SceneSpec& scene) {
  std::vector<std::string> c = {"time",           "step",
                                "dt",             "n_fluid",
                                "fluid_front_x",  "max_density_error",
                                "mean_density_error", "kinetic_energy",
                                "momentum_x",     "momentum_y",
                                "momentum_z",     "clamped",
                                "pressure_iterations", "divergence_iterations"};
  for (int p = 0; p < int(Phase::Count); ++p) c.push_back(std::string("ms_") + phase_name(Phase(p)));
  c.push_back("ms_step");
  for (const GaugeSpec& g : scene.gauges) c.push_back(g.name);
  return c;
}

class Progress {
 public:
  Progress(bool on, double duration) : on_(on), tty_(isatty(2)), duration_(duration) {}
  void update(double t, long steps, double wall, bool force) {
    if (!on_) return;
    const double frac = duration_ > 0 ? std::min(1.0, t / duration_) : 1.0;
    if (tty_) {
      if (!force && wall - last_ < 0.2) return;
    } else if (!force && frac < next_) {
      return;
    }
    last_ = wall;
    next_ = std::floor(frac * 10 + 1e-9) / 10 + 0.1;
    const double rate = wall > 0 ? steps / wall : 0;
    const double eta = frac > 0 ? wall * (1 - frac) / frac : 0;
    char bar[21];
    const int filled = int(frac * 20);
    for (int i = 0; i < 20; ++i) bar[i] = i < filled ? '#' : '-';
    bar[20] = 0;
    std::fprintf(stderr, "%s[%s] %3d%%  t = %.3f / %.3f s  %ld steps  %.1f steps/s  ETA %.0f s%s",
                 tty_ ? "\r" : "", bar, int(frac * 100), t, duration_, steps, rate, eta,
                 tty_ ? "   " : "\n");
    std::fflush(stderr);
  }
  void done() {
    if (on_ && tty_) std::fprintf(stderr, "\n");
  }

 private:
  bool on_, tty_;
  double duration_, last_ = -1, next_ = 0;
};

}  // namespace

RunSummary run_scene(const SceneSpec& scene, const RunOptions& opt) {
  if (opt.threads > 0) set_cpu_threads(opt.threads);
  const double duration = opt.duration >= 0 ? opt.duration : scene.simulation.duration;
  // Everything that can fail on input happens before the first file is written.
  const FluidModel model = compile_fluid(scene);
  std::unique_ptr<FluidSolver> solver = make_fluid_solver(model, opt.backend);

  RunSummary sum;
  sum.out_dir = opt.out_dir;
  const std::string frames_dir = opt.out_dir + "/frames";
  io::ensure_directory(frames_dir);
  io::GaugeWriter gauges(opt.out_dir + "/gauges.csv", gauge_columns(scene));
  std::unique_ptr<io::PvdCollection> pvd;
  if (scene.output.vtu) pvd = std::make_unique<io::PvdCollection>(opt.out_dir + "/fluid.pvd");

  // What a reader of the folder needs besides the frames (the renderer: radius and tank).
  nlohmann::json info = {
      {"scene", scene.path},
      {"name", scene.name},
      {"particle_radius", scene.fluid.particle_radius},
      {"domain",
       {{"min", {scene.domain.lo.x, scene.domain.lo.y, scene.domain.lo.z}},
        {"max", {scene.domain.hi.x, scene.domain.hi.y, scene.domain.hi.z}}}},
      {"solver", scene.simulation.solver == SolverKind::DFSPH ? "dfsph" : "wcsph"},
      {"backend", opt.backend == Backend::Cuda ? "cuda" : "cpu"},
      {"fps", scene.output.fps}};
  io::write_file_atomic(opt.out_dir + "/run.json", info.dump(2) + "\n");

  const double frame_dt = 1.0 / scene.output.fps;
  const auto t0 = Clock::now();
  auto wall = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  Progress progress(opt.progress, duration);
  FluidSnapshot snap;
  StepInfo last;
  long steps_since = 0, piter = 0, diter = 0, clamped = 0;

  auto write_frame = [&](int frame) {
    solver->snapshot(snap);
    char name[64];
    std::snprintf(name, sizeof name, "fluid_%06d", frame);
    const io::PointSet ps = fluid_frame(snap);
    if (scene.output.vtu) {
      io::write_vtu(frames_dir + "/" + name + ".vtu", ps);
      pvd->add(solver->time(), std::string("frames/") + name + ".vtu");
    }
    if (scene.output.ply) io::write_ply(frames_dir + "/" + name + ".ply", ps);
    const FrameMetrics m = compute_metrics(snap, model, scene.gauges, scene.domain);
    const Profile& prof = solver->profile();
    const double per = prof.steps ? 1.0 / double(prof.steps) : 0.0;
    std::vector<double> row = {solver->time(),
                               double(solver->steps()),
                               last.dt,
                               double(snap.n),
                               m.front_x,
                               m.max_density_error,
                               m.mean_density_error,
                               m.kinetic_energy,
                               m.momentum[0],
                               m.momentum[1],
                               m.momentum[2],
                               double(clamped),
                               steps_since ? double(piter) / steps_since : 0.0,
                               steps_since ? double(diter) / steps_since : 0.0};
    double total = 0;
    for (int p = 0; p < int(Phase::Count); ++p) {
      row.push_back(prof.ms[p] * per);
      total += prof.ms[p] * per;
    }
    row.push_back(total);
    for (double v : m.probes) row.push_back(v);
    gauges.row(row);
    solver->reset_profile();
    steps_since = piter = diter = 0;
    ++sum.frames;
  };

  write_frame(0);
  int frame = 1;
  while (solver->time() < duration - 1e-12) {
    const double next = std::min(duration, frame * frame_dt);
    try {
      last = solver->step(next - solver->time());
    } catch (const SimulationError&) {
      progress.done();
      throw;
    }
    ++steps_since;
    piter += last.pressure_iterations;
    diter += last.divergence_iterations;
    clamped += last.clamped;
    if (solver->time() >= next - 1e-9 * std::max(1.0, next)) {
      write_frame(frame);
      ++frame;
    }
    progress.update(solver->time(), solver->steps(), wall(), false);
  }
  progress.update(solver->time(), solver->steps(), wall(), true);
  progress.done();
  sum.steps = solver->steps();
  sum.particles = solver->count();
  sum.sim_seconds = solver->time();
  sum.wall_seconds = wall();
  return sum;
}

}  // namespace sphfem
