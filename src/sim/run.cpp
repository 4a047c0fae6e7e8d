// The run loop: the fluid step, inside which (ray-traced coupling) the bodies step with the
// same dt and exchange momentum with the particles; frames, gauges and progress.
#include "sphfem/sim/run.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/collide/collider.h"
#include "sphfem/couple/ray_coupling.h"
#include "sphfem/fem/energy.h"
#include "sphfem/fem/solver.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/io/gauges.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/pvd.h"
#include "sphfem/io/run_info.h"
#include "sphfem/io/vtu.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/limits.h"
#include "sphfem/sim/body_frames.h"
#include "sphfem/sim/checkpoint.h"
#include "sphfem/sim/fluid_frame.h"
#include "sphfem/sim/metrics.h"
#include "sphfem/sim/simulation.h"
#include "sphfem/sim/state.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

namespace {

using Clock = std::chrono::steady_clock;

std::vector<std::string> gauge_columns(const SceneSpec& scene) {
  std::vector<std::string> c = {"time",
                                "step",
                                "dt",
                                "n_fluid",
                                "fluid_front_x",
                                "max_density_error",
                                "mean_density_error",
                                "kinetic_energy",
                                "momentum_x",
                                "momentum_y",
                                "momentum_z",
                                "clamped",
                                "pressure_iterations",
                                "divergence_iterations",
                                "fem_cg_iterations",
                                "leaked",
                                "crossed",
                                "inside_bodies",
                                "contacts",
                                "momentum_total_x",
                                "momentum_total_y",
                                "momentum_total_z",
                                "body_contacts",
                                "wall_held",
                                "min_surface_gap",
                                "inverted_elements",
                                "intersecting_pairs",
                                "body_halvings"};
  for (int k = 0; k < int(Stage::Count); ++k)
    c.push_back(std::string("ms_") + stage_name(Stage(k)));
  c.push_back("ms_leak_check");
  c.push_back("ms_step");
  for (const GaugeSpec& g : scene.gauges) {
    if (g.kind != GaugeKind::Node) {
      c.push_back(g.name);
      continue;
    }
    for (const char* axis : {"_dx", "_dy", "_dz"}) c.push_back(g.name + axis);
  }
  for (const BodySpec& b : scene.bodies) {
    c.push_back(b.name + "_kinetic_energy");
    c.push_back(b.name + "_elastic_energy");
    for (const char* axis : {"_fluid_force_x", "_fluid_force_y", "_fluid_force_z"})
      c.push_back(b.name + axis);
  }
  return c;
}

// Global node followed by each node gauge, -1 for the fluid gauges.
std::vector<int> gauge_nodes(const SceneSpec& scene, const BodiesModel& bodies) {
  std::vector<int> nodes;
  for (const GaugeSpec& g : scene.gauges) {
    if (g.kind != GaugeKind::Node) {
      nodes.push_back(-1);
      continue;
    }
    const int b = body_index(scene, g.body);
    if (b < 0)
      throw std::runtime_error("gauge '" + g.name + "' follows body '" + g.body +
                               "', which the scene does not have");
    nodes.push_back(nearest_rest_node(bodies, b, g.position));
  }
  return nodes;
}

// The first body with a non-finite node, or -1.
int non_finite_body(const BodiesModel& m, const BodySnapshot& s) {
  for (std::size_t b = 0; b + 1 < m.node_offset.size(); ++b)
    for (int i = m.node_offset[b]; i < m.node_offset[b + 1]; ++i)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(double(s.x[i][c])) || !std::isfinite(double(s.v[i][c]))) return int(b);
  return -1;
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// A body that blew up, reported as the fluid reports its own: the step, the body, the fix.
SimulationError body_blow_up(long step, double t, const BodiesModel& m, int body) {
  const std::string who = body >= 0 ? "body \"" + m.bodies[std::size_t(body)].name + "\" (bodies[" +
                                          std::to_string(body) + "]) became"
                                    : "the FEM solve of the bodies became";
  return SimulationError(step, "step " + std::to_string(step) + " (t = " + fmt(t) + " s): " + who +
                                   " non-finite (NaN); lower simulation.dt_max, raise "
                                   "fem.cg_max_iterations or fem.newton_iterations, or check "
                                   "the bodies' material values");
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
  if (opt.duration >= 0)
    check_frame_limit(duration, scene.output.fps, scene.path, "--duration (simulation.duration)");
  // Everything that can fail on input happens before the first file is written.
  Simulation sim(scene, opt.backend);
  FluidSolver* solver = sim.fluid();
  BodySolver* fem = sim.bodies();
  RayCoupling* hook = sim.coupling();
  const FluidModel& model = sim.fluid_model();
  const BodiesModel& bodies = sim.bodies_model();
  const std::vector<int> gauge_node = gauge_nodes(scene, bodies);

  RunSummary sum;
  sum.out_dir = opt.out_dir;
  const std::string frames_dir = io::frames_dir(opt.out_dir);
  const std::string checkpoint_file = io::checkpoint_path(opt.out_dir);
  const std::uint64_t identity = scene_identity(scene);
  // A resumed run reads and checks its checkpoint before it touches any file.
  Checkpoint resumed;
  if (opt.resume) {
    resumed = read_checkpoint(checkpoint_file);
    if (resumed.scene != identity)
      throw CheckpointError(checkpoint_file +
                            ": the checkpoint was written by another scene (or the scene was "
                            "edited since); resume with the scene that wrote it, or run again "
                            "without --resume");
    try {
      sim.load(resumed.state);
    } catch (const std::invalid_argument& e) {
      throw CheckpointError(checkpoint_file + ": " + e.what() + "; run again without --resume");
    }
  }
  const RunCursor& rc = resumed.cursor;
  io::ensure_directory(frames_dir);
  io::GaugeWriter gauges =
      opt.resume ? io::GaugeWriter(io::gauges_path(opt.out_dir), gauge_columns(scene),
                                   std::size_t(rc.next_frame))
                 : io::GaugeWriter(io::gauges_path(opt.out_dir), gauge_columns(scene));
  std::unique_ptr<io::PvdCollection> pvd, bodies_pvd, tets_pvd, obstacles_pvd;
  if (scene.output.vtu && solver)
    pvd = std::make_unique<io::PvdCollection>(opt.out_dir + "/fluid.pvd");
  if (scene.output.vtu && fem) {
    bodies_pvd = std::make_unique<io::PvdCollection>(opt.out_dir + "/bodies.pvd");
    tets_pvd = std::make_unique<io::PvdCollection>(opt.out_dir + "/bodies_tets.pvd");
  }
  // Obstacles that stay put: one file for the whole run, beside the collections; on a path, a
  // file per frame.
  const bool obstacles_move = scene.output.vtu && sim.obstacles().moving();
  if (obstacles_move)
    obstacles_pvd = std::make_unique<io::PvdCollection>(opt.out_dir + "/obstacles.pvd");
  else if (scene.output.vtu && !sim.obstacles().empty())
    io::write_vtu(opt.out_dir + "/obstacles.vtu", obstacle_surface(sim.obstacles()));
  auto frame_file = [](const char* kind, int frame, const char* ext) {
    char name[64];
    std::snprintf(name, sizeof name, "%s_%06d%s", kind, frame, ext);
    return std::string(name);
  };
  if (opt.resume) {
    // The collections list the frames the checkpoint follows; later ones are written again.
    auto restore = [&](io::PvdCollection* c, const char* kind) {
      if (!c) return;
      std::vector<io::PvdCollection::Entry> e;
      for (std::size_t k = 0; k < rc.frame_times.size(); ++k)
        e.push_back({rc.frame_times[k], "frames/" + frame_file(kind, int(k), ".vtu"), 0});
      c->restore(std::move(e));
    };
    restore(pvd.get(), "fluid");
    restore(bodies_pvd.get(), "bodies");
    restore(tets_pvd.get(), "bodies_tets");
    restore(obstacles_pvd.get(), "obstacles");
  }

  // What a reader of the folder needs besides the frames (the renderer: radius and tank).
  io::RunInfo info;
  info.scene = scene.path;
  info.name = scene.name;
  info.particle_radius = scene.fluid.particle_radius;
  info.domain_min = scene.domain.lo;
  info.domain_max = scene.domain.hi;
  info.solver = scene.simulation.solver == SolverKind::DFSPH ? "dfsph" : "wcsph";
  info.backend = opt.backend == Backend::Cuda ? "cuda" : "cpu";
  info.fps = scene.output.fps;
  for (const BodySpec& b : scene.bodies) info.bodies.push_back(b.name);
  const OutputSpec& o = scene.output;
  const Vec3d eye = o.camera_position - o.camera_target;
  // A position equal to the target asks for automatic framing: no camera is written then.
  if (dot(eye, eye) > 0)
    info.camera = io::RunCamera{o.camera_position, o.camera_target, o.camera_fov};
  io::write_run_info(opt.out_dir, info);

  const double frame_dt = 1.0 / scene.output.fps;
  const auto t0 = Clock::now();
  auto wall = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  Progress progress(opt.progress, duration);
  FluidSnapshot snap;
  BodySnapshot body_snap;
  std::unique_ptr<BodyFrames> body_frames;
  std::unique_ptr<BodyEnergyMeter> meter;
  if (fem) {
    body_frames = std::make_unique<BodyFrames>(fem->model());
    meter = std::make_unique<BodyEnergyMeter>(fem->model());
  }
  StepInfo last;
  double t = 0, t_frame = 0;
  long steps = 0, steps_since = 0, piter = 0, diter = 0, clamped = 0;
  long crossed_total = 0, inside_max = 0;
  std::vector<double> frame_times;
  int frame = 1;
  if (opt.resume) {
    t = rc.t;
    t_frame = rc.t_frame;
    steps = rc.steps;
    clamped = rc.clamped;
    crossed_total = rc.crossed;
    inside_max = rc.inside_max;
    last.dt = rc.last_dt;
    frame_times = rc.frame_times;
    frame = rc.next_frame;
    if (meter) meter->set_rotations(rc.energy_rotations);
    sum.frames = frame;
  }
  // Written after the frame that reaches each multiple of checkpoint_every, and at the end.
  const double every = scene.output.checkpoint_every;
  double next_checkpoint = every > 0 ? (std::floor(t / every + 1e-9) + 1) * every : 1e300;
  auto checkpoint = [&] {
    Checkpoint c;
    c.scene = identity;
    c.cursor.next_frame = frame;
    c.cursor.t = t;
    c.cursor.t_frame = t_frame;
    c.cursor.steps = steps;
    c.cursor.clamped = clamped;
    c.cursor.crossed = crossed_total;
    c.cursor.inside_max = inside_max;
    c.cursor.last_dt = last.dt;
    c.cursor.frame_times = frame_times;
    if (meter) c.cursor.energy_rotations = meter->rotations();
    sim.save(c.state);
    write_checkpoint(checkpoint_file, c);
    sum.state_hash = state_hash(c.state);
  };

  auto body_metrics = [&](BodyMetrics& bm) {
    fem->snapshot(body_snap);
    const int bad = non_finite_body(bodies, body_snap);
    if (bad >= 0) throw body_blow_up(steps, t, bodies, bad);
    meter->measure(body_snap, bm.kinetic_energy, bm.elastic_energy);
    for (int node : gauge_node)
      if (node >= 0) bm.displacement.push_back(Vec3d(body_snap.x[node] - bodies.x0[node]));
  };

  auto write_frame = [&](int frame) {
    char name[64];
    // Bodies first: a blown-up body stops the run before any part of this frame is written.
    BodyMetrics bm;
    if (fem) body_metrics(bm);
    if (solver) sim.snapshot(snap);
    const FrameMetrics m = compute_metrics(snap, model, scene.gauges, scene.domain);
    // Leaks: particles inside a body now, and those that crossed a surface since the last frame.
    const long inside = solver && fem ? sim.count_inside(snap.x, body_snap.x) : 0;
    const RayCouplingStats hs = hook ? hook->stats() : RayCouplingStats();
    crossed_total += hs.crossed;
    inside_max = std::max(inside_max, inside);
    Vec3d p_total(m.momentum[0], m.momentum[1], m.momentum[2]);
    if (fem)
      for (int i = 0; i < bodies.nodes; ++i)
        p_total += Vec3d(body_snap.v[std::size_t(i)]) * double(bodies.mass[std::size_t(i)]);
    if (solver && (scene.output.vtu || scene.output.ply)) {
      std::snprintf(name, sizeof name, "fluid_%06d", frame);
      const io::PointSet ps = fluid_frame(snap);
      if (scene.output.vtu) {
        io::write_vtu(frames_dir + "/" + name + ".vtu", ps);
        pvd->add(t, std::string("frames/") + name + ".vtu");
      }
      if (scene.output.ply) io::write_ply(frames_dir + "/" + name + ".ply", ps);
    }
    if (fem && scene.output.vtu) {
      std::snprintf(name, sizeof name, "bodies_%06d.vtu", frame);
      io::write_vtu(frames_dir + "/" + name, body_frames->surface(body_snap));
      bodies_pvd->add(t, std::string("frames/") + name);
      std::snprintf(name, sizeof name, "bodies_tets_%06d.vtu", frame);
      io::write_vtu(frames_dir + "/" + name, body_frames->tets(body_snap));
      tets_pvd->add(t, std::string("frames/") + name);
    }
    if (obstacles_pvd) {
      std::snprintf(name, sizeof name, "obstacles_%06d.vtu", frame);
      io::write_vtu(frames_dir + "/" + name, obstacle_surface(sim.obstacles(), t));
      obstacles_pvd->add(t, std::string("frames/") + name);
    }
    const StepProfile& prof = sim.profile();
    const BodyProfile fprof = fem ? fem->profile() : BodyProfile();
    const double per = prof.steps ? 1.0 / double(prof.steps) : 0.0;
    const double fper = fprof.steps ? 1.0 / double(fprof.steps) : 0.0;
    std::vector<double> row = {t,
                               double(steps),
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
                               steps_since ? double(diter) / steps_since : 0.0,
                               double(fprof.cg_iterations) * fper,
                               double(inside + hs.crossed),
                               double(hs.crossed),
                               double(inside),
                               hs.steps ? double(hs.contacts) / double(hs.steps) : 0.0,
                               p_total.x,
                               p_total.y,
                               p_total.z};
    {
      const BodyContactTally ct = fem ? sim.take_body_contact_tally() : BodyContactTally();
      const double per_step = ct.steps ? 1.0 / double(ct.steps) : 0.0;
      row.insert(row.end(), {double(ct.pairs) * per_step, double(ct.held) * per_step,
                             std::isfinite(ct.min_gap) ? ct.min_gap : -1.0,
                             fem ? double(inverted_elements(bodies, body_snap.x)) : 0.0,
                             fem ? double(intersecting_pairs(bodies, body_snap.x)) : 0.0,
                             double(ct.halvings)});
    }
    for (int k = 0; k < int(Stage::Count); ++k) row.push_back(prof.ms[k] * per);
    row.push_back(hs.ms_leak_check * per);
    row.push_back(prof.total() * per);
    std::size_t probe = 0, followed = 0;
    for (const GaugeSpec& g : scene.gauges) {
      if (g.kind != GaugeKind::Node) {
        row.push_back(m.probes.at(probe++));
        continue;
      }
      const Vec3d d = bm.displacement.at(followed++);
      row.insert(row.end(), {d.x, d.y, d.z});
    }
    const double span = t - t_frame;
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      row.push_back(bm.kinetic_energy.at(b));
      row.push_back(bm.elastic_energy.at(b));
      // Mean force of the fluid on the body since the last frame: impulse over time.
      const Vec3d f = b < hs.body_impulse.size() && span > 0 ? hs.body_impulse[b] / span : Vec3d();
      row.insert(row.end(), {f.x, f.y, f.z});
    }
    if (hook) hook->reset_stats();
    t_frame = t;
    frame_times.push_back(t);
    gauges.row(row);
    sim.reset_profile();
    steps_since = piter = diter = 0;
    ++sum.frames;
  };

