// What the Python module's Simulation holds: the core Simulation, the scene's gauge series and
// the frame clock, so that stepping from Python goes as `sphfem run` goes: steps end on the
// scene's frame times (1 / output.fps) and the gauges are recorded there (docs/python.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sphfem/io/pvd.h"
#include "sphfem/sim/body_frames.h"
#include "sphfem/sim/gauge_series.h"
#include "sphfem/sim/simulation.h"

namespace sphfem::python {

class Session {
 public:
  Session(const SceneSpec& scene, Backend backend);

  // One step of at most dt_limit seconds (<= 0: none) that ends no later than the next frame
  // time; a step reaching it records the gauges.
  StepInfo step(double dt_limit);
  // Steps until `seconds` more have passed, as `sphfem run` does for a run of that length;
  // returns the number of steps.
  long advance(double seconds);

  // The particles at the present state, as the frames have them; one snapshot per state,
  // shared by every array made from it and kept alive by them.
  std::shared_ptr<const FluidSnapshot> fluid();
  BodySnapshot bodies();

  // frames/<kind>_NNNNNN.{vtu,ply} of the present state in out_dir, with the .pvd collections
  // and run.json that `sphfem render` and ParaView read; numbered from 0 by the calls for one
  // folder (a call for another folder starts again from 0). Returns the files written.
  std::vector<std::string> write_frame(const std::string& out_dir);

  // The state as a checkpoint file (sim/checkpoint.h), and back; load() throws CheckpointError
  // for a file of another scene or a damaged one.
  void save(const std::string& path) const;
  void load(const std::string& path);
  std::string state_hash() const;

  void move_pinned(const std::vector<int>& nodes, const std::vector<Vec3d>& x);
  // The state changed: cached snapshots are stale.
  void changed() { ++version_; }

  Simulation& sim() { return *sim_; }
  const GaugeSeries& gauges() const { return *gauges_; }

 private:
  double next_frame_time() const { return frame_ * frame_dt_; }
  void after_step(double next);

  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<GaugeSeries> gauges_;
  std::unique_ptr<BodyFrames> body_frames_;
  double frame_dt_ = 0;
  int frame_ = 1;  // the next frame of the clock (frame 0 is the start)
  // write_frame's folder, its frames so far and their collections.
  std::string out_dir_;
  int written_ = 0;
  std::unique_ptr<io::PvdCollection> pvd_[3];  // fluid, bodies, bodies_tets
  long version_ = 0;                           // of the state, for the snapshot cache
  long snap_version_ = -1;
  std::shared_ptr<FluidSnapshot> snap_;
};

}  // namespace sphfem::python
