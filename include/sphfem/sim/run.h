// Running a scene: the fluid and body solvers, frame files, gauges.csv and progress, as
// `sphfem run` does.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "sphfem/core/backend.h"
#include "sphfem/scene/spec.h"

namespace sphfem {

struct RunOptions {
  std::string out_dir;  // created if missing; frames/ and gauges.csv go inside
  Backend backend = Backend::Cpu;
  int threads = 0;       // CPU threads, 0 = all cores
  double duration = -1;  // s, overrides simulation.duration when >= 0
  bool progress = true;  // progress line on stderr
  // Continue from out_dir's checkpoint.bin: frames and gauge rows after it are written again,
  // those before it kept. Throws CheckpointError for an unusable checkpoint.
  bool resume = false;
};

struct RunSummary {
  std::string out_dir;
  long steps = 0;
  int frames = 0;
  int particles = 0;
  int bodies = 0, body_nodes = 0;
  long crossed = 0;     // particles that crossed a body surface, summed over the run
  long inside_max = 0;  // most particles inside a body at any frame
  double sim_seconds = 0;
  double wall_seconds = 0;
  std::uint64_t state_hash = 0;  // of the final state (sim/state.h)
};

// Throws SceneError/std::runtime_error before writing anything when the scene cannot run,
// and SimulationError when the fluid or a body blows up (every frame already written is kept).
RunSummary run_scene(const SceneSpec& scene, const RunOptions& options);

}  // namespace sphfem
