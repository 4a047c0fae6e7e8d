// The Python module's simulation session (session.h).
#include "session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/run_info.h"
#include "sphfem/io/vtu.h"
#include "sphfem/sim/checkpoint.h"
#include "sphfem/sim/fluid_frame.h"

namespace sphfem::python {

Session::Session(const SceneSpec& scene, Backend backend)
    : sim_(std::make_unique<Simulation>(scene, backend)), frame_dt_(1.0 / scene.output.fps) {
  gauges_ = std::make_unique<GaugeSeries>(*sim_);
  if (sim_->bodies()) body_frames_ = std::make_unique<BodyFrames>(sim_->bodies_model());
  // Frame 0, as a run's first gauge row.
  gauges_->record(*fluid(), bodies());
}

// Like the run loop: a frame is reached when the time is within round-off of it.
static bool reached(double t, double next) { return t >= next - 1e-9 * std::max(1.0, next); }

StepInfo Session::step(double dt_limit) {
  const double next = next_frame_time();
  double left = next - sim_->time();
  if (dt_limit > 0) left = std::min(left, dt_limit);
  StepInfo info;
  if (sim_->fluid()) {
    info = sim_->step(left);
  } else {
    // Bodies alone: equal steps of at most dt_max, as the run loop takes them.
    const double n = std::max(1.0, std::ceil(left / sim_->scene().simulation.dt_max - 1e-9));
    info = sim_->step(left / n);
  }
  after_step(next);
  return info;
}

void Session::after_step(double next) {
  changed();
  if (!reached(sim_->time(), next)) return;
  gauges_->record(*fluid(), bodies());
  ++frame_;
}

long Session::advance(double seconds) {
  if (!(seconds >= 0)) throw std::invalid_argument("advance: seconds must be >= 0");
  const double end = sim_->time() + seconds;
  long steps = 0;
  while (sim_->time() < end - 1e-12) {
    const double next = std::min(end, next_frame_time());
    const double left = next - sim_->time();
    if (sim_->fluid()) {
      sim_->step(left);
    } else {
      const double n = std::max(1.0, std::ceil(left / sim_->scene().simulation.dt_max - 1e-9));
      sim_->step(left / n);
    }
    after_step(next_frame_time());
    ++steps;
  }
  return steps;
}

std::shared_ptr<const FluidSnapshot> Session::fluid() {
  if (snap_version_ != version_ || !snap_) {
    auto s = std::make_shared<FluidSnapshot>();
    sim_->snapshot(*s);
    snap_ = std::move(s);
    snap_version_ = version_;
  }
  return snap_;
}

BodySnapshot Session::bodies() {
  BodySnapshot b;
  if (sim_->bodies()) sim_->bodies()->snapshot(b);
  return b;
}

std::vector<std::string> Session::write_frame(const std::string& out_dir) {
  const SceneSpec& scene = sim_->scene();
  const std::string dir = io::frames_dir(out_dir);
  io::ensure_directory(dir);
  if (out_dir != out_dir_ || !pvd_[0]) {
    out_dir_ = out_dir;
    written_ = 0;
    int k = 0;
    for (const char* kind : {"fluid", "bodies", "bodies_tets"})
      pvd_[k++] = std::make_unique<io::PvdCollection>(out_dir + "/" + kind + ".pvd");
    io::RunInfo info;
    info.scene = scene.path;
    info.name = scene.name;
    info.particle_radius = scene.fluid.particle_radius;
    info.domain_min = scene.domain.lo;
    info.domain_max = scene.domain.hi;
    info.solver = scene.simulation.solver == SolverKind::DFSPH ? "dfsph" : "wcsph";
    info.fps = scene.output.fps;
    for (const BodySpec& b : scene.bodies) info.bodies.push_back(b.name);
    io::write_run_info(out_dir, info);
  }
  char num[16];
  std::snprintf(num, sizeof num, "_%06d", written_);
  std::vector<std::string> files;
  const double t = sim_->time();
  auto vtu = [&](int k, const char* kind, const io::PointSet& ps) {
    const std::string name = std::string(kind) + num + ".vtu";
    files.push_back(dir + "/" + name);
    io::write_vtu(files.back(), ps);
    pvd_[k]->add(t, "frames/" + name);
  };
  if (sim_->fluid()) {
    const io::PointSet ps = fluid_frame(*fluid());
    vtu(0, "fluid", ps);
    if (scene.output.ply) {
      files.push_back(dir + "/fluid" + num + ".ply");
      io::write_ply(files.back(), ps);
    }
  }
  if (body_frames_) {
    const BodySnapshot b = bodies();
    vtu(1, "bodies", body_frames_->surface(b));
    vtu(2, "bodies_tets", body_frames_->tets(b));
  }
  ++written_;
  return files;
}

void Session::save(const std::string& path) const {
  Checkpoint c;
  c.scene = scene_identity(sim_->scene());
  c.cursor.next_frame = frame_;
  c.cursor.t = sim_->time();
  c.cursor.t_frame = (frame_ - 1) * frame_dt_;
  c.cursor.steps = sim_->steps();
  sim_->save(c.state);
  write_checkpoint(path, c);
}

void Session::load(const std::string& path) {
  const Checkpoint c = read_checkpoint(path);
  if (c.scene != scene_identity(sim_->scene()))
    throw CheckpointError(path +
                          ": the checkpoint was written by another scene (or the scene was "
                          "edited since); load it into a Simulation of the scene that wrote it");
  try {
    sim_->load(c.state);
  } catch (const std::invalid_argument& e) {
    throw CheckpointError(path + ": " + e.what() + "; load it into a Simulation of its scene");
  }
  frame_ = c.cursor.next_frame;
  changed();
}

std::string Session::state_hash() const {
  SimState s;
  sim_->save(s);
  return hash_hex(sphfem::state_hash(s));
}

void Session::move_pinned(const std::vector<int>& nodes, const std::vector<Vec3d>& x) {
  sim_->move_pinned(nodes, x);
  changed();
}

}  // namespace sphfem::python