  try {
    if (!opt.resume) write_frame(0);
    const double dt_max = scene.simulation.dt_max;
    while (t < duration - 1e-12) {
      const double next = std::min(duration, frame * frame_dt);
      double dt = 0;
      // Without fluid: equal steps of at most dt_max that end on the frame's time.
      const double left = next - t;
      const double n = std::max(1.0, std::ceil(left / dt_max - 1e-9));
      try {
        last = sim.step(solver ? left : left / n);
      } catch (const BodyStepError&) {
        fem->snapshot(body_snap);
        throw body_blow_up(steps + 1, t, bodies, non_finite_body(bodies, body_snap));
      }
      dt = last.dt;
      t = solver ? solver->time() : (n <= 1.0 ? next : t + dt);
      ++steps;
      ++steps_since;
      piter += last.pressure_iterations;
      diter += last.divergence_iterations;
      clamped += last.clamped;
      if (t >= next - 1e-9 * std::max(1.0, next)) {
        write_frame(frame);
        ++frame;
        if (t >= next_checkpoint - 1e-9 * std::max(1.0, t) && t < duration - 1e-12) {
          checkpoint();
          next_checkpoint = (std::floor(t / every + 1e-9) + 1) * every;
        }
      }
      progress.update(t, steps, wall(), false);
    }
  } catch (const SimulationError&) {
    progress.done();
    throw;
  }
  checkpoint();
  progress.update(t, steps, wall(), true);
  progress.done();
  sum.steps = steps;
  sum.crossed = crossed_total;
  sum.inside_max = inside_max;
  sum.particles = solver ? solver->count() : 0;
  sum.bodies = int(bodies.bodies.size());
  sum.body_nodes = bodies.nodes;
  sum.sim_seconds = t;
  sum.wall_seconds = wall();
  return sum;
}

}  // namespace sphfem
